// The accuracy experiments (experiments/kinds/convergence_experiment.cc,
// experiments/kinds/work_precision_experiment.cc) in-process: small definitions
// parsed with parse_experiment, tasks run directly, their CSV rows read back
// and checked against what the methods must do (fitted orders against
// IntegratorInfo.order, errors shrinking with the tolerance, cost growing as
// dt shrinks) and against the data contract of experiments/README.md.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "csv_fields.h"
#include "experiment_tasks.h"
#include "experiments/kinds/experiment.h"
#include "integrators/registry/registry.h"

namespace springlab::test_experiments_accuracy {
namespace {

using Json = nlohmann::json;
using testing::definition_error;
using testing::Record;

const std::vector<std::string> kConvergenceColumns = {
    "scene", "integrator", "adaptive", "parameter", "value", "error", "steps", "force_evals",
    "wall_seconds", "status"};
const std::vector<std::string> kOrdersColumns = {"scene", "integrator", "adaptive",
                                                 "theoretical_order", "fitted_order", "points"};
const std::vector<std::string> kWorkPrecisionColumns = {
    "scene", "integrator", "adaptive", "parameter", "value", "error", "wall_seconds",
    "force_evals", "steps", "status"};

double number(const std::string& field) { return csv_fields::field_number(field, /*empty_allowed=*/true); }

const Json kBaseDt = {{"1", 1e-3}, {"2", 1e-2}, {"4", 1e-2}, {"6", 4e-2}};

Json oscillator_convergence(const std::string& integrator) {
  return {{"experiment", "convergence"},
          {"name", "convergence"},
          {"integrators", Json::array({integrator})},
          {"newton_tol", 1e-12},
          {"base_dt", kBaseDt},
          {"halvings", 4},
          {"tolerances", {1e-4, 1e-8}},
          {"cases", Json::array({{{"scene", "oscillator"}, {"t_end", 1}, {"reference", "exact"}}})}};
}

// A short nonlinear chain (w_max about 190 rad/s) against a tight RK4 run.
Json chain_case(double t_end = 0.25, double reference_dt = 2.5e-5) {
  return {{"scene", "chain"},
          {"parameters", {{"n", 4}, {"horizontal", 1}}},
          {"t_end", t_end},
          {"reference", {{"integrator", "rk4"}, {"dt", reference_dt}}}};
}

// ------------------------------------------------------------ convergence

TEST(ExperimentAccuracyConvergence, TablesFollowTheDataContract) {
  const LoadedExperiment loaded = testing::parse_definition(oscillator_convergence("verlet"));
  const std::vector<TableSpec> tables = loaded.experiment->tables();
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[0].suffix, "");
  EXPECT_EQ(tables[0].columns, kConvergenceColumns);
  EXPECT_EQ(tables[1].suffix, "orders");
  EXPECT_EQ(tables[1].columns, kOrdersColumns);
  EXPECT_EQ(loaded.name, "convergence");
}

class ExperimentAccuracyOrder : public ::testing::TestWithParam<std::string> {};

// The oscillator against its exact solution: a fixed-step method of order p
// gains a factor 2^p per halving; an adaptive one follows its tolerance.
TEST_P(ExperimentAccuracyOrder, OscillatorAgainstExactSolution) {
  const std::string name = GetParam();
  const IntegratorInfo info = make_integrator(name)->info();
  const LoadedExperiment loaded = testing::parse_definition(oscillator_convergence(name));
  ASSERT_EQ(loaded.experiment->task_count(), 1u);
  const auto tables = testing::task_rows(loaded, 0);
  const std::vector<Record>& points = tables[0];
  ASSERT_EQ(tables[1].size(), 1u);
  const Record& orders = tables[1][0];
  EXPECT_EQ(orders.at("scene"), "oscillator");
  EXPECT_EQ(orders.at("integrator"), name);
  EXPECT_EQ(orders.at("adaptive"), info.adaptive ? "1" : "0");
  for (const Record& p : points) {
    EXPECT_EQ(p.at("scene"), "oscillator");
    EXPECT_EQ(p.at("integrator"), name);
    EXPECT_EQ(p.at("status"), "completed");
    EXPECT_GT(number(p.at("error")), 0.0);
    EXPECT_GT(number(p.at("wall_seconds")), 0.0);
  }
  if (info.adaptive) {
    ASSERT_EQ(points.size(), 2u);
    EXPECT_EQ(points[0].at("parameter"), "rtol");
    EXPECT_EQ(number(points[0].at("value")), 1e-4);
    EXPECT_EQ(number(points[1].at("value")), 1e-8);
    const double loose = number(points[0].at("error"));
    const double tight = number(points[1].at("error"));
    EXPECT_LE(tight * 100.0, loose) << "rtol 1e-4: " << loose << ", rtol 1e-8: " << tight;
    EXPECT_EQ(number(orders.at("theoretical_order")), 1.0);
    EXPECT_EQ(orders.at("points"), "2");
    // Two points: the fitted order is their slope.
    EXPECT_NEAR(number(orders.at("fitted_order")), std::log(loose / tight) / std::log(1e4), 1e-9);
  } else {
    ASSERT_EQ(points.size(), 4u);
    const double base = info.order >= 6 ? 4e-2 : (info.order >= 2 ? 1e-2 : 1e-3);  // kBaseDt
    // The error is of the positions, and the oscillator's force depends on x
    // alone: fox-goodwin's positions are Numerov's method, of order 4.
    const int order = std::max(info.order, info.position_order);
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double dt = base / std::pow(2.0, static_cast<double>(k));
      EXPECT_EQ(points[k].at("parameter"), "dt");
      EXPECT_DOUBLE_EQ(number(points[k].at("value")), dt);
      EXPECT_EQ(number(points[k].at("steps")), std::round(1.0 / dt));
    }
    EXPECT_EQ(number(orders.at("theoretical_order")), order);
    EXPECT_EQ(orders.at("points"), "4");
    EXPECT_NEAR(number(orders.at("fitted_order")), order, 0.2);
    // Every single halving, not just the fit, gains about 2^p.
    for (std::size_t k = 1; k < points.size(); ++k) {
      const double gain = number(points[k - 1].at("error")) / number(points[k].at("error"));
      EXPECT_NEAR(std::log2(gain), order, 0.3) << "halving " << k;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ExperimentAccuracy, ExperimentAccuracyOrder,
                         ::testing::ValuesIn(integrator_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string name = p.param;
                           for (char& c : name) c = c == '-' ? '_' : c;
                           return name;
                         });

// A nonlinear chain against a reference run computed inside each task.
TEST(ExperimentAccuracyConvergence, ChainAgainstReferenceRun) {
  Json d = oscillator_convergence("verlet");
  d["integrators"] = {"symplectic-euler", "verlet", "rk4"};
  d["cases"] = Json::array({chain_case()});
  const LoadedExperiment loaded = testing::parse_definition(d);
  ASSERT_EQ(loaded.experiment->task_count(), 3u);
  const int expected[] = {1, 2, 4};
  for (std::size_t task = 0; task < 3; ++task) {
    const auto tables = testing::task_rows(loaded, task);
    ASSERT_EQ(tables[0].size(), 4u);
    for (const Record& p : tables[0]) EXPECT_EQ(p.at("status"), "completed");
    const Record& orders = tables[1].at(0);
    EXPECT_EQ(orders.at("scene"), "chain");
    EXPECT_NEAR(number(orders.at("fitted_order")), expected[task], 0.2) << orders.at("integrator");
  }
}

// Diverged points keep their row, with an empty error, and stay out of the fit.
TEST(ExperimentAccuracyConvergence, DivergedPointsHaveNoErrorAndNoFit) {
  Json d = oscillator_convergence("explicit-euler");
  d["base_dt"] = {{"1", 0.05}};
  d["halvings"] = 2;
  d["cases"] = Json::array({chain_case(1.0, 1e-4)});
  const LoadedExperiment loaded = testing::parse_definition(d);
  const auto tables = testing::task_rows(loaded, 0);
  ASSERT_EQ(tables[0].size(), 2u);
  for (const Record& p : tables[0]) {
    EXPECT_EQ(p.at("status"), "diverged");
    EXPECT_EQ(p.at("error"), "");
    EXPECT_LT(number(p.at("steps")), 1.0 / number(p.at("value")));
  }
  const Record& orders = tables[1].at(0);
  EXPECT_EQ(orders.at("fitted_order"), "");
  EXPECT_EQ(orders.at("points"), "0");
  EXPECT_EQ(orders.at("theoretical_order"), "1");
}

TEST(ExperimentAccuracyConvergence, FailedReferenceRunIsAnError) {
  Json d = oscillator_convergence("implicit-euler");
  d["base_dt"] = {{"1", 0.05}};
  d["halvings"] = 2;
  Json c = chain_case(1.0);
  c["reference"] = {{"integrator", "explicit-euler"}, {"dt", 0.02}};
  d["cases"] = Json::array({c});
  const LoadedExperiment loaded = testing::parse_definition(d);
  try {
    loaded.experiment->run_task(0);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("def.json: cases[0].reference: the reference run "
                                          "(explicit-euler, dt 0.02) on scene 'chain' diverged "
                                          "at t = ",
                                          0),
              0u)
        << e.what();
  }
}

TEST(ExperimentAccuracyConvergence, SettingsNameTheSweeps) {
  Json d = oscillator_convergence("rk4");
  d["integrators"] = {"rk4", "cvode-bdf"};
  const LoadedExperiment loaded = testing::parse_definition(d);
  const Json s = loaded.experiment->settings();
  EXPECT_EQ(s.at("integrators"), Json({"rk4", "cvode-bdf"}));
  EXPECT_EQ(s.at("cases").at(0).at("reference"), "exact");
  EXPECT_EQ(s.at("cases").at(0).at("t_end"), 1.0);
  EXPECT_EQ(s.at("sweeps").at("rk4").at("values"), Json({1e-2, 5e-3, 2.5e-3, 1.25e-3}));
  EXPECT_EQ(s.at("sweeps").at("cvode-bdf").at("parameter"), "rtol");
  EXPECT_EQ(s.at("sweeps").at("cvode-bdf").at("values"), Json({1e-4, 1e-8}));
}

TEST(ExperimentAccuracyConvergence, DefinitionErrorsNameTheElement) {
  Json d = oscillator_convergence("rk4");
  d["halving"] = 5;
  EXPECT_EQ(definition_error(d),
            "def.json: unknown key 'halving' (allowed: experiment, name, title, description, "
            "integrators, rtol, atol, newton_tol, cases, base_dt, halvings, tolerances, "
            "atol_factor)");

  d = oscillator_convergence("rk4");
  d["cases"][0]["dt"] = 0.01;
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0]: unknown key 'dt' (allowed: scene, parameters, t_end, reference)");

