#include "integrators/newton_velocity_solver.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace springlab {

void ImplicitIntegrator::residual(double h, const VelocityImplicitScheme& s, const Vector& v,
                                  Vector& r) {
  xs_ = x_ + h * (s.a * v_ + s.b * v);
  vs_ = (1.0 - s.c) * v_ + s.c * v;
  eval_force(t_ + s.t_eval_offset * h, xs_, vs_, f_);
  r = system().mass().cwiseProduct(v - v_) - h * f_;
}

double ImplicitIntegrator::converged_norm(const Vector& r) const {
  return r.cwiseQuotient(system().mass()).lpNorm<Eigen::Infinity>();
}

bool ImplicitIntegrator::factorize_newton_matrix(double t, const Vector& x, const Vector& v,
                                                 double h, double c, double b,
                                                 std::string& error) {
  factor_h_ = 0.0;  // refresh() records what the new matrix is for
  eval_jacobians(t, x, v, &dfdx_, &dfdv_);
  // All three share the model's pattern: combine value by value.
  if (jacobian_.nonZeros() != dfdx_.nonZeros()) jacobian_ = dfdx_;
  const Vector& m = system().mass();
  const Eigen::Index nnz = dfdx_.nonZeros();
  const double* px = dfdx_.valuePtr();
  const double* pv = dfdv_.valuePtr();
  double* pj = jacobian_.valuePtr();
  const double cx = -h * h * b, cv = -h * c;
  for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k] + cv * pv[k];
  jacobian_.diagonal() += m;
  ++mutable_stats().factorizations;
  if (!solver_.factorize(jacobian_, system().jacobian_symmetric())) {
    error = solver_.error();
    return false;
  }
  return true;
}

bool ImplicitIntegrator::solve_newton_system(const Vector& rhs, Vector& dv) {
  ++mutable_stats().linear_solves;
  return solver_.solve(rhs, dv);
}

StepResult ImplicitIntegrator::do_initialize() {
  solver_.reset();
  jacobian_ = SparseMatrix();
  factor_h_ = 0.0;
  refresh_next_step_ = false;
  return StepResult::success();
}

namespace {
// See the header: a kept matrix contracting the error by less than this per
// iteration is refactorized at once ...
constexpr double kRefreshRate = 0.5;
// ... and one that ended a step contracting by less than this is
// refactorized at the start of the next step.
constexpr double kRefreshNextStep = 0.25;
// The kept matrix is for another step size when h differs by more than this.
constexpr double kMaxStepChange = 0.2;
}  // namespace

bool ImplicitIntegrator::refresh(double h, const VelocityImplicitScheme& s, const Vector& v,
                                 std::string& error) {
  xs_ = x_ + h * (s.a * v_ + s.b * v);
  vs_ = (1.0 - s.c) * v_ + s.c * v;
  if (!factorize_newton_matrix(t_ + s.t_eval_offset * h, xs_, vs_, h, s.c, s.b, error)) {
    return false;
  }
  factor_h_ = h;
  factor_b_ = s.b;
  factor_c_ = s.c;
  return true;
}

StepResult ImplicitIntegrator::solve_velocity(double h, const VelocityImplicitScheme& s,
                                              Vector& v) {
  StepResult result = newton(h, s, v, /*keep_matrix=*/true);
  if (!result.ok) {
    // Kept matrices lead Newton along another path than fresh ones, and the
    // line search on ||r|| can stall on either: redo the step the classic
    // way, with a fresh matrix at every iteration, before calling it failed.
    factor_h_ = 0.0;
    result = newton(h, s, v, /*keep_matrix=*/false);
  }
  if (!result.ok) {
    ++mutable_stats().nonlinear_failures;
    factor_h_ = 0.0;
  }
  return result;
}

