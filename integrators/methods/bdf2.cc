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
  previous_.have = false;
  return VelocityImplicitMethod::do_initialize();
}

StepResult Bdf2::do_step(double h) {
  const StepResult result = formula_step(h);
  if (result.ok) return result;
  // Solved again in substeps (the header): the history put back before
  // each split is tried, and after none worked.
  kept_ = previous_;
  start_ = {.have = true, .x = x_, .v = v_, .h = h};
  const StepResult parts = retry_in_substeps(
      h, result, [this](double dt) { return formula_step(dt); }, nullptr,
      [this] { previous_ = kept_; });
  // Solved: the next step's history is this step's start, one h back.
  previous_ = parts.ok ? start_ : kept_;
  return parts;
}

StepResult Bdf2::formula_step(double h) {
  VelocityImplicitScheme scheme{.t_eval_offset = 1.0, .a = 0.0, .b = 1.0, .c = 1.0};
  if (previous_.have) {
    const double w = h / previous_.h;
    const double c0 = w * w / (1.0 + 2.0 * w), b = (1.0 + w) / (1.0 + 2.0 * w);
    v_c_ = v_ + c0 * (v_ - previous_.v);
    x_o_ = c0 * (x_ - previous_.x);
    scheme.b = b;
    scheme.weight = b;
    scheme.inertia = &v_c_;
    scheme.x_offset = &x_o_;
  }
  const StepResult result = solve_velocity(h, scheme, v_new_);
  if (!result.ok) return result;
  previous_.x = x_;
  previous_.v = v_;
  if (previous_.have) x_ += x_o_;
  x_ += (h * scheme.b) * v_new_;
  v_.swap(v_new_);
  previous_.h = h;
  previous_.have = true;
  return result;
}

SPRINGLAB_INTEGRATOR(Bdf2, bdf2_integrator)

}  // namespace springlab
