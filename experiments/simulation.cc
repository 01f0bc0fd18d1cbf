#include "experiments/simulation.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "integrators/registry.h"

namespace springlab {

const char* to_string(RunStatus status) {
  switch (status) {
    case RunStatus::kCompleted: return "completed";
    case RunStatus::kDiverged: return "diverged";
    case RunStatus::kFailed: return "failed";
  }
  return "unknown";
}

TimeGrid make_time_grid(double dt, double t_end) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("dt must be a positive number");
  if (!(t_end > 0.0) || !std::isfinite(t_end)) {
    throw std::invalid_argument("t_end must be a positive number");
  }
  const double ratio = t_end / dt;
  if (ratio > 1e9) throw std::invalid_argument("t_end / dt exceeds 1e9 steps");
  const double whole = std::round(ratio);
  TimeGrid grid;
  grid.dt = dt;
  grid.t_end = t_end;
  grid.steps = std::abs(ratio - whole) <= 1e-9 ? static_cast<long>(whole)
                                               : static_cast<long>(std::ceil(ratio));
  grid.steps = std::max(grid.steps, 1L);
  return grid;
}

std::vector<double> time_grid(double dt, double t_end) {
  const TimeGrid grid = make_time_grid(dt, t_end);
  std::vector<double> times;
  for (long k = 1; k <= grid.steps; ++k) times.push_back(grid.at(k));
  return times;
}

RunResult simulate(const MassSpringModel& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers) {
  if (settings.every < 1) throw std::invalid_argument("every must be >= 1");
  const TimeGrid grid = make_time_grid(settings.dt, settings.t_end);
  auto integrator = make_integrator(settings.integrator);

  RunResult result;
  result.integrator = settings.integrator;
  result.dt = settings.dt;
  result.t_end = settings.t_end;

  const auto start = std::chrono::steady_clock::now();
  const Vector& x0 = model.initial_positions();
  const Vector& v0 = model.initial_velocities();
  result.energy_initial = model.energies(x0, v0).total();
  const double bound = settings.blowup * model.energy_scale();
  auto notify = [&](double t, const Vector& x, const Vector& v) {
    for (Observer* o : observers) o->observe(t, x, v);
  };
  notify(0.0, x0, v0);

  StepResult step = integrator->initialize(model, 0.0, x0, v0, settings.options);
  if (!step.ok) {
    result.status = RunStatus::kFailed;
    result.failure = step.message;
    result.diverged_at = 0.0;
  }
  double t_good = 0.0;
  Vector x_good = x0, v_good = v0;
  bool good_observed = true;  // has the last good state been written?
  for (long k = 1; k <= grid.steps && result.status == RunStatus::kCompleted; ++k) {
    const double t = grid.at(k);
    step = integrator->advance_to(t);
    if (!step.ok) {
      result.status = RunStatus::kFailed;
      result.failure = step.message;
      result.diverged_at = t;
      break;
    }
    const Vector& x = integrator->x();
    const Vector& v = integrator->v();
    bool blown = !x.allFinite() || !v.allFinite();
    if (!blown && bound > 0.0) {
      const Energies e = model.energies(x, v);
      blown = e.kinetic + e.spring > bound || !std::isfinite(e.total());
    }
    if (blown) {
      result.status = RunStatus::kDiverged;
      result.diverged_at = t;
      break;
    }
    t_good = t;
    x_good = x;
    v_good = v;
    good_observed = k == grid.steps || k % settings.every == 0;
    if (good_observed) notify(t, x, v);
  }
  // A run that stopped early still ends its output at its last good state.
  if (!good_observed) notify(t_good, x_good, v_good);

  result.stats = integrator->stats();
  result.t_final = t_good;
  result.energy_final = model.energies(x_good, v_good).total();
  result.x_final = std::move(x_good);
  result.v_final = std::move(v_good);
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace springlab
