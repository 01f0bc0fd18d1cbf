#include "integrators/methods/newmark_family.h"

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

std::vector<std::string> NewmarkFamily::options_read() const {
  std::vector<std::string> read = {"newton-tol", "max-newton"};
  for (const std::string& option : parameter_options()) read.push_back(option);
  return read;
}

StepResult NewmarkFamily::do_initialize() {
  StepResult base = VelocityImplicitMethod::do_initialize();
  if (!base.ok) return base;
  if (std::string why = check_options(options(), x_.size()); !why.empty()) {
    return StepResult::failure(why);
  }
  p_ = parameters(options());
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
  const double beta = p_.beta, gamma = p_.gamma, am = p_.alpha_m, af = p_.alpha_f;
  const bool alpha_free = am == 0.0 && af == 0.0;
  if (beta == 0.0 && alpha_free &&
      system().velocity_dependence() == VelocityDependence::kNone) {
    return explicit_step(h);
  }
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
