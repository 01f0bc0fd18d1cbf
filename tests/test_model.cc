// The model's analytic derivatives against central finite differences, at
// random states with stretched and compressed springs, in 2-D and 3-D, with
// every force kind on; and force = -grad(potential energy) for the
// conservative terms.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <random>

#include "models/mass_spring_model.h"

namespace springlab {
namespace {

// A small random scene exercising every force: a fixed particle, springs with
// positive and zero rest length, spring damping, drag, gravity and wind.
Scene random_scene(int dim, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene s;
  s.name = "random";
  s.dimension = dim;
  s.gravity.head(dim).setConstant(-3.0);
  s.drag = 0.3;
  s.wind = Wind{Eigen::Vector3d(1.0, 0.5, dim == 3 ? -0.5 : 0.0), 0.2, 0.5, 1.5};
  const int n = 6;
  for (int p = 0; p < n; ++p) {
    Particle particle;
    for (int r = 0; r < dim; ++r) {
      particle.x[r] = u(rng) + p;
      particle.v[r] = u(rng);
    }
    particle.mass = 1.0 + 0.5 * p;
    particle.fixed = p == 2;
    s.particles.push_back(particle);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if ((i + j) % 3 == 0) continue;
      Spring spring{i, j, 10.0 + i + j, 0.0, 0.4 * ((i + j) % 2)};
      const double l = (s.particles[i].x - s.particles[j].x).norm();
      // stretched, compressed and zero-rest-length springs
      spring.rest = (i + j) % 5 == 0 ? 0.0 : l * (((i + j) % 2 == 0) ? 0.7 : 1.4);
      s.springs.push_back(spring);
    }
  }
  return s;
}

class ModelDerivatives : public ::testing::TestWithParam<int> {};

TEST_P(ModelDerivatives, JacobiansMatchCentralDifferences) {
  const int dim = GetParam();
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const MassSpringModel model(random_scene(dim, seed));
    const double t = 0.37 * seed;
    const Vector x = model.initial_positions();
    const Vector v = model.initial_velocities();
    SparseMatrix dfdx, dfdv;
    model.jacobians(t, x, v, &dfdx, &dfdv);
    const Eigen::MatrixXd Kx(dfdx), Kv(dfdv);
    const double eps = 1e-6;
    Vector fp, fm;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector xp = x, xm = x;
      xp[k] += eps;
      xm[k] -= eps;
      model.force(t, xp, v, fp);
      model.force(t, xm, v, fm);
      const Vector column_x = (fp - fm) / (2 * eps);
      EXPECT_LT((Kx.col(k) - column_x).norm(), 1e-6 * (1.0 + column_x.norm()))
          << "dF/dx column " << k << " seed " << seed;
      Vector vp = v, vm = v;
      vp[k] += eps;
      vm[k] -= eps;
      model.force(t, x, vp, fp);
      model.force(t, x, vm, fm);
      const Vector column_v = (fp - fm) / (2 * eps);
      EXPECT_LT((Kv.col(k) - column_v).norm(), 1e-6 * (1.0 + column_v.norm()))
          << "dF/dv column " << k << " seed " << seed;
    }
  }
}

TEST_P(ModelDerivatives, ConservativeForceIsMinusEnergyGradient) {
  const int dim = GetParam();
  Scene s = random_scene(dim, 7);
  s.drag = 0.0;
  s.wind.reset();
  for (Spring& spring : s.springs) spring.damping = 0.0;
  const MassSpringModel model(s);
  const Vector x = model.initial_positions();
  const Vector v = model.initial_velocities();
  Vector f;
  model.force(0.0, x, v, f);
  const double eps = 1e-6;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    Vector xp = x, xm = x;
    xp[k] += eps;
    xm[k] -= eps;
    const Energies ep = model.energies(xp, v), em = model.energies(xm, v);
    const double dV = ((ep.spring + ep.gravity) - (em.spring + em.gravity)) / (2 * eps);
    EXPECT_NEAR(f[k], -dV, 1e-6 * (1.0 + std::abs(f[k]))) << "coordinate " << k;
  }
}

