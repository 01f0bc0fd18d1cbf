// The "fluid-viscosity" element kind: the laminar viscous force of a fluid
// (docs/physics.md "Fluids"), the SPH form of nu laplacian(v) of Morris,
// Fox and Zhu (1997, J. Comput. Phys. 136:214) with constant mu = rho0 nu
// and both densities taken as rho0 (as weakly compressible SPH keeps them
// within about 1 %):
//
//   F_i = -sum_j kappa_ij (v_i - v_j),
//   kappa_ij = -(2 nu m_i m_j / rho0) r W'(r) / (r^2 + eta^2) >= 0,
//   r = |x_i - x_j|,  eta^2 = 0.01 h^2 (keeps coincident particles finite).
//
// It has no scene key of its own: it reads each fluid's "viscosity"
// (fluids.h, fluid_kind.cc); a fluid of viscosity 0 has none. The pair
// forces are equal and opposite (momentum is conserved); its power
// F.v = -sum_pairs kappa |v_i - v_j|^2 <= 0 is what the "viscous-work"
// column accumulates (docs/physics.md "Energies").
// Jacobians, with w = v_i - v_j, u = (x_i - x_j) / r, kappa = C phi(r):
//   dF_i/dv_i = -kappa I, dF_i/dv_j = kappa I          (symmetric, semidefinite)
//   dF_i/dx_i = -C phi'(r) w u^T, dF_i/dx_j = +C phi'(r) w u^T  (not symmetric)
//   phi = r W' / (r^2 + eta^2),
//   phi' = r W'' / (r^2 + eta^2) + W' (eta^2 - r^2) / (r^2 + eta^2)^2,
// and F_j = -F_i. Its pairs change as the fluid moves: like the pressure's
// (fluid_pressure_force.cc) its pattern holds the pairs within 2h + a skin
// and follows the fluid.
//
// Lagging (MechanicalSystem::lag_normal_forces, as friction's normal
// forces). Evaluated live, the viscosity is a force of (x, v) like spring
// damping: no potential, and a dF/dx that is not symmetric, so Newton would
// work on ||r|| with sparse LU. The hand-written implicit methods lag its
// pairs and coefficients kappa_ij from the step's start during their solve:
// it is then F = -dW/dv of the dissipation potential
//   W(v) = 1/2 sum_pairs kappa_ij |v_i - v_j|^2    (kappa_ij at x_n),
// with dF/dx = 0 and dF/dv = -d^2W/dv^2 symmetric, negative semidefinite,
// so Newton minimizes the step's incremental potential with the symmetric
// definite matrix (Cholesky, CG). The change within a step is kappa's
// variation over h (O(h), as for friction); explicit and adaptive methods
// evaluate it live.
#include <cmath>
#include <memory>
#include <vector>

#include "models/core/element_kind.h"
#include "models/fluids/fluid_forces.h"
#include "models/fluids/fluid_pattern.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_particles.h"

namespace springlab {
namespace {

constexpr double kEta2 = 0.01;         // eta^2 / h^2

class FluidViscosityForce final : public ForceTerm {
 public:
  FluidViscosityForce(std::vector<std::shared_ptr<SphParticles>> fluids, std::vector<double> nu,
                      int dim, int free_particles, std::vector<double> x_all)
      : fluids_(std::move(fluids)),
        nu_(std::move(nu)),
        dim_(dim),
        free_(free_particles),
        pattern_(1.0, dim, x_all),
        x_size_(x_all.size()) {}

  std::string_view name() const override { return "fluid-viscosity"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kCoupled; }
  // Live: dF/dx is not symmetric and F has no potential; lagged: F = -dW/dv
  // (see the header).
  bool symmetric_jacobians() const override { return lagged_; }
  bool derives_from_potentials() const override { return lagged_; }
  double velocity_potential(const Configuration& c) const override {
    if (!lagged_) return 0.0;
    double sum = 0.0;
    for (const LaggedPair& p : lagged_pairs_) {
      double w2 = 0.0;
      for (int r = 0; r < dim_; ++r) {
        const double w = c.v[p.a * dim_ + r] - c.v[p.b * dim_ + r];
        w2 += w * w;
      }
      sum += 0.5 * p.kappa * w2;
    }
    return sum;
  }
  void lag(const Configuration* c, double) override {
    lagged_ = false;
    lagged_pairs_.clear();
    lagged_slots_.clear();
    if (c == nullptr) return;
    for_each_pair(*c, [&](const Pair& p) {
      const double kappa = p.C * p.phi;
      if (kappa != 0.0) lagged_pairs_.push_back({p.a, p.b, kappa});
    });
    // Where the lagged pairs were found: the pattern declares the pairs
    // around it for the duration of the lag (they do not move with c).
    x_lag_.assign(c->x, c->x + x_size_);
    lagged_ = true;
  }

