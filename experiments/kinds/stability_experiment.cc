// stability: the largest stable step of each fixed-step method against
// stiffness k, found by bisection on log dt (docs/command-line.md "The command line" divergence
// rule), next to the theoretical limit from w_max = sqrt(largest eigenvalue of M^-1 K)
// at the initial state:
//   - a finite limit (w h)* on the undamped oscillator: dt* = (w h)* / w_max
//     (2 for symplectic Euler and Verlet, 2 sqrt 2 for RK4);
//   - none (empty) for A-stable methods;
//   - on a damped fastest mode (drag), for a method with a scalar stability
//     function R: the largest h with |R(h lambda)| <= 1 for the mode's
//     eigenvalues (explicit Euler: c / w_max^2 for damping c < 2 w_max);
//   - for a method unstable at every step on an undamped mode (explicit
//     Euler, |R(i w h)| > 1), the step at which the top mode's energy grows by
//     the blow-up factor B within the simulated time T: (T / h) ln |R(i w h)|^2
//     = ln B. That limit shrinks as T grows. (Exact for the oscillator, where
//     all the energy is in that mode; an estimate for multi-mode scenes.)
// theoretical_max_dt (stability.h) gives it; find_max_stable_dt starts its
// bracket there, and runs each trial at least 100 steps (T is extended).
// The simulated time is `periods` periods of the fastest mode, so every k
// is tested for the same number of oscillations.
// Plus a map: final / initial energy on a (dt, k) grid for a few methods.
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/output_files.h"
#include "experiments/analysis/stability.h"
#include "integrators/registry/registry.h"
#include "models/model/modal_analysis.h"

