#include "integrators/sundials/ida_integrator.h"

#include <ida/ida.h>
#include <ida/ida_ls.h>

#include "integrators/core/integrator_entry.h"

namespace springlab {

using sundials::check;
using sundials::check_created;

const SundialsCalls& IdaIntegrator::calls() {
  static const SundialsCalls calls = {
      .prefix = "IDA",
      .evolve_call = "IDASolve",
      .order_call = "SetMaxOrd",
      .set_error_handler = IDASetErrHandlerFn,
      .set_tolerances = IDASStolerances,
      .set_user_data = IDASetUserData,
      .set_max_steps = IDASetMaxNumSteps,
      .set_order = IDASetMaxOrd,
      .set_stop_time = IDASetStopTime,
      .evolve = [](void* mem, double t_out, N_Vector y, N_Vector yp, double* t) {
        return IDASolve(mem, t_out, t, y, yp, IDA_NORMAL);
      },
      .set_linear_solver = IDASetLinearSolver,
      .get_steps = IDAGetNumSteps,
      .get_error_test_fails = IDAGetNumErrTestFails,
      .get_nonlinear_iterations = IDAGetNumNonlinSolvIters,
      .get_nonlinear_failures = IDAGetNumNonlinSolvConvFails,
      .get_linear_setups = IDAGetNumLinSolvSetups,
      .get_jacobian_evals = IDAGetNumJacEvals};
  return calls;
}

IdaIntegrator::IdaIntegrator()
    : SundialsIntegrator({.name = "ida",
                          .scheme = "IDA BDF orders 1-5 on x' - v = 0, M v' - F(t, x, v) = 0",
                          .order = 5,
                          .adaptive = true,
                          .implicit = true,
                          .iterates_to_tolerance = true,
                          // BDF5's wedge (Hairer & Wanner II, Table V.2.3)
                          .stability = StabilityKind::kAAlpha,
                          .stability_alpha = 51.84,
                          .stability_note = "at the default --max-order 5; orders 3, 4: 86.0, "
                                            "73.4 deg; orders 1-2 (--max-order 2): L-stable"},
                         calls(),
                         {.orders = {1, 2, 3, 4, 5},
                          .order_meaning = "its highest BDF order",
                          .newton_matrix = true}) {}

void IdaIntegrator::create() {
  // Consistent y'(0): x' = v, v' = M^-1 F.
  yp_ = sundials::make_vector(2 * n(), context_.get());
  if (evaluate_rhs(ForcePart::kAll, true, t_, y_.get(), yp_.get()) != 0) {
    throw sundials::Failure("the initial forces are not finite");
  }
  adopt(check_created(IDACreate(context_.get()), "IDACreate"), IDAFree);
  check(IDAInit(memory(), residual, t_, y_.get(), yp_.get()), "IDAInit", log_.last);
}

void IdaIntegrator::attach_jacobian(bool matrix_free) {
  if (matrix_free) {
    check(IDASetJacTimes(memory(), jtimes_setup, jtimes), "IDASetJacTimes", log_.last);
  } else {
    check(IDASetJacFn(memory(), jacobian), "IDASetJacFn", log_.last);
  }
}

int IdaIntegrator::residual(double t, N_Vector y, N_Vector yp, N_Vector r, void* self) {
  auto* me = static_cast<IdaIntegrator*>(self);
  if (me->stop_requested()) return -1;  // unrecoverable: IDASolve returns at once
  const Eigen::Index n = me->n();
  const auto in = sundials::view(y);
  const auto rate = sundials::view(yp);
  auto out = sundials::view(r);
  const Vector x = in.head(n), v = in.tail(n);
  ++me->mutable_stats().force_evals;
  me->system().force(t, x, v, me->force_);
  out.head(n) = rate.head(n) - v;
  out.tail(n) = me->system().mass().cwiseProduct(rate.tail(n)) - me->force_;
  return out.allFinite() ? 0 : 1;  // recoverable: IDA retries a smaller step
}

int IdaIntegrator::jacobian(double t, double cj, N_Vector y, N_Vector, N_Vector, SUNMatrix G,
                            void* self, N_Vector, N_Vector, N_Vector) {
  auto* me = static_cast<IdaIntegrator*>(self);
  me->evaluate_jacobians(ForcePart::kAll, t, y);
  if (sundials::is_reduced(G)) {
    sundials::set_dae_jacobian(G, cj);  // dF/dx, dF/dv stay in dfdx_, dfdv_
  } else {
    me->jacobian_->fill_dae(me->dfdx_, me->dfdv_, cj, G);
  }
  return 0;
}

int IdaIntegrator::jtimes_setup(double t, N_Vector y, N_Vector, N_Vector, double, void* self) {
  static_cast<IdaIntegrator*>(self)->evaluate_jacobians(ForcePart::kAll, t, y);
  return 0;
}

int IdaIntegrator::jtimes(double, N_Vector, N_Vector, N_Vector, N_Vector v, N_Vector Gv,
                          double cj, void* self, N_Vector, N_Vector) {
  auto* me = static_cast<IdaIntegrator*>(self);
  me->jacobian_->dae_times(me->dfdx_, me->dfdv_, cj, N_VGetArrayPointer(v),
                           N_VGetArrayPointer(Gv));
  return 0;
}

SPRINGLAB_INTEGRATOR(IdaIntegrator, ida_integrator)

}  // namespace springlab