  void add_force(const Configuration& c, double* f) const override {
    if (lagged_) {
      add_lagged(c.v, f);
      return;
    }
    for_each_pair(c, [&](const Pair& p) { add_pair(c.v, p.a, p.b, p.C * p.phi, f); });
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    pattern_.declare(fluids_, builder, free_);
  }
  void bind_jacobian(const SparseMatrix& pattern) override {
    pattern_matrix_ = &pattern;
    lagged_slots_.clear();
  }
  // Neighbours couple: fluid_pattern.h. Lagged, the pairs are those at the
  // lag's configuration, whatever c is.
  bool pattern_varies() const override { return true; }
  std::string pattern_change() const override {
    return "its particles change neighbours (a fluid)";
  }
  bool pattern_holds(const Configuration& c) const override {
    return pattern_.holds(fluids_, lagged_ ? x_lag_.data() : c.x);
  }
  void follow_pattern(const Configuration& c) override {
    pattern_.follow(fluids_, lagged_ ? x_lag_.data() : c.x);
  }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    if (dim_ == 2) add_jacobians_d<2>(c, dfdx, dfdv); else add_jacobians_d<3>(c, dfdx, dfdv);
  }
  // Lagged: dF/dx = 0, and the force is linear in v, F = dF/dv v, so
  // dF/dv p is the lagged force at the velocities p (live, dF/dx is not
  // symmetric: the matrix is assembled).
  bool has_jacobian_products() const override { return lagged_; }
  void add_jacobian_products(const Configuration&, bool, const double* p, double*,
                             double* dfdv_p) const override {
    if (dfdv_p != nullptr) add_lagged(p, dfdv_p);
  }

 private:
  // C = -2 nu m_a m_b / rho0.
  double coefficient(std::size_t k, int a, int b) const {
    const SphParticles& fluid = *fluids_[k];
    return -2.0 * nu_[k] * fluid.mass(a) * fluid.mass(b) / fluid.eos().rho0;
  }
  // phi(r) and phi'(r).
  static void shape(const SphParticles& fluid, double r, double& phi, double& slope) {
    const CubicSpline& w = fluid.kernel();
    const double eta2 = kEta2 * w.h * w.h;
    const double s = r * r + eta2;
    const double w1 = w.slope(r);
    phi = r * w1 / s;
    slope = r * w.curvature(r) / s + w1 * (eta2 - r * r) / (s * s);
  }

  template <int D>
  void add(double* values, int p, int q, const double (&M)[D][D], double s) const {
    if (p >= free_ || q >= free_) return;
    add_block<D>(values, find_block_slot(*pattern_matrix_, D, p, q), M, s);
  }

  // One pair of a fluid at the configuration: its particles' internal
  // indices a, b, separation d = x_a - x_b and length r, C and phi(r), phi'(r).
  struct Pair {
    int a, b;
    const double* d;
    double r, C, phi, slope;
  };
  template <class Visit>
  void for_each_pair(const Configuration& c, Visit visit) const {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      SphParticles& fluid = *fluids_[k];
      fluid.update(c.x);
      const auto& pairs = fluid.pairs();
      for (std::size_t e = 0; e < pairs.size(); ++e) {
        const auto [a, b] = pairs[e];
        Pair p{.a = fluid.index(a), .b = fluid.index(b), .d = fluid.separation(e),
               .r = fluid.distance(e), .C = coefficient(k, a, b)};
        shape(fluid, p.r, p.phi, p.slope);
        visit(p);
      }
    }
  }

  // f += pair (a, b)'s force -kappa (v_a - v_b) on a, its opposite on b.
  void add_pair(const double* v, int a, int b, double kappa, double* f) const {
    for (int r = 0; r < dim_; ++r) {
      const double force = -kappa * (v[a * dim_ + r] - v[b * dim_ + r]);
      f[a * dim_ + r] += force;
      f[b * dim_ + r] -= force;
    }
  }
  // f += the lagged pairs' forces at velocities v (every particle).
  void add_lagged(const double* v, double* f) const {
    for (const LaggedPair& p : lagged_pairs_) add_pair(v, p.a, p.b, p.kappa, f);
  }

