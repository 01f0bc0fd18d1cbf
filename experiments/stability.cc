#include "experiments/stability.h"

#include <cmath>
#include <stdexcept>

namespace springlab {

StabilityResult find_max_stable_dt(const MassSpringModel& model, const StabilitySettings& s) {
  if (!(s.dt_min > 0.0) || !(s.dt_max > s.dt_min)) {
    throw std::invalid_argument("need 0 < dt-min < dt-max");
  }
  StabilityResult result;
  result.integrator = s.run.integrator;
  auto stable = [&](double dt) {
    RunSettings run = s.run;
    run.dt = dt;
    ++result.runs;
    return !simulate(model, run).diverged();
  };
  if (stable(s.dt_max)) {
    result.max_stable_dt = result.lo = result.hi = s.dt_max;
    return result;
  }
  if (!stable(s.dt_min)) {
    result.max_stable_dt = 0.0;
    result.lo = 0.0;
    result.hi = s.dt_min;
    return result;
  }
  double lo = s.dt_min, hi = s.dt_max;
  while (hi / lo > 1.0 + s.rel_tol) {
    const double mid = std::sqrt(lo * hi);
    (stable(mid) ? lo : hi) = mid;
  }
  result.max_stable_dt = result.lo = lo;
  result.hi = hi;
  return result;
}

}  // namespace springlab
