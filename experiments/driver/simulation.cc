#include "experiments/driver/simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/driver/divergence.h"
#include "experiments/driver/divergence_check.h"
#include "integrators/registry/registry.h"
#include "models/core/decimal_text.h"

namespace springlab {

namespace {
thread_local const std::atomic<bool>* thread_stop = nullptr;
}  // namespace

StopScope::StopScope(const std::atomic<bool>* stop) : previous_(thread_stop) { thread_stop = stop; }
StopScope::~StopScope() { thread_stop = previous_; }

const std::atomic<bool>* thread_stop_request() { return thread_stop; }

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

  // dt's shortest decimal, d x 10^e: "0.3" -> 3, -1; "2.5e-07" -> 25, -8.
  const std::string decimal = shortest_decimal(dt);
  const auto e_at = decimal.find('e');
  std::string mantissa = decimal.substr(0, e_at);
  int exponent = e_at == std::string::npos ? 0 : std::stoi(decimal.substr(e_at + 1));
  if (const auto point = mantissa.find('.'); point != std::string::npos) {
    exponent -= static_cast<int>(mantissa.size() - point - 1);
    mantissa.erase(point, 1);
  }
  const double digits = std::stod(mantissa);
  const double largest = static_cast<double>(grid.steps) * digits;  // k d for the largest k
  if (std::abs(exponent) <= 22 && largest < 9007199254740992.0 /* 2^53 */) {
    grid.digits = digits;
    static constexpr double kPowersOfTen[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                              1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                              1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};  // exact
    grid.scale = kPowersOfTen[std::abs(exponent)];
    grid.divide = exponent < 0;
  }
  return grid;
}

std::vector<double> time_grid(double dt, double t_end) {
  const TimeGrid grid = make_time_grid(dt, t_end);
  std::vector<double> times;
  for (long k = 1; k <= grid.steps; ++k) times.push_back(grid.at(k));
  return times;
}

namespace {

// The options a run's integrator gets: a thread's stop request (StopScope)
// where the settings carry none.
IntegratorOptions run_options(const RunSettings& settings) {
  IntegratorOptions options = settings.options;
  if (options.stop == nullptr) options.stop = thread_stop;
  return options;
}

}  // namespace

std::unique_ptr<Integrator> prepare_integrator(const Model& model,
                                               const RunSettings& settings) {
  return prepare_integrator(model, settings, make_integrator(settings.integrator));
}

std::unique_ptr<Integrator> prepare_integrator(const Model& model, const RunSettings& settings,
                                               std::unique_ptr<Integrator> integrator) {
  const StepResult step = integrator->initialize(model, 0.0, model.initial_positions(),
                                                 model.initial_velocities(), run_options(settings));
  // Every method's do_initialize refuses with StepResult::refusal; a start
  // that fails otherwise (an integrator bound twice) gives its message.
  if (!step.ok) {
    throw RunRefused(step.message,
                     step.refused.text.empty() ? Refusal{step.message, {}} : step.refused);
  }
  return integrator;
}

RunResult simulate(const Model& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers) {
  return simulate(model, settings, observers, nullptr);
}

RunResult simulate(const Model& model, const RunSettings& settings,
                   const std::vector<Observer*>& observers, std::unique_ptr<Integrator> prepared) {
  if (settings.every < 1) throw std::invalid_argument("every must be >= 1");
  const TimeGrid grid = make_time_grid(settings.dt, settings.t_end);
  const bool initialized = prepared != nullptr;
  std::unique_ptr<Integrator> integrator =
      initialized ? std::move(prepared) : make_integrator(settings.integrator);

  RunResult result;
  result.integrator = settings.integrator;
  result.dt = settings.dt;
  result.t_end = settings.t_end;

  const auto start = std::chrono::steady_clock::now();
  const Vector& x0 = model.initial_positions();
  const Vector& v0 = model.initial_velocities();
  Energies energies = model.energies(x0, v0);
  result.energy_initial = energies.total();
  const double bound = settings.blowup * model.energy_scale();
  auto notify = [&](double t, const Vector& x, const Vector& v) {
    for (Observer* o : observers) o->observe(t, x, v);
  };
  notify(0.0, x0, v0);

  const IntegratorOptions options = run_options(settings);
  auto stop_requested = [&] {
    return options.stop != nullptr && options.stop->load(std::memory_order_relaxed);
  };
  StepResult step;
  if (!std::isfinite(result.energy_initial) || !std::isfinite(model.energy_scale())) {
    // Nothing to integrate: the energy already overflows a double. (An
    // infinite --blowup is a request: only a non-finite state then stops.)
    result.status = RunStatus::kDiverged;
    result.failure = "the initial energy is not finite";
    result.diverged_at = 0.0;
  } else if (initialized) {
    // Bound to (x0, v0) by prepare_integrator.
  } else if (step = integrator->initialize(model, 0.0, x0, v0, options); !step.ok) {
    result.status = RunStatus::kFailed;
    result.failure = step.message;
    result.diverged_at = 0.0;
  }
  // The rule of divergence.h, decided fast (divergence_check.h); it keeps
  // the last good state, (x0, v0) first.
  DivergenceCheck check(model, bound, energies, integrator->overshoot_steps());
  double t_good = 0.0;
  bool good_observed = true;  // has the last good state been written?
  for (long k = 1; k <= grid.steps && result.status == RunStatus::kCompleted; ++k) {
    const double t = grid.at(k);
    if (stop_requested()) throw StopRequested();
    step = integrator->advance_to(t);
    if (!step.ok) {
      if (stop_requested()) throw StopRequested();
      result.status = RunStatus::kFailed;
      result.failure = step.message;
      // A fixed-step method failed in the step ending at t; an adaptive one
      // says how far it got (CVODE's t reached), which is where it failed.
      result.diverged_at = integrator->t() > t_good ? integrator->t() : t;
      break;
    }
    const Vector& x = integrator->x();
    const Vector& v = integrator->v();
    if (std::optional<Verdict> verdict = check.judge(x, v, t)) {
      result.status = RunStatus::kDiverged;
      result.diverged_at = t;
      result.verdict = verdict;
      result.failure = verdict_text(
          *verdict, model, {settings.integrator, settings.blowup, integrator->overshoot_steps()},
          x, v);
      break;
    }
    t_good = t;
    good_observed = k == grid.steps || k % settings.every == 0;
    if (good_observed) notify(t, x, v);
  }
  for (const FallbackCount& f : integrator->fallbacks()) {
    result.warnings.push_back(
        {.code = WarningCode::kFallback, .fallback = f.fallback, .steps = f.steps});
  }
  for (const OvershootWindow::Overshoot& o : check.window().overshoots()) {
    if (result.verdict && o.rule == result.verdict->rule) continue;  // it ended the run
    result.warnings.push_back({.code = WarningCode::kOvershoot, .rule = o.rule, .steps = o.steps,
                               .ratio = o.peak_ratio, .t = o.t_peak});
  }
  // A run that stopped early still ends its output at its last good state.
  Vector x_good = check.x_good(), v_good = check.v_good();
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
