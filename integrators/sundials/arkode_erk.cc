#include "integrators/sundials/arkode_erk.h"

#include <arkode/arkode_erkstep.h>

#include <cmath>

#include "integrators/core/integrator_entry.h"

namespace springlab {

using sundials::check_created;

const SundialsCalls& ArkodeErk::calls() {
  static const SundialsCalls calls = {
      .prefix = "ERKStep",
      .evolve_call = "ERKStepEvolve",
      .order_call = "SetOrder",
      .set_error_handler = ERKStepSetErrHandlerFn,
      .set_tolerances = ERKStepSStolerances,
      .set_user_data = ERKStepSetUserData,
      .set_max_steps = ERKStepSetMaxNumSteps,
      .set_order = ERKStepSetOrder,
      .set_stop_time = ERKStepSetStopTime,
      .evolve = [](void* mem, double t_out, N_Vector y, N_Vector, double* t) {
        return ERKStepEvolve(mem, t_out, y, t, ARK_NORMAL);
      },
      .set_linear_solver = nullptr,
      .get_steps = ERKStepGetNumSteps,
      .get_error_test_fails = ERKStepGetNumErrTestFails,
      .get_nonlinear_iterations = nullptr,
      .get_nonlinear_failures = nullptr,
      .get_linear_setups = nullptr,
      .get_jacobian_evals = nullptr};
  return calls;
}

// ARKODE has default ERK tables of orders 2-6 and 8 (7 would silently be 8).
ArkodeErk::ArkodeErk()
    : SundialsIntegrator({.name = "arkode-erk",
                          .scheme = "ARKODE explicit Runge-Kutta, embedded error estimate",
                          .order = 4,
                          .adaptive = true,
                          // The order-4 Zonneveld table's R(z) is RK4's.
                          .stability = StabilityKind::kConditional,
                          .stability_limit = 2.0 * std::sqrt(2.0),
                          .stability_note = "at the default order 4; the step control keeps "
                                            "h inside the region"},
                         calls(),
                         {.orders = {2, 3, 4, 5, 6, 8},
                          .order_meaning = "the order of ARKODE's default explicit table"}) {}

void ArkodeErk::create() {
  adopt(check_created(ERKStepCreate(ode_rhs, t_, y_.get(), context_.get()), "ERKStepCreate"),
        ERKStepFree);
}

SPRINGLAB_INTEGRATOR(ArkodeErk, arkode_erk_integrator)

}  // namespace springlab
