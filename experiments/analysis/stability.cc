#include "experiments/analysis/stability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "experiments/io/output_files.h"
#include "integrators/registry/registry.h"
#include "models/model/modal_analysis.h"

namespace springlab {

namespace {

// A damping rate as a student reads it: six significant digits (512, not
// 512.000000000038, the sum's round-off).
std::string damping_text(double c) {
  std::ostringstream out;
  out << std::setprecision(6) << c;
  return out.str();
}

// Refuses, before any run, a step whose trial would have no valid grid.
void check_grid(const char* option, double dt, double t_end, double run_time) {
  try {
    make_time_grid(dt, run_time);
  } catch (const std::invalid_argument& e) {
    std::string what = std::string(option) + " " + format_number(dt) + " with --t-end " +
                       format_number(t_end);
    if (run_time > t_end) {
      what += " (a trial there runs " + format_number(run_time) +
              " s: at least 100 steps and 20 periods of the fastest mode)";
    }
    throw std::invalid_argument(what + ": " + e.what());
  }
}

// The top eigenvector psi (|psi| = 1) of A = M^-1/2 K M^-1/2: dense up to
// 1000 unknowns, power iteration on A + c I (c a Gershgorin bound) above,
// from a fixed start with a component along every mode.
Vector top_eigenvector(const SparseMatrix& a) {
  if (a.rows() <= 1000) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(a)};
    return eig.eigenvectors().col(a.rows() - 1);
  }
  double c = 0.0;
  for (int j = 0; j < a.outerSize(); ++j) {
    double row = 0.0;
    for (SparseMatrix::InnerIterator it(a, j); it; ++it) row += std::abs(it.value());
    c = std::max(c, row);
  }
  Vector q(a.rows());
  for (Eigen::Index i = 0; i < q.size(); ++i) q[i] = 1.0 + 0.5 * std::sin(1.0 + 7.0 * i);
  q.normalize();
  double previous = 0.0;
  for (int iteration = 0; iteration < 5000; ++iteration) {
    Vector z = a * q + c * q;
    const double estimate = q.dot(z);
    q = z.normalized();
    if (std::abs(estimate - previous) <= 1e-12 * std::abs(estimate)) break;
    previous = estimate;
  }
  return q;
}

// The largest h whose h lambda lies in |R| <= 1 for every lambda: a scan of
// 100 points per decade from 1e-6 / |lambda| up to 100 / |lambda|, then
// bisection. Empty when no step up there leaves the region; 0 when even the
// first does.
std::optional<double> largest_stable_step(const IntegratorInfo& info,
                                          const std::vector<std::complex<double>>& lambda) {
  double size = 0.0;
  for (const auto& l : lambda) size = std::max(size, std::abs(l));
  auto unstable = [&](double h) {
    for (const auto& l : lambda) {
      if (std::abs(info.stability_function(h * l)) > 1.0 + 1e-12) return true;
    }
    return false;
  };
  double lo = 1e-6 / size;
  if (unstable(lo)) return 0.0;
  const double ratio = std::pow(10.0, 0.01);
  double hi = lo * ratio;
  while (!unstable(hi)) {
    if (hi > 100.0 / size) return std::nullopt;
    lo = hi;
    hi *= ratio;
  }
  while (hi / lo > 1.0 + 1e-12) {
    const double mid = std::sqrt(lo * hi);
    if (!(mid > lo && mid < hi)) break;
    (unstable(mid) ? hi : lo) = mid;
  }
  return lo;
}

}  // namespace

FastestMode fastest_mode(const Model& model) {
  FastestMode mode;
  mode.w = max_angular_frequency(model);
  SparseMatrix dfdx, dfdv;
  model.jacobians(0.0, model.initial_positions(), model.initial_velocities(), &dfdx, &dfdv);
  bool damped = false;
  for (int j = 0; j < dfdv.outerSize() && !damped; ++j) {
    for (SparseMatrix::InnerIterator it(dfdv, j); it; ++it) damped = damped || it.value() != 0.0;
  }
  if (!damped || !(mode.w > 0.0)) return mode;
  const Vector s = model.mass().cwiseSqrt().cwiseInverse();
  const SparseMatrix k = -0.5 * (SparseMatrix(dfdx.transpose()) + dfdx);
  const SparseMatrix d = -0.5 * (SparseMatrix(dfdv.transpose()) + dfdv);
  const Vector psi = top_eigenvector(s.asDiagonal() * k * s.asDiagonal());
  const Vector phi = s.asDiagonal() * psi;  // phi^T M phi = |psi|^2 = 1
  mode.damping = std::max(0.0, phi.dot(d * phi));
  return mode;
}

