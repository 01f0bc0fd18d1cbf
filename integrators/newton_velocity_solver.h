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
// the implicit midpoint rule is (1/4, 1/4, 1/2) at t* = t_n + h/2; the
// discrete gradient adds Gonzalez's correction to the midpoint rule
// (discrete_gradient.h).
//
// Minimization. When every force derives from potentials (Mechanical-
// System::derives_from_potentials: springs, gravity; drag and wind through a
// dissipation potential of v), r is the gradient of the step's incremental
// potential
//   Phi(v) = |v - v_n|^2_M / 2 + V(x*(v)) / b + (h / c) W(t*, v*(v)),
// J is its Hessian, and Newton minimizes Phi (the variational form of
// implicit Euler; Kane et al. 2000, Gast et al. 2015):
//   - the update dv solves J dv = -r by conjugate gradients (CG), truncated
//     where J has negative curvature (compressed springs make it indefinite),
//     so dv always descends Phi (preconditioned_cg.h);
//   - a line search asks Phi to fall by 1e-4 of its first-order prediction
//     (Armijo; below Phi's round-off, ||r|| must fall);
//   - where the update of the exact J needed a line search, or none of its
//     steps descends, the next update uses the definite part of J (each
//     compressed spring's negative transverse stiffness dropped: Mechanical-
//     System::definite_jacobians), positive definite, whose update always
//     descends; a full update goes back to the exact J, which converges
//     quadratically near the solution. With a definite matrix the search
//     cannot fail but to round-off: Newton does not give up while a descent
//     direction exists, only after --max-newton iterations.
//   - Where the potential curves down along the update (a saddle of Phi: a
//     buckling cloth), the step's equations have solutions of lower Phi
//     nearby: the search doubles the step while Phi keeps falling, also when
//     the update is already below the tolerance. Where the step's equations
//     have several solutions, Newton thus prefers the lower potential.
// Without such a potential (spring damping depends on x and v together) the
// merit function is ||r||^2, for which the exact Newton update is a descent
// direction whatever J's inertia; J is not symmetric there and is factored
// by sparse LU at every iteration.
//
// Linear algebra. CG is preconditioned by a Cholesky factor (CHOLMOD,
// supernodal: sparse_direct_solver.h) of the definite Newton matrix, made
// at some earlier iterate and kept across iterations and steps while CG
// converges fast with it: a CG solve that needs more than kCgSoftLimit
// products has it refreshed before the next solve; one not converged after
// kCgHardLimit is redone at once with a fresh factor. On cloth 64 a
// factorization costs as much as 15-30 CG iterations (a triangular solve
// pair with the factor and a product with J each).
//
// Stopping (--newton-tol, in m/s). Converged when the update just computed
// -- an estimate of the error before it -- is below the tolerance in the max
// norm: ||dv||_inf <= newton_tol, or, while Newton converges only linearly
// at an observed rate q > 1/2 (a soft, nearly singular direction),
// q/(1-q) ||dv||_inf <= newton_tol; the update is then taken. A velocity
// tolerance scales with the problem: its round-off floor is about
// eps ||v||, independent of the cloth's size and stiffness, where the
// residual's floor (h k eps |x| / m) grows like n^2 for an n x n cloth. A
// tolerance below 1e3 eps (||v|| + ||v_n||) is met at that floor. The
// default (integrator.h) is chosen from a measurement: the solver error it
// leaves stays far below the step's own discretization error
// (benchmarks/README.md, BM_NewtonAccuracy). CG stops when its estimated
// error (the preconditioned residual) is below min(0.1, ||r||/||r_0||) of
// ||dv||, or 0.1 x the tolerance.
#pragma once

#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "integrators/preconditioned_cg.h"
#include "integrators/preconditioned_minres.h"
#include "integrators/sparse_direct_solver.h"

