#include "integrators/sundials/sundials_integrator.h"

#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <sstream>

namespace springlab {

using sundials::check;
using sundials::check_created;

namespace {

// The return codes every package shares (CV_, IDA_, ARK_ TOO_MUCH_WORK, ...).
constexpr int kTooMuchWork = -1, kTooMuchAccuracy = -2, kErrorTestFailures = -3,
              kConvergenceFailures = -4;

// {1, 2, 3, 4, 5, 8} -> "1-5, 8"
std::string join(const std::vector<int>& orders) {
  std::string text;
  for (std::size_t k = 0; k < orders.size();) {
    std::size_t end = k;
    while (end + 1 < orders.size() && orders[end + 1] == orders[end] + 1) ++end;
    if (!text.empty()) text += ", ";
    text += std::to_string(orders[k]);
    if (end > k) {
      text += '-';
      text += std::to_string(orders[end]);
    }
    k = end + 1;
  }
  return text;
}

std::string number(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

}  // namespace

long sundials_step_limit(const IntegratorOptions& options, Eigen::Index first_order_unknowns) {
  if (options.max_steps > 0) return options.max_steps;
  const double scaled = kStepBudget / static_cast<double>(std::max<Eigen::Index>(first_order_unknowns, 1));
  return std::clamp(static_cast<long>(scaled), kMinStepLimit, kMaxStepLimit);
}

SundialsIntegrator::SundialsIntegrator(IntegratorInfo info, const SundialsCalls& calls,
                                       SundialsMethod method)
    : Integrator(std::move(info)), calls_(calls), method_(std::move(method)) {}

// Members are destroyed in reverse order: memory_ (which refers to the
// solvers and vectors) first, then the rest, the context last.
SundialsIntegrator::~SundialsIntegrator() { memory_.reset(); }

std::vector<std::string> SundialsIntegrator::options_read() const {
  std::vector<std::string> names = {"rtol", "atol", "max-steps", "max-order"};
  if (method_.newton_matrix) names.insert(names.end(), {"linear-solver", "dq-jacobian"});
  if (method_.stald) names.push_back("stald");
  return names;
}

std::string SundialsIntegrator::check_options(const IntegratorOptions& o, Eigen::Index dofs) const {
  const Eigen::Index unknowns = 2 * dofs;
  if (o.rtol < kMinRelativeTolerance) {
    return "--rtol " + number(o.rtol) + ": below double precision's unit roundoff (2.2e-16), a "
           "tolerance no solver can meet: use --rtol 1e-14 or more";
  }
  if (o.max_order != 0 &&
      std::find(method_.orders.begin(), method_.orders.end(), o.max_order) == method_.orders.end()) {
    return "--max-order " + std::to_string(o.max_order) + ": " + name() + " takes " +
           join(method_.orders) + " (" + method_.order_meaning + ")";
  }
  if (o.stald && !method_.stald) {
    return "--stald: stability limit detection is cvode-bdf's, " + name() + " has none";
  }
  if (!method_.newton_matrix) return {};
  LinearSolverKind kind = LinearSolverKind::kNone;
  try {
    kind = linear_solver_kind(o.linear_solver, unknowns);
  } catch (const sundials::Failure& e) {
    return e.what();
  }
  const std::string picked =
      o.linear_solver == "auto" ? " (--linear-solver auto picks reduced above 100 unknowns; this system has " +
                                      std::to_string(unknowns) + ")"
                                : "";
  if (o.dq_jacobian && (kind == LinearSolverKind::kKlu || kind == LinearSolverKind::kReduced)) {
    return "--dq-jacobian: SUNDIALS forms difference-quotient Jacobians only as dense matrices" +
           picked + ": add --linear-solver dense or gmres";
  }
  if (kind == LinearSolverKind::kDense && unknowns > kMaxDenseUnknowns) {
    return "--linear-solver dense: a " + std::to_string(unknowns) + " x " + std::to_string(unknowns) +
           " Newton matrix, over the cap of " + std::to_string(kMaxDenseUnknowns) +
           " unknowns for a dense one (each factorization would take seconds): use --linear-solver "
           "reduced, klu or gmres";
  }
  return {};
}

void SundialsIntegrator::adopt(void* memory, sundials::SolverMemory::FreeFn free_fn) {
  memory_ = sundials::SolverMemory(memory, free_fn);
  check(calls_.set_error_handler(memory, sundials::ErrorLog::handler, &log_),
        call("SetErrHandlerFn").c_str());
}

StepResult SundialsIntegrator::do_initialize() {
  memory_.reset();
  linear_solver_.reset();
  nonlinear_solver_.reset();
  matrix_.reset();
  y_.reset();
  yp_.reset();
  log_.last.clear();
  analytic_jacobians_ = 0;
  // What keeps it from starting on this system is a refusal (integrator.h
  // StepResult::refusal): the sentence without the name, as data.
  if (std::string why = check_options(options(), n()); !why.empty()) {
    return StepResult::refusal(name(), {why, {}});
  }
  if (method_.newton_matrix && system().pattern_varies()) {
    // Its Newton matrix (first_order_jacobian.h) and KLU's analysis keep
    // the pattern of the first step.
    return StepResult::refusal(
        name(), {"this system's Jacobian pattern changes as " + system().pattern_change() +
                     ", and SUNDIALS' Newton matrices keep the pattern of the first step: "
                     "use arkode-erk (adaptive, explicit), or implicit-euler, bdf2 or another "
                     "implicit method of springlab's own",
                 {}});
  }
  step_limit_ = sundials_step_limit(options(), 2 * n());
  try {
    if (!context_) {
      SUNContext context = nullptr;
      check(SUNContext_Create(nullptr, &context), "SUNContext_Create");
      context_.reset(context);
    }
    y_ = sundials::make_vector(2 * n(), context_.get());
    state_to_vector(y_.get());
    create();
    configure();
  } catch (const sundials::Failure& e) {
    return StepResult::refusal(name(), {e.what(), {}});
  }
  return StepResult::success();
}

void SundialsIntegrator::configure() {
  const IntegratorOptions& o = options();
  void* mem = memory();
  check(calls_.set_tolerances(mem, o.rtol, o.atol), call("SStolerances").c_str(), log_.last);
  check(calls_.set_user_data(mem, this), call("SetUserData").c_str());
  check(calls_.set_max_steps(mem, step_limit_), call("SetMaxNumSteps").c_str(), log_.last);
  if (o.max_order > 0) check(calls_.set_order(mem, o.max_order), call(calls_.order_call).c_str(), log_.last);
  if (!method_.newton_matrix) return;
  const LinearSolverKind kind = linear_solver_kind();
  create_linear_solver(kind);
  check(calls_.set_linear_solver(mem, linear_solver_.get(), matrix_.get()),
        call("SetLinearSolver").c_str(), log_.last);
  // Without our callbacks the package differences f itself: dense
  // difference quotients, or J v products for GMRES.
  if (!o.dq_jacobian) attach_jacobian(kind == LinearSolverKind::kGmres);
}

StepResult SundialsIntegrator::do_step(double) {
  return StepResult::failure(name() + ": adaptive methods advance with advance_to()");
}

StepResult SundialsIntegrator::advance_to(double t_out) {
  if (!(t_out > t_)) return StepResult::failure(name() + ": output time must increase");
  double t_reached = t_;
  int flag = calls_.set_stop_time(memory(), t_out);
  if (flag >= 0) flag = calls_.evolve(memory(), t_out, y_.get(), yp_.get(), &t_reached);
  vector_to_state(y_.get());
  read_counters(mutable_stats());
  if (flag >= 0) {
    t_ = t_out;
    return StepResult::success();
  }
  t_ = t_reached;
  std::ostringstream message;
  message << name() << ": " << calls_.evolve_call << " failed at t = " << t_reached << " (flag "
          << flag << ")";
  if (stop_requested()) {
    message << ": stopped on request";
    return StepResult::failure(message.str());
  }
  if (!log_.last.empty()) message << ": " << log_.last;
  // What to try, for the failures a student meets.
  switch (flag) {
    case kTooMuchWork:
      message << "; " << step_limit_ << " internal steps did not reach the next output time ("
              << (options().max_steps > 0 ? "--max-steps" : "the default limit, 5e6 / unknowns")
              << "): "
              << (info().implicit ? "try a shorter --dt output interval, a looser --rtol"
                                  : "the system may be too stiff for an explicit method, try an "
                                    "implicit one, a looser --rtol")
              << ", or allow more with --max-steps";
      break;
    case kTooMuchAccuracy:
      message << "; the tolerance is below what double precision resolves here: raise --rtol or "
                 "--atol";
      break;
    case kErrorTestFailures:
      message << "; the error test kept failing (the step shrank to nothing): the tolerance may be "
                 "too tight for double precision, try a looser --rtol or --atol";
      break;
    case kConvergenceFailures:
      message << "; Newton kept failing to converge: try a looser --rtol, another "
                 "--linear-solver, or a shorter --dt output interval";
      break;
    default:
      break;
  }
  return StepResult::failure(message.str());
}

void SundialsIntegrator::read_counters(IntegratorStats& s) {
  void* mem = memory();
  auto get = [mem](int (*fn)(void*, long*), long& out) {
    long value = 0;
    if (fn != nullptr && fn(mem, &value) >= 0) out = value;
  };
  get(calls_.get_steps, s.steps);
  get(calls_.get_error_test_fails, s.rejected_steps);
  get(calls_.get_nonlinear_iterations, s.newton_iterations);
  get(calls_.get_nonlinear_failures, s.nonlinear_failures);
  // force_evals are counted in our callbacks, difference quotients included.
  long difference_quotients = 0;
  if (method_.newton_matrix) {
    s.linear_solves = s.newton_iterations;  // one linear solve per Newton iteration
    get(calls_.get_linear_setups, s.factorizations);
    if (options().dq_jacobian) get(calls_.get_jacobian_evals, difference_quotients);
  }
  s.jacobian_evals = analytic_jacobians_ + difference_quotients;
}

SundialsIntegrator::LinearSolverKind SundialsIntegrator::linear_solver_kind(const std::string& choice,
                                                                            Eigen::Index unknowns) {
  if (choice == "dense") return LinearSolverKind::kDense;
  if (choice == "klu") return LinearSolverKind::kKlu;
  if (choice == "gmres") return LinearSolverKind::kGmres;
  if (choice == "reduced") return LinearSolverKind::kReduced;
  if (choice == "auto") return unknowns <= 100 ? LinearSolverKind::kDense : LinearSolverKind::kReduced;
  throw sundials::Failure("--linear-solver: unknown '" + choice +
                          "' (dense, klu, gmres, reduced, auto)");
}

SundialsIntegrator::LinearSolverKind SundialsIntegrator::linear_solver_kind() const {
  return linear_solver_kind(options().linear_solver, 2 * n());
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
    case LinearSolverKind::kReduced:
      // The n x n matrix M - gamma D - gamma^2 K (reduced_newton_solver.h).
      reduced_ = {&system(), &dfdx_, &dfdv_, jacobian_.get()};
      matrix_.reset(check_created(sundials::make_reduced_matrix(reduced_, ctx), "SUNMatNewEmpty"));
      linear_solver_.reset(
          check_created(sundials::make_reduced_solver(reduced_, ctx), "SUNLinSolNewEmpty"));
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

bool SundialsIntegrator::stop_requested() const {
  return options().stop != nullptr && options().stop->load(std::memory_order_relaxed);
}

int SundialsIntegrator::evaluate_rhs(ForcePart part, bool with_velocity, double t, N_Vector y,
                                     N_Vector ydot) {
  if (stop_requested()) return -1;  // unrecoverable: the solver returns at once
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
  if (sundials::is_reduced(J)) {
    sundials::set_ode_jacobian(J);  // dF/dx, dF/dv stay in dfdx_, dfdv_
  } else {
    me->jacobian_->fill_ode(me->dfdx_, me->dfdv_, J);
  }
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