double trial_run_time(const StabilitySettings& s, double w, double h) {
  double t = std::max(s.run.t_end, s.min_steps * h);
  if (w > 0.0) t = std::max(t, s.min_periods * 2.0 * std::numbers::pi / w);
  return t;
}

StabilityResult find_max_stable_dt(const Model& model, const StabilitySettings& s) {
  if (!(s.dt_min > 0.0) || !(s.dt_max > s.dt_min) || !std::isfinite(s.dt_max)) {
    throw std::invalid_argument("need 0 < dt-min < dt-max");
  }
  if (!(s.rel_tol > 0.0)) throw std::invalid_argument("rel-tol must be positive");
  if (s.min_steps < 1 || !(s.min_periods >= 0.0)) {
    throw std::invalid_argument("a trial needs at least one step");
  }
  check_grid("--dt-min", s.dt_min, s.run.t_end, s.run.t_end);
  check_grid("--dt-max", s.dt_max, s.run.t_end, s.run.t_end);
  StabilityResult result;
  result.integrator = s.run.integrator;
  result.mode = fastest_mode(model);
  const double w = result.mode.w;
  auto run_time = [&](double h) { return trial_run_time(s, w, h); };
  check_grid("--dt-min", s.dt_min, s.run.t_end, run_time(s.dt_min));
  check_grid("--dt-max", s.dt_max, s.run.t_end, run_time(s.dt_max));
  if (w > 0.0) result.min_run_time = s.min_periods * 2.0 * std::numbers::pi / w;
  // What the method claims at the run's options (newmark --beta 0 is the
  // central difference, not average acceleration).
  const IntegratorInfo info = make_integrator(s.run.integrator)->info_for(s.run.options);
  result.theory = theoretical_max_dt(info, result.mode, run_time, s.run.blowup);

  double lo = 0.0, hi = 0.0;  // largest stable, smallest diverging step so far
  auto stable = [&](double dt) {
    RunSettings run = s.run;
    run.dt = dt;
    run.t_end = run_time(dt);
    // A stable orbit of a symplectic method swings the fastest mode's energy
    // by up to energy_excursion(w h) (integrator.h): that is not divergence.
    run.blowup = s.run.blowup * energy_excursion(info, dt * w);
    ++result.runs;
    if (s.on_trial) s.on_trial({result.runs, dt, run.t_end, lo, hi});
    std::vector<Observer*> observers;
    if (s.observer != nullptr) observers.push_back(s.observer);
    const bool ok = !simulate(model, run, observers).diverged();
    (ok ? lo : hi) = dt;
    return ok;
  };
  auto finish = [&](StabilityOutcome outcome) {
    result.outcome = outcome;
    switch (outcome) {
      case StabilityOutcome::kStableUpToDtMax:
        result.max_stable_dt = result.lo = result.hi = s.dt_max;
        break;
      case StabilityOutcome::kUnstableAtDtMin:
        result.max_stable_dt = result.lo = 0.0;
        result.hi = s.dt_min;
        break;
      case StabilityOutcome::kBracketed:
        result.max_stable_dt = result.lo = lo;
        result.hi = hi;
        break;
    }
    result.lo_run_time = result.lo > 0.0 ? run_time(result.lo) : 0.0;
    result.no_stable_step = info.stability == StabilityKind::kConditional &&
                            info.stability_limit == 0.0 && w > 0.0 && !(result.mode.damping > 0.0);
    if (info.stability_function && w > 0.0 && result.lo > 0.0) {
      // The fastest mode's eigenvalues: lambda^2 + c lambda + w^2 = 0.
      const double c = result.mode.damping;
      const std::complex<double> root = std::sqrt(std::complex<double>(c * c / 4.0 - w * w, 0.0));
      result.growth_at_lo = 0.0;
      for (const std::complex<double> lambda : {-c / 2.0 + root, -c / 2.0 - root}) {
        result.growth_at_lo =
            std::max(result.growth_at_lo, std::norm(info.stability_function(result.lo * lambda)));
      }
    }
    return result;
  };

  if (result.theory.dt && *result.theory.dt > 0.0) {
    // Around the theory: [guess / 2, 2 guess], widened by 4 until it straddles.
    const double guess = std::clamp(*result.theory.dt, s.dt_min, s.dt_max);
    double up = std::min(2.0 * guess, s.dt_max);
    while (stable(up)) {
      if (up >= s.dt_max) return finish(StabilityOutcome::kStableUpToDtMax);
      up = std::min(4.0 * up, s.dt_max);
    }
    if (lo == 0.0) {
      double down = std::max(0.5 * guess, s.dt_min);
      if (down >= hi) down = std::max(0.25 * hi, s.dt_min);
      while (!stable(down)) {
        if (down <= s.dt_min) return finish(StabilityOutcome::kUnstableAtDtMin);
        down = std::max(0.25 * down, s.dt_min);
      }
    }
  } else {
    // No theory: dt_max, then down by factors of 10 to the first stable step.
    if (stable(s.dt_max)) return finish(StabilityOutcome::kStableUpToDtMax);
    double down = s.dt_max;
    do {
      if (down <= s.dt_min) return finish(StabilityOutcome::kUnstableAtDtMin);
      down = std::max(0.1 * down, s.dt_min);
    } while (!stable(down));
  }
  // Each halving of log(hi/lo) takes one run; hi/lo starts below 2^2048 and
  // the loop also ends once no double lies strictly between lo and hi.
  for (int halving = 0; halving < 200 && hi / lo > 1.0 + s.rel_tol; ++halving) {
    const double mid = std::sqrt(lo) * std::sqrt(hi);  // no overflow of lo * hi
    if (!(mid > lo && mid < hi)) break;                  // neighbours: nothing left to split
    stable(mid);
  }
  return finish(StabilityOutcome::kBracketed);
}