namespace springlab {

struct VelocityImplicitScheme {
  double t_eval_offset;  // t* = t_n + t_eval_offset * h
  double a, b, c;        // see the header comment
  // Gonzalez's discrete gradient of V in place of grad V(x*) (needs the
  // midpoint's (a, b, c) = (1/4, 1/4, 1/2), t* = t_n + h/2).
  bool discrete_gradient = false;
  // The step's end is x_{n+1} = x_n + end (x* - x_n): 1 where the forces
  // are evaluated at the end (implicit Euler), 2 at the midpoint.
  double end = 1.0;
  // The second-order and multistep methods (newmark_family.h, bdf2.h,
  // tr_bdf2.h) solve the more general
  //   r(v) = M (v - v_c) - h w F(t*, x*(v), v*(v)),
  //   x*(v) = x_n + x_o + h (a v_n + b v),
  // with a force weight w, an inertial centre v_c and a position offset x_o
  // fixed within the step (their predictors: a_n, x_{n-1}, a stage's
  // state). The incremental potential is then
  //   Phi(v) = |v - v_c|^2_M / 2 + (w / b) V(x*(v)) + (h w / c) W(t*, v*(v)),
  // and the Newton matrix J = M - h w c dF/dv - h^2 w b dF/dx.
  double weight = 1.0;               // w
  const Vector* inertia = nullptr;   // v_c; nullptr: v_n
  const Vector* x_offset = nullptr;  // x_o; nullptr: zero
};

class ImplicitIntegrator : public Integrator {
 protected:
  using Integrator::Integrator;

  // A new run (maybe of another system): forget the symbolic analyses and
  // the kept factorization.
  StepResult do_initialize() override;

  // Solves r(v) = 0 for v starting from v_n = v_; on success `v` holds the
  // solution. Counts force and Jacobian evaluations, factorizations, linear
  // solves and their iterations, Newton iterations. `quasi_newton`: L-BFGS
  // first (quasi_newton.cc; prepare_quasi_newton() must have succeeded),
  // Newton where it stalls.
  StepResult solve_velocity(double h, const VelocityImplicitScheme& scheme, Vector& v,
                            bool quasi_newton = false);
  // Builds L-BFGS's initial Hessian; false when the system's stiff forces
  // are not distance constraints (finite elements).
  bool prepare_quasi_newton();

  // One linear solve of a linearized step (linear-implicit-euler): with
  // K = dF/dx and D = dF/dv at (t, x, v) -- or their definite parts --
  //   (M - h c D - h^2 b K) dv = h (f + h K v_rhs).
  // False (with `error`) when the matrix is singular or dv not finite.
  bool solve_linearized(double t, const Vector& x, const Vector& v, const Vector& f, double h,
                        double b, double c, bool definite, Vector& dv, std::string& error);

 private:
  // r(v) of the step (x_n, v_n) = (x_, v_), and the merit function at v.
  void residual(double h, const VelocityImplicitScheme& s, const Vector& v, Vector& r);
  // The incremental potential at v (after residual() at this v), and the sum
  // of its parts' magnitudes (its round-off scale).
  double potential(double h, const VelocityImplicitScheme& s, const Vector& v,
                   double& magnitude) const;
  StepResult newton(double h, const VelocityImplicitScheme& s, Vector& v);
  // --solver quasi-newton (quasi_newton.cc): L-BFGS on the same potential;
  // false when it stalls (then Newton solves the step).
  bool quasi_newton(double h, const VelocityImplicitScheme& s, Vector& v);

