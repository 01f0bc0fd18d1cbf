// Pieces several experiment kinds share: the options a definition sets for
// every run, errors against a reference, least-squares slopes.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/definition.h"
#include "experiments/simulation.h"
#include "integrators/integrator.h"
#include "models/mass_spring_model.h"

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

// Resource caps of an experiment definition (README, "Reliability"), checked
// while the definition is read, before any task runs: the tasks it makes, the
// output rows it holds in memory until they are written in task order, and
// the scenes it holds, all together (at most what one scene may have:
// kMaxSceneParticles, kMaxSceneSprings). Each run has at most 1e9 steps
// (make_time_grid).
inline constexpr std::size_t kMaxExperimentTasks = 1'000'000;
inline constexpr std::size_t kMaxExperimentRows = 10'000'000;  // about 1.5 GB of text

// Each refuses a count over its cap with a message naming `key` of `o`.
void check_task_count(const DefinitionObject& o, const std::string& key, double tasks);
void check_output_rows(const DefinitionObject& o, const std::string& key, double rows);
std::string format_count(double count);  // whole, rounded up: "12000000", not "1.2e+07"
class SceneTotals {
 public:
  void add(const DefinitionObject& o, const std::string& key, const Scene& scene);

 private:
  std::size_t particles_ = 0, springs_ = 0;
};
// Rows the energy and damping-budget experiments hold for these cases, each
// run by `integrators` methods: refused over kMaxExperimentRows.
void check_timed_case_rows(const DefinitionObject& d, const std::vector<TimedCase>& cases,
                           std::size_t integrators);

// One integrator's accuracy sweep: dt values (fixed-step) or rtol values
// (adaptive), largest first. Shared by convergence and work-precision.
struct SweepMethod {
  std::string name;
  IntegratorInfo info;
  std::vector<double> values;
};
// {"integrators": [...], "sweeps": {name: {adaptive, parameter, values}}}
nlohmann::json sweeps_json(const std::vector<SweepMethod>& methods);

// rtol/atol (adaptive methods), newton_tol (implicit ones) from a definition.
IntegratorOptions definition_options(const DefinitionObject& o);

// The scene as a JSON object, for the settings file the report shows.
nlohmann::json scene_as_json(const Scene& scene);

// The exact solution of a scene that is the oscillator (one free particle on
// one undamped spring from a fixed one, released at rest, no other force):
// positions of the free unknowns at t. nullopt when the scene is not one.
std::optional<Vector> exact_oscillator_positions(const Scene& scene, double t);

// max over particles and axes of |x - x_ref|, the error measure the report names.
double position_error(const Vector& x, const Vector& x_ref);

// Least-squares slope of log(y) against log(x) over points with finite y > floor.
std::optional<double> log_log_slope(const std::vector<double>& x, const std::vector<double>& y,
                                    double floor = 0.0);

// Refuses a (dt, t_end) pair with no valid time grid, naming `key` of `o`.
void check_time_grid(const DefinitionObject& o, const char* key, double dt, double t_end);

// Fixed-step methods' dt by order: "base_dt": {"1": .., "2": .., "4": ..},
// picking the entry for the largest order key <= the method's order.
double base_dt_for_order(const DefinitionObject& o, const char* key, int order);

// Accuracy sweeps shared by the convergence and work-precision experiments,
// defined in convergence_experiment.cc (see there).
nlohmann::json accuracy_reference(const DefinitionObject& o, const char* key, const Scene& scene,
                                  double finest_dt);
Vector accuracy_reference_positions(const nlohmann::json& reference, const MassSpringModel& model,
                                    const Scene& scene, double t_end,
                                    const IntegratorOptions& options, const std::string& where);
std::vector<double> accuracy_sweep_values(const DefinitionObject& d, const IntegratorInfo& info);
RunResult accuracy_run(const MassSpringModel& model, const std::string& integrator, bool adaptive,
                       double value, double t_end, const IntegratorOptions& options,
                       double atol_factor);

}  // namespace springlab
