#include "integrators/newton/line_search.h"
#include "integrators/newton/newton_tolerances.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springlab {
namespace {

using newton::kArmijo;
// The longest update tried along a direction of negative curvature, m/s.
constexpr double kMaxEscape = 10.0;
constexpr double kGapCap = 0.9;
// Where the search gives up without a descent direction of the potential.
constexpr double kShortestStep = 1.0 / 1024.0;

}  // namespace

double LineSearch::noise(const Line& line) const {
  return 1e3 * std::numeric_limits<double>::epsilon() * std::max(line.magnitude, trial_.magnitude);
}

bool LineSearch::accept(NewtonProblem& problem, const Line& line, double alpha) {
  const double r_try_norm = trial_.r.norm();
  if (!std::isfinite(r_try_norm) || !problem.allowed()) return false;
  const bool residual_decreases = r_try_norm <= (1.0 - kArmijo * alpha) * line.r_norm;
  if (!line.minimize) return residual_decreases;
  trial_.phi = problem.potential(trial_.v, trial_.magnitude);
  if (!std::isfinite(trial_.phi)) return false;
  if (trial_.phi - line.phi <= kArmijo * alpha * line.slope) return true;
  return alpha * -line.slope <= noise(line) && residual_decreases;
}

bool LineSearch::expand(NewtonProblem& problem, const Line& line, double& alpha) {
  double best_phi = line.phi, best_magnitude = line.magnitude, best_alpha = 0.0;
  const double trusted = problem.trusted_fraction(line.v, line.dv);
  for (int k = 0; k < 40; ++k, alpha *= 2.0) {
    if (alpha * line.update > kMaxEscape || alpha > trusted) break;
    trial_.v = line.v + alpha * line.dv;
    problem.residual(trial_.v, trial_.r);
    trial_.phi = problem.potential(trial_.v, trial_.magnitude);
    if (!std::isfinite(trial_.phi) || trial_.phi > best_phi + noise(line) || !problem.allowed()) {
      break;
    }
    if (trial_.phi < best_phi) {
      best_phi = trial_.phi;
      best_magnitude = trial_.magnitude;
      best_alpha = alpha;
    }
  }
  if (!(best_phi < line.phi - noise(line))) return false;
  alpha = best_alpha;
  trial_.v = line.v + alpha * line.dv;
  problem.residual(trial_.v, trial_.r);
  trial_.phi = best_phi;
  trial_.magnitude = best_magnitude;
  return true;
}

bool LineSearch::search(NewtonProblem& problem, const Line& line, bool negative_curvature,
                        bool definite, double& alpha) {
  if (problem.has_forbidden_states()) {
    const double cap = problem.admissible_fraction(line.v, line.dv);
    // A cap below the search's own floor means the iterate is pinned at a
    // gap: search from the full step as without a cap, which ends in the
    // line search's failure (the step's equations have no solution that
    // keeps the gaps open).
    if (kGapCap * cap >= kShortestStep) alpha = std::min(alpha, kGapCap * cap);
  }
  // The trust region: its fraction, and the floor below relative to it.
  const double trusted = std::min(1.0, problem.trusted_fraction(line.v, line.dv));
  alpha = std::min(alpha, trusted);
  // With a descent direction of the potential the search cannot fail but
  // to round-off.
  const double alpha_min = (line.minimize && definite ? 1e-12 : kShortestStep) * trusted;
  for (;;) {
    trial_.v = line.v + alpha * line.dv;
    problem.residual(trial_.v, trial_.r);
    if (accept(problem, line, alpha)) break;
    alpha *= 0.5;
    if (alpha < alpha_min) return false;
  }
  if (alpha == 1.0 && line.minimize && negative_curvature) {
    // Accepted at the full step along negative curvature: longer still?
    double beta = 2.0;
    const Trial one = trial_;
    if (expand(problem, line, beta) && trial_.phi < one.phi) {
      alpha = beta;
    } else {
      trial_.v = one.v;
      trial_.r = one.r;
      trial_.phi = one.phi;
      trial_.magnitude = one.magnitude;
    }
  }
  return true;
}

}  // namespace springlab
