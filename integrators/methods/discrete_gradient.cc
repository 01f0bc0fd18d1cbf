#include "integrators/methods/discrete_gradient.h"

#include <memory>

#include "integrators/core/integrator_entry.h"

namespace springlab {

NewtonProblem& DiscreteGradient::newton_problem(VelocityStep& step) {
  gonzalez_.begin(step, own_gradients_);
  return gonzalez_;
}

std::unique_ptr<NewtonPolicy> DiscreteGradient::newton_policy(NewtonPolicy::Matrices matrices,
                                                              bool symmetric) {
  return discrete_gradient_phases(matrices, symmetric, gonzalez_);
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

StepResult DiscreteGradient::do_initialize() {
  generic_steps_ = 0;
  return VelocityImplicitMethod::do_initialize();
}

StepResult DiscreteGradient::gradient_step(double h, const VelocityImplicitScheme& scheme) {
  const StepResult result = solve_velocity(h, scheme, v_new_);
  if (!result.ok) return result;
  x_ += 0.5 * h * (v_ + v_new_);
  v_.swap(v_new_);
  return result;
}

StepResult DiscreteGradient::do_step(double h) {
  VelocityImplicitScheme scheme = {
      .t_eval_offset = 0.5, .a = 0.25, .b = 0.25, .c = 0.5, .end = 2.0};
  // With forces' own discrete gradients, no definite fallback inside the
  // step (velocity_step.h: it would be the generic gradient's solution).
  const bool own = system().has_own_discrete_gradients();
  own_gradients_ = true;
  scheme.definite_fallback = !own;
  const auto one_step = [&](double dt) { return gradient_step(dt, scheme); };
  const StepResult result = one_step(h);
  if (result.ok) return result;
  // The header: substeps (with the forces' own discrete gradients where
  // they have them), then Gonzalez's generic one. (Once in box-chain's 300
  // steps of 1/60 s, none at 10 ms, none on the tumbling box at 10 ms; once
  // in box-pile's runs that then fail on a contact: docs/integrators.md.)
  if (const StepResult parts = retry_in_substeps(h, result, one_step); parts.ok) return parts;
  if (!own) return result;
  own_gradients_ = false;
  scheme.definite_fallback = true;
  if (const StepResult generic = gradient_step(h, scheme); generic.ok) {
    ++generic_steps_;
    return generic;
  }
  return result;
}

std::vector<FallbackCount> DiscreteGradient::fallbacks() const {
  std::vector<FallbackCount> counts = VelocityImplicitMethod::fallbacks();  // the substeps
  if (generic_steps_ > 0) {
    counts.push_back({.fallback = Fallback::kGenericDiscreteGradient, .steps = generic_steps_});
  }
  return counts;
}

SPRINGLAB_INTEGRATOR(DiscreteGradient, discrete_gradient_integrator)

}  // namespace springlab
