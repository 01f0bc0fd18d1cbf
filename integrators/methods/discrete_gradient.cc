#include "integrators/methods/discrete_gradient.h"

#include <memory>

#include "integrators/core/integrator_entry.h"

namespace springlab {
namespace {

// Newton on the discrete gradient's step (newton_policy.h): its residual is
// no gradient, but with the correction's coefficient frozen it is that of
// the midpoint's potential + c |D|^2 (velocity_step.h). Phase 1 minimizes
// that potential with the coefficient frozen at each iteration's start
// (robust far from the solution); once a full exact update is taken, phase 2
// is Newton with the exact Jacobian (the rank-one term included) and a
// search on ||r||, quadratic near the solution; back to phase 1 when that
// search fails, and to phase 2 when phase 1's update does not descend even
// with the definite matrix.
class DiscreteGradientPhases final : public NewtonPolicy {
 public:
  DiscreteGradientPhases(Matrices matrices, bool symmetric, VelocityStep& step)
      : NewtonPolicy(matrices, symmetric), step_(step) {}

  void start(bool has_potential, NewtonMode& mode) override {
    NewtonPolicy::start(has_potential, mode);
    has_potential_ = has_potential;
    newton_phase_ = false;
    step_.freeze(mode.minimize);
    step_.set_frozen_coefficient(0.0);
  }

  void begin_iteration(NewtonMode& mode, NewtonIterate& it) override {
    if (has_potential_) {
      mode.minimize = !newton_phase_;
      step_.freeze(mode.minimize);
      mode.careful = mode.careful || newton_phase_;
    }
    // The coefficient at this v: the potential and r of the next
    // iterations use it.
    step_.update_frozen(it.r, it.phi);
  }

  bool retry_not_descending(NewtonMode& mode) override {
    if (NewtonPolicy::retry_not_descending(mode)) return true;
    if (!step_.frozen()) return false;
    newton_phase_ = true;  // the frozen potential is only a guide: Newton on r
    return true;
  }

  bool retry_search_failed(NewtonMode& mode, NewtonProblem& problem, NewtonIterate& it) override {
    if (!newton_phase_) return NewtonPolicy::retry_search_failed(mode, problem, it);
    // Back to the frozen potential, from v.
    newton_phase_ = false;
    mode.careful = false;
    step_.refreeze_at(it.v, it.r);
    it.phi = step_.potential(it.v, it.magnitude);
    return true;
  }

  void step_taken(NewtonMode& mode, double alpha) override {
    if (has_potential_ && !newton_phase_ && alpha == 1.0 && !mode.definite) newton_phase_ = true;
    NewtonPolicy::step_taken(mode, alpha);
  }

 private:
  VelocityStep& step_;
  bool has_potential_ = false;
  bool newton_phase_ = false;  // phase 2
};

}  // namespace

std::unique_ptr<NewtonPolicy> DiscreteGradient::newton_policy(NewtonPolicy::Matrices matrices,
                                                              bool symmetric, VelocityStep& step) {
  if (!step.scheme().discrete_gradient) {
    return VelocityImplicitMethod::newton_policy(matrices, symmetric, step);
  }
  return std::make_unique<DiscreteGradientPhases>(matrices, symmetric, step);
}

DiscreteGradient::DiscreteGradient()
    : VelocityImplicitMethod(
          {.name = "discrete-gradient",
           .scheme = "x' = x + h (v + v')/2,  M (v' - v) = -h grad_d V(x, x') + h F_nc(t + h/2, "
                     "(x + x')/2, (v + v')/2)",
           .order = 2,
           .implicit = true,
           .iterates_to_tolerance = true,
           // On the linear oscillator V is quadratic, the correction vanishes
           // and the step is the midpoint rule's: |R(i y)| = 1.
           .stability = StabilityKind::kA,
           .stability_limit = kInfinity,
           .stability_function =
               [](std::complex<double> z) { return (1.0 + z / 2.0) / (1.0 - z / 2.0); }}) {}

StepResult DiscreteGradient::step_in_parts(double h, int n, const VelocityImplicitScheme& scheme) {
  const double t0 = t_, dt = h / n;
  x_start_ = x_;
  v_start_ = v_;
  StepResult result;
  for (int i = 0; i < n && result.ok; ++i) {
    t_ = t0 + i * dt;
    result = solve_velocity(dt, scheme, v_new_);
    if (!result.ok) break;
    x_ += 0.5 * dt * (v_ + v_new_);
    v_.swap(v_new_);
  }
  t_ = t0;
  if (!result.ok) {
    x_ = x_start_;
    v_ = v_start_;
  }
  return result;
}

StepResult DiscreteGradient::do_step(double h) {
  VelocityImplicitScheme scheme = {
      .t_eval_offset = 0.5, .a = 0.25, .b = 0.25, .c = 0.5, .discrete_gradient = true, .end = 2.0};
  // With forces' own discrete gradients, no definite fallback inside the
  // step (velocity_step.h: it would be the generic gradient's solution).
  const bool own = system().has_own_discrete_gradients();
  scheme.definite_fallback = !own;
  StepResult result = solve_velocity(h, scheme, v_new_);
  if (result.ok) {
    x_ += 0.5 * h * (v_ + v_new_);
    v_.swap(v_new_);
    return result;
  }
  if (!own) return result;
  // The header: substeps with the forces' own discrete gradients, then
  // Gonzalez's generic one. (Once in box-chain's 300 steps of 1/60 s, none
  // at 10 ms, none on the tumbling box at 10 ms; once in box-pile's runs
  // that then fail on a contact: docs/integrators.md.)
  for (int n = 2; n <= 8; n *= 2) {
    if (step_in_parts(h, n, scheme).ok) return StepResult::success();
  }
  scheme.own_discrete_gradients = false;
  scheme.definite_fallback = true;
  if (StepResult generic = solve_velocity(h, scheme, v_new_); generic.ok) {
    ++generic_steps_;
    x_ += 0.5 * h * (v_ + v_new_);
    v_.swap(v_new_);
    return generic;
  }
  return result;
}

std::vector<FallbackCount> DiscreteGradient::fallbacks() const {
  if (generic_steps_ == 0) return {};
  return {{.fallback = Fallback::kGenericDiscreteGradient, .steps = generic_steps_}};
}

SPRINGLAB_INTEGRATOR(DiscreteGradient, discrete_gradient_integrator)

}  // namespace springlab
