// The model assembled from the element kinds: what it adds to the kinds'
// own terms (whose derivatives tests/test_element_kinds.cc checks for every
// kind): free/fixed particles, the energy report's columns and docs/physics.md's
// formulas, symmetry and velocity dependence, the spring's definite part,
// and the stiff / non-stiff split.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <random>
#include <stdexcept>

#include "models/fluids/fluids.h"
#include "models/scenes/builtin_scenes.h"
#include "models/contact/contact.h"
#include "models/springs/drag.h"
#include "models/springs/gravity.h"
#include "models/bodies/bodies.h"
#include "models/model/model.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"
#include "random_scenes.h"
#include "models/model/energy_layout.h"

namespace springlab::test_model {
namespace {

using testing::kind_named;
using testing::random_scene;

// Lowest eigenvalue of -m (m symmetric).
double lowest_stiffness(const SparseMatrix& m) {
  const Eigen::MatrixXd stiffness = -Eigen::MatrixXd(m);
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(stiffness).eigenvalues()[0];
}

class ModelDimensions : public ::testing::TestWithParam<int> {};

TEST_P(ModelDimensions, DampingDissipatesAndSymmetryIsReported) {
  const int dim = GetParam();
  Scene s = random_scene(dim, 3);
  s.remove<Wind>();
  s.remove<Gravity>();
  for (Plane& plane : s.block<Planes>()) plane.friction = 0.0;  // affine in v
  for (Body& body : s.block<Bodies>()) {
    body.friction = 0.0;         // likewise between bodies
    body.contact_damping = 0.0;  // (saturating in v_n: not affine either)
  }
  const Model damped(s);
  EXPECT_FALSE(damped.jacobian_symmetric());  // spring damping's dF/dx is not symmetric
  EXPECT_EQ(damped.velocity_dependence(), VelocityDependence::kCoupled);
  EXPECT_FALSE(damped.derives_from_potentials());
  // Drag and spring damping only remove energy: their power is -gamma|v|^2 - sum c (w.u)^2 < 0.
  EXPECT_LT(damped.nonconservative_power(0.0, damped.initial_positions(),
                                         damped.initial_velocities()), 0.0);
  for (Spring& spring : s.block<Springs>()) spring.damping = 0.0;
  for (Fluid& fluid : s.block<Fluids>()) fluid.viscosity = 0.0;  // a fluid's viscosity: no term
  const Model undamped(s);
  EXPECT_TRUE(undamped.jacobian_symmetric());
  EXPECT_EQ(undamped.velocity_dependence(), VelocityDependence::kDiagonal);
  EXPECT_TRUE(undamped.derives_from_potentials());
  SparseMatrix dfdx;
  undamped.jacobians(0.0, undamped.initial_positions(), undamped.initial_velocities(), &dfdx,
                     nullptr);
  const Eigen::MatrixXd K(dfdx);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
}

// The spring's definite part drops exactly the compressed springs' negative
// transverse stiffness: with compressed springs -dF/dx is indefinite and its
// definite part is not; once none is compressed the two are the same.
TEST_P(ModelDimensions, SpringDefinitePartDropsOnlyTheIndefinitePart) {
  const int dim = GetParam();
  Scene s = random_scene({&kind_named("spring")}, dim, 2);
  const Model model(s);
  const Vector x = model.initial_positions();
  const Vector v = model.initial_velocities();
  SparseMatrix dfdx, definite_dfdx;
  model.jacobians(0.0, x, v, &dfdx, nullptr);
  model.definite_jacobians(0.0, x, v, &definite_dfdx, nullptr);
  const double scale = Eigen::MatrixXd(dfdx).norm();
  ASSERT_LT(lowest_stiffness(dfdx), -1e-3 * scale) << "the scene must make -dF/dx indefinite";
  EXPECT_GT(lowest_stiffness(definite_dfdx), -1e-12 * scale);

  for (Spring& spring : s.block<Springs>()) {
    const double l = (s.particles[spring.i].x - s.particles[spring.j].x).norm();
    spring.rest = std::min(spring.rest, 0.9 * l);  // none compressed
  }
  const Model stretched(s);
  stretched.jacobians(0.0, x, v, &dfdx, nullptr);
  stretched.definite_jacobians(0.0, x, v, &definite_dfdx, nullptr);
  EXPECT_EQ(Eigen::MatrixXd(definite_dfdx), Eigen::MatrixXd(dfdx));
}

INSTANTIATE_TEST_SUITE_P(Dimensions, ModelDimensions, ::testing::Values(2, 3),
                         [](const auto& info) { return std::to_string(info.param) + "D"; });

TEST(Model, FixedParticlesAreNotUnknownsAndStayPut) {
  Scene s = random_scene(3, 11);
  const Model model(s);
  // 6 particles, one fixed; and 12 unknowns per free rigid body after them.
  const Eigen::Index bodies = 3 * body_pseudo_particles(s);
  EXPECT_EQ(model.dofs(), 5 * 3 + bodies);
  EXPECT_EQ(model.jacobian_pattern().rows(), 15 + bodies);
  Vector x = model.initial_positions();
  x.setConstant(42.0);
  const Eigen::MatrixXd all = model.scene_positions(x);
  EXPECT_EQ(all.row(2).transpose(), s.particles[2].x);  // the fixed particle
  EXPECT_EQ(all(0, 0), 42.0);
}

Scene hanging_spring() {
  Scene s;
  s.dimension = 2;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -10, 0);
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 5.0, true},
                 {Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(2, 0, 0), 2.0, false}};
  s.block<Springs>() = {{0, 1, 100.0, 2.0, 0.0}};
  return s;
}

