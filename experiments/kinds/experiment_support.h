// Pieces several experiment kinds share: the options a definition sets for
// every run, resource caps, the timed cases of energy and damping-budget
// (accuracy sweeps: accuracy_sweep.h).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/kinds/definition.h"
#include "experiments/kinds/experiment.h"
#include "experiments/driver/simulation.h"
#include "integrators/core/integrator.h"
#include "models/model/model.h"

namespace springlab {

// A scene run to t_end at step dt (the output interval for adaptive methods),
// recording every `every`-th output: the cases of the energy and
// damping-budget experiments, read from "cases".
struct TimedCase {
  Scene scene;
  double dt, t_end;
  int every;
};
std::vector<TimedCase> read_timed_cases(const DefinitionObject& d);
nlohmann::json timed_cases_json(const std::vector<TimedCase>& cases);

// The energy and damping-budget experiments: every integrator runs every
// case, one task per (case, integrator). This reads their common definition
// (options, integrators, cases; rows capped), counts their tasks and writes
// their settings; a kind adds its tables and what it records of a run.
class TimedCasesExperiment : public Experiment {
 public:
  std::size_t task_count() const override { return cases_.size() * integrators_.size(); }
  nlohmann::json settings() const override;

 protected:
  explicit TimedCasesExperiment(const DefinitionObject& d);
  struct Task {
    const TimedCase& c;
    RunSettings run;     // the integrator at the case's dt, t_end, every, options
    std::string prefix;  // "scene,integrator,dt": the first fields of its rows
  };
  Task task(std::size_t index) const;
  const std::vector<TimedCase>& cases() const { return cases_; }

 private:
  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  std::vector<TimedCase> cases_;
};

// Resource caps of an experiment definition (docs/reliability.md, "Reliability"), checked
// while the definition is read, before any task runs: the tasks it makes, the
// output rows it holds in memory until they are written in task order, and
// the scenes it holds, all together (at most what one scene may have:
// kMaxSceneParticles, and each element array's cap, e.g. kMaxSceneSprings).
// Each run has at most 1e9 steps (make_time_grid).
inline constexpr std::size_t kMaxExperimentTasks = 1'000'000;
inline constexpr std::size_t kMaxExperimentRows = 10'000'000;  // about 1.5 GB of text

// Each refuses a count over its cap with a message naming `key` of `o`.
void check_task_count(const DefinitionObject& o, const std::string& key, double tasks);
void check_output_rows(const DefinitionObject& o, const std::string& key, double rows);
std::string format_count(double count);  // whole, rounded up: "12000000", not "1.2e+07"
// A run's warnings (run_warnings.h) for a table's "warnings" column: their
// lines joined by "; " (empty when none).
std::string warnings_cell(const RunResult& r);
class SceneTotals {
 public:
  void add(const DefinitionObject& o, const std::string& key, const Scene& scene);

 private:
  std::size_t particles_ = 0;
  std::vector<std::size_t> elements_;  // per element array (element_counts), summed
};
// Rows the energy and damping-budget experiments hold for these cases, each
// run by `integrators` methods: refused over kMaxExperimentRows.
void check_timed_case_rows(const DefinitionObject& d, const std::vector<TimedCase>& cases,
                           std::size_t integrators);

// rtol/atol (adaptive methods), newton_tol (implicit ones) from a definition.
IntegratorOptions definition_options(const DefinitionObject& o);

// The scene as a JSON object, for the settings file the report shows.
nlohmann::json scene_as_json(const Scene& scene);

// Refuses a (dt, t_end) pair with no valid time grid, naming `key` of `o`.
void check_time_grid(const DefinitionObject& o, const char* key, double dt, double t_end);

}  // namespace springlab
