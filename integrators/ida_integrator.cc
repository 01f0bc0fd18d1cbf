#include "integrators/ida_integrator.h"

#include <ida/ida.h>
#include <ida/ida_ls.h>

namespace springlab {

using sundials::check;
using sundials::check_created;

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
                                            "73.4 deg; orders 1-2 (--max-order 2): L-stable"}) {}

void IdaIntegrator::create() {
  const IntegratorOptions& o = options();
  // Consistent y'(0): x' = v, v' = M^-1 F.
  yp_ = sundials::make_vector(2 * n(), context_.get());
  if (evaluate_rhs(ForcePart::kAll, true, t_, y_.get(), yp_.get()) != 0) {
    throw sundials::Failure("the initial forces are not finite");
  }
  memory_ = sundials::SolverMemory(check_created(IDACreate(context_.get()), "IDACreate"), IDAFree);
  void* mem = memory_.get();
  check(IDASetErrHandlerFn(mem, sundials::ErrorLog::handler, &log_), "IDASetErrHandlerFn");
  check(IDAInit(mem, residual, t_, y_.get(), yp_.get()), "IDAInit", log_.last);
  check(IDASStolerances(mem, o.rtol, o.atol), "IDASStolerances", log_.last);
  check(IDASetUserData(mem, this), "IDASetUserData");
  check(IDASetMaxNumSteps(mem, o.max_steps), "IDASetMaxNumSteps", log_.last);
  if (o.max_order > 0) check(IDASetMaxOrd(mem, o.max_order), "IDASetMaxOrd", log_.last);
  if (o.stald) throw sundials::Failure("--stald applies to cvode-bdf only");

  const LinearSolverKind kind = linear_solver_kind();
  create_linear_solver(kind);
  check(IDASetLinearSolver(mem, linear_solver_.get(), matrix_.get()), "IDASetLinearSolver",
        log_.last);
  if (o.dq_jacobian) return;
  if (kind == LinearSolverKind::kGmres) {
    check(IDASetJacTimes(mem, jtimes_setup, jtimes), "IDASetJacTimes", log_.last);
  } else {
    check(IDASetJacFn(mem, jacobian), "IDASetJacFn", log_.last);
  }
}

int IdaIntegrator::solve(double t_out, double& t_reached) {
  realtype t = t_;
  // Every output time is reached by a step of the solver (a stop time), not
  // by interpolating past it: ARKODE's interpolant in particular can be far
  // less accurate than the tolerance.
  if (const int stop = IDASetStopTime(memory_.get(), t_out); stop < 0) return stop;
  const int flag = IDASolve(memory_.get(), t_out, &t, y_.get(), yp_.get(), IDA_NORMAL);
  t_reached = t;
  return flag;
}

void IdaIntegrator::read_counters(IntegratorStats& s) const {
  void* mem = memory_.get();
  long value = 0;
  if (IDAGetNumSteps(mem, &value) == IDA_SUCCESS) s.steps = value;
  if (IDAGetNumErrTestFails(mem, &value) == IDA_SUCCESS) s.rejected_steps = value;
  if (IDAGetNumNonlinSolvIters(mem, &value) == IDA_SUCCESS) s.newton_iterations = value;
  if (IDAGetNumNonlinSolvConvFails(mem, &value) == IDA_SUCCESS) s.nonlinear_failures = value;
  s.linear_solves = s.newton_iterations;
  if (IDAGetNumLinSolvSetups(mem, &value) == IDA_SUCCESS) s.factorizations = value;
  if (options().dq_jacobian && IDAGetNumJacEvals(mem, &value) == IDA_SUCCESS) {
    const_cast<IdaIntegrator*>(this)->difference_quotient_jacobians_ = value;
  }
}

int IdaIntegrator::residual(double t, N_Vector y, N_Vector yp, N_Vector r, void* self) {
  auto* me = static_cast<IdaIntegrator*>(self);
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
  me->jacobian_->fill_dae(me->dfdx_, me->dfdv_, cj, G);
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

}  // namespace springlab
