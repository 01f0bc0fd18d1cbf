#include "integrators/newton/newton_loop.h"
#include "integrators/newton/newton_tolerances.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace springlab {
namespace {

// The forcing term (newton_loop.h): eta = min(kForcing, ||r|| / ||r_0||),
// or kForcingTolerance x the Newton tolerance; kAccurateForcing where a
// true Newton update is wanted.
constexpr double kForcing = 0.1;
constexpr double kForcingTolerance = 0.1;
constexpr double kAccurateForcing = 1e-3;
// The rank-one term is used while 1 + z.q stays above this.
constexpr double kMinShermanMorrison = 0.5;
// Updates below this many units of round-off of ||v||_inf are noise.
using newton::kRoundoff;

}  // namespace

StepResult NewtonLoop::solve(NewtonProblem& problem, const Pieces& pieces,
                             const Settings& settings, const Context& context,
                             IntegratorStats& stats, Vector& v) {
  auto fail = [&](const std::string& why) {
    std::ostringstream message;
    message << "Newton failed at t = " << context.t << " (h = " << context.h
            << "): " << why;
    return StepResult::failure(message.str());
  };
  NewtonPolicy& policy = pieces.policy;
  NewtonLinearSolver& linear = pieces.linear;
  search_ = &pieces.search;
  settings_ = settings;
  policy.start(problem.has_potential(), mode_);
  start(problem, v);
  linear.start_nonlinear_solve();
  NewtonIterate it{v, r_, phi_, magnitude_};
  std::string error;
  for (int iteration = 0, attempts = 0;;) {
    if (!r_.allFinite()) return fail("the residual is not finite");
    if (iteration == settings_.max_iterations || ++attempts > 3 * settings_.max_iterations) {
      return fail(no_convergence_text());
    }
    policy.begin_iteration(mode_, it);
    // 1-2. The matrix at v (r is the iterate's) and the update dv ~ -J^-1 r.
    if (!compute_update(problem, linear, v, error)) return fail(error);
    const double update = dv_.lpNorm<Eigen::Infinity>();
    // The slope of the potential along dv (negative: CG's iterates descend
    // but for round-off).
    const double slope = mode_.minimize ? r_.dot(dv_) : 0.0;
    const LineSearch::Line line{v, dv_, r_.norm(), phi_, magnitude_, slope, update,
                                mode_.minimize};
    search_->begin_line();
    // 3. Stop when the update is below the tolerance.
    double alpha = 1.0;
    bool accepted = false;  // a longer step along negative curvature
    if (converged(problem, line, alpha, accepted)) {
      ++stats.newton_iterations;
      v += dv_;
      return StepResult::success();
    }
    // 4. A step the merit accepts; where there is none, the policy's
    // fallback from the same iterate.
    if (!accepted && mode_.minimize && !(slope < 0.0)) {
      if (policy.retry_not_descending(mode_)) continue;
      return fail("the Newton update does not descend the incremental potential");
    }
    if (!accepted && !search_->search(problem, line, solved_.negative_curvature, mode_.definite,
                                     alpha)) {
      if (policy.retry_search_failed(mode_, problem, it)) continue;
      return fail(mode_.minimize ? "the line search could not decrease the incremental "
                                   "potential; try a smaller --dt"
                                 : "the line search could not reduce the residual; try a "
                                   "smaller --dt");
    }
    rate_ = alpha == 1.0 && previous_update_ > 0.0 ? update / previous_update_ : 0.0;
    previous_update_ = alpha == 1.0 ? update : 0.0;
    policy.step_taken(mode_, alpha);
    ++stats.newton_iterations;
    ++iteration;
    LineSearch::Trial& trial = search_->trial();
    v.swap(trial.v);
    r_.swap(trial.r);
    phi_ = trial.phi;
    magnitude_ = trial.magnitude;
    // Where the search had to shorten the update (a gap or a crossing of
    // surfaces in the way), the problem set up again around the new iterate
    // (the contacts between bodies found there): its r and Phi there. Not
    // after full updates: the set found at each iterate can alternate
    // between two (box-drop: 263 iterates, 1e-4 J apart), while on one set
    // Newton converges.
    if (alpha < 1.0 && problem.follow(v)) {
      problem.residual(v, r_);
      if (mode_.minimize) phi_ = problem.potential(v, magnitude_);
    }
  }
}

void NewtonLoop::start(NewtonProblem& problem, Vector& v) {
  v = settings_.start != nullptr ? *settings_.start : problem.start();
  problem.residual(v, r_);
  // The start leaves the states where the forces are defined (a barrier's
  // gap closed, an element inverted): the problem's other start.
  if (!r_.allFinite() && problem.fallback_start(v)) problem.residual(v, r_);
  if (!r_.allFinite() && problem.accepted_start(v)) problem.residual(v, r_);
  if (r_.allFinite() && problem.has_forbidden_states() && !problem.allowed()) {
    allowed_start(problem, v);
  }
  magnitude_ = 0.0;
  search_->reset();
  phi_ = mode_.minimize ? problem.potential(v, magnitude_) : 0.0;
  r_start_ = r_.norm();
  previous_update_ = 0.0;
  rate_ = 0.0;
  last_update_ = last_remaining_ = last_rate_ = 0.0;
  last_why_.clear();
}

