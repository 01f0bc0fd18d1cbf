// `springlab stability`: the largest step at which a run does not diverge
// (docs/command-line.md "The command line" divergence rule), by bisection on
// log(dt). It assumes stability is monotone in dt (true for the course's linear
// analysis; near a limit a nonlinear scene may not be).
//
// Every trial is long enough to show growth: a trial at step h runs for
//   T(h) = max(t_end, min_steps h, min_periods 2 pi / w_max)
// (w_max: the fastest mode at the initial state), i.e. past t_end when t_end
// is too short. "Stable at h" thus means "stayed bounded over at least 100
// steps and 20 periods of the fastest mode, and over t_end": a run of one
// step (t_end = h) cannot pass for stable.
//
// The search starts from the theoretical limit when the method has one
// (theoretical_max_dt below): the bracket [theory / 2, 2 theory], clipped to
// [dt_min, dt_max], widened by factors of 4 while its ends do not straddle
// the limit. Without a theory it tries dt_max, then steps down by factors of
// 10 to the first stable step (or dt_min). Then it bisects on log dt.
//
// The bisection ends when hi / lo <= 1 + rel_tol, or when lo and hi are
// neighbouring doubles (a rel_tol below 2^-52 cannot be met otherwise), or
// after 200 halvings: at most ~60 runs whatever the settings. A stop request
// (settings.run.options.stop) ends it at the next step (StopRequested).
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>

#include "experiments/driver/simulation.h"

namespace springlab {

// One trial of the search, as reported to StabilitySettings::on_trial before
// it runs.
struct StabilityTrial {
  int run = 0;           // 1, 2, ...
  double dt = 0.0;
  double t_end = 0.0;    // simulated time of this trial (>= the settings' t_end)
  double lo = 0.0;       // the bracket so far: largest stable step (0: none yet)
  double hi = 0.0;       // smallest diverging step (0: none yet)
};

// The stability search's default blow-up factor. A trial diverges when its
// kinetic + spring energy passes kStabilityBlowup * E_s * energy_excursion(w_max h)
// (integrator.h): low enough to see a mode that grows just past the limit
// before the scene's nonlinearity caps it (the cloth under gravity saturates
// near 70 E_s), while a symplectic method's bounded swing is allowed for.
inline constexpr double kStabilityBlowup = 10.0;

struct StabilitySettings {
  // integrator, t_end, options, blowup (dt is searched)
  RunSettings run = [] {
    RunSettings r;
    r.blowup = kStabilityBlowup;
    return r;
  }();
  double dt_min = 1e-6;
  double dt_max = 1.0;
  double rel_tol = 1e-3;    // stop when hi / lo <= 1 + rel_tol
  int min_steps = 100;      // a trial runs at least this many steps ...
  double min_periods = 20;  // ... and this many periods of the fastest mode
  // Called before each trial (progress on a terminal); may be empty.
  std::function<void(const StabilityTrial&)> on_trial = {};
  // Sees every trial's states (every step); may be null.
  Observer* observer = nullptr;
};

enum class StabilityOutcome {
  kBracketed,           // a stable and a diverging step: lo < limit <= hi
  kStableUpToDtMax,     // nothing diverged: max_stable_dt = lo = hi = dt_max
  kUnstableAtDtMin,     // even dt_min diverged: max_stable_dt = lo = 0, hi = dt_min
};

// The fastest mode of the linearized scene at its initial state: w_max
// (rad/s, max_angular_frequency) and its damping rate c (1/s): phi^T (-dF/dv)
// phi for the mode shape phi with phi^T M phi = 1, so that the mode's
// eigenvalues solve lambda^2 + c lambda + w^2 = 0 (exact for damping
// proportional to the mass, e.g. the course's drag on equal masses; an
// estimate otherwise). c = 0 for a scene without velocity-dependent forces.
struct FastestMode {
  double w = 0.0;
  double damping = 0.0;
};
FastestMode fastest_mode(const Model& model);

// What theory says the limit is (see theoretical_max_dt).
struct TheoryLimit {
  std::optional<double> dt;
  std::string rule;  // how dt follows from w_max, or why there is none
};

struct StabilityResult {
  std::string integrator;
  StabilityOutcome outcome = StabilityOutcome::kBracketed;
  double max_stable_dt = 0.0;  // dt_max when nothing diverged; 0 when even dt_min diverged
  double lo = 0.0, hi = 0.0;   // last stable and first unstable step tried
  int runs = 0;
  FastestMode mode;            // of the scene at t = 0
  TheoryLimit theory;          // for the trials' run times T(h)
  double min_run_time = 0.0;   // min_periods 2 pi / w_max (0 when w_max = 0)
  double lo_run_time = 0.0;    // T(lo): simulated time of the trial at lo (0 when lo = 0)
  // What a bracketed step means, from theory (issue 52: a "largest stable
  // dt" beside "unstable at every step"):
  //   - no_stable_step: the method has no stable step on the scene's
  //     fastest mode, undamped (explicit Euler: stability_limit 0, no
  //     damping): lo is only the largest step whose trial stayed within the
  //     bound, and it shrinks as the trial grows;
  //   - growth_at_lo: |R(lo lambda)|^2, the fastest mode's energy factor per
  //     step at lo, for a method with a stability function R (NaN without
  //     one): above 1, lo is unstable, its growth too slow to pass the bound
  //     within the trial (explicit Euler on the damped `spring`: 1.9 x theory).
  bool no_stable_step = false;
  double growth_at_lo = std::numeric_limits<double>::quiet_NaN();
};

// Throws std::invalid_argument, before any run, when the range is empty or
// a trial at dt_min (or dt_max) would have no valid time grid (over 1e9 steps).
StabilityResult find_max_stable_dt(const Model& model, const StabilitySettings& s);

// The simulated time of a trial at step h (the rule above).
double trial_run_time(const StabilitySettings& s, double w, double h);

// What theory says the limit is, for the fastest mode (w rad/s, damping c)
// of runs of length T(h) with blow-up factor `blowup`:
//   - a method with a scalar stability function R (explicit Euler, RK4, ...)
//     on a damped mode: the largest h with |R(h lambda)| <= 1 for both
//     eigenvalues lambda of the mode (for explicit Euler and c < 2 w:
//     dt = c / w^2);
//   - a method stable for w h <= c on the undamped oscillator: dt = c / w
//     (for a partitioned method on a damped mode this ignores the damping,
//     and the rule says so);
//   - none for an A- or L-stable method, one that declares no limit (unknown,
//     A(alpha)), or an adaptive one (it picks its steps);
//   - for a method unstable at every step on an undamped mode (explicit
//     Euler), the step at which the mode's energy grows by the blow-up factor
//     within T(h): (T(h) / h) ln |R(i w h)|^2 = ln B, so it shrinks as the run
//     grows (exact for the oscillator, an estimate for multi-mode scenes, and
//     meaningless for a mode that starts at rest).
TheoryLimit theoretical_max_dt(const IntegratorInfo& info, const FastestMode& mode,
                               const std::function<double(double)>& run_time, double blowup);
// The same for an undamped mode and runs of a fixed length t_end.
TheoryLimit theoretical_max_dt(const IntegratorInfo& info, double w, double t_end, double blowup);

}  // namespace springlab
