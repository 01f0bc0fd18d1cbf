#include "integrators/velocity_implicit_method.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace springlab {
namespace {

// Relative residual of the one linear solve of a linearized step.
constexpr double kLinearRtol = 1e-6;
constexpr double kRoundoff = 1e3 * std::numeric_limits<double>::epsilon();  // as Newton's

// Friction's normal forces from the step's start while the step is solved
// (MechanicalSystem::lag_normal_forces): friction then derives from a
// dissipation potential, and Newton minimizes.
class LagNormalForces {
 public:
  LagNormalForces(const MechanicalSystem& system, const Vector& x) : system_(system) {
    system_.lag_normal_forces(&x);
  }
  ~LagNormalForces() { system_.lag_normal_forces(nullptr); }
  LagNormalForces(const LagNormalForces&) = delete;
  LagNormalForces& operator=(const LagNormalForces&) = delete;

 private:
  const MechanicalSystem& system_;
};

}  // namespace

StepResult VelocityImplicitMethod::do_initialize() {
  model_ = CountedModel(system(), mutable_stats());
  matrix_.bind(model_);
  matrix_.reset();
  linear_.reset(mutable_stats());
  step_.bind(model_, matrix_);
  return StepResult::success();
}

StepResult VelocityImplicitMethod::newton(NewtonPolicy::Matrices matrices, Vector& v) {
  const NewtonLoop::Settings settings{.tol = options().newton_tol,
                                      .max_iterations = options().max_newton};
  const NewtonLoop::Context context{.method = name(), .t = t_, .h = step_.h()};
  const bool symmetric = system().jacobian_symmetric();
  if (step_.scheme().discrete_gradient) {
    DiscreteGradientPhases policy(matrices, symmetric, step_);
    return newton_.solve(step_, {policy, linear_, search_}, settings, context, mutable_stats(), v);
  }
  NewtonPolicy policy(matrices, symmetric);
  return newton_.solve(step_, {policy, linear_, search_}, settings, context, mutable_stats(), v);
}

StepResult VelocityImplicitMethod::solve_velocity(double h, const VelocityImplicitScheme& s,
                                                  Vector& v, bool quasi) {
  const LagNormalForces lag(system(), x_);
  step_.begin(t_, x_, v_, h, s);
  std::string quasi_rejected;  // why L-BFGS's answer was not taken
  // L-BFGS needs the potential; where it stalls, Newton solves the step.
  if (quasi && system().derives_from_potentials()) {
    const StepResult answer = quasi_newton(v, quasi_rejected);
    if (answer.ok) return answer;
  }
  StepResult result = newton(NewtonPolicy::Matrices::kAlternating, v);
  if (!result.ok && system().jacobian_symmetric() && !linear_.out_of_memory()) {
    // The definite fallback (see the header): projected Newton from the
    // step's start.
    ++mutable_stats().nonlinear_failures;
    StepResult second = newton(NewtonPolicy::Matrices::kDefinite, v);
    if (second.ok) return second;
    result = second;
  }
  if (!result.ok) ++mutable_stats().nonlinear_failures;
  if (!result.ok && !quasi_rejected.empty()) {
    const std::string own = name() + ": ";  // Newton's message names the method too
    const std::string newton_text = result.message.rfind(own, 0) == 0
                                        ? result.message.substr(own.size())
                                        : result.message;
    result = StepResult::failure(quasi_rejected + ", and " + newton_text);
  }
  return result;
}

// Where the step minimizes the incremental potential Phi, a solution lies
// no higher than the start guesses the solvers descend from: v_n, and the v
// that keeps the stage at x_n (Newton's start where v_n leaves the states
// with an energy; for implicit Euler, v = 0 and Phi = E_n, the step's
// starting energy). An answer above the lower of the two by more than
// Phi's round-off is an iterate that looked converged but is no minimizer
// (near-incompressible elements: block n=3 at poisson 0.49999999999 with
// L-BFGS, whose stiff initial Hessian makes its updates small while the
// residual is not, went from 47 J to 493 J in 1 s of "completed" steps,
// each answer up to 26 J above E_n). L-BFGS's answer is then not taken
// (`rejected` says why, and the failure is counted): Newton solves the step
// from its start. Newton's own answers are not checked so: its line search
// already asks Phi to fall, and near a state at rest the stored energy's
// round-off (a turned neo-Hookean block: 2.3e-14 J against terms of
// mu W ~ 300 J) is not Phi's parts' magnitude, so a check at that scale
// refuses good steps.
StepResult VelocityImplicitMethod::quasi_newton(Vector& v, std::string& rejected) {
  const VelocityImplicitScheme& s = step_.scheme();
  const double h = step_.h();
  const bool minimizes = s.b > 0.0 && s.c > 0.0 && !s.discrete_gradient;
  double phi_start = std::numeric_limits<double>::infinity(), magnitude_start = 0.0;
  if (minimizes) {
    Vector v_kept = (-s.a / s.b) * v_;
    if (s.x_offset != nullptr) v_kept -= (1.0 / (h * s.b)) * *s.x_offset;
    // Phi's round-off scale is that of both guesses' terms (at v_n the
    // inertia term is 0 and the stored energy may be nearly 0 too -- a
    // strain-free spin --, while the answer's terms carry the round-off of
    // the kinetic energy the guess at x_n holds).
    for (const Vector* guess : {&v_, &v_kept}) {
      double magnitude = 0.0;
      step_.stage(*guess);
      const double phi = step_.potential(*guess, magnitude);
      if (std::isfinite(magnitude)) magnitude_start = std::max(magnitude_start, magnitude);
      if (phi < phi_start) phi_start = phi;
    }
  }
  if (!lbfgs_.solve(step_, model_, inv_mass(), options().newton_tol, options().max_newton, v)) {
    return StepResult::failure("L-BFGS stalled");
  }
  if (!minimizes || !std::isfinite(phi_start)) return StepResult::success();
  double magnitude_end = 0.0;
  step_.stage(v);
  const double phi_end = step_.potential(v, magnitude_end);
  // (At least the smallest normal double: a state decayed into denormals,
  // 0 J to 4.9e-324 J, has nothing left to compare.)
  const double noise = std::max(kRoundoff * std::max(magnitude_start, magnitude_end),
                                std::numeric_limits<double>::min());
  if (phi_end <= phi_start + noise) return StepResult::success();
  // Above the start by more than round-off: still a solution if within
  // what the Newton tolerance leaves. Near the minimizer v*,
  // Phi(v) - Phi(v*) ~ r(v).(v - v*) / 2 <= ||r(v)||_1 tol / 2 (a body at
  // rest, turned: both about 1.5e-29 J, 3 % apart).
  step_.residual(v, r_end_);
  const double allowance = 0.5 * options().newton_tol * r_end_.lpNorm<1>();
  if (phi_end <= phi_start + noise + allowance) return StepResult::success();
  std::ostringstream message;
  message << name() << ": L-BFGS's step at t = " << t_ << " (h = " << h
          << ") raised the incremental potential from " << phi_start << " J to " << phi_end
          << " J (this method's step minimizes it: not a solution)";
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
