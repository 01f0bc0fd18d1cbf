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
// Step k ends at t_k = k dt, and t_N = T exactly (no accumulated drift).
struct TimeGrid {
  long steps = 0;
  double dt = 0.0;
  double t_end = 0.0;
  double at(long k) const { return k == steps ? t_end : static_cast<double>(k) * dt; }
};
// Throws std::invalid_argument for a non-positive or non-finite dt or t_end,
// or more than 1e9 steps.
TimeGrid make_time_grid(double dt, double t_end);
// t_1 .. t_N as a list (small grids: tests and tools).
std::vector<double> time_grid(double dt, double t_end);

// Runs to t_end or until the run diverges or fails (both are results, not
// exceptions). Divergence: a non-finite state, or kinetic + spring energy
// above blowup * E_s (E_s = model.energy_scale(); with E_s = 0 only a
// non-finite state counts). Throws std::invalid_argument for bad settings.
RunResult simulate(const MassSpringModel& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers = {});

const char* to_string(RunStatus status);

}  // namespace springlab