namespace springlab {
namespace {

struct StiffnessCase {
  std::string stiffness_parameter;
  std::vector<double> k;
  std::vector<Scene> scenes;  // one per k
  std::vector<std::string> integrators;  // the case's own list, else the experiment's
  std::optional<double> periods;        // the case's own, else the experiment's
  std::optional<double> blowup;         // the case's own, else the experiment's
};

struct LimitTask {
  std::size_t case_index, k_index;
  std::string integrator;
};

struct MapTask {
  std::size_t k_index;
  double dt;
  std::string integrator;
};

std::string k_text(double k) { return format_number(k); }

// Adaptive methods choose their own steps: there is no step size to limit.
std::vector<std::string> fixed_step_integrators(const DefinitionObject& d) {
  std::vector<std::string> names = definition_integrators(d, "integrators", "fixed-step");
  for (const std::string& name : names) {
    if (make_integrator(name)->info().adaptive) {
      d.fail("integrators", "'" + name + "' is adaptive: it has no step size to limit");
    }
  }
  return names;
}

class StabilityExperiment final : public Experiment {
 public:
  explicit StabilityExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "periods", "dt_min_factor", "dt_max_factor", "rel_tol", "blowup",
                  "cases", "map"});
    options_ = definition_options(d);
    integrators_ = fixed_step_integrators(d);
    periods_ = d.positive("periods", 100.0);
    dt_min_factor_ = d.positive("dt_min_factor", 1e-3);
    dt_max_factor_ = d.positive("dt_max_factor", 10.0);
    rel_tol_ = d.positive("rel_tol", 1e-3);
    blowup_ = d.positive("blowup", kStabilityBlowup);
    if (!(dt_max_factor_ > dt_min_factor_)) d.fail("dt_max_factor", "must exceed dt_min_factor");
    // A bisection runs `periods` periods of the fastest mode at dt_min too.
    const double steps_at_dt_min = periods_ * 2.0 * std::numbers::pi / dt_min_factor_;
    if (steps_at_dt_min > 1e9) {
      d.fail("periods", "a run at dt_min would take " + format_count(steps_at_dt_min) +
                            " steps (periods x 2 pi / dt_min_factor), over the cap of 1e9");
    }
    for (const DefinitionObject& c : d.objects("cases")) {
      c.allow_only({"scene", "parameters", "stiffness", "k", "integrators", "periods", "blowup"});
      cases_.push_back(read_sweep(c));
      StiffnessCase& added = cases_.back();
      if (c.has("integrators")) added.integrators = fixed_step_integrators(c);
      if (c.has("blowup")) added.blowup = c.positive("blowup");
      if (c.has("periods")) {
        added.periods = c.positive("periods");
        if (*added.periods * 2.0 * std::numbers::pi / dt_min_factor_ > 1e9) {
          c.fail("periods", "a run at dt_min would take over 1e9 steps (periods x 2 pi / "
                            "dt_min_factor)");
        }
      }
      const std::vector<std::string>& names =
          added.integrators.empty() ? integrators_ : added.integrators;
      check_task_count(c, "k",
                       static_cast<double>(limit_tasks_.size()) +
                           static_cast<double>(added.k.size() * names.size()));
      for (std::size_t ki = 0; ki < added.k.size(); ++ki) {
        for (const std::string& name : names) {
          limit_tasks_.push_back({cases_.size() - 1, ki, name});
        }
      }
    }
    if (d.has("map")) {
      const DefinitionObject m = d.object("map");
      m.allow_only({"scene", "parameters", "stiffness", "k", "dt", "t_end", "integrators"});
      map_ = read_sweep(m);
      map_integrators_ = fixed_step_integrators(m);
      map_t_end_ = m.positive("t_end");
      for (double dt : m.positives("dt")) {
        if (map_t_end_ / dt > 1e7) m.fail("dt", "more than 1e7 steps per run");
        map_dt_.push_back(dt);
      }
      check_task_count(m, "dt",
                       static_cast<double>(limit_tasks_.size()) +
                           static_cast<double>(map_integrators_.size()) *
                               static_cast<double>(map_->k.size()) *
                               static_cast<double>(map_dt_.size()));
      for (const std::string& name : map_integrators_) {
        for (std::size_t ki = 0; ki < map_->k.size(); ++ki) {
          for (double dt : map_dt_) map_tasks_.push_back({ki, dt, name});
        }
      }
    }
  }

  // The map's table only when the definition asks for a map (an empty one
  // would be a file with a header and no rows).
  std::vector<TableSpec> tables() const override {
    std::vector<TableSpec> specs = {
        {"", {"scene", "integrator", "k", "w_max", "t_end", "max_stable_dt", "bracket_lo",
              "bracket_hi", "theory_dt", "ratio"}}};
    if (map_) {
      specs.push_back(
          {"map", {"scene", "integrator", "k", "dt", "w_max", "energy_ratio", "diverged"}});
    }
    return specs;
  }

  std::size_t task_count() const override { return limit_tasks_.size() + map_tasks_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    TaskOutput out;
    out.rows.resize(map_ ? 2 : 1);  // one list per table
    if (index < limit_tasks_.size()) {
      out.rows[0].push_back(run_limit(limit_tasks_[index]));
    } else {
      out.rows[1].push_back(run_map(map_tasks_[index - limit_tasks_.size()]));
    }
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json cases = nlohmann::json::array();
    for (const StiffnessCase& c : cases_) {
      nlohmann::json one = {{"stiffness", c.stiffness_parameter}, {"k", c.k},
                            {"scene", scene_as_json(c.scenes.front())}};
      if (!c.integrators.empty()) one["integrators"] = c.integrators;
      if (c.periods) one["periods"] = *c.periods;
      if (c.blowup) one["blowup"] = *c.blowup;
      cases.push_back(std::move(one));
    }
    nlohmann::json s = {{"integrators", integrators_}, {"cases", cases},
                        {"periods", periods_}, {"blowup", blowup_},
                        {"dt_min_factor", dt_min_factor_}, {"dt_max_factor", dt_max_factor_}};
    if (map_) {
      s["map"] = {{"integrators", map_integrators_}, {"k", map_->k}, {"dt", map_dt_},
                  {"t_end", map_t_end_}, {"scene", scene_as_json(map_->scenes.front())}};
    }
    return s;
  }

 private:
  StiffnessCase read_sweep(const DefinitionObject& c) {
    StiffnessCase sweep;
    sweep.stiffness_parameter = c.string("stiffness", "k");
    sweep.k = c.positives("k");
    for (double k : sweep.k) {
      sweep.scenes.push_back(definition_scene(c, {{sweep.stiffness_parameter, k_text(k)}}));
      totals_.add(c, "k", sweep.scenes.back());
    }
    return sweep;
  }

  std::string run_limit(const LimitTask& task) const {
    const StiffnessCase& c = cases_[task.case_index];
    const Scene& scene = c.scenes[task.k_index];
    const Model model(scene);
    const double w = max_angular_frequency(model);
    const double t_end = c.periods.value_or(periods_) * 2.0 * std::numbers::pi / std::max(w, 1e-300);
    StabilitySettings s;
    s.run.integrator = task.integrator;
    s.run.t_end = t_end;
    s.run.blowup = c.blowup.value_or(blowup_);
    s.run.options = options_;
    s.dt_min = dt_min_factor_ / w;
    s.dt_max = dt_max_factor_ / w;
    s.rel_tol = rel_tol_;
    const StabilityResult r = find_max_stable_dt(model, s);
    const std::optional<double> theory = r.theory.dt;
    Row row;
    row.add(scene.name).add(task.integrator).add(c.k[task.k_index]).add(w).add(t_end)
        .add(r.max_stable_dt).add(r.lo).add(r.hi);
    if (theory) {
      row.add(*theory).add(r.max_stable_dt / *theory);
    } else {
      row.add_empty().add_empty();
    }
    return row.str();
  }

  std::string run_map(const MapTask& task) const {
    const Scene& scene = map_->scenes[task.k_index];
    const Model model(scene);
    RunSettings s;
    s.integrator = task.integrator;
    s.dt = task.dt;
    s.t_end = map_t_end_;  // the map's runs are `springlab run`'s: its blow-up factor
    s.options = options_;
    const RunResult r = simulate(model, s);
    Row row;
    row.add(scene.name).add(task.integrator).add(map_->k[task.k_index]).add(task.dt)
        .add(max_angular_frequency(model));
    if (r.energy_initial != 0.0) {
      row.add(r.energy_final / r.energy_initial);
    } else {
      row.add_empty();  // no ratio of a zero energy
    }
    return row.add(r.diverged() ? 1L : 0L).str();
  }

  IntegratorOptions options_;
  std::vector<std::string> integrators_, map_integrators_;
  double periods_, dt_min_factor_, dt_max_factor_, rel_tol_, blowup_;
  std::vector<StiffnessCase> cases_;
  std::optional<StiffnessCase> map_;
  std::vector<double> map_dt_;
  double map_t_end_ = 0.0;
  std::vector<LimitTask> limit_tasks_;
  std::vector<MapTask> map_tasks_;
  SceneTotals totals_;  // of cases_ and map_ (read_sweep adds to it)
};

}  // namespace

std::unique_ptr<Experiment> make_stability_experiment(const DefinitionObject& d) {
  return std::make_unique<StabilityExperiment>(d);
}

const ExperimentKind& stability_experiment_kind() {
  static const ExperimentKind kind{"stability", &make_stability_experiment};
  return kind;
}

}  // namespace springlab
