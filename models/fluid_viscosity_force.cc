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
#include <cmath>
#include <memory>
#include <vector>

#include "models/element_kind.h"
#include "models/fluid_forces.h"
#include "models/fluids.h"
#include "models/sph_particles.h"

namespace springlab {
namespace {

constexpr double kPatternSkin = 0.25;  // in kernel supports
constexpr double kEta2 = 0.01;         // eta^2 / h^2

class FluidViscosityForce final : public ForceTerm {
 public:
  FluidViscosityForce(std::vector<SphParticles> fluids, std::vector<double> nu, int dim,
                      int free_particles, const double* x_all)
      : fluids_(std::move(fluids)), nu_(std::move(nu)), dim_(dim), free_(free_particles) {
    follow(x_all);
  }

  std::string_view name() const override { return "fluid-viscosity"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kCoupled; }
  bool symmetric_jacobians() const override { return false; }

  void add_force(const Configuration& c, double* f) const override {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      SphParticles& fluid = fluids_[k];
      fluid.update(c.x);
      const auto& pairs = fluid.pairs();
      for (std::size_t e = 0; e < pairs.size(); ++e) {
        const auto [a, b] = pairs[e];
        double phi, slope;
        shape(fluid, fluid.distance(e), phi, slope);
        const double kappa = coefficient(k, a, b) * phi;
        const int pa = fluid.index(a), pb = fluid.index(b);
        for (int r = 0; r < dim_; ++r) {
          const double force = -kappa * (c.v[pa * dim_ + r] - c.v[pb * dim_ + r]);
          f[pa * dim_ + r] += force;
          f[pb * dim_ + r] -= force;
        }
      }
    }
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      for (const auto& [a, b] : pattern_[k].pairs()) {
        declare_pair_blocks(builder, fluids_[k].index(a), fluids_[k].index(b), free_);
      }
    }
  }
  void bind_jacobian(const SparseMatrix& pattern) override { pattern_matrix_ = &pattern; }
  bool pattern_varies() const override { return true; }
  bool pattern_holds(const Configuration& c) const override {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      const SphParticles& fluid = fluids_[k];
      const double limit = 0.5 * kPatternSkin * fluid.kernel().support();
      for (int a = 0; a < fluid.size(); ++a) {
        double d2 = 0.0;
        for (int r = 0; r < dim_; ++r) {
          const double d = c.x[fluid.index(a) * dim_ + r] -
                           pattern_x_[k][static_cast<std::size_t>(a * dim_ + r)];
          d2 += d * d;
        }
        if (!(d2 <= limit * limit)) return false;
      }
    }
    return true;
  }
  void follow_pattern(const Configuration& c) override { follow(c.x); }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    if (dim_ == 2) add_jacobians_d<2>(c, dfdx, dfdv); else add_jacobians_d<3>(c, dfdx, dfdv);
  }

 private:
  void follow(const double* x_all) {
    pattern_.assign(fluids_.size(), NeighbourGrid());
    pattern_x_.assign(fluids_.size(), {});
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      const SphParticles& fluid = fluids_[k];
      std::vector<double>& x0 = pattern_x_[k];
      x0.resize(static_cast<std::size_t>(fluid.size() * dim_));
      for (int a = 0; a < fluid.size(); ++a) {
        for (int r = 0; r < dim_; ++r) {
          x0[static_cast<std::size_t>(a * dim_ + r)] = x_all[fluid.index(a) * dim_ + r];
        }
      }
      pattern_[k].build(x0.data(), fluid.size(), dim_,
                        (1.0 + kPatternSkin) * fluid.kernel().support());
    }
  }

  // C = -2 nu m_a m_b / rho0.
  double coefficient(std::size_t k, int a, int b) const {
    const SphParticles& fluid = fluids_[k];
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

  template <int D>
  void add_jacobians_d(const Configuration& c, double* dfdx, double* dfdv) const {
    for (std::size_t k = 0; k < fluids_.size(); ++k) {
      SphParticles& fluid = fluids_[k];
      fluid.update(c.x);
      const auto& pairs = fluid.pairs();
      for (std::size_t e = 0; e < pairs.size(); ++e) {
        const auto [a, b] = pairs[e];
        const double r = fluid.distance(e);
        double phi, slope;
        shape(fluid, r, phi, slope);
        const double C = coefficient(k, a, b);
        const int pa = fluid.index(a), pb = fluid.index(b);
        if (dfdv != nullptr) {
          double K[D][D] = {};
          for (int i = 0; i < D; ++i) K[i][i] = C * phi;
          add<D>(dfdv, pa, pa, K, -1.0);
          add<D>(dfdv, pb, pb, K, -1.0);
          add<D>(dfdv, pa, pb, K, 1.0);
          add<D>(dfdv, pb, pa, K, 1.0);
        }
        if (dfdx != nullptr && r > 0.0) {
          const double* d = fluid.separation(e);
          double B[D][D];
          for (int i = 0; i < D; ++i) {
            const double w = c.v[pa * D + i] - c.v[pb * D + i];
            for (int j = 0; j < D; ++j) B[i][j] = C * slope * w * d[j] / r;
          }
          // dF_a/dx_a = -B, dF_a/dx_b = B, dF_b/dx_a = B, dF_b/dx_b = -B.
          add<D>(dfdx, pa, pa, B, -1.0);
          add<D>(dfdx, pb, pb, B, -1.0);
          add<D>(dfdx, pa, pb, B, 1.0);
          add<D>(dfdx, pb, pa, B, 1.0);
        }
      }
    }
  }

  mutable std::vector<SphParticles> fluids_;
  std::vector<double> nu_;
  int dim_, free_;
  std::vector<NeighbourGrid> pattern_;
  std::vector<std::vector<double>> pattern_x_;
  const SparseMatrix* pattern_matrix_ = nullptr;
};

}  // namespace

std::unique_ptr<ForceTerm> make_fluid_viscosity_force(const Scene& scene,
                                                      const ParticleOrder& order) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr) return nullptr;
  std::vector<SphParticles> particles;
  std::vector<double> nu;
  for (const Fluid& f : *fluids) {
    if (!(f.viscosity > 0.0)) continue;
    particles.push_back(make_sph_particles(scene, f, order.internal_of_scene));
    nu.push_back(f.viscosity);
  }
  if (particles.empty()) return nullptr;
  const int dim = order.dim;
  std::vector<double> x(order.scene_of_internal.size() * static_cast<std::size_t>(dim), 0.0);
  for (std::size_t p = 0; p < order.scene_of_internal.size(); ++p) {
    const int s = order.scene_of_internal[p];
    if (s < 0) continue;
    for (int r = 0; r < dim; ++r) {
      x[p * static_cast<std::size_t>(dim) + static_cast<std::size_t>(r)] =
          scene.particles[static_cast<std::size_t>(s)].x[r];
    }
  }
  return std::make_unique<FluidViscosityForce>(std::move(particles), std::move(nu), dim,
                                               order.free_particles, x.data());
}

namespace {

}  // namespace

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
