// work-precision: error against cost on one scene, every integrator over its
// sweep (fixed-step methods: base_dt by order and its halvings; adaptive ones:
// the tolerances). Wall time is the minimum over `repeats` runs of the same
// point (the least disturbed by the machine); error, force evaluations and
// steps come from the first (they do not change between repeats). One task
// per integrator; each task computes its own reference run.
#include <algorithm>
#include <memory>
#include <stdexcept>

#include "experiments/kinds/accuracy_sweep.h"
#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"

namespace springlab {

namespace {

class WorkPrecisionExperiment final : public Experiment {
 public:
  explicit WorkPrecisionExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "scene", "parameters", "t_end", "reference", "base_dt",
                  "halvings", "tolerances", "atol_factor", "repeats"});
    options_ = definition_options(d);
    repeats_ = d.count("repeats", 3, 1, 1000);
    AccuracySweep sweep = read_accuracy_sweep(d);
    methods_ = std::move(sweep.methods);
    atol_factor_ = sweep.atol_factor;
    const double finest_dt = sweep.finest_dt;
    scene_ = definition_scene(d);
    t_end_ = d.positive("t_end");
    reference_ = accuracy_reference(d, "reference", scene_, finest_dt);
    where_ = d.file() + ": reference";
    check_grid(d, finest_dt);
    if (reference_.is_object()) check_grid(d, reference_.at("dt").get<double>());
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "adaptive", "parameter", "value", "error", "wall_seconds",
                  "force_evals", "steps", "status"}}};
  }

  std::size_t task_count() const override { return methods_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const SweepMethod& m = methods_[index];
    const Model model(scene_);
    const Vector x_ref =
        accuracy_reference_positions(reference_, model, scene_, t_end_, options_, where_);
    const bool adaptive = m.info.adaptive;
    const std::string prefix = Row().add(scene_.name).add(m.name).add(adaptive ? 1 : 0).str();
    TaskOutput out;
    out.rows.resize(1);
    for (const double value : m.values) {
      const RunResult r =
          accuracy_run(model, m.name, adaptive, value, t_end_, options_, atol_factor_);
      double wall = r.wall_seconds;
      for (int k = 1; k < repeats_; ++k) {
        wall = std::min(wall, accuracy_run(model, m.name, adaptive, value, t_end_, options_,
                                           atol_factor_).wall_seconds);
      }
      Row row;
      row.raw(prefix).add(adaptive ? "rtol" : "dt").add(value);
      if (r.status == RunStatus::kCompleted) {
        row.add(position_error(r.x_final, x_ref));
      } else {
        row.add_empty();
      }
      row.add(wall).add(r.stats.force_evals).add(r.stats.steps).add(to_string(r.status));
      out.rows[0].push_back(row.str());
    }
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json s = sweeps_json(methods_);
    s.update({{"scene", scene_as_json(scene_)}, {"t_end", t_end_}, {"reference", reference_},
              {"atol_factor", atol_factor_}, {"repeats", repeats_}});
    return s;
  }

 private:
  // Refuses a sweep or reference of more than 1e9 steps before any task runs.
  void check_grid(const DefinitionObject& d, double dt) const {
    if (dt <= 0.0) return;
    check_time_grid(d, "t_end", dt, t_end_);
  }

  IntegratorOptions options_;
  double atol_factor_ = 1e-2;
  int repeats_ = 3;
  std::vector<SweepMethod> methods_;
  Scene scene_;
  double t_end_ = 1.0;
  nlohmann::json reference_;
  std::string where_;  // "FILE: reference", for messages
};

}  // namespace

std::unique_ptr<Experiment> make_work_precision_experiment(const DefinitionObject& d) {
  return std::make_unique<WorkPrecisionExperiment>(d);
}

const ExperimentKind& work_precision_experiment_kind() {
  static const ExperimentKind kind{"work-precision", &make_work_precision_experiment};
  return kind;
}

}  // namespace springlab
