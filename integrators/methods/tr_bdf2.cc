#include "integrators/methods/tr_bdf2.h"

#include <cmath>

#include "integrators/core/integrator_entry.h"

namespace springlab {
namespace {

const double kG = 2.0 - std::sqrt(2.0);
const double kC1 = 1.0 / (kG * (2.0 - kG));
const double kW = (1.0 - kG) / (2.0 - kG);

std::complex<double> tr_bdf2_function(std::complex<double> z) {
  const std::complex<double> s = kG * z;
  const std::complex<double> trapezoidal = (1.0 + s / 2.0) / (1.0 - s / 2.0);
  return (kC1 * trapezoidal - (kC1 - 1.0)) / (1.0 - kW * z);
}

}  // namespace

TrBdf2::TrBdf2()
    : VelocityImplicitMethod({.name = "tr-bdf2",
                          .scheme = "trapezoidal to t + g h, then BDF2 through it, g = 2 - sqrt 2",
                          .order = 2,
                          .implicit = true,
                          .iterates_to_tolerance = true,
                          .stability = StabilityKind::kL,
                          .stability_limit = kInfinity,
                          .stability_function = tr_bdf2_function,
                          .spectral_radius_infinity = 0.0}) {}

StepResult TrBdf2::do_initialize() {
  StepResult base = VelocityImplicitMethod::do_initialize();
  if (!base.ok) return base;
  eval_acceleration(t_, x_, v_, a_);
  return base;
}

StepResult TrBdf2::do_step(double h) {
  // The trapezoidal stage over g h: v_g = v_n + g h/2 (a_n + a_g),
  // x_g = x_n + g h/2 (v_n + v_g).
  const double hg = kG * h;
  v_c_ = v_ + (0.5 * hg) * a_;
  StepResult result = solve_velocity(
      hg, {.t_eval_offset = 1.0, .a = 0.5, .b = 0.5, .c = 1.0, .weight = 0.5, .inertia = &v_c_},
      v_g_);
  if (!result.ok) return result;
  x_g_ = x_ + (0.5 * hg) * (v_ + v_g_);
  // BDF2 through (t_n, t_n + g h, t_n + h).
  v_c_ = v_ + kC1 * (v_g_ - v_);
  x_o_ = kC1 * (x_g_ - x_);
  result = solve_velocity(h,
                          {.t_eval_offset = 1.0,
                           .a = 0.0,
                           .b = kW,
                           .c = 1.0,
                           .weight = kW,
                           .inertia = &v_c_,
                           .x_offset = &x_o_},
                          v_new_);
  if (!result.ok) return result;
  // a_{n+1} from the solved equation M (v' - v_c) = h w F.
  a_ = (v_new_ - v_c_) / (h * kW);
  x_ += x_o_ + (h * kW) * v_new_;
  v_.swap(v_new_);
  return result;
}

SPRINGLAB_INTEGRATOR(TrBdf2, tr_bdf2_integrator)

}  // namespace springlab
