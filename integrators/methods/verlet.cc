#include "integrators/methods/verlet.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

VelocityVerlet::VelocityVerlet()
    : Integrator({.name = "verlet",
                  .scheme = "v+ = v + h/2 a(x), x' = x + h v+, v' = v+ + h/2 a(x', v')",
                  .order = 2,
                  .symplectic = true,
                  .stability = StabilityKind::kConditional,
                  .stability_limit = 2.0,
                  // It conserves (v^2 + w^2 x^2 (1 - (w h)^2 / 4))/2.
                  .energy_excursion = [](double wh) { return 1.0 / (1.0 - wh * wh / 4.0); }}) {}

StepResult VelocityVerlet::do_initialize() {
  have_acceleration_ = false;
  solver_.reset();  // the next system's matrix may have another pattern
  solver_version_ = -1;
  return StepResult::success();
}

StepResult VelocityVerlet::do_step(double h) {
  if (!have_acceleration_) {
    eval_acceleration(t_, x_, v_, a_);
    have_acceleration_ = true;
  }
  v_half_ = v_ + 0.5 * h * a_;
  x_ += h * v_half_;
  return closing_kick(t_ + h, h, v_half_);
}

StepResult VelocityVerlet::closing_kick(double t, double h, const Vector& v_half) {
  const Vector& m = system().mass();
  const VelocityDependence dependence = system().velocity_dependence();
  if (dependence == VelocityDependence::kNone) {
    eval_acceleration(t, x_, v_half, a_);
    v_ = v_half + 0.5 * h * a_;
    return StepResult::success();
  }

  if (dependence == VelocityDependence::kNonlinear) return nonlinear_closing_kick(t, h, v_half);

  // F(t, x, v) = F(t, x, 0) + D v with D = dF/dv(t, x).
  eval_force(t, x_, Vector::Zero(x_.size()), f0_);
  eval_jacobians(t, x_, v_half, nullptr, &dfdv_);
  rhs_ = m.cwiseProduct(v_half) + 0.5 * h * f0_;
  if (dependence == VelocityDependence::kDiagonal) {
    const Vector d = dfdv_.diagonal();
    v_ = rhs_.array() / (m - 0.5 * h * d).array();
  } else {
    lhs_ = -0.5 * h * dfdv_;
    lhs_.diagonal() += m;
    // M - h/2 dF/dv is symmetric positive definite: dF/dv of drag, wind and
    // spring damping is symmetric negative semidefinite.
    ++mutable_stats().factorizations;
    if (solver_version_ != system().pattern_version()) {
      solver_.reset();  // a system whose pattern varies handed a new one
      solver_version_ = system().pattern_version();
    }
    if (!solver_.factorize(lhs_, MatrixKind::kPositiveDefinite)) {
      return StepResult::failure(name() + ": closing half-kick matrix: " + solver_.error());
    }
    ++mutable_stats().linear_solves;
    if (!solver_.solve(rhs_, v_)) {
      return StepResult::failure(name() + ": closing half-kick solve gave a non-finite velocity");
    }
  }
  a_ = (f0_ + dfdv_ * v_).cwiseQuotient(m);
  return StepResult::success();
}

StepResult VelocityVerlet::nonlinear_closing_kick(double t, double h, const Vector& v_half) {
  const Vector& m = system().mass();
  // r(v) = M (v - v_half) - h/2 F(t, x', v); returns ||r||.
  auto residual = [&](const Vector& v, Vector& f, Vector& r) {
    eval_force(t, x_, v, f);
    r = m.cwiseProduct(v - v_half) - 0.5 * h * f;
    return r.norm();
  };
  v_ = v_half;
  double r_norm = residual(v_, f0_, rhs_);
  for (int iteration = 0; iteration < options().max_newton; ++iteration) {
    eval_jacobians(t, x_, v_, nullptr, &dfdv_);
    lhs_ = -0.5 * h * dfdv_;
    lhs_.diagonal() += m;
    ++mutable_stats().newton_iterations;
    ++mutable_stats().factorizations;
    if (solver_version_ != system().pattern_version()) {
      solver_.reset();  // a system whose pattern varies handed a new one
      solver_version_ = system().pattern_version();
    }
    if (!solver_.factorize(lhs_, MatrixKind::kPositiveDefinite)) {
      return StepResult::failure(name() + ": closing half-kick matrix: " + solver_.error());
    }
    ++mutable_stats().linear_solves;
    if (!solver_.solve(-rhs_, dv_) || !dv_.allFinite()) {
      return StepResult::failure(name() + ": closing half-kick solve gave a non-finite velocity");
    }
    // Backtracking on ||r||: friction's smoothing makes r only C^1, and a
    // full Newton update can overshoot the kink at |v_t| = eps_v and cycle.
    // The update descends ||r||^2 (J is r's exact Jacobian), so some
    // fraction of it lowers ||r||.
    double alpha = 1.0, r_try = 0.0;
    for (int halving = 0; halving < 40; ++halving, alpha *= 0.5) {
      v_try_ = v_ + alpha * dv_;
      r_try = residual(v_try_, f_try_, r_try_);
      if (r_try < r_norm) break;
    }
    const double update = alpha * dv_.lpNorm<Eigen::Infinity>();
    if (!(r_try < r_norm) && update > options().newton_tol) break;  // no descent left
    v_.swap(v_try_);
    f0_.swap(f_try_);
    rhs_.swap(r_try_);
    r_norm = r_try;
    if (update <= options().newton_tol) {
      a_ = f0_.cwiseQuotient(m);
      return StepResult::success();
    }
  }
  return StepResult::failure(name() + ": the closing half-kick's Newton did not converge in " +
                             std::to_string(options().max_newton) +
                             " iterations; try a smaller --dt or a larger --max-newton");
}

SPRINGLAB_INTEGRATOR(VelocityVerlet, verlet_integrator)

}  // namespace springlab
