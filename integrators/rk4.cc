#include "integrators/rk4.h"

#include <cmath>

namespace springlab {

RungeKutta4::RungeKutta4()
    : Integrator({.name = "rk4",
                  .scheme = "y' = y + h/6 (k1 + 2 k2 + 2 k3 + k4)",
                  .order = 4,
                  .stability_limit = 2.0 * std::sqrt(2.0),
                  .stability_function = [](std::complex<double> z) {
                    return 1.0 + z * (1.0 + z / 2.0 * (1.0 + z / 3.0 * (1.0 + z / 4.0)));
                  }}) {}

StepResult RungeKutta4::do_step(double h) {
  // Stage k_s = (v_s, a_s); position increments use the stage velocities.
  const Vector& v1 = v_;
  eval_acceleration(t_, x_, v1, a1_);

  xs_ = x_ + 0.5 * h * v1;
  v2_ = v_ + 0.5 * h * a1_;
  eval_acceleration(t_ + 0.5 * h, xs_, v2_, a2_);

  xs_ = x_ + 0.5 * h * v2_;
  v3_ = v_ + 0.5 * h * a2_;
  eval_acceleration(t_ + 0.5 * h, xs_, v3_, a3_);

  xs_ = x_ + h * v3_;
  v4_ = v_ + h * a3_;
  eval_acceleration(t_ + h, xs_, v4_, a4_);

  x_ += (h / 6.0) * (v1 + 2.0 * v2_ + 2.0 * v3_ + v4_);
  v_ += (h / 6.0) * (a1_ + 2.0 * a2_ + 2.0 * a3_ + a4_);
  return StepResult::success();
}

}  // namespace springlab
