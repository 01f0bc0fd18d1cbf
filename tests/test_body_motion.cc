// The motion experiment with rigid bodies (experiments/kinds/motion_experiment.cc,
// docs/experiments-and-report.md "The report's player"): each frame holds the
// particles then every body's surface vertices at x = p + A X, and the
// settings give the player the points per frame and the bodies' surface
// triangles ("faces") to fill.
#include <gtest/gtest.h>

#include <string>

#include "csv_fields.h"
#include "experiment_tasks.h"
#include "experiments/driver/simulation.h"
#include "models/bodies/bodies.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"

namespace springlab::test_body_motion {
namespace {

TEST(BodyMotion, FramesHoldTheBodiesSurfaceVerticesAndTheSettingsTheirFaces) {
  const LoadedExperiment loaded = testing::parse_definition(nlohmann::json(
      {{"experiment", "motion"},
       {"integrators", nlohmann::json::array({"implicit-euler"})},
       {"cases", {{{"scene", "box-chain"}, {"parameters", {{"n", 2}}}, {"dt", 0.01},
                   {"t_end", 0.1}, {"every", 5}}}}}));
  const Scene scene = make_builtin_scene("box-chain", {{"n", "2"}});
  const nlohmann::json settings = loaded.experiment->settings();
  const nlohmann::json& c = settings.at("cases").at(0);
  // One particle (the fixed anchor), then 8 vertices per box, 12 triangles each.
  EXPECT_EQ(c.at("points"), 1 + 2 * 8);
  ASSERT_EQ(c.at("faces").size(), 2u * 12u);
  const RigidBody second = rigid_body(scene.get<Bodies>()[1]);
  EXPECT_EQ(c.at("faces").at(12).at(0), 1 + 8 + second.triangles[0][0]);

  const auto rows = testing::task_rows(loaded, 0);
  ASSERT_EQ(rows[1].size(), 3u);  // t = 0, 0.05, 0.1
  ASSERT_EQ(rows[0].size(), 3u * 17u);
  // The last frame: the run's final state, p + A X for every vertex.
  const Model model(scene);
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 0.01;
  s.t_end = 0.1;
  const RunResult r = simulate(model, s);
  const BodyLayout layout = body_layout(scene, model.particle_order());
  int i = 1;
  for (std::size_t b = 0; b < 2; ++b) {
    const BodyState st = body_state(layout.bodies[b], layout.first[b], r.x_final.data(),
                                    r.v_final.data());
    for (const Eigen::Vector3d& X : layout.bodies[b].X) {
      const testing::Record& row = rows[0][2 * 17 + static_cast<std::size_t>(i)];
      EXPECT_EQ(row.at("i"), std::to_string(i));
      const Eigen::Vector3d x = st.p + st.A * X;
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(csv_fields::field_number(row.at(std::string(1, "xyz"[a]))), x[a]) << i;
      }
      ++i;
    }
  }
}

}  // namespace
}  // namespace springlab::test_body_motion
