// Coulomb friction between rigid bodies (docs/physics.md "Contact between
// bodies"): at every vertex of body a inside box b (body_pairs.h), smoothed
// Coulomb friction as with the planes (friction_force.cc; IPC, Li et al.
// 2020, sec. 5.2) on the velocity of the vertex relative to b's material
// point under it, with mu = sqrt(mu_a mu_b) (each body's "friction") and
// the normal force f_n = -phi'(d) of the contact's penalty:
//
//   v_rel = sum_u c_u v_u,   v_t = T v_rel,   T = I - n n^T,  n = a_i / |a_i|,
//   f = -mu f_n g(|v_t|) v_t  on the vertex,  -f on b's point Y under it,
//
// so the generalized force on the pair's unknown u is F_u = c_u f, with
// c = (1, X, -1, -Y) (body_pairs.h). Both bodies feel the force at the same
// point, so the pair conserves linear and angular momentum.
//
// Jacobians (G = g I + (g'/y) v_t v_t^T, B = A_b^{-1}, dA_b/dt = A_b'):
//   dF_u/dv_w = -mu f_n c_u c_w (g T + (g'/y) v_t v_t^T);
//   dF_u/dq_w = c_u df/dq_w - [u = a_k of b] c_w f (B^T e_k)^T, where
//   df/dq_w = -mu (g v_t (df_n/dq_w)^T + f_n G dv_t/dq_w),
//   df_n/dq_w = -phi''(d) grad_w d,
//   dv_t/dq_w = T dv_rel/dq_w + [w = a_i of b] (-(n . v_rel) T - n v_t^T) / |a_i|,
//   dv_rel/dq_w = -c_w A_b' B      (through Y: dY/dq_w = c_w B).
//
// Lagged (MechanicalSystem::lag_normal_forces, as the planes' friction):
// f_n, the contacts, T and c are taken at the lagged state, and friction is
// F = -dW/dv of W(v) = sum mu f_n f0(|T v_rel|) with no x-dependence.
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_pairs.h"
#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"

namespace springlab {

// body_body_contact.cc: two overlapping boxes of their own (apart in
// kDefinite states).
void add_random_body_pair(Scene& scene, std::mt19937& rng, RandomStates states);
bool has_body_contacts(const Scene& scene);

namespace {

class BodyBodyFrictionForce final : public ForceTerm {
 public:
  BodyBodyFrictionForce(const Scene& scene, const BodyLayout& layout, const Contact& contact)
      : pairs_(scene, layout), law_(contact), eps_(contact.smoothing) {}

  std::string_view name() const override { return "body-body friction"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kNonlinear; }
  bool symmetric_jacobians() const override { return lagged_; }
  bool derives_from_potentials() const override { return lagged_; }

  double velocity_potential(const Configuration& c) const override {
    if (!lagged_) return 0.0;
    double sum = 0.0;
    for (const Sliding& s : lagged_contacts_) {
      const double y = (s.T * relative_velocity(s, c.v)).norm();
      sum += s.mu * s.f_n * friction_potential(y, eps_);
    }
    return sum;
  }

  void lag(const Configuration* c) override {
    lagged_ = false;
    lagged_contacts_.clear();
    if (c == nullptr) return;
    for_each_sliding(*c, [&](const Sliding& s) { lagged_contacts_.push_back(s); });
    lagged_ = true;
  }

  void add_force(const Configuration& c, double* f) const override {
    visit(c, [&](const Sliding& s) {
      const Eigen::Vector3d vt = s.T * relative_velocity(s, c.v);
      const FrictionWeight w = friction_weight(vt.squaredNorm(), eps_);
      const Eigen::Vector3d force = -s.mu * s.f_n * w.g * vt;
      for (std::size_t u = 0; u < 8; ++u) {
        if (s.index[u] < 0) continue;
        for (int r = 0; r < 3; ++r) f[3 * s.index[u] + r] += s.c[u] * force[r];
      }
    });
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    pairs_.declare_blocks(builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override { slots_ = pairs_.find_slots(pattern); }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    visit(c, [&](const Sliding& s) {
      const BlockSlot* slots = slots_.data() + s.pair * 64;
      const Eigen::Vector3d v_rel = relative_velocity(s, c.v);
      const Eigen::Vector3d vt = s.T * v_rel;
      const FrictionWeight w = friction_weight(vt.squaredNorm(), eps_);
      const Eigen::Matrix3d G = w.g * Eigen::Matrix3d::Identity() + w.g_over_y * vt * vt.transpose();
      if (dfdv != nullptr) {
        const Eigen::Matrix3d D = -s.mu * s.f_n * G * s.T;  // d f / d v_rel
        for (std::size_t u = 0; u < 8; ++u) {
          for (std::size_t q = 0; q < 8; ++q) {
            if (s.index[u] >= 0 && s.index[q] >= 0) add(dfdv, slots[8 * u + q], D, s.c[u] * s.c[q]);
          }
        }
      }
      if (dfdx == nullptr || lagged_) return;
      const Eigen::Vector3d force = -s.mu * s.f_n * w.g * vt;
      const Eigen::Matrix3d B = s.Ab.inverse();
      const Eigen::Matrix3d AdotB = s.Abdot * B;
      const double a_norm = s.Ab.col(s.axis).norm();
      const Eigen::Vector3d n = s.Ab.col(s.axis) / a_norm;
      for (std::size_t q = 0; q < 8; ++q) {
        if (s.index[q] < 0) continue;
        // df/dq_q
        Eigen::Matrix3d dvt = -s.c[q] * s.T * AdotB;
        if (q == 5 + static_cast<std::size_t>(s.axis)) {
          dvt += -(n.dot(v_rel) * s.T + n * vt.transpose()) / a_norm;
        }
        const Eigen::Matrix3d df = -s.mu * (w.g * vt * (-s.curvature * s.grad[q]).transpose() +
                                            s.f_n * G * dvt);
        for (std::size_t u = 0; u < 8; ++u) {
          if (s.index[u] < 0) continue;
          Eigen::Matrix3d block = s.c[u] * df;
          if (u >= 5) block -= s.c[q] * force * B.row(static_cast<Eigen::Index>(u - 5));
          add(dfdx, slots[8 * u + q], block, 1.0);
        }
      }
    });
  }

 private:
  // One vertex in contact with friction, and what its force needs.
  struct Sliding {
    std::size_t pair;
    int axis;
    std::array<int, 8> index;
    std::array<double, 8> c;
    std::array<Eigen::Vector3d, 8> grad;  // of the gap d
    Eigen::Matrix3d T, Ab, Abdot;
    double mu, f_n, curvature;
  };

  static void add(double* values, const BlockSlot& slot, const Eigen::Matrix3d& M, double s) {
    double K[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int q = 0; q < 3; ++q) K[r][q] = M(r, q);
    }
    add_block<3>(values, slot, K, s);
  }

