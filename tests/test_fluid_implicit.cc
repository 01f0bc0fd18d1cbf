// Fluids under the implicit methods (docs/physics.md "Fluids", "Implicit
// steps on a fluid"): the pressure Hessian's column assembly against its
// plain reference, the viscosity lagged at the step's start (a dissipation
// potential, symmetric Jacobians), and the frame steps.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "experiments/simulation.h"
#include "models/builtin_scenes.h"
#include "models/elastic_model.h"
#include "models/fluid_pressure_hessian.h"
#include "models/fluids.h"
#include "models/sph_particles.h"

namespace springlab {
namespace {

// A random blob of fluid without walls, gravity or planes, compressed so
// that every particle has pressure, moving at random; `fixed` of its
// particles are walls.
Scene blob(int dim, int n, unsigned seed, double viscosity, int fixed = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene s;
  s.dimension = dim;
  const double side = std::pow(static_cast<double>(n), 1.0 / dim) * 0.1;
  for (int p = 0; p < n; ++p) {
    Particle q;
    for (int r = 0; r < dim; ++r) {
      q.x[r] = 0.5 * side * u(rng);
      q.v[r] = u(rng);
    }
    q.mass = 0.01 * (1.0 + 0.2 * u(rng));
    q.fixed = p < fixed;
    if (q.fixed) q.v.setZero();
    s.particles.push_back(q);
  }
  Fluid f;
  f.count = n;
  f.spacing = 0.1;
  f.density = 0.2 / std::pow(0.1, dim) * 0.01;
  f.speed_of_sound = 3.0;
  f.viscosity = viscosity;
  s.block<Fluids>().push_back(f);
  return s;
}

// The column assembly (no search) and the plain one (a binary search per
// block, particle j by particle j) sum the same terms: equal to round-off,
// exact and definite, in 2-D and 3-D, with walls among the particles.
TEST(FluidPressureHessian, ColumnAssemblyEqualsThePlainOne) {
  for (int dim : {2, 3}) {
    const ElasticModel model(blob(dim, dim == 2 ? 60 : 50, 7, 0.0, 9));
    const Vector x = model.initial_positions(), v = model.initial_velocities();
    SparseMatrix dfdx;
    model.jacobians(0.0, x, v, &dfdx, nullptr);  // updates the particles at x
    const SparseMatrix& pattern = model.jacobian_pattern();
    SphParticles& fluid = *model.particle_order().sph.front();
    for (bool definite : {false, true}) {
      std::vector<double> column(static_cast<std::size_t>(pattern.nonZeros()), 0.0);
      std::vector<double> plain(column.size(), 0.0);
      PressureHessianScratch scratch;
      if (dim == 2) {
        add_pressure_stiffness<2>(fluid, model.free_particle_count(), pattern, definite,
                                  column.data(), scratch);
        add_pressure_stiffness_reference<2>(fluid, model.free_particle_count(), pattern, definite,
                                            plain.data());
      } else {
        add_pressure_stiffness<3>(fluid, model.free_particle_count(), pattern, definite,
                                  column.data(), scratch);
        add_pressure_stiffness_reference<3>(fluid, model.free_particle_count(), pattern, definite,
                                            plain.data());
      }
      double largest = 0.0, worst = 0.0;
      for (std::size_t k = 0; k < plain.size(); ++k) {
        largest = std::max(largest, std::abs(plain[k]));
        worst = std::max(worst, std::abs(column[k] - plain[k]));
      }
      ASSERT_GT(largest, 0.0);
      EXPECT_LT(worst, 1e-12 * largest) << dim << "-D, definite " << definite;
    }
  }
}

// The viscosity lagged (the hand-written implicit methods, during a step:
// MechanicalSystem::lag_normal_forces): its pairs and coefficients kappa
// from x_lag make it -dW/dv of W(v) = 1/2 sum kappa |v_i - v_j|^2, with
// dF/dx = 0 and a symmetric dF/dv; the model then derives from potentials
// and has symmetric Jacobians. At x_lag the force is the live one; away
// from it, the lagged kappa's. Cleared, it is live again.
TEST(FluidViscosity, LaggedIsTheGradientOfItsDissipationPotential) {
  for (int dim : {2, 3}) {
    const ElasticModel model(blob(dim, dim == 2 ? 40 : 30, 13, 0.05, 5));
    ASSERT_FALSE(model.derives_from_potentials());
    ASSERT_FALSE(model.jacobian_symmetric());
    const Vector x = model.initial_positions(), v = model.initial_velocities();
    Vector f_live;
    model.force(0.0, x, v, f_live);
    model.lag_normal_forces(&x);
    EXPECT_TRUE(model.derives_from_potentials());
    EXPECT_TRUE(model.jacobian_symmetric());
    Vector f;
    model.force(0.0, x, v, f);
    EXPECT_LT((f - f_live).norm(), 1e-12 * (1.0 + f.norm()));
    // Away from x_lag: F = -dV/dx - dW/dv, W of the lagged pairs.
    Vector y = x;
    for (Eigen::Index k = 0; k < y.size(); ++k) y[k] += 0.004 * std::sin(1.7 * k);
    model.force(0.0, y, v, f);
    const double eps = 1e-6;
    double worst = 0.0;
    for (Eigen::Index k = 0; k < v.size(); ++k) {
      Vector vp = v, vm = v;
      vp[k] += eps;
      vm[k] -= eps;
      const double dW =
          (model.velocity_potential(0.0, vp) - model.velocity_potential(0.0, vm)) / (2 * eps);
      const double dV = (model.position_potential(0.0, y + eps * Vector::Unit(y.size(), k)) -
                         model.position_potential(0.0, y - eps * Vector::Unit(y.size(), k))) /
                        (2 * eps);
      worst = std::max(worst, std::abs(f[k] + dV + dW) / (1.0 + std::abs(f[k])));
    }
    EXPECT_LT(worst, 1e-6) << dim << "-D";
    // dF/dv symmetric, and the viscosity's dF/dx gone: dF/dx is the
    // pressure's alone, symmetric.
    SparseMatrix dfdx, dfdv;
    model.jacobians(0.0, y, v, &dfdx, &dfdv);
    const Eigen::MatrixXd Kx(dfdx), Kv(dfdv);
    EXPECT_LT((Kv - Kv.transpose()).norm(), 1e-12 * (1.0 + Kv.norm()));
    EXPECT_LT((Kx - Kx.transpose()).norm(), 1e-12 * (1.0 + Kx.norm()));
    EXPECT_GT(Kv.norm(), 0.0);
    model.lag_normal_forces(nullptr);
    EXPECT_FALSE(model.derives_from_potentials());
    model.force(0.0, x, v, f);
    EXPECT_LT((f - f_live).norm(), 1e-12 * (1.0 + f.norm()));
  }
}

}  // namespace
}  // namespace springlab
