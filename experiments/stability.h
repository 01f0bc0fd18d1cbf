// `springlab stability`: the largest step at which a run of length t_end
// does not diverge (SPEC §6 divergence rule), by bisection on log(dt).
// It assumes stability is monotone in dt (true for the course's linear
// analysis; near a limit a nonlinear scene may not be).
#pragma once

#include <string>

#include "experiments/simulation.h"

namespace springlab {

struct StabilitySettings {
  RunSettings run;          // integrator, t_end, options, blowup (dt is searched)
  double dt_min = 1e-6;
  double dt_max = 1.0;
  double rel_tol = 1e-3;    // stop when hi / lo <= 1 + rel_tol
};

struct StabilityResult {
  std::string integrator;
  double max_stable_dt = 0.0;  // dt_max when nothing diverged; 0 when even dt_min diverged
  double lo = 0.0, hi = 0.0;   // last stable and first unstable step tried
  int runs = 0;
};

StabilityResult find_max_stable_dt(const MassSpringModel& model, const StabilitySettings& s);

}  // namespace springlab