  d = oscillator_convergence("rk4");
  d["cases"].push_back(chain_case());
  d["cases"][1]["reference"] = "exact";
  EXPECT_EQ(definition_error(d),
            "def.json: cases[1].reference: \"exact\" needs the oscillator (one free particle on "
            "one undamped spring, released at rest, no other force, never passing the anchor); "
            "scene 'chain' is not one: use {\"integrator\": \"rk4\", \"dt\": 1e-5}");

  d = oscillator_convergence("rk4");
  d["cases"][0]["parameters"] = {{"rest", 0.1}, {"amplitude", 0.2}};
  EXPECT_EQ(definition_error(d).rfind("def.json: cases[0].reference: \"exact\" needs", 0), 0u);

  d = oscillator_convergence("rk4");
  d["cases"][0]["reference"] = "analytic";
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].reference: expected \"exact\" or {\"integrator\": NAME, "
            "\"dt\": H}");

  d = oscillator_convergence("rk4");
  d["cases"][0].erase("reference");
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].reference: missing (\"exact\" or {\"integrator\": \"rk4\", "
            "\"dt\": 1e-5})");

  d = oscillator_convergence("rk4");
  d["cases"] = Json::array({chain_case()});
  d["cases"][0]["reference"]["dt"] = 1e-2;
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].reference.dt: must be below the smallest step of the sweep "
            "(0.00125), got 0.01");

  d["cases"][0]["reference"] = {{"integrator", "cvode-bdf"}, {"dt", 1e-5}};
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].reference.integrator: 'cvode-bdf' is adaptive; the reference "
            "must be a fixed-step method");

  d["cases"][0]["reference"] = {{"integrator", "rk5"}, {"dt", 1e-5}};
  EXPECT_EQ(definition_error(d).rfind("def.json: cases[0].reference.integrator: unknown "
                                      "integrator 'rk5' (did you mean 'rk4'?) (integrators: ",
                                      0),
            0u)
      << definition_error(d);

  d["cases"][0]["reference"] = {{"integrator", "rk4"}, {"dt", 1e-5}, {"rtol", 1e-9}};
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].reference: unknown key 'rtol' (allowed: integrator, dt)");
}

