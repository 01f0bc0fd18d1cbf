// The base of the hand-written implicit methods (implicit-euler,
// implicit-midpoint, discrete-gradient, linear-implicit-euler, the Newmark
// family, bdf2, tr-bdf2): each step solves the equations of a
// velocity-implicit step (velocity_step.h) for the new velocity by Newton
// (newton_loop.h), given its pieces:
//
//   the problem        VelocityStep: r(v), J(v), the incremental potential;
//                      a method may change it (newton_problem() below:
//                      the discrete gradient's correction)
//   the linear solver  NewtonLinearSolver: CG with a kept Cholesky factor,
//                      MINRES, LDL^T, LU
//   the line search    LineSearch: Armijo on the potential or ||r||, the
//                      barrier's step cap, negative curvature
//   the policy         NewtonPolicy: exact / definite matrices and the
//                      fallbacks; a method may give its own
//                      (newton_policy() below: the discrete gradient's)
//
// and, for the step as a whole, two more strategies:
//   - quasi-Newton (--solver quasi-newton, quasi_newton.h): L-BFGS on the
//     same incremental potential first; Newton where it stalls or where its
//     answer is no minimizer (below);
//   - the definite fallback: a step whose Newton fails (--max-newton
//     iterations, or a search that cannot descend) is solved again from its
//     start by projected Newton (every update from the definite matrix, a
//     descent direction of the incremental potential with a search that
//     cannot fail but to round-off). It converges linearly where Newton
//     with the exact matrix alternates with it and stalls near a buckling
//     state (cloth 96 at 1/60, t = 0.167: 200 iterations of long exact
//     updates cut to 1/64 between definite ones), at more iterations per
//     step than the exact matrix takes where it works, so it is the second
//     attempt, not the first.
//
// Where the step minimizes an incremental potential, an answer that lies
// above the potential of the step's start states (for backward Euler also
// above the start's energy) by more than the tolerance resolves is no
// solution: L-BFGS's is then not taken; Newton's is solved again from the
// kept state (x_n), and the step fails if that answer is refused too
// (incremental_potential_check.h).
//
// The plain textbook version of implicit-euler's step, which the tests
// compare this one with, is reference_backward_euler.h.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "integrators/newton/incremental_potential_check.h"
#include "integrators/core/integrator.h"
#include "integrators/newton/newton_loop.h"
#include "integrators/newton/quasi_newton.h"
#include "integrators/newton/velocity_step.h"

namespace springlab {

class VelocityImplicitMethod : public Integrator {
 public:
  bool factors_jacobian(const IntegratorOptions& options) const override {
    return options.solver != Solver::kQuasiNewton;
  }
  std::string factor_free_option(IntegratorOptions& options) const override {
    options.solver = Solver::kQuasiNewton;
    return "--solver quasi-newton (it factors a matrix of a third of the unknowns)";
  }
  std::vector<FallbackCount> fallbacks() const override;

 protected:
  using Integrator::Integrator;

  // A new run (maybe of another system): forget the symbolic analyses and
  // the kept factorization.
  StepResult do_initialize() override;

  // Solves the step of size h from (t_, x_, v_) for v; on success `v` holds
  // the solution. Counts force and Jacobian evaluations, factorizations,
  // linear solves and their iterations, Newton iterations. `quasi_newton`:
  // L-BFGS first (prepare_quasi_newton() must have succeeded), Newton where
  // it stalls.
  StepResult solve_velocity(double h, const VelocityImplicitScheme& scheme, Vector& v,
                            bool quasi_newton = false);
  // A step of h that failed (`failed`), solved again as 2, then 4, then 8
  // substeps of h / n, each `one_step(h / n)` from (t_, x_, v_) (which
  // leaves the state as it was when it fails); the first that works is
  // taken and counted (Fallback::kSubsteps, a run warning). For a method
  // that evaluates its forces short of the step's end (the midpoint rule,
  // the Newmark-alpha family: VelocityImplicitScheme::end > 1), a barrier
  // acts at that stage, and where it cannot stop a body within the step no
  // solution keeps the step's end out of contact (box-pile n=8 at 1 ms:
  // the midpoint at t = 0.088 s, generalized-alpha at 0.843 s); a shorter
  // step can. When no split works, the state (and `extra`, the method's
  // own, e.g. Newmark's a_n) is as before and `failed` stands. `restart`,
  // when given, is called before each split is tried: a method with a
  // history (bdf2) puts its own back there.
  StepResult retry_in_substeps(double h, const StepResult& failed,
                               const std::function<StepResult(double)>& one_step,
                               Vector* extra = nullptr,
                               const std::function<void()>& restart = nullptr);
  // Builds L-BFGS's initial Hessian; false when the system's stiff forces
  // are not distance constraints (finite elements).
  bool prepare_quasi_newton() { return lbfgs_.prepare(system()); }

  // One linear solve of a linearized step (linear-implicit-euler): with
  // K = dF/dx and D = dF/dv at (t, x, v) -- or their definite parts --
  //   (M - h c D - h^2 b K) dv = h (f + h K v).
  // False (with `error`) when the matrix is singular or dv not finite.
  bool solve_linearized(double t, const Vector& x, const Vector& v, const Vector& f, double h,
                        double b, double c, bool definite, Vector& dv, std::string& error);

  // The problem Newton solves for the step just begun in `step`: the step
  // itself here; a method that changes the step's equations gives its own
  // around it (the discrete gradient's correction, discrete_gradient_step.h).
  // The answer to another problem is not judged by the step's incremental
  // potential (incremental_potential_check.h): its r is no gradient of it.
  virtual NewtonProblem& newton_problem(VelocityStep& step) { return step; }
  // The Newton policy of this method's steps (newton_policy.h): the plain
  // one here; a method whose residual is no gradient gives its own (the
  // discrete gradient's two phases, discrete_gradient_step.h).
  virtual std::unique_ptr<NewtonPolicy> newton_policy(NewtonPolicy::Matrices matrices,
                                                      bool symmetric) {
    return std::make_unique<NewtonPolicy>(matrices, symmetric);
  }

 private:
  // Newton on the step begun in step_, with the given matrices.
  // From `start` (nullptr: v_n).
  StepResult newton(NewtonPolicy::Matrices matrices, const Vector* start, Vector& v);
  // newton(), failed where its answer raises the step's incremental
  // potential (incremental_potential_check.h): `refused` then holds why.
  StepResult checked_newton(NewtonPolicy::Matrices matrices, const Vector* start, Vector& v,
                            std::string& refused);
  // L-BFGS's answer, taken unless it raises the potential (see the .cc).
  StepResult quasi_newton(Vector& v, std::string& rejected);

  CountedModel model_;
  NewtonMatrix matrix_;
  NewtonLinearSolver linear_;
  LineSearch search_;
  VelocityStep step_;
  NewtonProblem* problem_ = &step_;  // newton_problem() of the step begun
  NewtonLoop newton_;
  Lbfgs lbfgs_;
  IncrementalPotentialCheck check_;
  Vector rhs_, r_end_;
  Vector x_part_, v_part_, extra_part_;  // the state before a step in substeps
  long substep_steps_ = 0;               // steps solved in substeps (this run)
};

}  // namespace springlab
