#include "integrators/sundials/arkode_ark.h"

#include <arkode/arkode_arkstep.h>

#include "integrators/core/integrator_entry.h"

namespace springlab {

using sundials::check;
using sundials::check_created;

const SundialsCalls& ArkodeArk::calls() {
  static const SundialsCalls calls = {
      .prefix = "ARKStep",
      .evolve_call = "ARKStepEvolve",
      .order_call = "SetOrder",
      .set_error_handler = ARKStepSetErrHandlerFn,
      .set_tolerances = ARKStepSStolerances,
      .set_user_data = ARKStepSetUserData,
      .set_max_steps = ARKStepSetMaxNumSteps,
      .set_order = ARKStepSetOrder,
      .set_stop_time = ARKStepSetStopTime,
      .evolve = [](void* mem, double t_out, N_Vector y, N_Vector, double* t) {
        return ARKStepEvolve(mem, t_out, y, t, ARK_NORMAL);
      },
      .set_linear_solver = ARKStepSetLinearSolver,
      .get_steps = ARKStepGetNumSteps,
      .get_error_test_fails = ARKStepGetNumErrTestFails,
      .get_nonlinear_iterations = ARKStepGetNumNonlinSolvIters,
      .get_nonlinear_failures = ARKStepGetNumNonlinSolvConvFails,
      .get_linear_setups = ARKStepGetNumLinSolvSetups,
      .get_jacobian_evals = ARKStepGetNumJacEvals};
  return calls;
}

ArkodeArk::ArkodeArk(bool imex, IntegratorInfo info, SundialsMethod method)
    : SundialsIntegrator(std::move(info), calls(), std::move(method)), imex_(imex) {}

ArkodeDirk::ArkodeDirk()
    : ArkodeArk(false,
                {.name = "arkode-dirk",
                 .scheme = "ARKODE diagonally implicit Runge-Kutta, Newton per stage",
                 .order = 4,
                 .adaptive = true,
                 .implicit = true,
                 .iterates_to_tolerance = true,
                 // Hairer & Wanner's SDIRK 5-stage order 4 (ARKODE_SDIRK_5_3_4).
                 .stability = StabilityKind::kL,
                 .stability_limit = kInfinity,
                 .stability_note = "at the default order 4"},
                {.orders = {2, 3, 4, 5},
                 .order_meaning = "the order of ARKODE's default DIRK table",
                 .newton_matrix = true}) {}

ArkodeImex::ArkodeImex()
    : ArkodeArk(true,
                {.name = "arkode-imex",
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
                                   "wind is explicit"},
                {.orders = {3, 4, 5},
                 .order_meaning = "the order of ARKODE's default IMEX table pair",
                 .newton_matrix = true}) {}

int ArkodeArk::explicit_rhs(double t, N_Vector y, N_Vector ydot, void* self) {
  return static_cast<ArkodeArk*>(self)->evaluate_rhs(ForcePart::kNonstiff, false, t, y, ydot);
}

void ArkodeArk::create() {
  implicit_part_ = imex_ ? ForcePart::kStiff : ForcePart::kAll;
  adopt(check_created(ARKStepCreate(imex_ ? explicit_rhs : nullptr, ode_rhs, t_, y_.get(),
                                    context_.get()),
                      "ARKStepCreate"),
        ARKStepFree);
}

void ArkodeArk::attach_jacobian(bool matrix_free) {
  if (matrix_free) {
    check(ARKStepSetJacTimes(memory(), ode_jtimes_setup, ode_jtimes), "ARKStepSetJacTimes",
          log_.last);
  } else {
    check(ARKStepSetJacFn(memory(), ode_jacobian), "ARKStepSetJacFn", log_.last);
  }
}

SPRINGLAB_INTEGRATOR(ArkodeDirk, arkode_dirk_integrator)

SPRINGLAB_INTEGRATOR(ArkodeImex, arkode_imex_integrator)

}  // namespace springlab
