// The fluid experiment (experiments/kinds/fluid_experiment.cc): a coarse dam
// break's rows against Martin and Moyce's table (the interpolated reference
// point, the front at T = 0, Ritter's bound, the energy budget), a refused
// run's row, the step limit's search beside the acoustic mode's theory, the
// 3-D water heights against MARIN's measured ones, and the definition's
// refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "experiment_tasks.h"

namespace springlab::test_fluid_experiment {
namespace {

using Json = nlohmann::json;
using testing::definition_error;
using testing::parse_definition;
using testing::task_rows;

std::string reference_file() {
  return std::string(SPRINGLAB_TEST_DATA) + "/../../experiments/reference/martin-moyce-1952.csv";
}

// The dam break a = 0.1 m at spacing 2 cm (50 water particles) to T = 2.2.
Json small_definition() {
  return {{"experiment", "fluid"},
          {"name", "fluid"},
          {"scene", "dam-break"},
          {"parameters", {{"a", 0.1}, {"spacing", 0.02}}},
          {"reference", reference_file()},
          {"t_end", 0.16},
          {"sample", 0.004},
          {"runs", {{{"integrator", "symplectic-euler"}, {"dt", 0.0002}},
                    {{"integrator", "projective-dynamics"}, {"dt", 0.004}}}},
          {"limits", {{"scene", "dam-break"},
                      {"parameters", {{"a", 0.1}, {"spacing", 0.02}}},
                      {"sound", {10}},
                      {"integrators", {"symplectic-euler"}},
                      {"t_end", 0.03},
                      {"blowup", 2},
                      {"dt_max_factor", 4}}}};
}

double number(const testing::Record& r, const std::string& column) {
  return std::stod(r.at(column));
}

TEST(FluidExperiment, DamBreakRowsAgainstTheMeasuredFront) {
  const LoadedExperiment e = parse_definition(small_definition());
  ASSERT_EQ(e.experiment->task_count(), 3u);
  const auto tables = task_rows(e, 0);
  // The reference: 15 points, as in the file.
  ASSERT_EQ(tables[2].size(), 15u);
  EXPECT_EQ(tables[2][0].at("T"), "0.41");
  EXPECT_EQ(tables[2][14].at("Z"), "4.11");
  // Rows every 4 ms and at the end; the front starts at the column's face.
  const auto& rows = tables[0];
  ASSERT_EQ(rows.size(), 41u);
  EXPECT_EQ(rows[0].at("T"), "0");
  EXPECT_NEAR(number(rows[0], "Z"), 1.0, 1e-12);
  const double time_scale = std::sqrt(2.0 * 9.81 / 0.1);
  EXPECT_NEAR(number(rows.back(), "T"), 0.16 * time_scale, 1e-12);
  ASSERT_EQ(tables[1].size(), 1u);
  const auto& run = tables[1][0];
  EXPECT_EQ(run.at("status"), "completed");
  // Martin and Moyce at T = 2, between (1.98, 2.33) and (2.20, 2.56).
  EXPECT_NEAR(number(run, "Z_T2_measured"), 2.33 + (2.0 - 1.98) / 0.22 * 0.23, 1e-12);
  EXPECT_NEAR(number(run, "Z_T2_error"), number(run, "Z_T2") / number(run, "Z_T2_measured") - 1.0,
              1e-12);
  EXPECT_LT(std::abs(number(run, "Z_T2_error")), 0.2);
  EXPECT_NEAR(number(run, "ritter_speed"), 2.0 * std::sqrt(2.0 * 9.81 * 0.1), 1e-12);
  EXPECT_LT(number(run, "front_speed_max"), number(run, "ritter_speed"));
  // The energy budget: the viscosity did work, and the symplectic method's
  // own share stays small beside the column's potential energy M g a.
  const double viscous = number(run, "viscous_work");
  EXPECT_GT(viscous, 0.0);
  const double drop = -(number(rows.back(), "total") - number(rows[0], "total"));
  EXPECT_GT(drop, 0.0);
  EXPECT_NEAR(number(rows.back(), "numerical"),
              number(rows.back(), "total") + viscous - number(rows[0], "total"), 1e-9 * drop);
  std::cout << "fluid experiment: Z(T=2) " << run.at("Z_T2") << " (" << run.at("Z_T2_error")
            << "), viscous work " << viscous << " J, numerical " << run.at("numerical")
            << " J, energy drop " << drop << " J\n";
  EXPECT_LT(std::abs(number(run, "numerical")), 0.5 * viscous);
}

TEST(FluidExperiment, ARefusedRunSaysWhyAtTheStart) {
  const LoadedExperiment e = parse_definition(small_definition());
  const auto tables = task_rows(e, 1);
  ASSERT_EQ(tables[1].size(), 1u);
  const auto& run = tables[1][0];
  EXPECT_EQ(run.at("status"), "failed");
  EXPECT_EQ(run.at("diverged_at"), "0");
  EXPECT_EQ(run.at("failure").rfind("projective-dynamics: ", 0), 0u) << run.at("failure");
  EXPECT_TRUE(tables[2].empty());  // the reference comes with the first task only
}

TEST(FluidExperiment, StepLimitBesideTheAcousticMode) {
  const LoadedExperiment e = parse_definition(small_definition());
  const auto rows = task_rows(e, 2)[3];
  ASSERT_EQ(rows.size(), 1u);
  const auto& r = rows[0];
  EXPECT_EQ(r.at("outcome"), "bracketed");
  const double c = number(r, "c"), h = number(r, "h");
  EXPECT_NEAR(c, 10.0 * std::sqrt(9.81 * 0.2), 1e-12);
  EXPECT_NEAR(h, 1.3 * 0.02, 1e-15);
  // Symplectic Euler's theory: 2 / w_max.
  EXPECT_NEAR(number(r, "dt_theory") * number(r, "w_max"), 2.0, 1e-9);
  const double ratio = number(r, "ratio");
  std::cout << "dam break limit: measured " << r.at("dt_max_stable") << " s, 2 / w_max "
            << r.at("dt_theory") << " s (ratio " << ratio << "), C = " << r.at("C_measured")
            << "\n";
  EXPECT_GT(ratio, 0.7);
  EXPECT_LT(ratio, 1.5);
  EXPECT_NEAR(number(r, "C_measured"),
              number(r, "dt_max_stable") * (c + number(r, "v_max")) / h, 1e-12);
}

// MARIN's 3-D dam break onto a box (SPHERIC test 2) at spacing 11 cm (495
// water particles, 5 layers: the measured 0.55 m deep exactly), symplectic
// Euler at 2 ms to 0.7 s: the gauge's height is n l over a column of n
// layers at rest (H4, in the water: 0.55 m) and 0 where there is no water
// (H2); over the run both stay near the measured heights, and the water
// reaches H2 (1.0 m downstream of its front) near the measured 0.367 s.
TEST(FluidExperiment, GaugesAgainstMarinsMeasuredHeights) {
  Json d = small_definition();
  d["t_end"] = 0.004;
  d["runs"] = {{{"integrator", "symplectic-euler"}, {"dt", 0.0002}}};
  d.erase("limits");
  d["gauges"] = {
      {"scene", "dam-break-obstacle"},
      {"parameters", {{"spacing", 0.11}}},
      {"integrator", "symplectic-euler"},
      {"dt", 0.002},
      {"t_end", 0.7},
      {"sample", 0.01},
      {"reference", std::string(SPRINGLAB_TEST_DATA) +
                        "/../../experiments/reference/kleefsman-2005-spheric-test2.csv"},
      {"gauges", {{{"name", "H2"}, {"x", 0.992}, {"z", 0.5}},
                  {{"name", "H4"}, {"x", 2.638}, {"z", 0.5}}}},
      {"bound", 0.03}};
  const LoadedExperiment e = parse_definition(d);
  ASSERT_EQ(e.experiment->task_count(), 2u);
  const auto tables = task_rows(e, 1);
  const auto& heights = tables[4];
  ASSERT_EQ(heights.size(), 2u * 71u);  // every 10 ms, t = 0 included, per gauge
  EXPECT_EQ(heights[0].at("gauge"), "H2");
  EXPECT_NEAR(number(heights[0], "height"), 0.0, 1e-12);
  EXPECT_EQ(heights[71].at("gauge"), "H4");
  EXPECT_NEAR(number(heights[71], "height"), 0.55, 0.02 * 0.55);
  const auto& summary = tables[5];
  ASSERT_EQ(summary.size(), 2u);
  for (const auto& g : summary) {
    EXPECT_EQ(g.at("status"), "completed");
    std::cout << "gauge " << g.at("gauge") << ": rms " << g.at("rms_error") << " m, largest "
              << g.at("max_error") << " m, arrival " << g.at("arrival_simulated") << " s (measured "
              << g.at("arrival_measured") << " s)\n";
  }
  EXPECT_LT(number(summary[0], "rms_error"), 0.04);  // H2, the front's flow
  EXPECT_LT(number(summary[1], "rms_error"), 0.02);  // H4, the draining column
  EXPECT_NEAR(number(summary[0], "arrival_measured"), 0.367, 0.002);
  EXPECT_NEAR(number(summary[0], "arrival_simulated"), 0.367, 0.08);
  EXPECT_EQ(summary[1].at("arrival_measured"), "");  // H4 starts in the water
  EXPECT_EQ(tables[6].size(), 2u * 101u);  // the measured rows, 0 to 1 s
}

TEST(FluidExperiment, DefinitionErrorsNameTheKey) {
  Json d = small_definition();
  d["reference"] = "no-such-file.csv";
  EXPECT_EQ(definition_error(d),
            "def.json: reference: cannot read 'no-such-file.csv' next to the "
            "definition");
  d = small_definition();
  d["scene"] = "spring";
  d.erase("parameters");
  EXPECT_NE(definition_error(d).find("scene: needs a fluid"), std::string::npos)
      << definition_error(d);
  d = small_definition();
  d["sample"] = 1.0;
  EXPECT_NE(definition_error(d).find("sample: must not exceed t_end"), std::string::npos)
      << definition_error(d);
}

}  // namespace
}  // namespace springlab::test_fluid_experiment
