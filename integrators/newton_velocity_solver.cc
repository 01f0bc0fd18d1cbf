#include "integrators/newton_velocity_solver.h"

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
  return StepResult::success();
}

StepResult ImplicitIntegrator::solve_velocity(double h, const VelocityImplicitScheme& s,
                                              Vector& v) {
  auto fail = [&](const std::string& why) {
    ++mutable_stats().nonlinear_failures;
    std::ostringstream message;
    message << name() << ": Newton failed at t = " << t_ << " (h = " << h << "): " << why;
    return StepResult::failure(message.str());
  };
  const double tol = options().newton_tol;
  v = v_;
  residual(h, s, v, r_);
  for (int iteration = 0;; ++iteration) {
    const double size = converged_norm(r_);
    if (!std::isfinite(size)) return fail("the residual is not finite");
    if (size <= tol * std::max(1.0, v.lpNorm<Eigen::Infinity>())) return StepResult::success();
    if (iteration == options().max_newton) {
      std::ostringstream why;
      why << "no convergence in " << options().max_newton << " iterations (||M^-1 r|| = " << size
          << ", tolerance " << tol << ")";
      return fail(why.str());
    }

    std::string error;
    xs_ = x_ + h * (s.a * v_ + s.b * v);
    vs_ = (1.0 - s.c) * v_ + s.c * v;
    if (!factorize_newton_matrix(t_ + s.t_eval_offset * h, xs_, vs_, h, s.c, s.b, error)) {
      return fail("Newton matrix is singular (" + error + ")");
    }
    ++mutable_stats().newton_iterations;
    if (!solve_newton_system(-r_, dv_)) return fail("the Newton update is not finite");
    // A full step below the tolerance means v is as exact as the residual's
    // round-off (about h k eps |x| / m) allows to tell: take it and stop.
    if (dv_.lpNorm<Eigen::Infinity>() <= tol * std::max(1.0, v.lpNorm<Eigen::Infinity>())) {
      v += dv_;
      return StepResult::success();
    }

    // Backtracking line search on ||r||_2.
    const double r_norm = r_.norm();
    double alpha = 1.0;
    for (;;) {
      v_try_ = v + alpha * dv_;
      residual(h, s, v_try_, r_try_);
      const double r_try_norm = r_try_.norm();
      if (std::isfinite(r_try_norm) && r_try_norm <= (1.0 - 1e-4 * alpha) * r_norm) break;
      alpha *= 0.5;
      if (alpha < 1.0 / 1024.0) {
        return fail("the line search could not reduce the residual");
      }
    }
    v.swap(v_try_);
    r_.swap(r_try_);
  }
}

}  // namespace springlab
