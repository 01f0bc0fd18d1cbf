// convergence: final-state error against the exact solution (oscillator) or a
// tight reference run, over a dt sweep (fixed-step methods) or a tolerance
// sweep (adaptive ones), and the order fitted to it. One task per
// (case, integrator): the task computes its own reference, so tasks stay
// independent for sharding.
//
// convergence-orders.csv: fitted_order is the least-squares slope of log error
// against log dt (fixed-step) or log rtol (adaptive) over the completed points
// whose error is above kErrorFloor (below it round-off, not the method, sets
// the error). theoretical_order is the method's global order for fixed-step
// methods; for adaptive ones it is 1: a tolerance-proportional error control
// makes the error proportional to rtol whatever the method's order.
//
// This file also defines the accuracy-sweep helpers that work-precision uses
// (declared again in work_precision_experiment.cc; they belong in
// experiment_support.h).
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "experiments/experiment.h"
#include "experiments/experiment_support.h"
#include "experiments/output_files.h"
#include "integrators/registry.h"

namespace springlab {

// ---------------------------------------------------------------- shared with work-precision

// Reads a reference: "exact" (the oscillator's exact solution; refused with a
// message naming the element when the scene is not that oscillator) or
// {"integrator": NAME, "dt": H} (a fixed-step run, H below finest_dt, the
// smallest step of the sweep; 0 = no fixed-step method in the sweep).
// Returns it normalized: "exact" or {"integrator", "dt"}.
nlohmann::json accuracy_reference(const DefinitionObject& o, const char* key, const Scene& scene,
                                  double finest_dt) {
  if (!o.has(key)) o.fail(key, "missing (\"exact\" or {\"integrator\": \"rk4\", \"dt\": 1e-5})");
  const nlohmann::json& raw = o.raw(key);
  if (raw.is_string()) {
    if (raw.get<std::string>() != "exact") {
      o.fail(key, "expected \"exact\" or {\"integrator\": NAME, \"dt\": H}");
    }
    bool exact = exact_oscillator_positions(scene, 0.0).has_value();
    if (exact) {
      // With rest > 0 the formula holds only while the spring keeps a positive length.
      const Spring& spring = scene.springs[0];
      const double l0 = (scene.particles[0].x - scene.particles[1].x).norm();
      exact = spring.rest == 0.0 || std::abs(l0 - spring.rest) < spring.rest;
    }
    if (!exact) {
      o.fail(key, "\"exact\" needs the oscillator (one free particle on one undamped spring, "
                  "released at rest, no other force, never passing the anchor); scene '" +
                      scene.name + "' is not one: use {\"integrator\": \"rk4\", \"dt\": 1e-5}");
    }
    return "exact";
  }
  if (!raw.is_object()) o.fail(key, "expected \"exact\" or {\"integrator\": NAME, \"dt\": H}");
  const DefinitionObject r = o.object(key);
  r.allow_only({"integrator", "dt"});
  const std::string name = r.string("integrator");
  if (!is_integrator(name)) r.fail("integrator", "unknown integrator '" + name + "'");
  if (make_integrator(name)->info().adaptive) {
    r.fail("integrator", "'" + name + "' is adaptive; the reference must be a fixed-step method");
  }
  const double dt = r.positive("dt");
  if (finest_dt > 0.0 && !(dt < finest_dt)) {
    r.fail("dt", "must be below the smallest step of the sweep (" + format_number(finest_dt) +
                     "), got " + format_number(dt));
  }
  return {{"integrator", name}, {"dt", dt}};
}

// The reference positions of the free unknowns at t_end. Throws
// std::runtime_error, its message starting with `where` (the definition's
// element), when the reference run does not complete.
Vector accuracy_reference_positions(const nlohmann::json& reference, const MassSpringModel& model,
                                    const Scene& scene, double t_end,
                                    const IntegratorOptions& options, const std::string& where) {
  if (reference.is_string()) {
    const std::optional<Vector> x = exact_oscillator_positions(scene, t_end);
    if (!x) throw std::runtime_error(where + ": scene '" + scene.name + "' has no exact solution");
    return *x;
  }
  RunSettings s;
  s.integrator = reference.at("integrator").get<std::string>();
  s.dt = reference.at("dt").get<double>();
  s.t_end = t_end;
  s.options = options;
  const RunResult r = simulate(model, s);
  if (r.status != RunStatus::kCompleted) {
    throw std::runtime_error(where + ": the reference run (" + s.integrator + ", dt " +
                             format_number(s.dt) + ") on scene '" + scene.name + "' " +
                             to_string(r.status) + " at t = " +
                             format_number(r.diverged_at.value_or(r.t_final)) +
                             (r.failure.empty() ? "" : ": " + r.failure));
  }
  return r.x_final;
}

// The sweep of one method: for a fixed-step one, base_dt (by its order) and
// `halvings` - 1 halvings of it; for an adaptive one, the `tolerances` (rtol).
// Validates halvings, tolerances and base_dt when present.
std::vector<double> accuracy_sweep_values(const DefinitionObject& d, const IntegratorInfo& info) {
  const int halvings = d.count("halvings", 5, 2, 40);
  std::vector<double> tolerances = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  if (d.has("tolerances")) tolerances = d.positives("tolerances");
  if (d.has("base_dt")) {
    if (d.object("base_dt").json().empty()) {
      d.fail("base_dt",
             "expected steps by method order, e.g. {\"1\": 2e-3, \"2\": 1e-2, \"4\": 4e-2}");
    }
    base_dt_for_order(d, "base_dt", std::numeric_limits<int>::max());  // validates every entry
  }
  for (std::size_t k = 0; k < tolerances.size(); ++k) {
    if (tolerances[k] >= 1.0) {
      d.fail("tolerances[" + std::to_string(k) + "]", "must be below 1 (a relative tolerance)");
    }
  }
  if (info.adaptive) return tolerances;
  double dt = base_dt_for_order(d, "base_dt", info.order);
  std::vector<double> steps;
  for (int k = 0; k < halvings; ++k, dt /= 2) steps.push_back(dt);
  return steps;
}

// One point of a sweep: a fixed-step run at dt = value, or an adaptive run at
// rtol = value, atol = value * atol_factor (output only at t_end).
RunResult accuracy_run(const MassSpringModel& model, const std::string& integrator, bool adaptive,
                       double value, double t_end, const IntegratorOptions& options,
                       double atol_factor) {
  RunSettings s;
  s.integrator = integrator;
  s.t_end = t_end;
  s.options = options;
  if (adaptive) {
    s.dt = t_end;
    s.options.rtol = value;
    s.options.atol = value * atol_factor;
  } else {
    s.dt = value;
  }
  return simulate(model, s);
}

// ---------------------------------------------------------------- convergence

namespace {

constexpr double kErrorFloor = 1e-13;  // errors at or below: round-off, left out of the fit

struct ConvergenceCase {
  Scene scene;
  double t_end;
  nlohmann::json reference;
  std::string where;  // "FILE: cases[i].reference", for messages
};

class ConvergenceExperiment final : public Experiment {
 public:
  explicit ConvergenceExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "cases", "base_dt", "halvings", "tolerances", "atol_factor"});
    options_ = definition_options(d);
    atol_factor_ = d.positive("atol_factor", 1e-2);
    double finest_dt = 0.0;
    for (const std::string& name : definition_integrators(d, "integrators", "all")) {
      SweepMethod m{name, make_integrator(name)->info(), {}};
      m.values = accuracy_sweep_values(d, m.info);
      if (!m.info.adaptive) {
        finest_dt = finest_dt > 0.0 ? std::min(finest_dt, m.values.back()) : m.values.back();
      }
      methods_.push_back(std::move(m));
    }
    SceneTotals totals;
    for (const DefinitionObject& c : d.objects("cases")) {
      c.allow_only({"scene", "parameters", "t_end", "reference"});
      ConvergenceCase k{definition_scene(c), c.positive("t_end"), {},
                        d.file() + ": cases[" + std::to_string(cases_.size()) + "].reference"};
      totals.add(c, "scene", k.scene);
      k.reference = accuracy_reference(c, "reference", k.scene, finest_dt);
      check_grid(c, k.t_end, k.reference.is_object() ? k.reference.at("dt").get<double>() : 0.0);
      if (finest_dt > 0.0) check_grid(c, k.t_end, finest_dt);
      cases_.push_back(std::move(k));
    }
    double rows_per_case = 0.0;  // one per sweep point, one fitted order per method
    for (const SweepMethod& m : methods_) {
      rows_per_case += static_cast<double>(m.values.size()) + 1.0;
    }
    check_output_rows(d, "cases", rows_per_case * static_cast<double>(cases_.size()));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "adaptive", "parameter", "value", "error", "steps",
                  "force_evals", "wall_seconds", "status"}},
            {"orders", {"scene", "integrator", "adaptive", "theoretical_order", "fitted_order",
                        "points"}}};
  }

  std::size_t task_count() const override { return cases_.size() * methods_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const ConvergenceCase& c = cases_[index / methods_.size()];
    const SweepMethod& m = methods_[index % methods_.size()];
    const MassSpringModel model(c.scene);
    const Vector x_ref =
        accuracy_reference_positions(c.reference, model, c.scene, c.t_end, options_, c.where);
    const bool adaptive = m.info.adaptive;
    const std::string prefix = Row().add(c.scene.name).add(m.name).add(adaptive ? 1 : 0).str();
    TaskOutput out;
    out.rows.resize(2);
    std::vector<double> errors;
    for (const double value : m.values) {
      const RunResult r =
          accuracy_run(model, m.name, adaptive, value, c.t_end, options_, atol_factor_);
      const bool completed = r.status == RunStatus::kCompleted;
      const double error = completed ? position_error(r.x_final, x_ref) : NAN;
      errors.push_back(error);
      Row row;
      row.raw(prefix).add(adaptive ? "rtol" : "dt").add(value);
      if (completed) {
        row.add(error);
      } else {
        row.add_empty();
      }
      row.add(r.stats.steps).add(r.stats.force_evals).add(r.wall_seconds).add(to_string(r.status));
      out.rows[0].push_back(row.str());
    }
    int points = 0;
    for (const double e : errors) points += std::isfinite(e) && e > kErrorFloor ? 1 : 0;
    const std::optional<double> fitted = log_log_slope(m.values, errors, kErrorFloor);
    Row orders;
    orders.raw(prefix).add(adaptive ? 1 : m.info.order);
    if (fitted) {
      orders.add(*fitted);
    } else {
      orders.add_empty();
    }
    orders.add(points);
    out.rows[1].push_back(orders.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json s = sweeps_json(methods_);
    for (const SweepMethod& m : methods_) {
      s["sweeps"][m.name]["theoretical_order"] = m.info.adaptive ? 1 : m.info.order;
    }
    nlohmann::json cases = nlohmann::json::array();
    for (const ConvergenceCase& c : cases_) {
      cases.push_back({{"scene", scene_as_json(c.scene)}, {"t_end", c.t_end},
                       {"reference", c.reference}});
    }
    s.update({{"cases", cases}, {"atol_factor", atol_factor_}, {"error_floor", kErrorFloor}});
    return s;
  }

 private:
  static void check_grid(const DefinitionObject& c, double t_end, double dt) {
    if (dt <= 0.0) return;
    check_time_grid(c, "t_end", dt, t_end);
  }

  IntegratorOptions options_;
  double atol_factor_ = 1e-2;
  std::vector<SweepMethod> methods_;
  std::vector<ConvergenceCase> cases_;
};

}  // namespace

std::unique_ptr<Experiment> make_convergence_experiment(const DefinitionObject& d) {
  return std::make_unique<ConvergenceExperiment>(d);
}

}  // namespace springlab
