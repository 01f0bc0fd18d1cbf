#include "integrators/methods/explicit_euler.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

ExplicitEuler::ExplicitEuler()
    : Integrator({.name = "explicit-euler",
                  .scheme = "x' = x + h v,  v' = v + h M^-1 F(t, x, v)",
                  .order = 1,
                  .stability = StabilityKind::kConditional,  // |1 + z| <= 1
                  .stability_limit = 0.0,
                  .stability_function = [](std::complex<double> z) { return 1.0 + z; }}) {}

StepResult ExplicitEuler::do_step(double h) {
  eval_acceleration(t_, x_, v_, a_);
  x_ += h * v_;
  v_ += h * a_;
  return StepResult::success();
}

SPRINGLAB_INTEGRATOR(ExplicitEuler, explicit_euler_integrator)

}  // namespace springlab
