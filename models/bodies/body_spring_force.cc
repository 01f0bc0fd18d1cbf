// Hooke springs with a body point at an end (body_springs.h, docs/physics.md
// "Springs to body points"). Each end is at
//   particle p:         x = x_p                  (weights w = (1))
//   point X of body b:  x = p + A X = p + sum_i X_i a_i   (w = (1, X_1, X_2, X_3))
// with X in the body's principal frame (X = R^T (X_file - c)), so
//   dx/dp = I,  dx/da_i = X_i I:  x = sum_alpha w_alpha q_alpha,
// q_alpha the end's unknowns (a particle, or the body's p, a_1, a_2, a_3).
// A fixed particle or a fixed body's point is a constant place.
//
// With d = x_i - x_j, l = |d|, u = d / l, the spring's force on end i is
// F = -k (1 - L/l) d (springs: spring_force.cc) and -F on end j, so the
// generalized force on unknown alpha of end e is s_e w_alpha F (s_i = +1,
// s_j = -1), and with K = k [u u^T + (1 - L/l)(I - u u^T)] (= dF/dx_j = -dF/dx_i)
//   dG_alpha / dq_beta = -s_alpha s_beta w_alpha w_beta K,
// a block matrix over the (up to 8) unknowns of the two ends. Its definite
// part clamps 1 - L/l at 0 (a compressed spring drops its negative
// transverse stiffness), as for particle springs. Potential k (l - L)^2 / 2.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_springs.h"
#include "models/core/element_kind.h"

namespace springlab {
namespace {

// One end: x = offset + sum_k w[k] x[index[k]]; its indices are unknowns
// when `free` (else they read a fixed particle's place, or there are none).
struct EndMap {
  int n = 0;
  int index[4] = {0, 0, 0, 0};
  double w[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  bool free = false;

  Eigen::Vector3d point(const double* x) const {
    Eigen::Vector3d out = offset;
    for (int k = 0; k < n; ++k) {
      for (int r = 0; r < 3; ++r) out[r] += w[k] * x[index[k] * 3 + r];
    }
    return out;
  }
};

// One unknown of a spring: internal index, weight w_alpha times the end's sign.
struct Unknown {
  int index;
  double sw;
};

struct SpringData {
  EndMap i, j;
  double k, rest;
  std::vector<Unknown> unknowns;  // of both ends' free unknowns, i's first
};

EndMap end_map(const Scene& scene, const ParticleOrder& order, const BodyLayout& layout,
               const SpringEnd& e) {
  EndMap m;
  if (!e.is_body()) {
    m.n = 1;
    m.index[0] = order.internal_of_scene[static_cast<std::size_t>(e.particle)];
    m.w[0] = 1.0;
    m.free = m.index[0] < order.free_particles;
    return m;
  }
  const RigidBody& body = layout.bodies[static_cast<std::size_t>(e.body)];
  const Eigen::Vector3d X = body.mass.frame.transpose() * (e.X - body.mass.centre);
  const int first = layout.first[static_cast<std::size_t>(e.body)];
  if (first < 0) {  // a fixed body: the point stays where it starts
    m.offset = spring_end_rest_point(scene, e);
    return m;
  }
  m.n = 4;
  m.free = true;
  const double w[4] = {1.0, X.x(), X.y(), X.z()};
  for (int a = 0; a < 4; ++a) {
    m.index[a] = first + a;
    m.w[a] = w[a];
  }
  return m;
}

class BodySpringForce final : public ForceTerm {
 public:
  BodySpringForce(const Scene& scene, const ParticleOrder& order) {
    const BodyLayout layout = body_layout(scene, order);
    for (const BodySpring& s : scene.get<BodySprings>()) {
      SpringData d{end_map(scene, order, layout, s.i), end_map(scene, order, layout, s.j), s.k,
                   s.rest, {}};
      for (const auto& [end, sign] : {std::pair{&d.i, 1.0}, std::pair{&d.j, -1.0}}) {
        if (!end->free) continue;
        for (int a = 0; a < end->n; ++a) d.unknowns.push_back({end->index[a], sign * end->w[a]});
      }
      springs_.push_back(std::move(d));
    }
  }

