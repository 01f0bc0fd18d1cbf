// The run driver: scene -> model -> integrator -> observer. It owns the
// output time grid and divergence detection (docs/command-line.md "The command line"); integrators
// only step, observers only record. No step reaches back.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/driver/run_warnings.h"
#include "integrators/core/integrator.h"
#include "models/model/model.h"
#include "models/core/verdict.h"

namespace springlab {

struct RunSettings {
  std::string integrator;
  double dt = 0.01;     // fixed-step methods: the step; adaptive ones: the output interval
  double t_end = 1.0;
  int every = 1;        // observe every K-th grid time (and always the last)
  double blowup = 1000.0;
  IntegratorOptions options;
};

// Receives the state at output times (t = 0, every K-th grid time, t_end).
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void observe(double t, const Vector& x, const Vector& v) = 0;
};

enum class RunStatus { kCompleted, kDiverged, kFailed };

struct RunResult {
  std::string integrator;
  double dt = 0.0;
  double t_end = 0.0;
  RunStatus status = RunStatus::kCompleted;
  std::optional<double> diverged_at;  // time of the step that diverged or failed
  std::string failure;                // the solver's message when kFailed, the verdict's when kDiverged
  std::optional<Verdict> verdict;     // the rule that ended a diverged run (divergence.h), as data
  std::vector<RunWarning> warnings;   // run_warnings.h: what a reader should know
  IntegratorStats stats;
  double wall_seconds = 0.0;
  double energy_initial = 0.0;
  double energy_final = 0.0;  // at the last good state
  double t_final = 0.0;       // time of the last good state
  Vector x_final, v_final;    // last good state (free unknowns)
  bool diverged() const { return status != RunStatus::kCompleted; }
};

// The grid of docs/command-line.md "The command line": round(T/dt) steps when T/dt is within 1e-9
// of a whole number, otherwise the last step is shortened to end exactly at T.
// Step k ends at t_k = k dt, and t_N = T exactly (no accumulated drift).
// t_k is k times dt *as written*: with dt's shortest decimal d x 10^e, t_k
// is the double nearest to (k d) x 10^e, one correctly rounded operation on
// exact operands while k d < 2^53 for every k and |e| <= 22 (any dt of up
// to 6 digits on any grid up to the 1e9-step cap). So --dt 0.1 gives
// t_3 = 0.3, not the double product 0.30000000000000004, and rows print the
// decimal a reader expects. Otherwise t_k = k dt, rounded once.
struct TimeGrid {
  long steps = 0;
  double dt = 0.0;
  double t_end = 0.0;
  double digits = 0.0;  // d (0: use k dt)
  double scale = 1.0;   // 10^|e|
  bool divide = false;  // e < 0
  double at(long k) const {
    if (k == steps) return t_end;
    if (digits == 0.0) return static_cast<double>(k) * dt;
    const double kd = static_cast<double>(k) * digits;  // exact: below 2^53
    return divide ? kd / scale : kd * scale;
  }
};
// Throws std::invalid_argument for a non-positive or non-finite dt or t_end,
// or more than 1e9 steps.
TimeGrid make_time_grid(double dt, double t_end);
// t_1 .. t_N as a list (small grids: tests and tools).
std::vector<double> time_grid(double dt, double t_end);

// Runs to t_end or until the run diverges or fails (both are results, not
// exceptions). Divergence: the rule of divergence.h after every step (a
// non-finite state; kinetic + spring energy, with every potential that
// counts with it, above blowup * E_s, E_s = model.energy_scale(), off when
// E_s = 0; the rules of the scene's kinds of matter: fluids, bodies), with
// a method's overshoot allowance. Throws std::invalid_argument for bad settings.
// A run that starts from a state whose energy does not fit in a double
// (coordinates near 1e300) diverges at t = 0. When settings.options.stop is
// set and becomes true, simulate throws StopRequested at the next step.
RunResult simulate(const Model& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers = {});

// A pairing the method refuses before its first step (a material it has no
// form for, the barrier with a projection method): prepare_integrator's
// error. what() is the method's one line ("xpbd: ... use ..."); reason()
// the same sentence without the method's name, and remedy() the scene
// setting that would make it work (or empty), both as the method gave them.
class RunRefused : public std::runtime_error {
 public:
  explicit RunRefused(const std::string& what, Refusal refused = {})
      : std::runtime_error(what), refused_(std::move(refused)) {}
  const std::string& reason() const { return refused_.text; }
  const SceneRemedy& remedy() const { return refused_.remedy; }

 private:
  Refusal refused_;
};

// What simulate() does before its first step: the settings' integrator,
// bound to the model's initial state. Throws RunRefused where the method
// refuses the model (simulate() would report that as a run failed at
// t = 0). The command line and the Python module call it before opening any
// output, so that a refused pairing is an error with nothing written; the
// integrator it returns then runs the run:
RunResult simulate(const Model& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers,
                   std::unique_ptr<Integrator> prepared);
std::unique_ptr<Integrator> prepare_integrator(const Model& model,
                                               const RunSettings& settings);
// The same with the integrator the caller made (make_integrator(settings.integrator)),
// so that the one object it asked about (options, memory) is the one that runs.
std::unique_ptr<Integrator> prepare_integrator(const Model& model, const RunSettings& settings,
                                               std::unique_ptr<Integrator> integrator);

class StopRequested : public std::runtime_error {
 public:
  StopRequested() : std::runtime_error("stopped on request") {}
};

// While alive, every simulate() on this thread whose settings carry no stop
// request of their own honours `stop`: the experiment runner's workers set
// it, so a Ctrl-C reaches the runs inside every experiment kind.
class StopScope {
 public:
  explicit StopScope(const std::atomic<bool>* stop);
  ~StopScope();
  StopScope(const StopScope&) = delete;
  StopScope& operator=(const StopScope&) = delete;

 private:
  const std::atomic<bool>* previous_;
};

// The stop request simulate() honours on this thread (StopScope's), or
// nullptr: for long work between a run's steps, such as the rigid
// experiment's reference, which an observer advances (issue 46.8).
const std::atomic<bool>* thread_stop_request();

const char* to_string(RunStatus status);

}  // namespace springlab