TEST(ExperimentAccuracyConvergence, BadSweepsAreRefused) {
  Json d = oscillator_convergence("explicit-euler");
  d["base_dt"] = {{"2", 1e-2}, {"4", 4e-2}};
  EXPECT_EQ(definition_error(d), "def.json: base_dt: has no entry for order 1 or below");

  d["base_dt"] = {{"one", 1e-3}};
  EXPECT_EQ(definition_error(d), "def.json: base_dt.one: keys are method orders (1, 2, 4, ...)");

  d["base_dt"] = {{"1", -1e-3}};
  EXPECT_EQ(definition_error(d), "def.json: base_dt.1: must be > 0 (got -0.001)");

  d["base_dt"] = Json::object();
  EXPECT_EQ(definition_error(d),
            "def.json: base_dt: expected steps by method order, e.g. {\"1\": 2e-3, \"2\": 1e-2, "
            "\"4\": 4e-2}");

  d.erase("base_dt");
  EXPECT_EQ(definition_error(d), "def.json: base_dt: missing");

  // Validated even when no method uses it.
  d = oscillator_convergence("cvode-bdf");
  d["base_dt"] = {{"1", 0}};
  EXPECT_EQ(definition_error(d), "def.json: base_dt.1: must be > 0 (got 0)");

  d = oscillator_convergence("rk4");
  d["halvings"] = 1;
  EXPECT_EQ(definition_error(d), "def.json: halvings: must be a whole number in [2, 40] (got 1)");

  d = oscillator_convergence("cvode-bdf");
  d["tolerances"] = {1e-4, 2};
  EXPECT_EQ(definition_error(d),
            "def.json: tolerances[1]: must be below 1 (a relative tolerance)");

  d["tolerances"] = {1e-4, -1e-6};
  EXPECT_EQ(definition_error(d), "def.json: tolerances[1]: must be a finite number > 0");
}

