// rk4 — the classic fourth-order Runge-Kutta method on y = (x, v),
// y' = f(t, y) = (v, M^-1 F(t, x, v)):
//
//   k1 = f(t, y), k2 = f(t + h/2, y + h/2 k1), k3 = f(t + h/2, y + h/2 k2),
//   k4 = f(t + h, y + h k3),   y_{n+1} = y_n + h/6 (k1 + 2 k2 + 2 k3 + k4)
//
// Order 4, four force evaluations per step. R(z) = 1 + z + z^2/2 + z^3/6 +
// z^4/24; on the undamped oscillator |R(i w h)| <= 1 exactly for
// w h <= 2 sqrt(2), so it is stable up to there, with a small energy loss
// per step (|R|^2 < 1) below it.
#pragma once

#include "integrators/core/integrator.h"

namespace springlab {

class RungeKutta4 final : public Integrator {
 public:
  RungeKutta4();

 protected:
  StepResult do_step(double h) override;

 private:
  // Stage state (xs_, vs_), the last force, and the running weighted sums
  // of the stage velocities and accelerations.
  Vector xs_, vs_, f_, sum_v_, sum_a_;
};

}  // namespace springlab