StepResult ImplicitIntegrator::newton(double h, const VelocityImplicitScheme& s, Vector& v,
                                      bool keep_matrix) {
  auto fail = [&](const std::string& why) {
    std::ostringstream message;
    message << name() << ": Newton failed at t = " << t_ << " (h = " << h << "): " << why;
    return StepResult::failure(message.str());
  };
  std::string error;
  // `exact`: the kept matrix is the Jacobian at the current iterate v, so its
  // update is a true Newton update.
  bool exact = false;
  auto make_exact = [&]() {
    if (!refresh(h, s, v, error)) return false;
    exact = true;
    return true;
  };

  const double tol = options().newton_tol;
  v = v_;
  residual(h, s, v, r_);
  const bool kept_fits = factor_h_ > 0.0 && factor_b_ == s.b && factor_c_ == s.c &&
                         std::abs(h / factor_h_ - 1.0) <= kMaxStepChange;
  const bool refresh_first = !kept_fits || refresh_next_step_;
  refresh_next_step_ = false;
  double previous_update = 0.0;  // ||dv||_inf of the last full update with the kept matrix
  double rate = 0.0;             // observed contraction rate (0: not observed yet)
  // iteration: updates taken (a kept matrix's update that is refused and
  // redone with a fresh one is a linear solve, not an iteration).
  for (int iteration = 0;;) {
    const double bound = tol * std::max(1.0, v.lpNorm<Eigen::Infinity>());
    const double size = converged_norm(r_);
    if (!std::isfinite(size)) return fail("the residual is not finite");
    if (size <= bound) break;
    if (iteration == options().max_newton) {
      std::ostringstream why;
      why << "no convergence in " << options().max_newton << " iterations (||M^-1 r|| = " << size
          << ", tolerance " << tol << ")";
      return fail(why.str());
    }
    if (((iteration == 0 && refresh_first) || (!keep_matrix && !exact)) && !make_exact()) {
      return fail("Newton matrix is singular (" + error + ")");
    }

    bool finite = solve_newton_system(-r_, dv_);
    double update = dv_.lpNorm<Eigen::Infinity>();
    // A kept matrix that gives no update, one contracting too slowly, or one
    // that would not reach the tolerance within max_newton iterations at the
    // rate it shows: refactorize here and take the true Newton update instead.
    bool too_slow = false;
    if (previous_update > 0.0) {
      const double r = update / previous_update;
      // Updates still to come at rate r before the error is below the bound,
      // and a margin of two: the budget is for the true Newton iteration.
      too_slow = r >= kRefreshRate ||
                 iteration + 1 + std::log(bound * (1.0 - r) / (r * update)) / std::log(r) >
                     options().max_newton - 2;
    }
    if (!exact && (!finite || too_slow)) {
      if (!make_exact()) return fail("Newton matrix is singular (" + error + ")");
      previous_update = 0.0;
      rate = 0.0;
      finite = solve_newton_system(-r_, dv_);
      update = dv_.lpNorm<Eigen::Infinity>();
    }
    if (!finite) return fail("the Newton update is not finite");
    if (previous_update > 0.0) rate = update / previous_update;

    // The update shows the error left after it below the tolerance: take it
    // and stop (an exact Newton update: the error left is far smaller).
    // (A kept matrix contracts at rate < kRefreshRate here, or was replaced.)
    const double remaining =
        exact || rate == 0.0 ? update : update * std::min(1.0, rate / (1.0 - rate));
    if (remaining <= bound) {
      ++mutable_stats().newton_iterations;
      v += dv_;
      refresh_next_step_ = refresh_next_step_ || (!exact && rate > kRefreshNextStep);
      return StepResult::success();
    }

    // The full update, if it decreases ||r||_2; else a kept matrix is
    // refactorized and the iteration redone, an exact one backtracks.
    const double r_norm = r_.norm();
    v_try_ = v + dv_;
    residual(h, s, v_try_, r_try_);
    double r_try_norm = r_try_.norm();
    if (std::isfinite(r_try_norm) && r_try_norm <= (1.0 - 1e-4) * r_norm) {
      previous_update = update;
    } else if (!exact) {
      // Refused at the first iteration: the kept matrix is too old for this
      // motion; the next step starts with a fresh one instead of trying it.
      if (iteration == 0) refresh_next_step_ = true;
      if (!make_exact()) return fail("Newton matrix is singular (" + error + ")");
      previous_update = 0.0;
      rate = 0.0;
      continue;
    } else {
      double alpha = 1.0;
      do {
        alpha *= 0.5;
        if (alpha < 1.0 / 1024.0) return fail("the line search could not reduce the residual");
        v_try_ = v + alpha * dv_;
        residual(h, s, v_try_, r_try_);
        r_try_norm = r_try_.norm();
      } while (!(std::isfinite(r_try_norm) && r_try_norm <= (1.0 - 1e-4 * alpha) * r_norm));
      previous_update = 0.0;  // a partial update says nothing of the contraction rate
      rate = 0.0;
    }
    ++mutable_stats().newton_iterations;
    ++iteration;
    v.swap(v_try_);
    r_.swap(r_try_);
    exact = false;
  }
  refresh_next_step_ = refresh_next_step_ || (!exact && rate > kRefreshNextStep);
  return StepResult::success();
}

}  // namespace springlab
