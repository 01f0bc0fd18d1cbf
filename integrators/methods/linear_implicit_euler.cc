#include "integrators/methods/linear_implicit_euler.h"

#include <sstream>

#include "integrators/core/integrator_entry.h"

namespace springlab {

LinearImplicitEuler::LinearImplicitEuler()
    : VelocityImplicitMethod({.name = "linear-implicit-euler",
                          .scheme = "(M - h D - h^2 K) dv = h (F0 + h K v),  v' = v + dv,  x' = x + h v'",
                          .order = 1,
                          .implicit = true,
                          .stability = StabilityKind::kL,
                          .stability_limit = kInfinity,
                          .stability_note = "for linear forces; one linearized step can fail on "
                                            "strongly nonlinear ones",
                          .stability_function =
                              [](std::complex<double> z) { return 1.0 / (1.0 - z); }}) {}

StepResult LinearImplicitEuler::do_step(double h) {
  const double t1 = t_ + h;
  eval_force(t1, x_, v_, f0_);
  std::string error;
  const bool definite = options().stiffness == Stiffness::kDefinite;
  ++mutable_stats().newton_iterations;
  if (!solve_linearized(t1, x_, v_, f0_, h, /*b=*/1.0, /*c=*/1.0, definite, dv_, error)) {
    ++mutable_stats().nonlinear_failures;
    std::ostringstream message;
    message << name() << ": the linear solve failed at t = " << t_ << " (" << error << ")";
    return StepResult::failure(message.str());
  }
  v_ += dv_;
  x_ += h * v_;
  return StepResult::success();
}

SPRINGLAB_INTEGRATOR(LinearImplicitEuler, linear_implicit_euler_integrator)

}  // namespace springlab
