// The pressure force of weakly compressible SPH (docs/physics.md "Fluids"),
// in Monaghan's symmetric form (Monaghan 1992, Annu. Rev. Astron.
// Astrophys. 30:543; Monaghan 2005, Rep. Prog. Phys. 68:1703):
//
//   F_i = -m_i sum_j m_j (A_i + A_j) G_ij,   A = p / rho^2 (fluids.h),
//   G_ij = grad_i W(|x_i - x_j|) = W'(r) / r (x_i - x_j).
//
// It is conservative: F = -dE/dx for the equation of state's internal
// energy E = sum_i m_i e(rho_i) (fluids.h: e' = p / rho^2), the "pressure"
// energy column, summed over every particle of the fluid (its fixed wall
// particles too: their density depends on the fluid's positions). The pair
// forces are equal and opposite: momentum is conserved.
//
// Jacobian (assembled in fluid_pressure_hessian.cc). With R_jk = d rho_j / d x_k (R_jj = sum_l m_l G_jl, R_jk =
// m_k G_kj for a neighbour k) and H_ij = grad grad W (the kernel's Hessian:
// W'/r I + (W'' - W'/r) u u^T), the Hessian of E is
//
//   d^2E/dx_a dx_k = sum_j m_j [ A'_j R_ja R_jk^T + A_j d^2 rho_j / dx_a dx_k ],
//
// a rank-one term per particle j coupling every pair (a, k) of j's
// neighbours (so dF/dx reaches two kernel supports, 4h), plus pair terms
// like springs': block (a, a) and (b, b) -K, (a, b) and (b, a) +K with
// K = m_a m_b (A_a + A_b) H_ab. A' >= 0 (fluids.h), so the rank-one part is
// semidefinite; the definite part (Newton's matrix) clamps the pair
// Hessians' eigenvalues (W'/r across, W'' along u) at 0.
//
// The neighbours change as the fluid moves, and with them the Jacobian's
// pattern: the term declares the pairs within 4h + a skin s of the
// positions where it last declared them, which hold every coupling while no
// particle has moved more than s / 2 since (the Verlet-list argument:
// Verlet 1967); past that it asks the model for a new pattern
// (ForceTerm::pattern_holds, follow_pattern).
//
// A trust region (ForceTerm::trusted_fraction; docs/physics.md "Implicit
// steps on a fluid"): the force and its Jacobian at x say nothing of a wall
// of particles further than the kernel's support 2h, and their
// linearization holds over a fraction of h. An implicit step at a frame
// step moves the front's particles 3 cm, more than the walls' 1.5 cm of
// particles and twice the support: a Newton update that moves a particle
// by that much from where its matrix was made can carry it through a wall
// (at 1/60 s on the default dam break, implicit Euler's first update moved
// water particle 59 1 cm into the floor; it left through the floor's
// bottom). So a water particle moves at most kTrustedMove h per update.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "models/fluids/fluid_forces.h"
#include "models/fluids/fluid_pattern.h"
#include "models/fluids/fluid_pressure_hessian.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_particles.h"

namespace springlab {
namespace {

// The longest move of a water particle in one update, in smoothing lengths.
constexpr double kTrustedMove = 0.5;

class FluidPressureForce final : public ForceTerm {
 public:
  FluidPressureForce(std::vector<std::shared_ptr<SphParticles>> fluids, int dim, int free_particles,
                     std::vector<double> x_all)
      : fluids_(std::move(fluids)),
        dim_(dim),
        free_(free_particles),
        pattern_(2.0, dim, x_all),
        x_all0_(std::move(x_all)),
        hessian_(fluids_.size()) {}

  // xpbd: the density constraints of position-based fluids
  // (fluid_density_projection.cc) instead of the pressure force.
  bool projects_positions() const override { return true; }
  std::unique_ptr<PositionProjection> position_projection() const override {
    std::vector<SphParticles> own;  // the projection's own copies: it searches elsewhere
    for (const auto& fluid : fluids_) own.push_back(*fluid);
    return make_fluid_density_projection(std::move(own), x_all0_, dim_, free_);
  }
  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "fluid forces have no projective form (xpbd runs them as position-based fluids)";
    return false;
  }

  std::string_view name() const override { return "fluid"; }
  bool conservative() const override { return true; }

  void add_force(const Configuration& c, double* f) const override {
    if (dim_ == 2) add_force_d<2>(c, f); else add_force_d<3>(c, f);
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for (const auto& shared : fluids_) {
      SphParticles& fluid = *shared;
      fluid.update(c.x);
      for (int a = 0; a < fluid.size(); ++a) {
        sum += fluid.mass(a) * fluid.eos().energy(fluid.density()[static_cast<std::size_t>(a)]);
      }
    }
    return sum;
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    pattern_.declare(fluids_, builder, free_);
  }
  void bind_jacobian(const SparseMatrix& pattern) override { pattern_matrix_ = &pattern; }

