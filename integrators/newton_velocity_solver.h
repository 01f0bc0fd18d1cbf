// The Newton-Raphson machinery shared by the implicit one-step methods.
//
// A velocity-implicit step solves for the new velocity v (half the unknowns
// of the full state: positions follow from v) the system
//
//   r(v) = M (v - v_n) - h F(t*, x*(v), v*(v)) = 0,
//   x*(v) = x_n + h (a v_n + b v),   v*(v) = (1 - c) v_n + c v,
//
// with Jacobian  J = dr/dv = M - h c dF/dv - h^2 b dF/dx  (sparse, on the
// model's pattern). Backward Euler is (a, b, c) = (0, 1, 1) at t* = t_n + h;
// the implicit midpoint rule is (1/4, 1/4, 1/2) at t* = t_n + h/2.
//
// Each iteration solves J dv = -r with a sparse direct factorization (the
// symbolic analysis is reused for the whole run) and then backtracks
// (alpha = 1, 1/2, ... 1/1024) until ||r|| decreases by at least 1e-4 alpha:
// the Newton direction is a descent direction for ||r||^2 whether or not J is
// definite, which it is not when springs are compressed. Converged when
// ||M^-1 r||_inf <= newton_tol * max(1, ||v||_inf) (a velocity, in m/s), or
// when a full Newton update ||dv||_inf is below that same bound (the residual
// of a stiff system bottoms out at round-off, h k eps |x| / m).
#pragma once

#include <string>

#include "integrators/integrator.h"
#include "integrators/sparse_direct_solver.h"

namespace springlab {

struct VelocityImplicitScheme {
  double t_eval_offset;  // t* = t_n + t_eval_offset * h
  double a, b, c;        // see the header comment
};

class ImplicitIntegrator : public Integrator {
 protected:
  using Integrator::Integrator;

  // A new run (maybe of another system): forget the symbolic analysis.
  StepResult do_initialize() override;

  // Solves r(v) = 0 for v starting from v_n = v_; on success `v` holds the
  // solution. Counts force and Jacobian evaluations, factorizations, linear
  // solves and Newton iterations.
  StepResult solve_velocity(double h, const VelocityImplicitScheme& scheme, Vector& v);

  // Assembles J = M - h c dF/dv - h^2 b dF/dx at the given point and
  // factorizes it; false (with message) when it is singular.
  bool factorize_newton_matrix(double t, const Vector& x, const Vector& v, double h, double c,
                               double b, std::string& error);
  // dv = J^-1 rhs with the last factorization.
  bool solve_newton_system(const Vector& rhs, Vector& dv);
  // dF/dx from the last factorize_newton_matrix().
  const SparseMatrix& last_dfdx() const { return dfdx_; }

 private:
  void residual(double h, const VelocityImplicitScheme& s, const Vector& v, Vector& r);
  double converged_norm(const Vector& r) const;

  SparseMatrix dfdx_, dfdv_, jacobian_;
  SparseDirectSolver solver_;
  Vector xs_, vs_, f_, r_, r_try_, dv_, v_try_;
};

}  // namespace springlab