TEST_P(ModelDerivatives, DampingDissipatesAndSymmetryIsReported) {
  const int dim = GetParam();
  Scene s = random_scene(dim, 3);
  s.wind.reset();
  s.gravity.setZero();
  const MassSpringModel damped(s);
  EXPECT_FALSE(damped.jacobian_symmetric());  // spring damping's dF/dx is not symmetric
  EXPECT_EQ(damped.velocity_dependence(), VelocityDependence::kCoupled);
  // Drag and spring damping only remove energy: their power is -gamma|v|^2 - sum c (w.u)^2 < 0.
  EXPECT_LT(damped.nonconservative_power(0.0, damped.initial_positions(),
                                         damped.initial_velocities()), 0.0);
  for (Spring& spring : s.springs) spring.damping = 0.0;
  const MassSpringModel undamped(s);
  EXPECT_TRUE(undamped.jacobian_symmetric());
  EXPECT_EQ(undamped.velocity_dependence(), VelocityDependence::kDiagonal);
  SparseMatrix dfdx;
  undamped.jacobians(0.0, undamped.initial_positions(), undamped.initial_velocities(), &dfdx,
                     nullptr);
  const Eigen::MatrixXd K(dfdx);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
}

// Without spring damping every force derives from potentials: F = -dV/dx
// (springs, gravity) - dW/dv (drag, wind), the form the implicit methods'
// line search minimizes; spring damping (x and v together) has none.
TEST_P(ModelDerivatives, ForceIsMinusGradientOfBothPotentials) {
  const int dim = GetParam();
  Scene s = random_scene(dim, 5);
  EXPECT_FALSE(MassSpringModel(s).derives_from_potentials());
  for (Spring& spring : s.springs) spring.damping = 0.0;
  const MassSpringModel model(s);
  ASSERT_TRUE(model.derives_from_potentials());
  const double t = 0.8;
  const Vector x = model.initial_positions();
  const Vector v = model.initial_velocities();
  Vector f;
  model.force(t, x, v, f);
  const double eps = 1e-6;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    Vector xp = x, xm = x, vp = v, vm = v;
    xp[k] += eps;
    xm[k] -= eps;
    vp[k] += eps;
    vm[k] -= eps;
    const double dV = (model.position_potential(t, xp) - model.position_potential(t, xm)) / (2 * eps);
    const double dW = (model.velocity_potential(t, vp) - model.velocity_potential(t, vm)) / (2 * eps);
    EXPECT_NEAR(f[k], -dV - dW, 1e-6 * (1.0 + std::abs(f[k]))) << "coordinate " << k;
  }
}

// definite_jacobians: dF/dx negative semidefinite where the exact one is not
// (the random scenes compress springs), dF/dv unchanged, and the exact dF/dx
// itself once no spring is compressed.
TEST_P(ModelDerivatives, DefiniteJacobianDropsOnlyTheIndefinitePart) {
  const int dim = GetParam();
  Scene s = random_scene(dim, 2);
  for (Spring& spring : s.springs) spring.damping = 0.0;
  const MassSpringModel model(s);
  const Vector x = model.initial_positions();
  const Vector v = model.initial_velocities();
  SparseMatrix dfdx, dfdv, definite_dfdx, definite_dfdv;
  model.jacobians(0.0, x, v, &dfdx, &dfdv);
  model.definite_jacobians(0.0, x, v, &definite_dfdx, &definite_dfdv);
  const auto lowest = [](const SparseMatrix& m) {
    const Eigen::MatrixXd stiffness = -Eigen::MatrixXd(m);
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(stiffness).eigenvalues()[0];
  };
  const double scale = Eigen::MatrixXd(dfdx).norm();
  ASSERT_LT(lowest(dfdx), -1e-3 * scale) << "the scene must make -dF/dx indefinite";
  EXPECT_GT(lowest(definite_dfdx), -1e-12 * scale);
  EXPECT_EQ(Eigen::MatrixXd(definite_dfdv), Eigen::MatrixXd(dfdv));

  for (Spring& spring : s.springs) {
    const double l = (s.particles[spring.i].x - s.particles[spring.j].x).norm();
    spring.rest = std::min(spring.rest, 0.9 * l);  // none compressed
  }
  const MassSpringModel stretched(s);
  stretched.jacobians(0.0, x, v, &dfdx, nullptr);
  stretched.definite_jacobians(0.0, x, v, &definite_dfdx, nullptr);
  EXPECT_EQ(Eigen::MatrixXd(definite_dfdx), Eigen::MatrixXd(dfdx));
}