  static Eigen::Vector3d relative_velocity(const Sliding& s, const double* v) {
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (std::size_t u = 0; u < 8; ++u) {
      if (s.index[u] < 0) continue;
      for (int r = 0; r < 3; ++r) out[r] += s.c[u] * v[3 * s.index[u] + r];
    }
    return out;
  }

  // The live contacts at c (positions, and b's dA/dt from c.v).
  template <typename Visit>
  void for_each_sliding(const Configuration& c, Visit visit) const {
    if (law_.model != ContactModel::kPenalty) return;
    pairs_.for_each_inside(c.x, [&](const BodyPairs::Touch& t) {
      const BodyPairs::Pair& pair = pairs_.pairs()[t.pair];
      if (!(pair.friction > 0.0)) return;
      const ContactPhi phi = law_(t.d);
      if (phi.slope == 0.0) return;
      Sliding s;
      s.pair = t.pair;
      s.axis = t.axis;
      s.index = pair.index;
      s.c = t.c;
      s.grad = pairs_.gap_gradient(t);
      const Eigen::Vector3d n = t.Ab.col(t.axis).normalized();
      s.T = Eigen::Matrix3d::Identity() - n * n.transpose();
      s.Ab = t.Ab;
      s.Abdot = c.v != nullptr ? pairs_.member(pair.b).A(c.v) : Eigen::Matrix3d::Zero();
      if (pairs_.member(pair.b).first < 0) s.Abdot.setZero();
      s.mu = pair.friction;
      s.f_n = -phi.slope;
      s.curvature = phi.curvature;
      visit(s);
    });
  }

  // Live, or the lagged contacts (their f_n, T, c fixed; no x-dependence).
  template <typename Visit>
  void visit(const Configuration& c, Visit visit_one) const {
    if (lagged_) {
      for (const Sliding& s : lagged_contacts_) visit_one(s);
      return;
    }
    for_each_sliding(c, visit_one);
  }

  BodyPairs pairs_;
  ContactLaw law_;
  double eps_;
  bool lagged_ = false;
  std::vector<Sliding> lagged_contacts_;
  std::vector<BlockSlot> slots_;
};

bool has_body_friction(const Scene& scene) {
  if (!has_body_contacts(scene)) return false;
  int rough = 0;
  for (const Body& b : scene.get<Bodies>()) rough += b.friction > 0.0 ? 1 : 0;
  return rough >= 2;
}

std::unique_ptr<ForceTerm> make_body_body_friction(const Scene& scene,
                                                   const ParticleOrder& order) {
  if (!has_body_friction(scene)) return nullptr;
  return std::make_unique<BodyBodyFrictionForce>(scene, body_layout(scene, order.free_particles),
                                                 scene.get<Contact>());
}

// Random instances: body-body contact's overlapping pair, then a friction
// coefficient for every body.
void add_random_body_friction_pair(Scene& scene, std::mt19937& rng, RandomStates states) {
  add_random_body_pair(scene, rng, states);
  if (scene.dimension != 3) return;
  std::uniform_real_distribution<double> u(0.3, 0.8);
  for (Body& b : scene.block<Bodies>()) b.friction = u(rng);
}

}  // namespace

void body_body_friction_memory(const Scene& scene, MemoryEstimate& out);  // body_pair_memory.cc

const ElementKind& body_body_friction_kind() {
  static const ElementKind kind = {
      .name = "body-body-friction",
      .refers_to_particles = true,
      .make = make_body_body_friction,
      .memory = body_body_friction_memory,  // body_pair_memory.cc
      .add_random = add_random_body_friction_pair,
  };
  return kind;
}

}  // namespace springlab
