#include "integrators/linear_implicit_euler.h"

#include <sstream>

namespace springlab {

LinearImplicitEuler::LinearImplicitEuler()
    : ImplicitIntegrator({.name = "linear-implicit-euler",
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
  if (!factorize_newton_matrix(t1, x_, v_, h, /*c=*/1.0, /*b=*/1.0, error)) {
    ++mutable_stats().nonlinear_failures;
    std::ostringstream message;
    message << name() << ": singular matrix at t = " << t_ << " (" << error << ")";
    return StepResult::failure(message.str());
  }
  ++mutable_stats().newton_iterations;
  rhs_ = h * (f0_ + h * (last_dfdx() * v_));
  if (!solve_newton_system(rhs_, dv_)) {
    return StepResult::failure(name() + ": the velocity update is not finite");
  }
  v_ += dv_;
  x_ += h * v_;
  return StepResult::success();
}

}  // namespace springlab
