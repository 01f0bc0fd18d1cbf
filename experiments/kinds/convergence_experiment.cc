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
// methods (its position_order where that is higher and F depends on x
// alone: fox-goodwin's positions are Numerov's, order 4); for adaptive ones it is 1: a tolerance-proportional error control
// makes the error proportional to rtol whatever the method's order.
//
// The sweeps, the reference and the error are accuracy_sweep.h's, shared
// with work-precision.
#include <cmath>
#include <memory>

#include "experiments/kinds/accuracy_sweep.h"
#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"

namespace springlab {

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
    AccuracySweep sweep = read_accuracy_sweep(d);
    methods_ = std::move(sweep.methods);
    atol_factor_ = sweep.atol_factor;
    const double finest_dt = sweep.finest_dt;
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
    const Model model(c.scene);
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
    // The error is of the positions: where F depends on x alone, a method
    // whose positions converge faster is held to that order.
    const bool positions_faster = m.info.position_order > m.info.order &&
                                  model.velocity_dependence() == VelocityDependence::kNone;
    Row orders;
    orders.raw(prefix).add(adaptive ? 1 : (positions_faster ? m.info.position_order : m.info.order));
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

const ExperimentKind& convergence_experiment_kind() {
  static const ExperimentKind kind{"convergence", &make_convergence_experiment};
  return kind;
}

}  // namespace springlab
