// linear-implicit-euler — backward Euler with a single Newton step, the
// Baraff-Witkin cloth integrator ("Large steps in cloth simulation", 1998).
// F is linearized at the start of the step, F(x + dx, v + dv) ~ F0 + K dx + D dv
// with K = dF/dx, D = dF/dv at (t_{n+1}, x_n, v_n), and dx = h (v_n + dv):
//
//   (M - h D - h^2 K) dv = h (F0 + h K v_n)
//   v_{n+1} = v_n + dv,   x_{n+1} = x_n + h v_{n+1}
//
// One force evaluation, one Jacobian, one sparse solve per step; no
// iteration, so no convergence to fail. Order 1; identical to backward Euler
// on linear forces (R(z) = 1/(1 - z), A-stable), it damps the same way.
#pragma once

#include "integrators/newton_velocity_solver.h"

namespace springlab {

class LinearImplicitEuler final : public ImplicitIntegrator {
 public:
  LinearImplicitEuler();
  std::vector<std::string> options_read() const override { return {"stiffness"}; }

 protected:
  StepResult do_step(double h) override;

 private:
  Vector f0_, dv_;
};

}  // namespace springlab
