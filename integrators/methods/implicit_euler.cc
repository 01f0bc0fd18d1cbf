#include "integrators/methods/implicit_euler.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

ImplicitEuler::ImplicitEuler()
    : VelocityImplicitMethod({.name = "implicit-euler",
                          .scheme = "v' = v + h M^-1 F(t + h, x + h v', v'),  x' = x + h v'",
                          .order = 1,
                          .implicit = true,
                          .iterates_to_tolerance = true,
                          .stability = StabilityKind::kL,  // R(z) = 1/(1 - z) -> 0
                          .stability_limit = kInfinity,
                          .stability_function =
                              [](std::complex<double> z) { return 1.0 / (1.0 - z); }}) {}

StepResult ImplicitEuler::do_initialize() {
  StepResult base = VelocityImplicitMethod::do_initialize();
  if (!base.ok || options().solver != Solver::kQuasiNewton) return base;
  if (!prepare_quasi_newton()) {
    return StepResult::failure(
        name() + " --solver quasi-newton: its initial Hessian is the local/global matrix of "
                 "distance constraints (springs) and elements, and this scene has stiff forces "
                 "that are neither; use --solver newton");
  }
  return base;
}

std::vector<std::string> ImplicitEuler::options_read() const {
  return {"newton-tol", "max-newton", "solver"};
}

StepResult ImplicitEuler::do_step(double h) {
  const StepResult result =
      solve_velocity(h, {.t_eval_offset = 1.0, .a = 0.0, .b = 1.0, .c = 1.0}, v_new_,
                     options().solver == Solver::kQuasiNewton);
  if (!result.ok) return result;
  x_ += h * v_new_;
  v_.swap(v_new_);
  return result;
}

SPRINGLAB_INTEGRATOR(ImplicitEuler, implicit_euler_integrator)

}  // namespace springlab
