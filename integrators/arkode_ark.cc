#include "integrators/arkode_ark.h"

#include <arkode/arkode_arkstep.h>

namespace springlab {

using sundials::check;
using sundials::check_created;

ArkodeArk::ArkodeArk(bool imex, IntegratorInfo info)
    : SundialsIntegrator(std::move(info)), imex_(imex) {}

ArkodeDirk::ArkodeDirk()
    : ArkodeArk(false, {.name = "arkode-dirk",
                        .scheme = "ARKODE diagonally implicit Runge-Kutta, Newton per stage",
                        .order = 4,
                        .adaptive = true,
                        .implicit = true,
                        .iterates_to_tolerance = true,
                        // Hairer & Wanner's SDIRK 5-stage order 4 (ARKODE_SDIRK_5_3_4).
                        .stability = StabilityKind::kL,
                        .stability_limit = kInfinity,
                        .stability_note = "at the default order 4"}) {}

ArkodeImex::ArkodeImex()
    : ArkodeArk(true, {.name = "arkode-imex",
                       .scheme = "ARKODE IMEX Runge-Kutta: springs, damping, drag implicit; "
                                 "gravity, wind explicit",
                       .order = 4,
                       .adaptive = true,
                       .implicit = true,
                       .iterates_to_tolerance = true,
                       // ARK4(3)6L[2]SA: its implicit table is L-stable.
                       .stability = StabilityKind::kL,
                       .stability_limit = kInfinity,
                       .stability_note = "for the implicit forces at the default order 4; "
                                         "wind is explicit"}) {}

int ArkodeArk::explicit_rhs(double t, N_Vector y, N_Vector ydot, void* self) {
  return static_cast<ArkodeArk*>(self)->evaluate_rhs(ForcePart::kNonstiff, false, t, y, ydot);
}

void ArkodeArk::create() {
  const IntegratorOptions& o = options();
  if (o.stald) throw sundials::Failure("--stald applies to cvode-bdf only");
  implicit_part_ = imex_ ? ForcePart::kStiff : ForcePart::kAll;
  memory_ = sundials::SolverMemory(
      check_created(ARKStepCreate(imex_ ? explicit_rhs : nullptr, ode_rhs, t_, y_.get(),
                                  context_.get()),
                    "ARKStepCreate"),
      ARKStepFree);
  void* mem = memory_.get();
  check(ARKStepSetErrHandlerFn(mem, sundials::ErrorLog::handler, &log_), "ARKStepSetErrHandlerFn");
  check(ARKStepSStolerances(mem, o.rtol, o.atol), "ARKStepSStolerances", log_.last);
  check(ARKStepSetUserData(mem, this), "ARKStepSetUserData");
  check(ARKStepSetMaxNumSteps(mem, o.max_steps), "ARKStepSetMaxNumSteps", log_.last);
  if (o.max_order > 0) check(ARKStepSetOrder(mem, o.max_order), "ARKStepSetOrder", log_.last);

  const LinearSolverKind kind = linear_solver_kind();
  create_linear_solver(kind);
  check(ARKStepSetLinearSolver(mem, linear_solver_.get(), matrix_.get()), "ARKStepSetLinearSolver",
        log_.last);
  if (o.dq_jacobian) return;
  if (kind == LinearSolverKind::kGmres) {
    check(ARKStepSetJacTimes(mem, ode_jtimes_setup, ode_jtimes), "ARKStepSetJacTimes", log_.last);
  } else {
    check(ARKStepSetJacFn(mem, ode_jacobian), "ARKStepSetJacFn", log_.last);
  }
}

int ArkodeArk::solve(double t_out, double& t_reached) {
  realtype t = t_;
  // Every output time is reached by a step of the solver (a stop time), not
  // by interpolating past it: ARKODE's interpolant in particular can be far
  // less accurate than the tolerance.
  if (const int stop = ARKStepSetStopTime(memory_.get(), t_out); stop < 0) return stop;
  const int flag = ARKStepEvolve(memory_.get(), t_out, y_.get(), &t, ARK_NORMAL);
  t_reached = t;
  return flag;
}

void ArkodeArk::read_counters(IntegratorStats& s) const {
  void* mem = memory_.get();
  long value = 0;
  if (ARKStepGetNumSteps(mem, &value) == ARK_SUCCESS) s.steps = value;
  if (ARKStepGetNumErrTestFails(mem, &value) == ARK_SUCCESS) s.rejected_steps = value;
  if (ARKStepGetNumNonlinSolvIters(mem, &value) == ARK_SUCCESS) s.newton_iterations = value;
  if (ARKStepGetNumNonlinSolvConvFails(mem, &value) == ARK_SUCCESS) s.nonlinear_failures = value;
  s.linear_solves = s.newton_iterations;
  if (ARKStepGetNumLinSolvSetups(mem, &value) == ARK_SUCCESS) s.factorizations = value;
  if (options().dq_jacobian && ARKStepGetNumJacEvals(mem, &value) == ARK_SUCCESS) {
    const_cast<ArkodeArk*>(this)->difference_quotient_jacobians_ = value;
  }
}

}  // namespace springlab