// ------------------------------------------------------------ work-precision

Json chain_work_precision() {
  return {{"experiment", "work-precision"},
          {"name", "wp"},
          {"integrators", {"symplectic-euler", "implicit-euler", "rk4", "cvode-bdf"}},
          {"scene", "chain"},
          {"parameters", {{"n", 4}, {"horizontal", 1}}},
          {"t_end", 0.25},
          {"reference", {{"integrator", "rk4"}, {"dt", 2.5e-5}}},
          {"base_dt", {{"1", 2e-3}, {"2", 4e-3}, {"4", 1e-2}}},
          {"halvings", 3},
          {"tolerances", {1e-4, 1e-7}},
          {"repeats", 2}};
}

TEST(ExperimentAccuracyWorkPrecision, CostGrowsAndErrorShrinks) {
  const LoadedExperiment loaded = testing::parse_definition(chain_work_precision());
  const std::vector<TableSpec> tables = loaded.experiment->tables();
  ASSERT_EQ(tables.size(), 1u);
  EXPECT_EQ(tables[0].suffix, "");
  EXPECT_EQ(tables[0].columns, kWorkPrecisionColumns);
  ASSERT_EQ(loaded.experiment->task_count(), 4u);
  const char* names[] = {"symplectic-euler", "implicit-euler", "rk4", "cvode-bdf"};
  for (std::size_t task = 0; task < 4; ++task) {
    const std::vector<Record> rows = testing::task_rows(loaded, task).at(0);
    const bool adaptive = task == 3;
    ASSERT_EQ(rows.size(), adaptive ? 2u : 3u) << names[task];
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Record& r = rows[k];
      EXPECT_EQ(r.at("scene"), "chain");
      EXPECT_EQ(r.at("integrator"), names[task]);
      EXPECT_EQ(r.at("adaptive"), adaptive ? "1" : "0");
      EXPECT_EQ(r.at("parameter"), adaptive ? "rtol" : "dt");
      EXPECT_EQ(r.at("status"), "completed");
      EXPECT_GT(number(r.at("wall_seconds")), 0.0);
      EXPECT_GT(number(r.at("error")), 0.0);
      if (k == 0) continue;
      const Record& prev = rows[k - 1];
      EXPECT_LT(number(r.at("value")), number(prev.at("value")));
      EXPECT_LT(number(r.at("error")), number(prev.at("error"))) << names[task];
      EXPECT_GT(number(r.at("force_evals")), number(prev.at("force_evals"))) << names[task];
      EXPECT_GT(number(r.at("steps")), number(prev.at("steps"))) << names[task];
      if (!adaptive) {
        // Halving dt doubles the steps; a method without Newton iterations
        // then doubles its force evaluations (one with them needs fewer
        // iterations per step as dt shrinks, but still more in all).
        EXPECT_EQ(number(r.at("steps")), 2 * number(prev.at("steps")));
        if (!make_integrator(names[task])->info().iterates_to_tolerance) {
          EXPECT_EQ(number(r.at("force_evals")), 2 * number(prev.at("force_evals")));
        }
      }
    }
    if (std::string(names[task]) == "rk4") {
      for (const Record& r : rows) {
        EXPECT_EQ(number(r.at("force_evals")), 4 * number(r.at("steps")));
      }
    }
  }
}

