#include "integrators/methods/bdf2.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

Bdf2::Bdf2()
    : VelocityImplicitMethod({.name = "bdf2",
                          .scheme = "y' = 4/3 y - 1/3 y_prev + 2/3 h f(t + h, y'), y = (x, v); "
                                    "first step implicit Euler",
                          .order = 2,
                          .implicit = true,
                          .iterates_to_tolerance = true,
                          .stability = StabilityKind::kL,
                          .stability_limit = kInfinity,
                          .spectral_radius_infinity = 0.0}) {}

StepResult Bdf2::do_initialize() {
  have_previous_ = false;
  return VelocityImplicitMethod::do_initialize();
}

StepResult Bdf2::do_step(double h) {
  const StepResult result = formula_step(h);
  if (result.ok) return result;
  // Solved again in substeps (the header), the history restored before
  // each split is tried and after none worked.
  x_previous_kept_ = x_previous_;
  v_previous_kept_ = v_previous_;
  const double h_previous = h_previous_;
  const bool had_previous = have_previous_;
  x_start_ = x_;
  v_start_ = v_;
  auto restore = [&] {
    x_previous_ = x_previous_kept_;
    v_previous_ = v_previous_kept_;
    h_previous_ = h_previous;
    have_previous_ = had_previous;
  };
  const StepResult parts = retry_in_substeps(
      h, result, [this](double dt) { return formula_step(dt); }, nullptr, restore);
  if (!parts.ok) {
    restore();
    return parts;
  }
  x_previous_.swap(x_start_);
  v_previous_.swap(v_start_);
  h_previous_ = h;
  have_previous_ = true;
  return parts;
}

StepResult Bdf2::formula_step(double h) {
  VelocityImplicitScheme scheme{.t_eval_offset = 1.0, .a = 0.0, .b = 1.0, .c = 1.0};
  if (have_previous_) {
    const double w = h / h_previous_;
    const double c0 = w * w / (1.0 + 2.0 * w), b = (1.0 + w) / (1.0 + 2.0 * w);
    v_c_ = v_ + c0 * (v_ - v_previous_);
    x_o_ = c0 * (x_ - x_previous_);
    scheme.b = b;
    scheme.weight = b;
    scheme.inertia = &v_c_;
    scheme.x_offset = &x_o_;
  }
  const StepResult result = solve_velocity(h, scheme, v_new_);
  if (!result.ok) return result;
  x_previous_ = x_;
  v_previous_ = v_;
  if (have_previous_) x_ += x_o_;
  x_ += (h * scheme.b) * v_new_;
  v_.swap(v_new_);
  h_previous_ = h;
  have_previous_ = true;
  return result;
}

SPRINGLAB_INTEGRATOR(Bdf2, bdf2_integrator)

}  // namespace springlab
