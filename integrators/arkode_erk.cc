#include "integrators/arkode_erk.h"

#include <arkode/arkode_erkstep.h>

#include <cmath>

namespace springlab {

using sundials::check;
using sundials::check_created;

ArkodeErk::ArkodeErk()
    : SundialsIntegrator({.name = "arkode-erk",
                          .scheme = "ARKODE explicit Runge-Kutta, embedded error estimate",
                          .order = 4,
                          .adaptive = true,
                          // The order-4 Zonneveld table's R(z) is RK4's.
                          .stability = StabilityKind::kConditional,
                          .stability_limit = 2.0 * std::sqrt(2.0),
                          .stability_note = "at the default order 4; the step control keeps "
                                            "h inside the region"}) {}

void ArkodeErk::create() {
  const IntegratorOptions& o = options();
  if (o.stald) throw sundials::Failure("--stald applies to cvode-bdf only");
  memory_ = sundials::SolverMemory(
      check_created(ERKStepCreate(ode_rhs, t_, y_.get(), context_.get()), "ERKStepCreate"),
      ERKStepFree);
  void* mem = memory_.get();
  check(ERKStepSetErrHandlerFn(mem, sundials::ErrorLog::handler, &log_), "ERKStepSetErrHandlerFn");
  check(ERKStepSStolerances(mem, o.rtol, o.atol), "ERKStepSStolerances", log_.last);
  check(ERKStepSetUserData(mem, this), "ERKStepSetUserData");
  check(ERKStepSetMaxNumSteps(mem, o.max_steps), "ERKStepSetMaxNumSteps", log_.last);
  if (o.max_order > 0) check(ERKStepSetOrder(mem, o.max_order), "ERKStepSetOrder", log_.last);
}

int ArkodeErk::solve(double t_out, double& t_reached) {
  realtype t = t_;
  // Every output time is reached by a step of the solver (a stop time), not
  // by interpolating past it: ARKODE's interpolant in particular can be far
  // less accurate than the tolerance.
  if (const int stop = ERKStepSetStopTime(memory_.get(), t_out); stop < 0) return stop;
  const int flag = ERKStepEvolve(memory_.get(), t_out, y_.get(), &t, ARK_NORMAL);
  t_reached = t;
  return flag;
}

void ArkodeErk::read_counters(IntegratorStats& s) const {
  void* mem = memory_.get();
  long value = 0;
  if (ERKStepGetNumSteps(mem, &value) == ARK_SUCCESS) s.steps = value;
  if (ERKStepGetNumErrTestFails(mem, &value) == ARK_SUCCESS) s.rejected_steps = value;
}

}  // namespace springlab