  // Sets xs_ = x*(v), vs_ = v*(v) of the step.
  void stage(double h, const VelocityImplicitScheme& s, const Vector& v);
  // Assembles out = M - h c D - h^2 b K at (t, x, v), of the exact or the
  // definite Jacobians; K stays in dfdx_.
  void assemble(double t, const Vector& x, const Vector& v, double h, double b, double c,
                bool definite, SparseMatrix& out);
  // Makes the kept preconditioner the Cholesky factor of the definite Newton
  // matrix at (t, x, v) (jacobian_ itself when it is that matrix). False,
  // with `error`, when that matrix is singular.
  bool refresh_preconditioner(double t, const Vector& x, const Vector& v, double h, double b,
                              double c, bool jacobian_is_definite, std::string& error);
  // d ~ jacobian_^-1 rhs: PCG preconditioned by the kept factor (refreshed
  // at (t, x, v) when it converges too slowly), or a direct factorization of
  // jacobian_ when it is not symmetric. `truncate`: stop CG at negative
  // curvature (Newton on a potential); else a direct LDL^T solves what CG
  // cannot. `exact`: jacobian_ holds the exact Jacobians.
  struct LinearSolve {
    bool ok = true;
    bool negative_curvature = false;
    bool converged = false;
  };
  LinearSolve solve_linear(double t, const Vector& x, const Vector& v, double h, double b,
                           double c, bool definite, const Vector& rhs, double rtol,
                           double atol, bool truncate, Vector& d, std::string& error,
                           int max_iterations = kCgHardLimit);
  // See newton_velocity_solver.cc.
  static constexpr int kCgSoftLimit = 10;
  static constexpr int kCgHardLimit = 30;

  // The kept factor at a step's start (see newton_velocity_solver.cc).
  struct StepStart {
    bool probe = false;
    long factorizations = 0;
  };
  StepStart begin_step();
  void end_first_solve(const StepStart& start);

  SparseMatrix dfdx_, dfdv_, jacobian_, preconditioner_matrix_;
  SparseDirectSolver direct_;          // factorizations of jacobian_ itself
  SparseDirectSolver preconditioner_;  // the kept Cholesky factor
  // Which pattern (MechanicalSystem::pattern_version) each matrix holds and
  // each solver analysed (-1: none yet): a system whose pattern varies
  // (fluids) may hand a new one at any evaluation; a solver given a matrix
  // of another pattern forgets its analysis first. With one pattern
  // (springs, elements) these stay equal after the first matrix.
  long jacobian_version_ = -1, preconditioner_matrix_version_ = -1;
  long direct_version_ = -1, preconditioner_version_ = -1;
  // factorize() of `solver` for a matrix of pattern `version`.
  static bool factorize_on(SparseDirectSolver& solver, long& analysed, long version,
                           const SparseMatrix& a, MatrixKind kind);
  bool preconditioner_valid_ = false;
  // Linearized steps (one solve each) left to start with a fresh factor.
  int fresh_steps_ = 0;
  bool direct_current_ = false;  // direct_ holds a factorization of jacobian_ as it is
  int cg_slow_ = 0;  // the last CG solve needed more than the soft limit
  CgScratch cg_;
  MinresScratch minres_;
  Vector xs_, vs_, f_, r_, r_try_, dv_, v_try_, jd_;
  // The discrete gradient's: D = y - x_n, y = x_n + D, the correction's
  // coefficient c (0: left out), F at y, the rank-one term's vectors.
  Vector delta_, y_, f_end_, z_, q_;
  double correction_ = 0.0;
  // On the potential path the coefficient is frozen for each iteration
  // (r is then the gradient of the midpoint's potential + c |D|^2).
  Vector x_end_;  // a trial's step end (has_forbidden_states)
  Vector x_cap_, dx_cap_;  // the step cap's state and step (has_forbidden_states)
  bool frozen_ = false;
  double frozen_c_ = 0.0;
  // The step's second attempt (solve_velocity): the definite matrix only.
  bool definite_only_ = false;
  double v_start_potential_ = 0.0;  // V(t*, x_n): the discrete gradient's

  // quasi_newton.cc: the particles' stiffness Laplacian L of the distance
  // constraints, the factor of M_p + h^2 L (one per step size), and the
  // L-BFGS history.
  struct QuasiNewtonState {
    int dim = 0;
    SparseMatrix laplacian;
    Vector particle_mass;
    SparseDirectSolver factor{FactorUse::kSolvedOften};
    double factored_h = 0.0;
    std::vector<Vector> s, y;  // the last updates and gradient changes
    std::vector<double> rho;   // 1 / (y . s)
    Vector q, z, v_try, r_try, v_long, r_long, d;
    Eigen::MatrixXd columns, solved;  // n x dim: one coordinate per column
  } qn_;
};

}  // namespace springlab
