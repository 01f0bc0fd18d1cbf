// `springlab stability`: the largest step at which a run of length t_end
// does not diverge (docs/command-line.md "The command line" divergence rule), by bisection on
// log(dt). It assumes stability is monotone in dt (true for the course's linear
// analysis; near a limit a nonlinear scene may not be).
//
// The bisection ends when hi / lo <= 1 + rel_tol, or when lo and hi are
// neighbouring doubles (a rel_tol below 2^-52 cannot be met otherwise), or
// after 200 halvings: at most ~60 runs whatever the settings. A stop request
// (settings.run.options.stop) ends it at the next step (StopRequested).
#pragma once

#include <optional>
#include <string>

#include "experiments/simulation.h"

namespace springlab {

struct StabilitySettings {
  RunSettings run;          // integrator, t_end, options, blowup (dt is searched)
  double dt_min = 1e-6;
  double dt_max = 1.0;
  double rel_tol = 1e-3;    // stop when hi / lo <= 1 + rel_tol
};

enum class StabilityOutcome {
  kBracketed,           // diverged at dt_max, not at dt_min: lo < limit <= hi
  kStableUpToDtMax,     // nothing diverged: max_stable_dt = lo = hi = dt_max
  kUnstableAtDtMin,     // even dt_min diverged: max_stable_dt = lo = 0, hi = dt_min
};

struct StabilityResult {
  std::string integrator;
  StabilityOutcome outcome = StabilityOutcome::kBracketed;
  double max_stable_dt = 0.0;  // dt_max when nothing diverged; 0 when even dt_min diverged
  double lo = 0.0, hi = 0.0;   // last stable and first unstable step tried
  int runs = 0;
};

// Throws std::invalid_argument, before any run, when the range is empty or
// a run at dt_min (or dt_max) would have no valid time grid (over 1e9 steps).
StabilityResult find_max_stable_dt(const ElasticModel& model, const StabilitySettings& s);

// What theory says the limit is, for the fastest mode w (rad/s) of a run of
// t_end with blow-up factor `blowup`:
//   - a method stable for w h <= c on the undamped oscillator: dt = c / w;
//   - none for an A- or L-stable method, one that declares no limit (unknown,
//     A(alpha)), or an adaptive one (it picks its steps);
//   - for a method unstable at every step (|R(i w h)| > 1: explicit Euler),
//     the step at which the mode's energy grows by the blow-up factor within
//     t_end, (t_end / h) ln |R(i w h)|^2 = ln B, so it shrinks as t_end grows
//     (exact for the oscillator, an estimate for multi-mode scenes).
struct TheoryLimit {
  std::optional<double> dt;
  std::string rule;  // how dt follows from w_max, or why there is none
};
TheoryLimit theoretical_max_dt(const IntegratorInfo& info, double w, double t_end, double blowup);

}  // namespace springlab
