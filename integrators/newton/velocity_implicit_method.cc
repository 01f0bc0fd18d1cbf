#include "integrators/newton/velocity_implicit_method.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "integrators/core/lagged_normal_forces.h"

namespace springlab {
namespace {

// Relative residual of the one linear solve of a linearized step.
constexpr double kLinearRtol = 1e-6;

}  // namespace

StepResult VelocityImplicitMethod::do_initialize() {
  model_ = CountedModel(system(), mutable_stats());
  matrix_.bind(model_);
  matrix_.reset();
  linear_.reset(mutable_stats());
  step_.bind(model_, matrix_);
  substep_steps_ = 0;
  return StepResult::success();
}

StepResult VelocityImplicitMethod::retry_in_substeps(
    double h, const StepResult& failed, const std::function<StepResult(double)>& one_step,
    Vector* extra, const std::function<void()>& restart) {
  // (Out of memory: a split needs the same factor.)
  if (linear_.out_of_memory()) return failed;
  const double t0 = t_;
  x_part_ = x_;
  v_part_ = v_;
  if (extra != nullptr) extra_part_ = *extra;
  for (int n = 2; n <= 8; n *= 2) {
    const double dt = h / n;
    if (restart) restart();
    StepResult result;
    for (int i = 0; i < n && result.ok; ++i) {
      t_ = t0 + i * dt;
      result = one_step(dt);
    }
    t_ = t0;  // (advance_to moves it)
    if (result.ok) {
      ++substep_steps_;
      return result;
    }
    x_ = x_part_;
    v_ = v_part_;
    if (extra != nullptr) *extra = extra_part_;
  }
  return failed;
}

std::vector<FallbackCount> VelocityImplicitMethod::fallbacks() const {
  if (substep_steps_ == 0) return {};
  return {{.fallback = Fallback::kSubsteps, .steps = substep_steps_}};
}

StepResult VelocityImplicitMethod::newton(NewtonPolicy::Matrices matrices, const Vector* start,
                                          Vector& v) {
  const NewtonLoop::Settings settings{
      .tol = options().newton_tol, .max_iterations = options().max_newton, .start = start};
  const NewtonLoop::Context context{.t = t_, .h = step_.h()};
  const std::unique_ptr<NewtonPolicy> policy =
      newton_policy(matrices, system().jacobian_symmetric());
  return newton_.solve(*problem_, {*policy, linear_, search_}, settings, context, mutable_stats(),
                       v);
}

StepResult VelocityImplicitMethod::solve_velocity(double h, const VelocityImplicitScheme& s,
                                                  Vector& v, bool quasi) {
  const LaggedNormalForces lag(system(), x_, &v_, h);
  step_.begin(t_, x_, v_, h, s);
  problem_ = &newton_problem(step_);
  const bool lbfgs = quasi && system().derives_from_potentials();
  check_.begin(step_, options().newton_tol, problem_ == &step_);
  std::string quasi_rejected;  // why L-BFGS's answer was not taken
  // L-BFGS needs the potential; where it stalls, Newton solves the step.
  if (lbfgs) {
    const StepResult answer = quasi_newton(v, quasi_rejected);
    if (answer.ok) return answer;
  }
  std::string refused;  // why Newton's answer from v_n was not taken
  StepResult result = checked_newton(NewtonPolicy::Matrices::kAlternating, nullptr, v, refused);
  const Vector* start = nullptr;
  if (!result.ok && !refused.empty() && !linear_.out_of_memory()) {
    // An answer that raised the potential (or the energy): Newton again from
    // the kept state (the tetrahedron above: from v = 0, 3 J -> 0.059 J in
    // that step). Not after other failures: those runs keep their results.
    ++mutable_stats().nonlinear_failures;
    start = &check_.kept();
    lag.again();
    std::string again;
    result = checked_newton(NewtonPolicy::Matrices::kAlternating, start, v, again);
    if (result.ok) return result;
  }
  if (!result.ok && s.definite_fallback && system().jacobian_symmetric() &&
      !linear_.out_of_memory()) {
    // The definite fallback (see the header): projected Newton from the
    // step's start (or the kept state).
    ++mutable_stats().nonlinear_failures;
    lag.again();
    std::string again;
    StepResult second = checked_newton(NewtonPolicy::Matrices::kDefinite, start, v, again);
    if (second.ok) return second;
    result = second;
  }
  if (!result.ok) ++mutable_stats().nonlinear_failures;
  // The attempts' reasons are composed without the method's name
  // ("L-BFGS stalled ..., and Newton failed ..."), which goes in front once.
  if (!result.ok && !refused.empty() && result.message != refused) {
    result = StepResult::failure(refused + "; from the step's start state, " + result.message);
  }
  if (!result.ok && !quasi_rejected.empty()) {
    result = StepResult::failure(quasi_rejected + ", and " + result.message);
  }
  if (!result.ok) result.message = name() + ": " + result.message;
  return result;
}

// Newton's answer, judged (incremental_potential_check.h): one above the
// lower of the step's two start states' potential (or, for backward Euler,
// energy) by more than the tolerance resolves is no solution of the step
// (one near-incompressible tetrahedron went from 3 J to 1,494 J in one step
// of 1 ms, "converged").
StepResult VelocityImplicitMethod::checked_newton(NewtonPolicy::Matrices matrices,
                                                  const Vector* start, Vector& v,
                                                  std::string& refused) {
  StepResult result = newton(matrices, start, v);
  if (!result.ok || !check_.active()) return result;
  const std::string rise = check_.judge(step_, v, options().newton_tol, r_end_, linear_);
  if (rise.empty()) return result;
  std::ostringstream message;
  message << "Newton's answer at t = " << t_ << " (h = " << step_.h() << ") "
          << rise
          << ": this method's step minimizes the incremental potential, so the answer is no "
             "solution (a point where the iteration stopped short, or a higher stationary "
             "point); try a smaller --dt or --newton-tol, or for finite elements a Poisson "
             "ratio further from 0.5";
  refused = message.str();
  return StepResult::failure(refused);
}

// L-BFGS's answer is judged as Newton's (incremental_potential_check.h):
// one above the start is an iterate that looked converged but is no
// minimizer (near-incompressible elements: block n=3 at poisson
// 0.49999999999 with L-BFGS, whose stiff initial Hessian makes its updates
// small while the residual is not, went from 47 J to 493 J in 1 s of
// "completed" steps). L-BFGS's answer is then not taken (`rejected` says
// why, and the failure is counted): Newton solves the step from its start.
StepResult VelocityImplicitMethod::quasi_newton(Vector& v, std::string& rejected) {
  if (!lbfgs_.solve(step_, model_, inv_mass(), options().newton_tol, options().max_newton, v)) {
    // Newton solves the step; should it fail too, its message says that
    // L-BFGS stalled first.
    std::ostringstream message;
    message << "L-BFGS stalled at t = " << t_ << " (h = " << step_.h()
            << ": no descent, a failed search or --max-newton iterations)";
    rejected = message.str();
    return StepResult::failure(rejected);
  }
  const std::string rise = check_.judge(step_, v, options().newton_tol, r_end_, linear_);
  if (rise.empty()) return StepResult::success();
  std::ostringstream message;
  message << "L-BFGS's step at t = " << t_ << " (h = " << step_.h()
          << ") " << rise << " (this method's step minimizes the incremental potential: not a "
             "solution)";
  rejected = message.str();
  ++mutable_stats().nonlinear_failures;  // Newton from the step's start
  return StepResult::failure(rejected);
}

bool VelocityImplicitMethod::solve_linearized(double t, const Vector& x, const Vector& v,
                                              const Vector& f, double h, double b, double c,
                                              bool definite, Vector& dv, std::string& error) {
  matrix_.set_point({.t = t, .x = &x, .v = &v, .h = h, .b = b, .c = c});
  matrix_.assemble(definite, linear_.matrix(definite, system().jacobian_symmetric(), matrix_));
  rhs_.noalias() = matrix_.dfdx() * v;
  rhs_ = h * (f + h * rhs_);  // the right-hand side
  if (!definite) return linear_.solve_directly(rhs_, dv, error);
  linear_.start_nonlinear_solve();
  return linear_.solve(rhs_, {.rtol = kLinearRtol, .atol = 0.0, .truncate = false}, dv, error).ok;
}

}  // namespace springlab
