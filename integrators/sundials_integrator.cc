#include "integrators/sundials_integrator.h"

#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <sstream>

namespace springlab {

using sundials::check;
using sundials::check_created;

SundialsIntegrator::SundialsIntegrator(IntegratorInfo info) : Integrator(std::move(info)) {}

// Members are destroyed in reverse order: memory_ (which refers to the
// solvers and vectors) first, then the rest, the context last.
SundialsIntegrator::~SundialsIntegrator() { memory_.reset(); }

StepResult SundialsIntegrator::do_initialize() {
  memory_.reset();
  linear_solver_.reset();
  nonlinear_solver_.reset();
  matrix_.reset();
  y_.reset();
  log_.last.clear();
  analytic_jacobians_ = 0;
  difference_quotient_jacobians_ = 0;
  try {
    if (!context_) {
      SUNContext context = nullptr;
      check(SUNContext_Create(nullptr, &context), "SUNContext_Create");
      context_.reset(context);
    }
    y_ = sundials::make_vector(2 * n(), context_.get());
    state_to_vector(y_.get());
    create();
  } catch (const sundials::Failure& e) {
    return StepResult::failure(name() + ": " + e.what());
  }
  return StepResult::success();
}

StepResult SundialsIntegrator::do_step(double) {
  return StepResult::failure(name() + ": adaptive methods advance with advance_to()");
}

StepResult SundialsIntegrator::advance_to(double t_out) {
  if (!(t_out > t_)) return StepResult::failure(name() + ": output time must increase");
  double t_reached = t_;
  const int flag = solve(t_out, t_reached);
  vector_to_state(y_.get());
  IntegratorStats& s = mutable_stats();
  const long evals = s.force_evals;
  read_counters(s);
  s.force_evals = evals;  // counted in our callbacks, difference quotients included
  s.jacobian_evals = analytic_jacobians_ + difference_quotient_jacobians_;
  if (flag < 0) {
    t_ = t_reached;
    std::ostringstream message;
    message << name() << ": " << solve_call() << " failed at t = " << t_reached << " (flag "
            << flag << ")";
    if (!log_.last.empty()) message << ": " << log_.last;
    return StepResult::failure(message.str());
  }
  t_ = t_out;
  return StepResult::success();
}

SundialsIntegrator::LinearSolverKind SundialsIntegrator::linear_solver_kind() const {
  const std::string& choice = options().linear_solver;
  if (choice == "dense") return LinearSolverKind::kDense;
  if (choice == "klu") return LinearSolverKind::kKlu;
  if (choice == "gmres") return LinearSolverKind::kGmres;
  if (choice == "auto") return 2 * n() <= 100 ? LinearSolverKind::kDense : LinearSolverKind::kKlu;
  throw sundials::Failure("unknown --linear-solver '" + choice + "' (dense, klu, gmres, auto)");
}

const char* SundialsIntegrator::linear_solver_name(LinearSolverKind kind) const {
  switch (kind) {
    case LinearSolverKind::kNone: return "none";
    case LinearSolverKind::kDense: return "dense";
    case LinearSolverKind::kKlu: return "klu";
    case LinearSolverKind::kGmres: return "gmres";
  }
  return "?";
}

void SundialsIntegrator::create_linear_solver(LinearSolverKind kind) {
  const sunindextype size = static_cast<sunindextype>(2 * n());
  SUNContext ctx = context_.get();
  jacobian_ = std::make_unique<sundials::FirstOrderJacobian>(system());
  switch (kind) {
    case LinearSolverKind::kNone:
      return;
    case LinearSolverKind::kDense:
      matrix_.reset(check_created(SUNDenseMatrix(size, size, ctx), "SUNDenseMatrix"));
      linear_solver_.reset(
          check_created(SUNLinSol_Dense(y_.get(), matrix_.get(), ctx), "SUNLinSol_Dense"));
      return;
    case LinearSolverKind::kKlu:
      if (options().dq_jacobian) {
        throw sundials::Failure("--dq-jacobian needs --linear-solver dense or gmres: SUNDIALS "
                                "forms difference-quotient Jacobians only as dense matrices");
      }
      matrix_.reset(check_created(SUNSparseMatrix(size, size, jacobian_->nonzeros(), CSC_MAT, ctx),
                                  "SUNSparseMatrix"));
      linear_solver_.reset(
          check_created(SUNLinSol_KLU(y_.get(), matrix_.get(), ctx), "SUNLinSol_KLU"));
      // AMD, not KLU's default COLAMD: the Newton matrix has a symmetric
      // pattern, and AMD's ordering factors cloth n = 64 in 369 ms against
      // COLAMD's 747 ms (BM_LinearSolver/klu-amd vs klu).
      check(SUNLinSol_KLUSetOrdering(linear_solver_.get(), 0), "SUNLinSol_KLUSetOrdering");
      return;
    case LinearSolverKind::kGmres:
      linear_solver_.reset(
          check_created(SUNLinSol_SPGMR(y_.get(), SUN_PREC_NONE, 0, ctx), "SUNLinSol_SPGMR"));
      return;
  }
}

void SundialsIntegrator::state_to_vector(N_Vector y) const {
  auto v = sundials::view(y);
  v.head(n()) = x_;
  v.tail(n()) = v_;
}

void SundialsIntegrator::vector_to_state(N_Vector y) {
  const auto v = sundials::view(y);
  x_ = v.head(n());
  v_ = v.tail(n());
}

int SundialsIntegrator::evaluate_rhs(ForcePart part, bool with_velocity, double t, N_Vector y,
                                     N_Vector ydot) {
  const auto in = sundials::view(y);
  auto out = sundials::view(ydot);
  x_scratch_ = in.head(n());
  v_scratch_ = in.tail(n());
  ++mutable_stats().force_evals;
  system().force(part, t, x_scratch_, v_scratch_, f_scratch_);
  if (with_velocity) {
    out.head(n()) = v_scratch_;
  } else {
    out.head(n()).setZero();
  }
  out.tail(n()) = f_scratch_.cwiseQuotient(system().mass());
  // A non-finite force is recoverable for SUNDIALS (it retries a smaller step).
  return out.allFinite() ? 0 : 1;
}

void SundialsIntegrator::evaluate_jacobians(ForcePart part, double t, N_Vector y) {
  const auto in = sundials::view(y);
  x_scratch_ = in.head(n());
  v_scratch_ = in.tail(n());
  ++analytic_jacobians_;
  system().jacobians(part, t, x_scratch_, v_scratch_, &dfdx_, &dfdv_);
}

int SundialsIntegrator::ode_rhs(double t, N_Vector y, N_Vector ydot, void* self) {
  auto* me = static_cast<SundialsIntegrator*>(self);
  return me->evaluate_rhs(me->implicit_part_, true, t, y, ydot);
}

int SundialsIntegrator::ode_jacobian(double t, N_Vector y, N_Vector, SUNMatrix J, void* self,
                                     N_Vector, N_Vector, N_Vector) {
  auto* me = static_cast<SundialsIntegrator*>(self);
  me->evaluate_jacobians(me->implicit_part_, t, y);
  me->jacobian_->fill_ode(me->dfdx_, me->dfdv_, J);
  return 0;
}

int SundialsIntegrator::ode_jtimes_setup(double t, N_Vector y, N_Vector, void* self) {
  auto* me = static_cast<SundialsIntegrator*>(self);
  me->evaluate_jacobians(me->implicit_part_, t, y);
  return 0;
}

int SundialsIntegrator::ode_jtimes(N_Vector v, N_Vector Jv, double, N_Vector, N_Vector,
                                   void* self, N_Vector) {
  auto* me = static_cast<SundialsIntegrator*>(self);
  me->jacobian_->ode_times(me->dfdx_, me->dfdv_, N_VGetArrayPointer(v), N_VGetArrayPointer(Jv));
  return 0;
}

}  // namespace springlab