  template <int D>
  void add_jacobians_d(const Configuration& c, double* dfdx, double* dfdv) const {
    if (lagged_) {
      // dF/dv = -d^2W/dv^2; dF/dx = 0. The pairs are fixed for the lag:
      // their slots are found once per lag and pattern.
      if (dfdv == nullptr) return;
      if (lagged_slots_.size() != lagged_pairs_.size()) {
        lagged_slots_.clear();
        for (const LaggedPair& p : lagged_pairs_) {
          lagged_slots_.push_back(find_pair_slots(*pattern_matrix_, D, p.a, p.b, free_));
        }
      }
      for (std::size_t k = 0; k < lagged_pairs_.size(); ++k) {
        double K[D][D] = {};
        for (int i = 0; i < D; ++i) K[i][i] = lagged_pairs_[k].kappa;
        add_pair_blocks<D>(dfdv, lagged_slots_[k], K, -1.0);
      }
      return;
    }
    for_each_pair(c, [&](const Pair& p) {
      if (dfdv != nullptr) {
        double K[D][D] = {};
        for (int i = 0; i < D; ++i) K[i][i] = p.C * p.phi;
        add<D>(dfdv, p.a, p.a, K, -1.0);
        add<D>(dfdv, p.b, p.b, K, -1.0);
        add<D>(dfdv, p.a, p.b, K, 1.0);
        add<D>(dfdv, p.b, p.a, K, 1.0);
      }
      if (dfdx != nullptr && p.r > 0.0) {
        double B[D][D];
        for (int i = 0; i < D; ++i) {
          const double w = c.v[p.a * D + i] - c.v[p.b * D + i];
          for (int j = 0; j < D; ++j) B[i][j] = p.C * p.slope * w * p.d[j] / p.r;
        }
        // dF_a/dx_a = -B, dF_a/dx_b = B, dF_b/dx_a = B, dF_b/dx_b = -B.
        add<D>(dfdx, p.a, p.a, B, -1.0);
        add<D>(dfdx, p.b, p.b, B, -1.0);
        add<D>(dfdx, p.a, p.b, B, 1.0);
        add<D>(dfdx, p.b, p.a, B, 1.0);
      }
    });
  }

  // Shared with the pressure (ParticleOrder::sph): one search per
  // configuration for both.
  std::vector<std::shared_ptr<SphParticles>> fluids_;
  std::vector<double> nu_;
  int dim_, free_;
  FluidPattern pattern_;  // the pairs declared in the Jacobian's pattern
  const SparseMatrix* pattern_matrix_ = nullptr;
  // The lag (see the header): each pair's internal indices and kappa at the
  // lag's configuration x_lag_ (every particle, internal order).
  struct LaggedPair {
    int a, b;
    double kappa;
  };
  bool lagged_ = false;
  std::vector<LaggedPair> lagged_pairs_;
  mutable std::vector<PairSlots> lagged_slots_;  // of the bound pattern (empty: to find)
  std::vector<double> x_lag_;
  std::size_t x_size_ = 0;  // every particle's coordinates
};

}  // namespace

std::unique_ptr<ForceTerm> make_fluid_viscosity_force(const Scene& scene,
                                                      const ParticleOrder& order) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr) return nullptr;
  std::vector<std::shared_ptr<SphParticles>> particles;
  std::vector<double> nu;
  for (std::size_t k = 0; k < fluids->size(); ++k) {
    if (!((*fluids)[k].viscosity > 0.0)) continue;
    particles.push_back(shared_sph_particles(scene, k, order));
    nu.push_back((*fluids)[k].viscosity);
  }
  if (particles.empty()) return nullptr;
  return std::make_unique<FluidViscosityForce>(std::move(particles), std::move(nu), order.dim,
                                               order.free_particles,
                                               internal_positions(scene, order));
}

const ElementKind& fluid_kind();               // fluid_kind.cc
bool scene_has_viscous_fluid(const Scene& scene);  // fluid_kind.cc

namespace {

// The viscosity lives on a fluid: a random instance is a random fluid
// (fluid_kind.cc), which has one.
void add_random_viscosity(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (!scene.has<Fluids>()) fluid_kind().add_random(scene, rng, states);
}

}  // namespace

const ElementKind& fluid_viscosity_kind() {
  static const ElementKind kind = {
      .name = "fluid-viscosity",
      .make = make_fluid_viscosity_force,
      .energy = {.name = "viscous-work", .work = true, .present = scene_has_viscous_fluid},
      .add_random = add_random_viscosity,
  };
  return kind;
}

}  // namespace springlab