TheoryLimit theoretical_max_dt(const IntegratorInfo& info, const FastestMode& mode,
                               const std::function<double(double)>& run_time, double blowup) {
  std::ostringstream rule;
  const double w = mode.w, c = mode.damping;
  if (info.adaptive) return {std::nullopt, "none: an adaptive method chooses its own steps"};
  if (!(w > 0.0)) return {std::nullopt, "none: the scene has no oscillating mode (w_max = 0)"};
  // A- and L-stable methods have none; unknown and A(alpha) declare none.
  if (info.stability != StabilityKind::kConditional || !std::isfinite(info.stability_limit)) {
    return {std::nullopt, "none: " + stability_text(info)};
  }
  if (c > 0.0 && info.stability_function) {
    // The damped mode: lambda^2 + c lambda + w^2 = 0.
    const std::complex<double> root = std::sqrt(std::complex<double>(c * c / 4.0 - w * w, 0.0));
    const std::vector<std::complex<double>> lambda = {-c / 2.0 + root, -c / 2.0 - root};
    const std::optional<double> h = largest_stable_step(info, lambda);
    rule << "|R(h lambda)| <= 1 for the fastest mode, lambda^2 + c lambda + w_max^2 = 0 with "
            "damping c = "
         << damping_text(c) << " 1/s";
    if (!h || *h <= 0.0) return {std::nullopt, "none: " + rule.str()};
    return {*h, rule.str()};
  }
  if (info.stability_limit > 0.0) {
    rule << std::setprecision(4) << info.stability_limit << " / w_max";
    if (c > 0.0) {
      rule << " (undamped: the fastest mode's damping c = " << damping_text(c)
           << " 1/s is not taken into account)";
    }
    return {info.stability_limit / w, rule.str()};
  }
  if (!info.stability_function) return {std::nullopt, "unknown"};
  // (T(h) / h) ln |R(i w h)|^2 = ln B, increasing in h: bisect on log h.
  auto growth = [&](double h) {
    return run_time(h) / h * std::log(std::norm(info.stability_function({0.0, w * h})));
  };
  double lo = 1e-12 / w, hi = 10.0 / w;
  const double target = std::log(blowup);
  if (growth(hi) < target) return {std::nullopt, "none within 10 / w_max"};
  for (int iteration = 0; iteration < 200 && hi / lo > 1.0 + 1e-12; ++iteration) {
    const double mid = std::sqrt(lo * hi);
    if (!(mid > lo && mid < hi)) break;
    (growth(mid) < target ? lo : hi) = mid;
  }
  rule << "no stable step undamped; the step at which the fastest mode alone grows x"
       << format_number(blowup)
       << " within a trial (exact for an oscillator that holds E_s; a scene's fastest mode "
          "starts with less of the energy, so it passes the bound later, at a larger step)";
  return {std::sqrt(lo * hi), rule.str()};
}

TheoryLimit theoretical_max_dt(const IntegratorInfo& info, double w, double t_end, double blowup) {
  return theoretical_max_dt(info, FastestMode{w, 0.0}, [t_end](double) { return t_end; }, blowup);
}

}  // namespace springlab
