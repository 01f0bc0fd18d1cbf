// tr-bdf2 — a trapezoidal stage, then BDF2 through the stage (Bank, Coughran,
// Fichtner, Grosse, Rose and Smith, IEEE Trans. CAD 4, 1985; Hosea and
// Shampine, Appl. Numer. Math. 20, 1996), on y = (x, v), y' = (v, M^-1 F):
//
//   y_g     = y_n + g h/2 (f_n + f_g)                         (t_n + g h)
//   y_{n+1} = y_n + c1 (y_g - y_n) + w h f_{n+1},
//   g = 2 - sqrt(2),  c1 = 1 / (g (2 - g)),  w = (1 - g) / (2 - g).
//
// Both stages are velocity-implicit systems of velocity_step.h,
// solved by the same Newton as implicit Euler (--newton-tol, --max-newton).
// With this g both stages have the same Newton matrix M - (h w)^2 K for
// forces independent of v (g h / 2 = w h). Bathe's composite method (2005)
// is a member of this family.
//
// Order 2. L-stable: R(z) = (c1 R_T(g z) - (c1 - 1)) / (1 - w z), with the
// trapezoidal R_T(s) = (1 + s/2)/(1 - s/2), goes to 0 as |z| -> infinity.
#pragma once

#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

class TrBdf2 final : public VelocityImplicitMethod {
 public:
  TrBdf2();

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  Vector a_;  // f_n's acceleration half, M^-1 F at the step's start
  Vector v_c_, x_o_, v_g_, x_g_, v_new_;
};

}  // namespace springlab
