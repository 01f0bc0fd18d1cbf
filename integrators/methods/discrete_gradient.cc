#include "integrators/methods/discrete_gradient.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

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

StepResult DiscreteGradient::do_step(double h) {
  VelocityImplicitScheme scheme = {
      .t_eval_offset = 0.5, .a = 0.25, .b = 0.25, .c = 0.5, .discrete_gradient = true, .end = 2.0};
  StepResult result = solve_velocity(h, scheme, v_new_);
  // A step whose Newton fails with the forces' own discrete gradients (their
  // exact derivative in the matrix: velocity_step.cc) is solved again with
  // Gonzalez's discrete gradient for every force: energy still exact,
  // angular momentum kept only to Newton's tolerance in that step. Rare:
  // once in box-chain's 300 steps of 1/60 s, none at 10 ms, none on the
  // tumbling box; once in box-pile's runs that then fail on a contact
  // (docs/integrators.md).
  if (!result.ok && system().has_own_discrete_gradients()) {
    scheme.own_discrete_gradients = false;
    if (StepResult generic = solve_velocity(h, scheme, v_new_); generic.ok) result = generic;
  }
  if (!result.ok) return result;
  x_ += 0.5 * h * (v_ + v_new_);
  v_.swap(v_new_);
  return result;
}

SPRINGLAB_INTEGRATOR(DiscreteGradient, discrete_gradient_integrator)

}  // namespace springlab