TEST(Model, EnergiesFollowSpecFormulas) {
  const Model model(hanging_spring());
  const Energies e = model.energies(model.initial_positions(), model.initial_velocities());
  EXPECT_DOUBLE_EQ(e.kinetic(), 0.5 * 2.0 * 4.0);
  EXPECT_DOUBLE_EQ(e["spring"], 0.5 * 100.0 * 1.0);
  EXPECT_DOUBLE_EQ(e["gravity"], -2.0 * (-10.0) * (-3.0));  // fixed particle stores nothing
  EXPECT_EQ(e.total(), (e.kinetic() + e["spring"]) + e["gravity"]);
  // docs/command-line.md "The command line"'s blow-up measure:
  EXPECT_EQ(e.kinetic_and_spring(), e.kinetic() + e["spring"]);
  // E_s = T + U + m_free (|g| d + 0): d = 3 (bounding-box diagonal)
  EXPECT_DOUBLE_EQ(model.energy_scale(), 4.0 + 50.0 + 2.0 * 10.0 * 3.0);
}

// The blow-up measure adds each potential's magnitude: a negative elastic
// energy (issue #38: a corotated block at poisson -0.9999 reached 1.49e9 J of
// kinetic energy, cancelled by as much negative elastic energy) cannot hide
// a kinetic energy that blows up.
TEST(Model, BlowUpMeasureAddsPotentialMagnitudesSoNoneCancels) {
  const Scene block = make_builtin_scene("block", {{"n", "2"}});
  const auto layout = std::make_shared<const EnergyLayout>(energy_layout(block));
  Energies e(layout);
  e.set_kinetic(1.49e9);
  e.add(layout->find("elastic"), -1.49e9);
  e.add(layout->find("spring"), 2.0);
  e.finish();
  EXPECT_EQ(e.kinetic_and_spring(), 1.49e9 + 1.49e9 + 2.0);
}

// docs/command-line.md "The command line": t,kinetic,spring,gravity,total for every spring scene,
// the potentials 0 where the scene has none; the values in column order.
TEST(Model, EnergyColumnsAreTheSpecsAndAbsentPotentialsAreZero) {
  const std::vector<std::string> spec = {"kinetic", "spring", "gravity", "total"};
  Scene s = hanging_spring();
  const Model model(s);
  EXPECT_EQ(model.energy_columns(), spec);
  s.remove<Gravity>();
  s.block<Springs>().clear();
  const Model bare(s);
  EXPECT_EQ(bare.energy_columns(), spec);
  const Energies e = bare.energies(bare.initial_positions(), bare.initial_velocities());
  ASSERT_EQ(e.values().size(), 4u);
  EXPECT_EQ(e.values()[0], 4.0);  // kinetic
  EXPECT_EQ(e.values()[1], 0.0);  // no spring
  EXPECT_EQ(e.values()[2], 0.0);  // no gravity
  EXPECT_EQ(e.values()[3], 4.0);  // total
  EXPECT_THROW(e["elastic"], std::out_of_range);  // no such column here
  // One table over several scenes has the union of their columns.
  EXPECT_EQ(energy_layout({&s, &s}).columns, spec);
}

// The energies of a state, filled in place, match the ones returned.
TEST(Model, EnergiesIntoAnExistingObjectMatch) {
  const Model model(random_scene(3, 6));
  Energies e = model.energies(model.initial_positions(), model.initial_velocities());
  const Vector x = model.initial_positions() * 1.1;
  const Vector v = model.initial_velocities() * 0.5;
  model.energies(x, v, e);
  EXPECT_EQ(e.values(), model.energies(x, v).values());
}

TEST(Model, AbsentForcesAreNotAssembled) {
  Scene s;
  s.dimension = 2;
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), 1.0, false}};
  s.block<Springs>() = {{0, 1, 10.0, 1.0, 0.0}};
  s.block<Drag>().gamma = 0.0;  // present but zero: no term
  const Model model(s);
  ASSERT_EQ(model.terms().size(), 1u);
  EXPECT_EQ(model.terms()[0]->name(), "spring");
  EXPECT_EQ(model.velocity_dependence(), VelocityDependence::kNone);
}

// IMEX methods evaluate the stiff and non-stiff forces apart: together they
// must be exactly the whole, forces and Jacobians alike.
TEST(Model, StiffAndNonstiffPartsAddUpToTheWhole) {
  const Scene s = random_scene(3, 5);
  const Model model(s);
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
  const double cw = s.get<Wind>().coefficient;
  ASSERT_GT(cw, 0.0);
  // (on the particles only: wind does not blow on rigid bodies)
  Eigen::MatrixXd particles = Eigen::MatrixXd::Zero(wind.rows(), wind.cols());
  const Eigen::Index particle_dofs = 3 * model.free_particle_count();
  particles.topLeftCorner(particle_dofs, particle_dofs).setIdentity();
  EXPECT_LT((wind + cw * particles).norm(), 1e-12);
}

}  // namespace
}  // namespace springlab::test_model