  // The trust region (see the top): kTrustedMove h / max |dx_i| over the
  // water particles.
  bool has_trust_region() const override { return true; }
  double trusted_fraction(const Configuration&, const double* dx) const override {
    double fraction = std::numeric_limits<double>::infinity();
    for (const auto& shared : fluids_) {
      const SphParticles& fluid = *shared;
      const double reach = kTrustedMove * fluid.kernel().h;
      for (int a = 0; a < fluid.size(); ++a) {
        const int i = fluid.index(a);
        if (i >= free_) continue;  // a wall particle
        double move2 = 0.0;
        for (int r = 0; r < dim_; ++r) move2 += dx[i * dim_ + r] * dx[i * dim_ + r];
        if (move2 * fraction * fraction > reach * reach) fraction = reach / std::sqrt(move2);
      }
    }
    return fraction;
  }

  // Pairs within two supports couple (a common neighbour): fluid_pattern.h.
  bool pattern_varies() const override { return true; }
  std::string pattern_change() const override {
    return "its particles change neighbours (a fluid)";
  }
  bool pattern_holds(const Configuration& c) const override { return pattern_.holds(fluids_, c.x); }
  void follow_pattern(const Configuration& c) override { pattern_.follow(fluids_, c.x); }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    if (dim_ == 2) add_stiffness_d<2>(c, dfdx, false); else add_stiffness_d<3>(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    if (dim_ == 2) add_stiffness_d<2>(c, dfdx, true); else add_stiffness_d<3>(c, dfdx, true);
  }
  // dF/dx p without the reach-two matrix (fluid_pressure_hessian.h).
  bool has_jacobian_products() const override { return true; }
  void add_jacobian_products(const Configuration& c, bool definite, const double* p,
                             double* dfdx_p, double*) const override {
    if (dfdx_p == nullptr) return;
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      SphParticles& fluid = *fluids_[k];
      fluid.update(c.x);
      if (dim_ == 2) {
        add_pressure_stiffness_product<2>(fluid, free_, definite, p, dfdx_p, hessian_[k]);
      } else {
        add_pressure_stiffness_product<3>(fluid, free_, definite, p, dfdx_p, hessian_[k]);
      }
    }
  }

 private:
  template <int D>
  void add_force_d(const Configuration& c, double* f) const {
    for (const auto& shared : fluids_) {
      SphParticles& fluid = *shared;
      fluid.update(c.x);
      a_.resize(static_cast<std::size_t>(fluid.size()));
      for (int k = 0; k < fluid.size(); ++k) {
        a_[static_cast<std::size_t>(k)] = fluid.eos().a(fluid.density()[static_cast<std::size_t>(k)]);
      }
      const auto& pairs = fluid.pairs();
      for (std::size_t k = 0; k < pairs.size(); ++k) {
        const auto [a, b] = pairs[k];
        const double s = -fluid.mass(a) * fluid.mass(b) *
                         (a_[static_cast<std::size_t>(a)] + a_[static_cast<std::size_t>(b)]) *
                         fluid.kernel().slope_over_r(fluid.distance(k));
        const double* d = fluid.separation(k);
        double* fa = f + fluid.index(a) * D;
        double* fb = f + fluid.index(b) * D;
        for (int r = 0; r < D; ++r) {
          fa[r] += s * d[r];
          fb[r] -= s * d[r];
        }
      }
    }
  }

  template <int D>
  void add_stiffness_d(const Configuration& c, double* values, bool definite) const {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      SphParticles& fluid = *fluids_[k];
      fluid.update(c.x);
      add_pressure_stiffness<D>(fluid, free_, *pattern_matrix_, definite, values, hessian_[k]);
    }
  }

  // Shared with the viscosity (ParticleOrder::sph).
  std::vector<std::shared_ptr<SphParticles>> fluids_;
  int dim_, free_;
  FluidPattern pattern_;  // the pairs declared in the Jacobian's pattern
  const SparseMatrix* pattern_matrix_ = nullptr;
  std::vector<double> x_all0_;  // every particle at the start, internal order
  mutable std::vector<double> a_;
  mutable std::vector<PressureHessianScratch> hessian_;  // per fluid
};

}  // namespace

std::unique_ptr<ForceTerm> make_fluid_pressure_force(const Scene& scene, const ParticleOrder& order) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr || fluids->empty()) return nullptr;
  std::vector<std::shared_ptr<SphParticles>> particles;
  for (std::size_t k = 0; k < fluids->size(); ++k) {
    particles.push_back(shared_sph_particles(scene, k, order));
  }

  return std::make_unique<FluidPressureForce>(std::move(particles), order.dim,
                                              order.free_particles,
                                              internal_positions(scene, order));
}

}  // namespace springlab