void NewtonLoop::allowed_start(NewtonProblem& problem, Vector& v) {
  // The midpoint methods evaluate the forces at x_n + h (v_n + v) / 4 and
  // end at x_n + h (v_n + v) / 2 (generalized-alpha likewise, its end
  // 1 / (1 - alpha_f) as far as its stage): from v = v_n, a body that
  // reaches a barrier's gap within the step has its forces' state short of
  // the gap (r finite) but its end beyond it. Every trial near such a start
  // is refused (LineSearch::accept), so the search could only fail
  // (box-pile n=8 at 1 ms, when the second box lands at t = 0.054 s). The
  // accepted start (the state of the last step: its end allowed) is one
  // that is allowed; from there, the way towards v is capped as the line
  // search caps a step (0.9 of the fraction at which a gap closes, halved
  // while the state is still refused, e.g. by an interpenetration the
  // fraction does not foresee).
  rhs_ = v;
  if (!problem.accepted_start(v) && !problem.fallback_start(v)) {
    v = rhs_;
    problem.residual(v, r_);
    return;
  }
  dv_ = rhs_ - v;
  constexpr double kGapCap = 0.9, kShortest = 1.0 / 1024.0;
  const double cap = problem.admissible_fraction(v, dv_);
  for (double alpha = std::min(1.0, kGapCap * cap); alpha >= kShortest; alpha *= 0.5) {
    q_ = v + alpha * dv_;
    problem.residual(q_, r_);
    if (r_.allFinite() && problem.allowed()) {
      v.swap(q_);
      return;
    }
  }
  problem.residual(v, r_);
}

bool NewtonLoop::compute_update(NewtonProblem& problem, NewtonLinearSolver& linear,
                                const Vector& v, std::string& error) {
  problem.matrix(v, mode_.definite, linear);
  const double r_norm = r_.norm();
  const double eta = mode_.careful ? kAccurateForcing
                                   : std::min(kForcing, r_start_ > 0.0 ? r_norm / r_start_ : kForcing);
  const double atol = mode_.careful ? 0.0 : kForcingTolerance * settings_.tol;
  rhs_ = -r_;
  solved_ = linear.solve(rhs_, {.rtol = eta, .atol = atol, .truncate = mode_.minimize}, dv_, error);
  if (!solved_.ok) return false;
  const NewtonProblem::RankOne term = problem.rank_one();
  if (term.u != nullptr) {
    // Sherman and Morrison: dv -= (z.dv / (1 + z.q)) q, q = J^-1 u.
    const Vector& z = *term.z;
    if (!linear.solve(*term.u, {.rtol = eta, .atol = 0.0, .truncate = false}, q_, error).ok) {
      return false;
    }
    const double denominator = 1.0 + z.dot(q_);
    if (denominator > kMinShermanMorrison || (mode_.careful && denominator != 0.0)) {
      // Where the merit is the potential, only if the update still descends.
      const double step = z.dot(dv_) / denominator;
      if (!mode_.minimize || r_.dot(dv_ - step * q_) < 0.0) dv_ -= step * q_;
    }
  }
  return true;
}

bool NewtonLoop::converged(NewtonProblem& problem, const LineSearch::Line& line, double& alpha,
                           bool& escaping) {
  const double update = line.update, rate = rate_;
  last_update_ = update;
  last_rate_ = rate;
  // Converging linearly at `rate`, what remains after the update.
  const double remaining = rate > 0.5 && rate < 1.0 ? update * rate / (1.0 - rate) : update;
  last_remaining_ = remaining;
  last_why_ = solved_.converged || solved_.negative_curvature
                  ? ""
                  : "its linear solve stopped short of its own tolerance";
  if (!solved_.converged && !solved_.negative_curvature) return false;
  // A tolerance below the round-off of v is met at that round-off: that of
  // v itself, and the v below which the positions the forces see do not
  // move beyond their own round-off (an iterate there is as good as the
  // state can resolve; the update is then noise of the residual mapped by
  // J^-1: 1.28e-12 m/s, stalled, on a box hung from a stiff spring at
  // newton_tol 1e-12, depending on the BLAS kernel).
  const double floor = kRoundoff * (line.v.lpNorm<Eigen::Infinity>() +
                                    problem.start().lpNorm<Eigen::Infinity>() +
                                    problem.position_resolution());
  const bool small = remaining <= settings_.tol || update <= floor;
  if (!small) return false;
  // Where states are forbidden, the last update must not end in one (a
  // barrier's gap closed by it): then it is searched like any other.
  if (problem.has_forbidden_states() && !(problem.admissible_fraction(line.v, line.dv) > 1.0)) {
    last_why_ = "it would close a barrier's gap";
    return false;
  }
  // Where the potential curves down (a saddle of it, not a minimum: a
  // buckling cloth), the step's equations have lower solutions nearby:
  // leave along that direction if the potential visibly falls.
  alpha = update > 0.0 ? settings_.tol / update : 1.0;
  if (!solved_.negative_curvature || !search_->expand(problem, line, alpha)) return true;
  last_why_ = "the incremental potential kept falling beyond it (negative curvature)";
  escaping = true;
  return false;
}

std::string NewtonLoop::no_convergence_text() const {
  // Say why the last update, even one below the tolerance, did not end the
  // iteration.
  std::ostringstream why;
  why << "no convergence in " << settings_.max_iterations << " iterations (last update "
      << last_update_ << " m/s, tolerance " << settings_.tol << " m/s";
  if (last_remaining_ > settings_.tol && last_remaining_ > last_update_) {
    why << "; converging linearly at the rate " << last_rate_
        << ", it leaves an error of about " << last_remaining_ << " m/s";
  } else if (last_update_ <= settings_.tol && !last_why_.empty()) {
    why << "; not taken: " << last_why_;
  }
  why << "); try a larger --max-newton or a smaller --dt";
  return why.str();
}

}  // namespace springlab
