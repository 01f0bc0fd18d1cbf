// The run driver: scene -> model -> integrator -> observer. It owns the
// output time grid and divergence detection (SPEC §6); integrators only step,
// observers only record. No step reaches back.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "models/mass_spring_model.h"

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
  std::string failure;                // the solver's message when kFailed
  IntegratorStats stats;
  double wall_seconds = 0.0;
  double energy_initial = 0.0;
  double energy_final = 0.0;  // at the last good state
  double t_final = 0.0;       // time of the last good state
  Vector x_final, v_final;    // last good state (free unknowns)
  bool diverged() const { return status != RunStatus::kCompleted; }
};

// The grid of SPEC §6: round(T/dt) steps when T/dt is within 1e-9 of a whole
// number, otherwise the last step is shortened to end exactly at T.
// Returns t_1 .. t_N (t_0 = 0 excluded), with t_k = k dt and t_N = T exactly.
std::vector<double> time_grid(double dt, double t_end);

// Runs to t_end or until the run diverges or fails (both are results, not
// exceptions). Divergence: a non-finite state, or kinetic + spring energy
// above blowup * E_s (E_s = model.energy_scale(); with E_s = 0 only a
// non-finite state counts). Throws std::invalid_argument for bad settings.
RunResult simulate(const MassSpringModel& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers = {});

const char* to_string(RunStatus status);

}  // namespace springlab