  std::string_view name() const override { return "body spring"; }
  bool conservative() const override { return true; }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for (const SpringData& s : springs_) {
      const double stretch = (s.i.point(c.x) - s.j.point(c.x)).norm() - s.rest;
      sum += 0.5 * s.k * stretch * stretch;
    }
    return sum;
  }

  void add_force(const Configuration& c, double* f) const override {
    for (const SpringData& s : springs_) {
      const Eigen::Vector3d F = force_on_i(s, c.x);
      for (const Unknown& u : s.unknowns) {
        for (int r = 0; r < 3; ++r) f[u.index * 3 + r] += u.sw * F[r];
      }
    }
  }

  // The fast solvers: a spring from a particle to a fixed body's point is a
  // distance constraint to an anchor; one whose end moves with a body's 12
  // unknowns has no such form.
  bool distance_constraints(std::vector<DistanceConstraint>& out) const override {
    for (const SpringData& s : springs_) {
      if (s.i.n == 4 || s.j.n == 4) return false;
    }
    for (const SpringData& s : springs_) {
      const EndMap& particle = s.i.n == 1 ? s.i : s.j;
      const EndMap& anchor = s.i.n == 1 ? s.j : s.i;
      if (!particle.free) continue;  // a fixed particle to a fixed body: moves nothing
      out.push_back({.a = particle.index[0], .b = -1, .anchor = anchor.offset, .stiffness = s.k,
                     .length = s.rest});
    }
    return true;
  }
  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "a spring to a free body's point has no distance-constraint form (its end moves with "
          "the body's 12 unknowns); use implicit-euler or another Newton method";
    return false;
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (const SpringData& s : springs_) {
      for (const Unknown& a : s.unknowns) {
        for (const Unknown& b : s.unknowns) builder.add_block(a.index, b.index);
      }
    }
  }
  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    for (const SpringData& s : springs_) {
      for (const Unknown& a : s.unknowns) {
        for (const Unknown& b : s.unknowns) slots_.push_back(find_block_slot(pattern, 3, a.index, b.index));
      }
    }
  }
  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx != nullptr) add_stiffness(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    add_stiffness(c, dfdx, true);
  }

 private:
  static Eigen::Vector3d force_on_i(const SpringData& s, const double* x) {
    const Eigen::Vector3d d = s.i.point(x) - s.j.point(x);
    const double l = d.norm();
    if (l == 0.0) return Eigen::Vector3d::Zero();  // no direction (exact for L = 0 too)
    return -s.k * (1.0 - s.rest / l) * d;
  }

  // -s_a s_b w_a w_b K on block (a, b).
  void add_stiffness(const Configuration& c, double* dfdx, bool definite) const {
    std::size_t slot = 0;
    for (const SpringData& s : springs_) {
      const Eigen::Vector3d d = s.i.point(c.x) - s.j.point(c.x);
      const double l = d.norm();
      double K[3][3];
      if (s.rest == 0.0 || l == 0.0) {
        // Linear (L = 0): K = k I; a positive-rest spring at zero length has
        // no defined K, use 0 (as spring_force.cc).
        const double diag = s.rest == 0.0 ? s.k : 0.0;
        for (int r = 0; r < 3; ++r) {
          for (int q = 0; q < 3; ++q) K[r][q] = r == q ? diag : 0.0;
        }
      } else {
        const Eigen::Vector3d u = d / l;
        double transverse = 1.0 - s.rest / l;
        if (definite) transverse = std::max(transverse, 0.0);
        for (int r = 0; r < 3; ++r) {
          for (int q = 0; q < 3; ++q) {
            K[r][q] = s.k * (u[r] * u[q] + transverse * ((r == q ? 1.0 : 0.0) - u[r] * u[q]));
          }
        }
      }
      for (const Unknown& a : s.unknowns) {
        for (const Unknown& b : s.unknowns) add_block<3>(dfdx, slots_[slot++], K, -a.sw * b.sw);
      }
    }
  }

  std::vector<SpringData> springs_;
  std::vector<BlockSlot> slots_;
};

}  // namespace

std::unique_ptr<ForceTerm> make_body_spring_force(const Scene& scene, const ParticleOrder& order) {
  if (scene.get<BodySprings>().empty()) return nullptr;
  return std::make_unique<BodySpringForce>(scene, order);
}

}  // namespace springlab
