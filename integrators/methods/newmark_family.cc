#include "integrators/methods/newmark_family.h"

#include <algorithm>
#include <cmath>

namespace springlab {

NewmarkParameters generalized_alpha_parameters(double rho_inf) {
  NewmarkParameters p;
  p.alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
  p.alpha_f = rho_inf / (rho_inf + 1.0);
  p.gamma = 0.5 - p.alpha_m + p.alpha_f;
  const double s = 1.0 - p.alpha_m + p.alpha_f;
  p.beta = 0.25 * s * s;
  return p;
}

NewmarkParameters hht_parameters(double alpha) {
  NewmarkParameters p;
  p.alpha_m = 0.0;
  p.alpha_f = -alpha;
  p.gamma = 0.5 - alpha;
  p.beta = 0.25 * (1.0 - alpha) * (1.0 - alpha);
  return p;
}

int newmark_overshoot_steps(const NewmarkParameters& p) {
  const double am = p.alpha_m, af = p.alpha_f, beta = p.beta, gamma = p.gamma;
  // Unconditionally stable (the header: Hughes 9.1)?
  if (!(am <= af && af <= 0.5 && beta >= 0.25 + 0.5 * (af - am)) || !(gamma >= 0.5)) return 0;
  // At w h = 1e3: the peak's step no longer depends on w h there (hht-alpha:
  // step 5 at 1e3, 1e4 and 1e6), and the recurrence's round-off (terms of
  // (w h)^2 cancelling) stays near 1e-10, below the 1e-6 that counts as a
  // rise (at 1e6 it made newmark's conserved energy "rise").
  const double w = 1.0, h = 1e3;
  constexpr int kPhases = 16, kSteps = 2000;
  int peak_step = 0;
  for (int phase = 0; phase < kPhases; ++phase) {
    const double theta = 2.0 * 3.141592653589793 * phase / kPhases;
    double x = std::cos(theta), v = w * std::sin(theta), a = -w * w * x;
    const double e0 = 0.5 * (v * v + w * w * x * x);
    double peak = e0;
    int at = 0;
    for (int k = 1; k <= kSteps; ++k) {
      // (1 - am) a' + am a = -w^2 ((1 - af) x' + af x), x' = x + h v + h^2 ((1/2 - beta) a + beta a').
      const double rhs = -am * a - w * w * ((1.0 - af) * (x + h * v + h * h * (0.5 - beta) * a) +
                                            af * x);
      const double a_new = rhs / ((1.0 - am) + w * w * (1.0 - af) * h * h * beta);
      const double x_new = x + h * v + h * h * ((0.5 - beta) * a + beta * a_new);
      v += h * ((1.0 - gamma) * a + gamma * a_new);
      x = x_new;
      a = a_new;
      const double e = 0.5 * (v * v + w * w * x * x);
      if (e > peak) {
        peak = e;
        at = k;
      }
    }
    if (peak > (1.0 + 1e-6) * e0) peak_step = std::max(peak_step, at);
  }
  return peak_step;
}

std::vector<std::string> NewmarkFamily::options_read() const {
  std::vector<std::string> read = {"newton-tol", "max-newton"};
  for (const std::string& option : parameter_options()) read.push_back(option);
  return read;
}

StepResult NewmarkFamily::do_initialize() {
  StepResult base = VelocityImplicitMethod::do_initialize();
  if (!base.ok) return base;
  if (std::string why = check_options(options(), x_.size()); !why.empty()) {
    return StepResult::refusal(name(), {why, {}});
  }
  p_ = parameters(options());
  overshoot_ = newmark_overshoot_steps(p_);
  // a_0 from the equations of motion at the start (Hughes 9.1.1).
  eval_acceleration(t_, x_, v_, a_);
  return StepResult::success();
}

StepResult NewmarkFamily::explicit_step(double h) {
  // beta = 0, F independent of v: x' explicit, then a' = M^-1 F(t', x').
  x_ += h * v_ + (0.5 * h * h) * a_;
  eval_acceleration(t_ + h, x_, v_, f_);
  v_ += h * ((1.0 - p_.gamma) * a_ + p_.gamma * f_);
  a_.swap(f_);
  return StepResult::success();
}

StepResult NewmarkFamily::do_step(double h) {
  const double beta = p_.beta, am = p_.alpha_m, af = p_.alpha_f;
  const bool alpha_free = am == 0.0 && af == 0.0;
  if (beta == 0.0 && alpha_free &&
      system().velocity_dependence() == VelocityDependence::kNone) {
    return explicit_step(h);
  }
  const StepResult result = implicit_step(h);
  if (result.ok || !(af > 0.0)) return result;
  // The forces at t_{n+1-alpha_f}, short of the step's end: a step a
  // barrier cannot close in one, solved again in substeps
  // (velocity_implicit_method.h).
  return retry_in_substeps(h, result, [this](double dt) { return implicit_step(dt); }, &a_);
}

StepResult NewmarkFamily::implicit_step(double h) {
  const double beta = p_.beta, gamma = p_.gamma, am = p_.alpha_m, af = p_.alpha_f;
  // The header's v_c and x*; x* - x_n is (1 - alpha_f) times x_{n+1} - x_n.
  const double kappa = 0.5 - beta - beta * (1.0 - gamma) / gamma;
  v_c_ = v_ + (h * ((1.0 - gamma) - gamma * am / (1.0 - am))) * a_;
  VelocityImplicitScheme scheme{.t_eval_offset = 1.0 - af,
                                .a = (1.0 - af) * (1.0 - beta / gamma),
                                .b = (1.0 - af) * beta / gamma,
                                .c = 1.0 - af,
                                .end = 1.0 / (1.0 - af),
                                .weight = gamma / (1.0 - am),
                                .inertia = &v_c_};
  if (kappa != 0.0) {
    x_o_ = ((1.0 - af) * h * h * kappa) * a_;
    scheme.x_offset = &x_o_;
  }
  const StepResult result = solve_velocity(h, scheme, v_new_);
  if (!result.ok) return result;
  // a_{n+1} from the velocity update, x_{n+1} without it (its Newton error
  // is not divided by h there).
  Vector& a_new = f_;
  a_new = (v_new_ - v_ - (h * (1.0 - gamma)) * a_) / (h * gamma);
  x_ += h * ((1.0 - beta / gamma) * v_ + (beta / gamma) * v_new_);
  if (kappa != 0.0) x_ += (h * h * kappa) * a_;
  v_.swap(v_new_);
  a_.swap(a_new);
  return result;
}

}  // namespace springlab
