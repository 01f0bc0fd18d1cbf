// Hooke springs (SPEC §2), the course's F^int:
//   d = x_i - x_j, l = |d|, u = d / l
//   F_i = -k (l - L) u,  F_j = -F_i,  V = k (l - L)^2 / 2
// Stiffness block (dF_i/dx_i = -K, dF_i/dx_j = +K):
//   K = k [ u u^T + (1 - L/l) (I - u u^T) ]
// K is indefinite when the spring is compressed (l < L): the transverse term
// is negative, which is why implicit methods cannot assume a definite matrix.
// A zero-rest-length spring is linear: F_i = -k d, K = k I.
#include <cmath>
#include <memory>
#include <vector>

#include "models/force_registry.h"

namespace springlab {
namespace {

struct SpringData {
  int a, b;  // internal particle indices
  double k, rest;
};

class SpringForce final : public ForceTerm {
 public:
  SpringForce(std::vector<SpringData> springs, int dim, int free_particles)
      : springs_(std::move(springs)), dim_(dim), free_(free_particles) {}

  std::string_view name() const override { return "spring"; }
  bool conservative() const override { return true; }
  EnergyKind energy_kind() const override { return EnergyKind::kSpring; }

  void add_force(const Configuration& c, double* f) const override {
    if (dim_ == 2) add_force_d<2>(c, f); else add_force_d<3>(c, f);
  }

  double potential_energy(const Configuration& c) const override {
    double energy = 0.0;
    for (const SpringData& s : springs_) {
      double l2 = 0.0;
      for (int r = 0; r < dim_; ++r) {
        const double d = c.x[s.a * dim_ + r] - c.x[s.b * dim_ + r];
        l2 += d * d;
      }
      const double stretch = std::sqrt(l2) - s.rest;
      energy += 0.5 * s.k * stretch * stretch;
    }
    return energy;
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (const SpringData& s : springs_) declare_pair_blocks(builder, s.a, s.b, free_);
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    slots_.reserve(springs_.size());
    for (const SpringData& s : springs_) {
      slots_.push_back(find_pair_slots(pattern, dim_, s.a, s.b, free_));
    }
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    if (dim_ == 2) add_stiffness_d<2>(c, dfdx); else add_stiffness_d<3>(c, dfdx);
  }

 private:
  template <int D>
  void add_force_d(const Configuration& c, double* f) const {
    for (const SpringData& s : springs_) {
      const double* xa = c.x + s.a * D;
      const double* xb = c.x + s.b * D;
      double d[D];
      double l2 = 0.0;
      for (int r = 0; r < D; ++r) {
        d[r] = xa[r] - xb[r];
        l2 += d[r] * d[r];
      }
      // F_i = -k (l - L) d / l = -k (1 - L/l) d; with L = 0 simply -k d.
      double scale = s.k;
      if (s.rest != 0.0) {
        const double l = std::sqrt(l2);
        scale = l > 0.0 ? s.k * (1.0 - s.rest / l) : 0.0;
      }
      double* fa = f + s.a * D;
      double* fb = f + s.b * D;
      for (int r = 0; r < D; ++r) {
        fa[r] -= scale * d[r];
        fb[r] += scale * d[r];
      }
    }
  }

  template <int D>
  void add_stiffness_d(const Configuration& c, double* values) const {
    for (std::size_t n = 0; n < springs_.size(); ++n) {
      const SpringData& s = springs_[n];
      double K[D][D];
      spring_stiffness<D>(c.x + s.a * D, c.x + s.b * D, s.k, s.rest, K);
      add_pair_blocks<D>(values, slots_[n], K, -1.0);  // dF_a/dx_a = -K
    }
  }

  template <int D>
  static void spring_stiffness(const double* xa, const double* xb, double k, double rest,
                               double (&K)[D][D]) {
    double d[D];
    double l2 = 0.0;
    for (int r = 0; r < D; ++r) {
      d[r] = xa[r] - xb[r];
      l2 += d[r] * d[r];
    }
    const double l = std::sqrt(l2);
    if (rest == 0.0 || l == 0.0) {
      // Linear spring (or a degenerate one with no direction): K = k I when
      // L = 0; a positive-rest spring at zero length has no defined K, use 0.
      const double diag = rest == 0.0 ? k : 0.0;
      for (int r = 0; r < D; ++r)
        for (int q = 0; q < D; ++q) K[r][q] = r == q ? diag : 0.0;
      return;
    }
    const double transverse = k * (1.0 - rest / l);
    const double axial_minus_transverse = k - transverse;  // k L / l
    for (int r = 0; r < D; ++r) {
      for (int q = 0; q < D; ++q) {
        const double uu = d[r] * d[q] / l2;
        K[r][q] = axial_minus_transverse * uu + (r == q ? transverse : 0.0);
      }
    }
  }

  std::vector<SpringData> springs_;
  std::vector<PairSlots> slots_;
  int dim_;
  int free_;
};

}  // namespace

std::unique_ptr<ForceTerm> make_spring_force(const Scene& scene, const ParticleOrder& order) {
  std::vector<SpringData> springs;
  springs.reserve(scene.springs.size());
  for (const Spring& s : scene.springs) {
    if (s.k == 0.0) continue;  // a pure damper: spring_damping_force.cc
    springs.push_back({order.internal_of_scene[s.i], order.internal_of_scene[s.j], s.k, s.rest});
  }
  if (springs.empty()) return nullptr;
  return std::make_unique<SpringForce>(std::move(springs), order.dim, order.free_particles);
}

}  // namespace springlab
