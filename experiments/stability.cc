#include "experiments/stability.h"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "experiments/output_files.h"

namespace springlab {

namespace {

// Refuses, before any run, a step whose run would have no valid grid.
void check_grid(const char* option, double dt, double t_end) {
  try {
    make_time_grid(dt, t_end);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(option) + " " + format_number(dt) + " with --t-end " +
                                format_number(t_end) + ": " + e.what());
  }
}

}  // namespace

StabilityResult find_max_stable_dt(const ElasticModel& model, const StabilitySettings& s) {
  if (!(s.dt_min > 0.0) || !(s.dt_max > s.dt_min) || !std::isfinite(s.dt_max)) {
    throw std::invalid_argument("need 0 < dt-min < dt-max");
  }
  if (!(s.rel_tol > 0.0)) throw std::invalid_argument("rel-tol must be positive");
  check_grid("--dt-min", s.dt_min, s.run.t_end);
  check_grid("--dt-max", s.dt_max, s.run.t_end);
  StabilityResult result;
  result.integrator = s.run.integrator;
  auto stable = [&](double dt) {
    RunSettings run = s.run;
    run.dt = dt;
    ++result.runs;
    return !simulate(model, run).diverged();
  };
  if (stable(s.dt_max)) {
    result.outcome = StabilityOutcome::kStableUpToDtMax;
    result.max_stable_dt = result.lo = result.hi = s.dt_max;
    return result;
  }
  if (!stable(s.dt_min)) {
    result.outcome = StabilityOutcome::kUnstableAtDtMin;
    result.max_stable_dt = 0.0;
    result.lo = 0.0;
    result.hi = s.dt_min;
    return result;
  }
  double lo = s.dt_min, hi = s.dt_max;
  // Each halving of log(hi/lo) takes one run; hi/lo starts below 2^2048 and
  // the loop also ends once no double lies strictly between lo and hi.
  for (int halving = 0; halving < 200 && hi / lo > 1.0 + s.rel_tol; ++halving) {
    const double mid = std::sqrt(lo) * std::sqrt(hi);  // no overflow of lo * hi
    if (!(mid > lo && mid < hi)) break;                  // neighbours: nothing left to split
    (stable(mid) ? lo : hi) = mid;
  }
  result.max_stable_dt = result.lo = lo;
  result.hi = hi;
  return result;
}

TheoryLimit theoretical_max_dt(const IntegratorInfo& info, double w, double t_end, double blowup) {
  std::ostringstream rule;
  if (info.adaptive) return {std::nullopt, "none: an adaptive method chooses its own steps"};
  if (!(w > 0.0)) return {std::nullopt, "none: the scene has no oscillating mode (w_max = 0)"};
  // A- and L-stable methods have none; unknown and A(alpha) declare none.
  if (info.stability != StabilityKind::kConditional || !std::isfinite(info.stability_limit)) {
    return {std::nullopt, "none: " + stability_text(info)};
  }
  if (info.stability_limit > 0.0) {
    rule << std::setprecision(4) << info.stability_limit << " / w_max";
    return {info.stability_limit / w, rule.str()};
  }
  if (!info.stability_function) return {std::nullopt, "unknown"};
  // (T / h) ln |R(i w h)|^2 = ln B, increasing in h: bisect on log h.
  auto growth = [&](double h) {
    return t_end / h * std::log(std::norm(info.stability_function({0.0, w * h})));
  };
  double lo = 1e-12 / w, hi = 10.0 / w;
  const double target = std::log(blowup);
  if (growth(hi) < target) return {std::nullopt, "none within 10 / w_max"};
  for (int iteration = 0; iteration < 200 && hi / lo > 1.0 + 1e-12; ++iteration) {
    const double mid = std::sqrt(lo * hi);
    if (!(mid > lo && mid < hi)) break;
    (growth(mid) < target ? lo : hi) = mid;
  }
  rule << "unstable at every step: the energy grows x" << format_number(blowup) << " within t_end";
  return {std::sqrt(lo * hi), rule.str()};
}

}  // namespace springlab