INSTANTIATE_TEST_SUITE_P(Dimensions, ModelDerivatives, ::testing::Values(2, 3),
                         [](const auto& info) { return std::to_string(info.param) + "D"; });

TEST(Model, FixedParticlesAreNotUnknownsAndStayPut) {
  Scene s = random_scene(3, 11);
  const MassSpringModel model(s);
  EXPECT_EQ(model.dofs(), 5 * 3);  // 6 particles, one fixed
  EXPECT_EQ(model.jacobian_pattern().rows(), 15);
  Vector x = model.initial_positions();
  x.setConstant(42.0);
  const Eigen::MatrixXd all = model.scene_positions(x);
  EXPECT_EQ(all.row(2).transpose(), s.particles[2].x);  // the fixed particle
  EXPECT_EQ(all(0, 0), 42.0);
}

TEST(Model, EnergiesFollowSpecFormulas) {
  Scene s;
  s.dimension = 2;
  s.gravity = Eigen::Vector3d(0, -10, 0);
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 5.0, true},
                 {Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(2, 0, 0), 2.0, false}};
  s.springs = {{0, 1, 100.0, 2.0, 0.0}};
  const MassSpringModel model(s);
  const Energies e = model.energies(model.initial_positions(), model.initial_velocities());
  EXPECT_DOUBLE_EQ(e.kinetic, 0.5 * 2.0 * 4.0);
  EXPECT_DOUBLE_EQ(e.spring, 0.5 * 100.0 * 1.0);
  EXPECT_DOUBLE_EQ(e.gravity, -2.0 * (-10.0) * (-3.0));  // fixed particle stores nothing
  // E_s = T + U + m_free (|g| d + 0): d = 3 (bounding-box diagonal)
  EXPECT_DOUBLE_EQ(model.energy_scale(), 4.0 + 50.0 + 2.0 * 10.0 * 3.0);
}

TEST(Model, AbsentForcesAreNotAssembled) {
  Scene s;
  s.dimension = 2;
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), 1.0, false}};
  s.springs = {{0, 1, 10.0, 1.0, 0.0}};
  const MassSpringModel model(s);
  ASSERT_EQ(model.terms().size(), 1u);
  EXPECT_EQ(model.terms()[0]->name(), "spring");
  EXPECT_EQ(model.velocity_dependence(), VelocityDependence::kNone);
}

}  // namespace
}  // namespace springlab

namespace springlab {
namespace {

// IMEX methods evaluate the stiff and non-stiff forces apart: together they
// must be exactly the whole, forces and Jacobians alike.
TEST(Model, StiffAndNonstiffPartsAddUpToTheWhole) {
  const MassSpringModel model(random_scene(3, 5));
  const Vector& x = model.initial_positions();
  const Vector& v = model.initial_velocities();
  Vector all, stiff, nonstiff;
  model.force(ForcePart::kAll, 0.3, x, v, all);
  model.force(ForcePart::kStiff, 0.3, x, v, stiff);
  model.force(ForcePart::kNonstiff, 0.3, x, v, nonstiff);
  EXPECT_LT((stiff + nonstiff - all).norm(), 1e-12 * all.norm());
  EXPECT_GT(nonstiff.norm(), 0.0);  // gravity and wind are there
  SparseMatrix dx_all, dv_all, dx_stiff, dv_stiff;
  model.jacobians(ForcePart::kAll, 0.3, x, v, &dx_all, &dv_all);
  model.jacobians(ForcePart::kStiff, 0.3, x, v, &dx_stiff, &dv_stiff);
  EXPECT_EQ(Eigen::MatrixXd(dx_all), Eigen::MatrixXd(dx_stiff));  // gravity, wind: no dF/dx
  // Wind's -c_w I is the only velocity Jacobian outside the stiff part.
  const Eigen::MatrixXd wind = Eigen::MatrixXd(dv_all) - Eigen::MatrixXd(dv_stiff);
  const double cw = 0.2;  // random_scene's wind coefficient
  EXPECT_LT((wind + cw * Eigen::MatrixXd::Identity(wind.rows(), wind.cols())).norm(), 1e-12);
}

}  // namespace
}  // namespace springlab
