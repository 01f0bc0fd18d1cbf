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
// The Newton matrix is factorized rarely (a chord, or modified, Newton
// method, as CVODE and IDA do): its sparse LDL^T -- the dominant cost, ~170 ms
// for cloth n = 64 against ~6 ms for a solve with it -- is kept across
// iterations and steps while the iteration converges fast with it, and
// refactorized at the current iterate when
//   - there is none yet, or h moved by more than 20% from the h it was made
//     for (the last step of a run may be cut short to land on t_end);
//   - the contraction rate ||dv_k|| / ||dv_k-1|| reached 1/2, or would not
//     reach the tolerance within max_newton iterations: a stale matrix is
//     slowing Newton down;
//   - a full update with the stale matrix does not decrease ||r||.
// A step that ended contracting slower than 1/4 per iteration, or whose first
// update with the kept matrix was refused, has the next step start with a
// fresh matrix. Newton iterations count the updates taken; a refused one is
// a linear solve only.
// The residual is always the exact one, so the root is the same as with a
// fresh matrix; only the path to it changes.
//
// The line search. When every force derives from potentials (Mechanical-
// System::derives_from_potentials), r is the gradient of the step's
// incremental potential
//   Phi(v) = |v - v_n|^2_M / 2 + V(x*(v)) / b + (h / c) W(t*, v*(v)),
// and Newton minimizes it: an update is taken when Phi decreases by at least
// 1e-4 of its first-order prediction (Armijo; below Phi's round-off, when
// ||r|| decreases), else a fresh matrix backtracks (alpha = 1, 1/2, ...
// 1/1024). Phi is not convex where springs are compressed, and there the
// Jacobian's update may climb it: then, and for the rest of the solve once a
// line search was needed, the matrix is made of the definite part of the
// Jacobian (MechanicalSystem::definite_jacobians), whose updates always
// descend; a full update taken with it goes back to the Jacobian, which
// converges quadratically near the root. Without such a potential (spring
// damping), the merit function is ||r||^2, for which the exact Newton update
// is a descent direction whether or not J is definite -- but that search can
// stall at a local minimum of ||r||. A step that fails with kept matrices is
// solved again with a fresh matrix at every iteration (the classic
// Newton-Raphson), and a potential-path failure once more on ||r||, before
// the failure is reported.
//
// Converged when ||M^-1 r||_inf <= newton_tol * max(1, ||v||_inf) (a
// velocity, in m/s), or when the update dv just taken shows the remaining
// error below that same bound: an exact Newton update ||dv||_inf itself, a
// chord update rate / (1 - rate) ||dv||_inf with rate its observed
// contraction rate (||dv||_inf itself before a rate is observed). The
// residual of a stiff system bottoms out at round-off, h k eps |x| / m, so
// the update test is the one that ends most solves.
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

  // A new run (maybe of another system): forget the symbolic analysis and
  // the kept factorization.
  StepResult do_initialize() override;

  // Solves r(v) = 0 for v starting from v_n = v_; on success `v` holds the
  // solution. Counts force and Jacobian evaluations, factorizations, linear
  // solves and Newton iterations.
  StepResult solve_velocity(double h, const VelocityImplicitScheme& scheme, Vector& v);

  // Assembles J = M - h c dF/dv - h^2 b dF/dx at the given point and
  // factorizes it; false (with message) when it is singular.
  // With `definite`, of the definite part of the Jacobians (MechanicalSystem::
  // definite_jacobians), which makes J positive definite.
  bool factorize_newton_matrix(double t, const Vector& x, const Vector& v, double h, double c,
                               double b, std::string& error, bool definite = false);
  // dv = J^-1 rhs with the last factorization.
  bool solve_newton_system(const Vector& rhs, Vector& dv);
  // dF/dx from the last factorize_newton_matrix().
  const SparseMatrix& last_dfdx() const { return dfdx_; }

 private:
  void residual(double h, const VelocityImplicitScheme& s, const Vector& v, Vector& r);
  double converged_norm(const Vector& r) const;
  // The incremental potential at v, whose gradient is r(v) (after residual()
  // at this v), and the sum of its parts' magnitudes (its round-off scale).
  double merit(double h, const VelocityImplicitScheme& s, const Vector& v,
               double& magnitude) const;
  // One Newton solve; keep_matrix false: a fresh matrix at every iteration;
  // potential: definite matrices, line search on the incremental potential.
  StepResult newton(double h, const VelocityImplicitScheme& s, Vector& v, bool keep_matrix,
                    bool potential);
  // Factorizes the Newton matrix at iterate v of the step (x_n, v_n, h).
  bool refresh(double h, const VelocityImplicitScheme& s, const Vector& v, bool definite,
               std::string& error);

  // The kept factorization: made for step size factor_h_ and weights
  // (b, c) = (factor_b_, factor_c_); none when factor_h_ == 0.
  double factor_h_ = 0.0, factor_b_ = 0.0, factor_c_ = 0.0;
  bool factor_definite_ = false;
  bool refresh_next_step_ = false;

  SparseMatrix dfdx_, dfdv_, jacobian_;
  SparseDirectSolver solver_;
  Vector xs_, vs_, f_, r_, r_try_, dv_, v_try_;
};

}  // namespace springlab
