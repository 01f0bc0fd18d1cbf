// Newton-Raphson as the textbook has it (Nocedal and Wright, "Numerical
// Optimization", 2006, Algorithm 3.2 with a line search; Kelley, "Solving
// Nonlinear Equations with Newton's Method", 2003, for the inexact linear
// solves), on a NewtonProblem (newton_problem.h): at each iterate v
//
//   1. the residual r(v) and the matrix J(v)       (the problem)
//   2. the update dv ~ -J^-1 r                      (NewtonLinearSolver)
//   3. stop when dv is below the tolerance           (below)
//   4. a step v + alpha dv the merit accepts         (LineSearch)
//
// with the matrix (exact or definite), the merit (the potential or ||r||)
// and what to do when an update fails chosen by a NewtonPolicy
// (newton_policy.h). Used by every hand-written implicit method for its step
// (velocity_implicit_method.h) on the step's equations (velocity_step.h).
//
// The linear solve is inexact: CG stops once its estimated error is below
// eta ||dv||_inf, eta = min(0.1, ||r|| / ||r_0||) (tighter as Newton
// converges), or below 0.1 x the Newton tolerance; where a true Newton
// update is wanted (the policy's "careful" mode) eta = 1e-3.
//
// A rank-one term u z^T of the matrix (the discrete gradient's) is solved
// by Sherman and Morrison: (J + u z^T)^-1 b = d - (z.d / (1 + z.q)) q with
// d = J^-1 b, q = J^-1 u, while 1 + z.q stays above 1/2 (near 0 the term
// makes the matrix nearly singular: the matrix without it gives the better
// direction), and, where the merit is a potential, only if the update still
// descends it.
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
// (benchmarks/README.md, BM_NewtonAccuracy). Where states are forbidden
// (barriers), an update below the tolerance that would close a gap is
// searched like any other. Along a direction of negative curvature the
// search first tries longer steps (line_search.h).
//
// At most --max-newton iterations, and 3 x as many updates (retries from
// the same iterate included), so no cycle of fallbacks runs on; a failure
// is a message naming the last update, the tolerance and what to try.
#pragma once

#include <string>

#include "integrators/newton/line_search.h"
#include "integrators/newton/newton_linear_solver.h"
#include "integrators/newton/newton_policy.h"

namespace springlab {

class NewtonLoop {
 public:
  struct Settings {
    double tol = 1e-4;   // m/s
    int max_iterations = 200;
    // Where the iteration starts instead of problem.start() (a second
    // attempt from another state); nullptr: problem.start().
    const Vector* start = nullptr;
  };
  // Which step, for a failure's message: "Newton failed at t = T (h = H):
  // why" (the method puts its name in front, once).
  struct Context {
    double t, h;
  };
  // The strategies the loop is given.
  struct Pieces {
    NewtonPolicy& policy;        // the matrix and the fallbacks
    NewtonLinearSolver& linear;  // the update
    LineSearch& search;          // the step along it
  };
  // Solves problem's r(v) = 0 from problem.start() (or settings.start); v holds the solution on
  // success. Counts Newton iterations in `stats`.
  StepResult solve(NewtonProblem& problem, const Pieces& pieces, const Settings& settings,
                   const Context& context, IntegratorStats& stats, Vector& v);

 private:
  void start(NewtonProblem& problem, Vector& v);
  // Where the start's forces are defined but its state is not allowed (the
  // step's end past a barrier's gap, NewtonProblem::allowed): a start
  // between a state the last step accepted and it, as near it as allowed.
  void allowed_start(NewtonProblem& problem, Vector& v);
  // dv (and, with a rank-one term, q) at v in the mode: false, with `error`.
  bool compute_update(NewtonProblem& problem, NewtonLinearSolver& linear, const Vector& v,
                      std::string& error);
  // The convergence test: whether the update ends the iteration (or,
  // along negative curvature, a longer step was accepted: `escaping`).
  bool converged(NewtonProblem& problem, const LineSearch::Line& line, double& alpha,
                 bool& escaping);
  std::string no_convergence_text() const;

  Settings settings_;
  NewtonMode mode_;
  NewtonLinearSolver::Result solved_;
  LineSearch* search_ = nullptr;
  Vector r_, rhs_, dv_, q_;
  double phi_ = 0.0, magnitude_ = 0.0, r_start_ = 0.0;
  double previous_update_ = 0.0;  // ||dv||_inf of the last full update
  double rate_ = 0.0;             // its ratio to the one before (0: not known)
  // What the convergence test made of the last update: the update, the
  // error it estimates to remain, the rate that estimate used, and why an
  // update below the tolerance was not taken.
  double last_update_ = 0.0, last_remaining_ = 0.0, last_rate_ = 0.0;
  std::string last_why_;
};

}  // namespace springlab
