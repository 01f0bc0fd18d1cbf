#include "integrators/cvode_integrator.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

namespace springlab {

using sundials::check;
using sundials::check_created;

CvodeIntegrator::CvodeIntegrator(int multistep_method, IntegratorInfo info)
    : SundialsIntegrator(std::move(info)), multistep_method_(multistep_method) {}

CvodeBdf::CvodeBdf()
    : CvodeIntegrator(CV_BDF, {.name = "cvode-bdf",
                               .scheme = "CVODE BDF orders 1-5, Newton with the analytic Jacobian",
                               .order = 5,
                               .adaptive = true,
                               .implicit = true,
                               .iterates_to_tolerance = true,
                               // BDF5's wedge (Hairer & Wanner II, Table V.2.3)
                               .stability = StabilityKind::kAAlpha,
                               .stability_alpha = 51.84,
                               .stability_note = "at the default --max-order 5; orders 3, 4: "
                                                 "86.0, 73.4 deg; orders 1-2 "
                                                 "(--max-order 2): L-stable"}) {}

CvodeAdams::CvodeAdams()
    : CvodeIntegrator(CV_ADAMS,
                      {.name = "cvode-adams",
                       .scheme = "CVODE Adams-Moulton orders 1-12, fixed-point iteration",
                       .order = 12,
                       .adaptive = true,
                       // Fixed-point iteration converges only for h |lambda| below about 1.
                       .stability = StabilityKind::kConditional,
                       .stability_note = "fixed-point iteration: the step control keeps "
                                         "h |lambda| of the fastest mode near 1"}) {}

void CvodeIntegrator::create() {
  const IntegratorOptions& o = options();
  memory_ = sundials::SolverMemory(
      check_created(CVodeCreate(multistep_method_, context_.get()), "CVodeCreate"), CVodeFree);
  void* mem = memory_.get();
  check(CVodeSetErrHandlerFn(mem, sundials::ErrorLog::handler, &log_), "CVodeSetErrHandlerFn");
  check(CVodeInit(mem, ode_rhs, t_, y_.get()), "CVodeInit", log_.last);
  check(CVodeSStolerances(mem, o.rtol, o.atol), "CVodeSStolerances", log_.last);
  check(CVodeSetUserData(mem, this), "CVodeSetUserData");
  check(CVodeSetMaxNumSteps(mem, o.max_steps), "CVodeSetMaxNumSteps", log_.last);
  if (o.max_order > 0) check(CVodeSetMaxOrd(mem, o.max_order), "CVodeSetMaxOrd", log_.last);
  if (o.stald) {
    if (multistep_method_ != CV_BDF) throw sundials::Failure("--stald applies to cvode-bdf only");
    check(CVodeSetStabLimDet(mem, SUNTRUE), "CVodeSetStabLimDet", log_.last);
  }

  if (multistep_method_ == CV_ADAMS) {
    nonlinear_solver_.reset(check_created(SUNNonlinSol_FixedPoint(y_.get(), 0, context_.get()),
                                          "SUNNonlinSol_FixedPoint"));
    check(CVodeSetNonlinearSolver(mem, nonlinear_solver_.get()), "CVodeSetNonlinearSolver",
          log_.last);
    return;
  }
  const LinearSolverKind kind = linear_solver_kind();
  create_linear_solver(kind);
  check(CVodeSetLinearSolver(mem, linear_solver_.get(), matrix_.get()), "CVodeSetLinearSolver",
        log_.last);
  if (o.dq_jacobian) return;  // CVODE's difference quotients (dense) or J v (GMRES)
  if (kind == LinearSolverKind::kGmres) {
    check(CVodeSetJacTimes(mem, ode_jtimes_setup, ode_jtimes), "CVodeSetJacTimes", log_.last);
  } else {
    check(CVodeSetJacFn(mem, ode_jacobian), "CVodeSetJacFn", log_.last);
  }
}

int CvodeIntegrator::solve(double t_out, double& t_reached) {
  realtype t = t_;
  // Every output time is reached by a step of the solver (a stop time), not
  // by interpolating past it: ARKODE's interpolant in particular can be far
  // less accurate than the tolerance.
  if (const int stop = CVodeSetStopTime(memory_.get(), t_out); stop < 0) return stop;
  const int flag = CVode(memory_.get(), t_out, y_.get(), &t, CV_NORMAL);
  t_reached = t;
  return flag;
}

void CvodeIntegrator::read_counters(IntegratorStats& s) const {
  void* mem = memory_.get();
  long value = 0;
  if (CVodeGetNumSteps(mem, &value) == CV_SUCCESS) s.steps = value;
  if (CVodeGetNumErrTestFails(mem, &value) == CV_SUCCESS) s.rejected_steps = value;
  if (CVodeGetNumNonlinSolvIters(mem, &value) == CV_SUCCESS) s.newton_iterations = value;
  if (CVodeGetNumNonlinSolvConvFails(mem, &value) == CV_SUCCESS) s.nonlinear_failures = value;
  if (multistep_method_ == CV_BDF) {
    s.linear_solves = s.newton_iterations;  // one linear solve per Newton iteration
    if (CVodeGetNumLinSolvSetups(mem, &value) == CV_SUCCESS) s.factorizations = value;
    if (options().dq_jacobian && CVodeGetNumJacEvals(mem, &value) == CV_SUCCESS) {
      const_cast<CvodeIntegrator*>(this)->difference_quotient_jacobians_ = value;
    }
  }
}

}  // namespace springlab
