// The Newmark family and its alpha methods: the integrators of structural
// dynamics (Hughes, "The Finite Element Method", 1987, ch. 9).
//
// The state carries the acceleration a_n besides x_n and v_n. One step of
// the generalized-alpha method (Chung and Hulbert, J. Appl. Mech. 60, 1993,
// eqs. 2-5) finds a_{n+1} with
//
//   x_{n+1} = x_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
//   v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})
//   M ((1 - alpha_m) a_{n+1} + alpha_m a_n) = F(t_{n+1-alpha_f}, x_{n+1-alpha_f}, v_{n+1-alpha_f}),
//
// where y_{n+1-alpha_f} = (1 - alpha_f) y_{n+1} + alpha_f y_n. Newmark (1959)
// is alpha_m = alpha_f = 0; Hilber, Hughes and Taylor's alpha method (1977) is
// alpha_m = 0, alpha_f = -alpha. The unknown here is v_{n+1}: eliminating
// a_{n+1} = (v_{n+1} - v_n - h (1 - gamma) a_n) / (h gamma) leaves
//
//   M (v_{n+1} - v_c) - h w F(t*, x*(v_{n+1}), v*(v_{n+1})) = 0,
//   v_c = v_n + h ((1 - gamma) - gamma alpha_m / (1 - alpha_m)) a_n,  w = gamma / (1 - alpha_m),
//   x* = x_n + (1 - alpha_f) (h ((1 - beta/gamma) v_n + beta/gamma v_{n+1}) + h^2 kappa a_n),
//   kappa = 1/2 - beta - beta (1 - gamma) / gamma,   v* = alpha_f v_n + (1 - alpha_f) v_{n+1},
//
// the velocity-implicit step of velocity_step.h with a weight, an
// inertial centre and an offset: solved by the same Newton (minimizing the
// same kind of incremental potential where the forces derive from one).
// With beta = 0 (the central difference) x_{n+1} is explicit, and so is the
// step when F does not depend on v.
//
// On the undamped oscillator (Hughes 9.1): second order iff
// gamma = 1/2 + alpha_f - alpha_m; unconditionally stable iff
// alpha_m <= alpha_f <= 1/2 and beta >= 1/4 + (alpha_f - alpha_m)/2;
// with gamma = 1/2, alpha's 0, stable for w h <= 1 / sqrt(gamma/2 - beta).
// gamma > 1/2 damps (first order); the alpha methods damp the high modes
// while staying second order.
#pragma once

#include <string>
#include <vector>

#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

struct NewmarkParameters {
  double alpha_m = 0.0, alpha_f = 0.0, beta = 0.25, gamma = 0.5;
};

// Chung and Hulbert's parameters from the spectral radius at infinity
// (1993, eqs. 25-27): alpha_m = (2 rho - 1)/(rho + 1), alpha_f = rho/(rho + 1),
// gamma = 1/2 - alpha_m + alpha_f, beta = (1 - alpha_m + alpha_f)^2 / 4.
NewmarkParameters generalized_alpha_parameters(double rho_inf);
// Hilber-Hughes-Taylor (1977) for alpha in [-1/3, 0]: alpha_f = -alpha,
// gamma = (1 - 2 alpha)/2, beta = (1 - alpha)^2 / 4; rho_inf = (1 + alpha)/(1 - alpha).
NewmarkParameters hht_parameters(double alpha);

// The overshoot of a parameter set (Integrator::overshoot_steps; Hilber and
// Hughes, "Collocation, dissipation and 'overshoot' for time integration
// schemes in structural dynamics", Earthquake Eng. Struct. Dyn. 6, 1978):
// on the undamped oscillator at w h = 1e3, the step of the largest energy
// E_k = (v_k^2 + w^2 x_k^2) / 2 over starts of every phase, when it exceeds
// E_0 (by 1e-6 relative); 0 when no start's energy rises, or when the set
// is not unconditionally stable (its energy then grows at large w h for
// good). Measured by the scalar recurrence of the header's three
// equations: hht-alpha at alpha -0.1 peaks at step 5 (x343 at w h = 1e3,
// x3.4e4 at 1e4: the energy grows like (w h)^2), generalized-alpha at
// rho_inf 0.5 at step 1 (x3.9e3 at w h = 1e3, x3.9e5 at 1e4), newmark's
// average acceleration never (0).
int newmark_overshoot_steps(const NewmarkParameters& p);

class NewmarkFamily : public VelocityImplicitMethod {
 public:
  std::vector<std::string> options_read() const override;

  // The parameters a run with `options` uses (the method's own where an
  // option is not given).
  virtual NewmarkParameters parameters(const IntegratorOptions& options) const = 0;
  // newmark_overshoot_steps of the run's parameters.
  int overshoot_steps() const override { return overshoot_; }

 protected:
  using VelocityImplicitMethod::VelocityImplicitMethod;
  StepResult do_initialize() override;
  StepResult do_step(double h) override;
  // The options this method takes beyond Newton's (e.g. "beta", "gamma").
  virtual std::vector<std::string> parameter_options() const { return {}; }

 private:
  StepResult explicit_step(double h);
  // The implicit step (the header's); on failure the state is unchanged.
  StepResult implicit_step(double h);

  NewmarkParameters p_;
  int overshoot_ = 0;
  Vector a_;  // a_n: the algorithmic acceleration
  Vector v_c_, x_o_, v_new_, f_;
};

}  // namespace springlab
