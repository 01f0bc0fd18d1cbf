#include "integrators/newton_velocity_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
                                                 std::string& error, bool definite) {
  factor_h_ = 0.0;  // refresh() records what the new matrix is for
  // No force depends on v: dF/dv = 0 is neither assembled nor stored (on
  // cloth n = 128, 23 MB of values and indices).
  SparseMatrix* dfdv =
      system().velocity_dependence() == VelocityDependence::kNone ? nullptr : &dfdv_;
  if (definite) {
    eval_definite_jacobians(t, x, v, &dfdx_, dfdv);
  } else {
    eval_jacobians(t, x, v, &dfdx_, dfdv);
  }
  // All three share the model's pattern: combine value by value.
  if (jacobian_.nonZeros() != dfdx_.nonZeros()) jacobian_ = dfdx_;
  const Vector& m = system().mass();
  const Eigen::Index nnz = dfdx_.nonZeros();
  const double* px = dfdx_.valuePtr();
  double* pj = jacobian_.valuePtr();
  const double cx = -h * h * b, cv = -h * c;
  if (dfdv != nullptr) {
    const double* pv = dfdv_.valuePtr();
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k] + cv * pv[k];
  } else {
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k];
  }
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
  dfdv_ = SparseMatrix();  // the next system may not need it
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
                                 bool definite, std::string& error) {
  xs_ = x_ + h * (s.a * v_ + s.b * v);
  vs_ = (1.0 - s.c) * v_ + s.c * v;
  if (!factorize_newton_matrix(t_ + s.t_eval_offset * h, xs_, vs_, h, s.c, s.b, error, definite)) {
    return false;
  }
  factor_h_ = h;
  factor_b_ = s.b;
  factor_c_ = s.c;
  factor_definite_ = definite;
  return true;
}

StepResult ImplicitIntegrator::solve_velocity(double h, const VelocityImplicitScheme& s,
                                              Vector& v) {
  // On the incremental potential when the forces derive from potentials,
  // else on ||r||: first with kept matrices, then with a fresh one at every
  // iteration (the classic Newton-Raphson) -- kept matrices lead Newton along
  // another path than fresh ones -- and, if the potential path fails too (a
  // term whose projected stiffness is not definite), the classic one on ||r||.
  const bool potential = system().derives_from_potentials() && s.b > 0.0 && s.c > 0.0;
  StepResult result = newton(h, s, v, /*keep_matrix=*/true, potential);
  if (!result.ok) {
    factor_h_ = 0.0;
    result = newton(h, s, v, /*keep_matrix=*/false, potential);
  }
  if (!result.ok && potential) {
    factor_h_ = 0.0;
    result = newton(h, s, v, /*keep_matrix=*/false, /*potential=*/false);
  }
  if (!result.ok) {
    ++mutable_stats().nonlinear_failures;
    factor_h_ = 0.0;
  }
  return result;
}

double ImplicitIntegrator::merit(double h, const VelocityImplicitScheme& s, const Vector& v,
                                 double& magnitude) const {
  // xs_ and vs_ are those of the last residual(), at this v.
  const double t = t_ + s.t_eval_offset * h;
  const double inertia = 0.5 * (v - v_).cwiseAbs2().dot(system().mass());
  const double stored = system().position_potential(t, xs_) / s.b;
  const double dissipated = h / s.c * system().velocity_potential(t, vs_);
  magnitude = inertia + std::abs(stored) + std::abs(dissipated);
  return inertia + stored + dissipated;
}

StepResult ImplicitIntegrator::newton(double h, const VelocityImplicitScheme& s, Vector& v,
                                      bool keep_matrix, bool potential) {
  auto fail = [&](const std::string& why) {
    std::ostringstream message;
    message << name() << ": Newton failed at t = " << t_ << " (h = " << h << "): " << why;
    return StepResult::failure(message.str());
  };
  std::string error;
  // `exact`: the kept matrix is the one made at the current iterate v (on the
  // potential path: the definite part of the Jacobian there).
  bool exact = false;
  // Far from the root, where the Jacobian's update needed a line search, the
  // definite part of the Jacobian leads the way (longer steps); near it, the
  // Jacobian itself (quadratic convergence).
  bool prefer_definite = false;
  auto make_exact = [&](bool definite = false) {
    if (!refresh(h, s, v, definite || prefer_definite, error)) return false;
    exact = true;
    return true;
  };

  const double tol = options().newton_tol;
  v = v_;
  residual(h, s, v, r_);
  double magnitude = 0.0, magnitude_try = 0.0;
  double phi = potential ? merit(h, s, v, magnitude) : 0.0;
  const bool kept_fits = factor_h_ > 0.0 && factor_b_ == s.b && factor_c_ == s.c &&
                         std::abs(h / factor_h_ - 1.0) <= kMaxStepChange;
  bool refresh_first = !kept_fits || refresh_next_step_;
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
    if ((refresh_first || (!keep_matrix && !exact)) && !make_exact()) {
      return fail("Newton matrix is singular (" + error + ")");
    }
    refresh_first = false;

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
    // The slope of the merit function along dv: negative with a positive
    // definite matrix, fresh or kept.
    const double slope = r_.dot(dv_);
    if (potential && !(slope < 0.0)) {
      // The Jacobian is indefinite (compressed springs) and its update
      // climbs the potential: take the update of its definite part instead.
      if (exact && factor_definite_) {
        return fail("the Newton update does not descend the incremental potential");
      }
      if (!make_exact(/*definite=*/exact)) {
        return fail("Newton matrix is singular (" + error + ")");
      }
      previous_update = 0.0;
      rate = 0.0;
      continue;
    }
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

    // Whether the update scaled by alpha is taken: on the potential path,
    // when the incremental potential decreases by 1e-4 of its first-order
    // prediction (Armijo) -- or, once that prediction is below the
    // potential's round-off, when ||r|| decreases; on the other path, when
    // ||r|| decreases by 1e-4 alpha.
    const double r_norm = r_.norm();
    double phi_try = 0.0;
    auto accept = [&](double alpha) {
      const double r_try_norm = r_try_.norm();
      if (!std::isfinite(r_try_norm)) return false;
      const bool residual_decreases = r_try_norm <= (1.0 - 1e-4 * alpha) * r_norm;
      if (!potential) return residual_decreases;
      phi_try = merit(h, s, v_try_, magnitude_try);
      if (!std::isfinite(phi_try)) return false;
      if (phi_try - phi <= 1e-4 * alpha * slope) return true;
      const double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                           std::max(magnitude, magnitude_try);
      return alpha * -slope <= noise && residual_decreases;
    };
    v_try_ = v + dv_;
    residual(h, s, v_try_, r_try_);
    if (accept(1.0)) {
      previous_update = update;
      if (exact && factor_definite_) prefer_definite = false;
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
        if (alpha < 1.0 / 1024.0) {
          return fail(potential ? "the line search could not decrease the incremental potential"
                                : "the line search could not reduce the residual");
        }
        v_try_ = v + alpha * dv_;
        residual(h, s, v_try_, r_try_);
      } while (!accept(alpha));
      if (potential) prefer_definite = true;
      previous_update = 0.0;  // a partial update says nothing of the contraction rate
      rate = 0.0;
    }
    ++mutable_stats().newton_iterations;
    ++iteration;
    v.swap(v_try_);
    r_.swap(r_try_);
    phi = phi_try;
    magnitude = magnitude_try;
    exact = false;
  }
  refresh_next_step_ = refresh_next_step_ || (!exact && rate > kRefreshNextStep);
  return StepResult::success();
}

}  // namespace springlab
