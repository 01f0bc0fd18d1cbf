#include "integrators/sundials/cvode_integrator.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include "integrators/core/integrator_entry.h"

namespace springlab {

using sundials::check;
using sundials::check_created;

const SundialsCalls& CvodeIntegrator::calls() {
  static const SundialsCalls calls = {
      .prefix = "CVode",
      .evolve_call = "CVode",
      .order_call = "SetMaxOrd",
      .set_error_handler = CVodeSetErrHandlerFn,
      .set_tolerances = CVodeSStolerances,
      .set_user_data = CVodeSetUserData,
      .set_max_steps = CVodeSetMaxNumSteps,
      .set_order = CVodeSetMaxOrd,
      .set_stop_time = CVodeSetStopTime,
      .evolve = [](void* mem, double t_out, N_Vector y, N_Vector, double* t) {
        return CVode(mem, t_out, y, t, CV_NORMAL);
      },
      .set_linear_solver = CVodeSetLinearSolver,
      .get_steps = CVodeGetNumSteps,
      .get_error_test_fails = CVodeGetNumErrTestFails,
      .get_nonlinear_iterations = CVodeGetNumNonlinSolvIters,
      .get_nonlinear_failures = CVodeGetNumNonlinSolvConvFails,
      .get_linear_setups = CVodeGetNumLinSolvSetups,
      .get_jacobian_evals = CVodeGetNumJacEvals};
  return calls;
}

CvodeIntegrator::CvodeIntegrator(int multistep_method, IntegratorInfo info, SundialsMethod method)
    : SundialsIntegrator(std::move(info), calls(), std::move(method)),
      multistep_method_(multistep_method) {}

CvodeBdf::CvodeBdf()
    : CvodeIntegrator(CV_BDF,
                      {.name = "cvode-bdf",
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
                                         "(--max-order 2): L-stable"},
                      {.orders = {1, 2, 3, 4, 5},
                       .order_meaning = "its highest BDF order",
                       .newton_matrix = true,
                       .stald = true}) {}

CvodeAdams::CvodeAdams()
    : CvodeIntegrator(CV_ADAMS,
                      {.name = "cvode-adams",
                       .scheme = "CVODE Adams-Moulton orders 1-12, fixed-point iteration",
                       .order = 12,
                       .adaptive = true,
                       // Fixed-point iteration converges only for h |lambda| below about 1.
                       .stability = StabilityKind::kConditional,
                       .stability_note = "fixed-point iteration: the step control keeps "
                                         "h |lambda| of the fastest mode near 1"},
                      {.orders = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12},
                       .order_meaning = "its highest Adams-Moulton order"}) {}

void CvodeIntegrator::create() {
  adopt(check_created(CVodeCreate(multistep_method_, context_.get()), "CVodeCreate"), CVodeFree);
  check(CVodeInit(memory(), ode_rhs, t_, y_.get()), "CVodeInit", log_.last);
  if (options().stald) check(CVodeSetStabLimDet(memory(), SUNTRUE), "CVodeSetStabLimDet", log_.last);
  if (multistep_method_ == CV_ADAMS) {
    nonlinear_solver_.reset(check_created(SUNNonlinSol_FixedPoint(y_.get(), 0, context_.get()),
                                          "SUNNonlinSol_FixedPoint"));
    check(CVodeSetNonlinearSolver(memory(), nonlinear_solver_.get()), "CVodeSetNonlinearSolver",
          log_.last);
  }
}

void CvodeIntegrator::attach_jacobian(bool matrix_free) {
  if (matrix_free) {
    check(CVodeSetJacTimes(memory(), ode_jtimes_setup, ode_jtimes), "CVodeSetJacTimes", log_.last);
  } else {
    check(CVodeSetJacFn(memory(), ode_jacobian), "CVodeSetJacFn", log_.last);
  }
}

SPRINGLAB_INTEGRATOR(CvodeAdams, cvode_adams_integrator)

SPRINGLAB_INTEGRATOR(CvodeBdf, cvode_bdf_integrator)

}  // namespace springlab