TEST(ExperimentAccuracyWorkPrecision, ExplicitEulerDivergesWhereImplicitEulerRuns) {
  Json d = chain_work_precision();
  d["integrators"] = {"explicit-euler", "implicit-euler"};
  d["base_dt"] = {{"1", 0.02}};
  d["halvings"] = 2;
  d["t_end"] = 1;
  d["reference"]["dt"] = 1e-4;
  d["repeats"] = 1;
  const LoadedExperiment loaded = testing::parse_definition(d);
  const std::vector<Record> explicit_rows = testing::task_rows(loaded, 0).at(0);
  const std::vector<Record> implicit_rows = testing::task_rows(loaded, 1).at(0);
  ASSERT_EQ(explicit_rows.size(), 2u);
  ASSERT_EQ(implicit_rows.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(explicit_rows[k].at("status"), "diverged");
    EXPECT_EQ(explicit_rows[k].at("error"), "");
    EXPECT_EQ(implicit_rows[k].at("status"), "completed");
    EXPECT_GT(number(implicit_rows[k].at("error")), 0.0);
  }
}

TEST(ExperimentAccuracyWorkPrecision, DefinitionErrorsNameTheElement) {
  Json d = chain_work_precision();
  d["cases"] = Json::array();
  EXPECT_EQ(definition_error(d),
            "def.json: unknown key 'cases' (allowed: experiment, name, title, description, "
            "integrators, rtol, atol, newton_tol, scene, parameters, t_end, reference, base_dt, "
            "halvings, tolerances, atol_factor, repeats)");

  d = chain_work_precision();
  d["reference"] = "exact";
  EXPECT_EQ(definition_error(d),
            "def.json: reference: \"exact\" needs the oscillator (one free particle on one "
            "undamped spring, released at rest, no other force, never passing the anchor); scene "
            "'chain' is not one: use {\"integrator\": \"rk4\", \"dt\": 1e-5}");

  d = chain_work_precision();
  d["repeats"] = 0;
  EXPECT_EQ(definition_error(d), "def.json: repeats: must be a whole number in [1, 1000] (got 0)");

  d = chain_work_precision();
  d.erase("t_end");
  EXPECT_EQ(definition_error(d), "def.json: t_end: missing");
}

TEST(ExperimentAccuracyWorkPrecision, OscillatorMayUseTheExactSolution) {
  Json d = chain_work_precision();
  d["scene"] = "oscillator";
  d.erase("parameters");
  d["reference"] = "exact";
  d["integrators"] = {"verlet"};
  d["repeats"] = 1;
  const LoadedExperiment loaded = testing::parse_definition(d);
  const std::vector<Record> rows = testing::task_rows(loaded, 0).at(0);
  ASSERT_EQ(rows.size(), 3u);
  // Verlet, order 2: each halving of dt divides the error by about 4.
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_NEAR(number(rows[k - 1].at("error")) / number(rows[k].at("error")), 4.0, 0.4);
  }
}

}  // namespace
}  // namespace springlab::test_experiments_accuracy
