// Contact between rigid bodies (models/body_body_contact.cc, docs/physics.md
// "Contact between bodies"): the pair force conserves the total linear and
// angular momentum through a collision (implicit midpoint), and a two-box
// stack comes to rest with the top box on the bottom one at the heights
// the penalty's closed-form depths give, under implicit Euler. (Force and
// Jacobian against central differences: the shared kind suites,
// tests/test_element_kinds.cc.)
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "experiments/simulation.h"
#include "models/bodies.h"
#include "models/builtin_scenes.h"
#include "models/contact.h"
#include "models/elastic_model.h"
#include "models/gravity.h"
#include "models/springs.h"

namespace springlab {
namespace {

RunResult run(const ElasticModel& model, const std::string& integrator, double dt, double t_end,
              double newton_tol) {
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  s.options.newton_tol = newton_tol;
  return simulate(model, s);
}

// A spinning box thrown at a resting, turned one, no gravity: a corner of
// each ends up inside the other during the 0.5 s. The pair force derives from
// a potential invariant under translations and rotations of everything, so
// the implicit midpoint keeps sum m p' and sum (m p x p' + sum_i J_i a_i x
// a_i') to its Newton tolerance: 1e-10 relative over 500 steps, while the
// struck box gains more than 10 % of the thrown one's momentum.
TEST(BodyContact, ACollisionConservesTotalMomentum) {
  Scene scene;
  scene.name = "collision";
  scene.dimension = 3;
  scene.block<Springs>();
  Body thrown;
  thrown.shape = Body::Shape::kBox;
  thrown.size = {0.2, 0.15, 0.1};
  thrown.position = Eigen::Vector3d(-0.3, 0.03, 0.02);
  thrown.orientation = {0.3, 0.2, 0.5};
  thrown.v = {1.0, 0.0, 0.0};
  thrown.omega = {0.0, 3.0, 2.0};
  thrown.rigidity = 1e5;
  Body struck = thrown;
  struck.size = {0.3, 0.2, 0.2};
  struck.position = Eigen::Vector3d::Zero();
  struck.orientation = {0.0, 0.0, 0.2};
  struck.v.setZero();
  struck.omega.setZero();
  scene.block<Bodies>().push_back(thrown);
  scene.block<Bodies>().push_back(struck);
  scene.block<Contact>().stiffness = 1e4;
  validate_scene(scene, "collision");
  const ElasticModel model(scene);
  const BodyLayout layout = body_layout(scene, 0);
  auto total = [&](const Vector& x, const Vector& v, Eigen::Vector3d& P, Eigen::Vector3d& L) {
    P.setZero();
    L.setZero();
    for (std::size_t b = 0; b < 2; ++b) {
      const BodyState s = body_state(layout.bodies[b], layout.first[b], x.data(), v.data());
      P += s.linear_momentum;
      L += s.angular_momentum;
    }
  };
  Eigen::Vector3d P0, L0, P, L;
  total(model.initial_positions(), model.initial_velocities(), P0, L0);
  const RunResult r = run(model, "implicit-midpoint", 1e-3, 0.5, 1e-13);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  total(r.x_final, r.v_final, P, L);
  EXPECT_LT((P - P0).norm() / P0.norm(), 1e-10);
  EXPECT_LT((L - L0).norm() / L0.norm(), 1e-10);
  const BodyState hit = body_state(layout.bodies[1], layout.first[1], r.x_final.data(),
                                   r.v_final.data());
  EXPECT_GT(hit.linear_momentum.norm(), 0.1 * P0.norm());
}

// box-pile with n = 2: a 0.2 x 0.1 x 0.15 m box (3 kg) on the ground and a
// 0.8 times smaller one (1.536 kg) dropped on it, turned 0.15 rad about
// the vertical. At rest each box stands on four corners of penalty k_c = 1e5
// N/m, whose mean depth is the load over 4 k_c whatever its distribution:
// the bottom sinks (m_1 + m_2) g / (4 k_c) = 1.11e-4 m into the ground and
// the top (m_2 g) / (4 k_c) = 3.8e-5 m into the bottom box, so the centres
// rest at 0.05 - 1.11e-4 and 0.14 - 1.49e-4 m. The affine bodies' own
// compression under these loads, F / (8 kappa area) of their heights, is
// below 2e-5 m: the heights within 5e-5 m, both boxes still (speeds below
// 1e-3 m/s), the top one's centre above the bottom one's top face's
// interior. Implicit Euler, h = 2e-3 s, 2 s.
TEST(BodyContact, ATwoBoxStackComesToRestUnderImplicitEuler) {
  const Scene scene = make_builtin_scene("box-pile", {{"n", "2"}});
  const ElasticModel model(scene);
  const RunResult r = run(model, "implicit-euler", 2e-3, 2.0, 1e-8);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const BodyLayout layout = body_layout(scene, 0);
  const BodyState bottom =
      body_state(layout.bodies[0], layout.first[0], r.x_final.data(), r.v_final.data());
  const BodyState top =
      body_state(layout.bodies[1], layout.first[1], r.x_final.data(), r.v_final.data());
  const double g = 9.81, k = 1e5, m1 = 3.0, m2 = 1.536;
  const double ground_depth = (m1 + m2) * g / (4 * k), top_depth = m2 * g / (4 * k);
  EXPECT_NEAR(bottom.p.y(), 0.05 - ground_depth, 5e-5);
  EXPECT_NEAR(top.p.y(), 0.1 + 0.04 - ground_depth - top_depth, 5e-5);
  EXPECT_LT(bottom.dp.norm(), 1e-3);
  EXPECT_LT(top.dp.norm(), 1e-3);
  EXPECT_LT(std::abs(top.p.x() - bottom.p.x()), 0.1 - 0.064);
  EXPECT_LT(std::abs(top.p.z() - bottom.p.z()), 0.075 - 0.064);
  RecordProperty("bottom_height_error", std::to_string(bottom.p.y() - (0.05 - ground_depth)));
  RecordProperty("top_height_error",
                 std::to_string(top.p.y() - (0.14 - ground_depth - top_depth)));
}

}  // namespace
}  // namespace springlab
