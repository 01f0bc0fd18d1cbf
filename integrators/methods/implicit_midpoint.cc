#include "integrators/methods/implicit_midpoint.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

ImplicitMidpoint::ImplicitMidpoint()
    : VelocityImplicitMethod({.name = "implicit-midpoint",
                          .scheme = "y' = y + h f(t + h/2, (y + y')/2)",
                          .order = 2,
                          .implicit = true,
                          .iterates_to_tolerance = true,
                          .symplectic = true,
                          .stability = StabilityKind::kA,  // |R(i y)| = 1: no damping
                          .stability_limit = kInfinity,
                          .stability_function =
                              [](std::complex<double> z) { return (1.0 + z / 2.0) / (1.0 - z / 2.0); }}) {}

StepResult ImplicitMidpoint::midpoint_step(double h) {
  const StepResult result =
      solve_velocity(h, {.t_eval_offset = 0.5, .a = 0.25, .b = 0.25, .c = 0.5, .end = 2.0}, v_new_);
  if (!result.ok) return result;
  x_ += 0.5 * h * (v_ + v_new_);
  v_.swap(v_new_);
  return result;
}

StepResult ImplicitMidpoint::do_step(double h) {
  const StepResult result = midpoint_step(h);
  if (result.ok) return result;
  // The forces at the midpoint: a step a barrier cannot close in one,
  // solved again in substeps (velocity_implicit_method.h).
  return retry_in_substeps(h, result, [this](double dt) { return midpoint_step(dt); });
}

SPRINGLAB_INTEGRATOR(ImplicitMidpoint, implicit_midpoint_integrator)

}  // namespace springlab
