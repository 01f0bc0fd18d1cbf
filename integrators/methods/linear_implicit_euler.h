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
//
// --stiffness (IntegratorOptions::stiffness): K exact (the default, as
// Baraff and Witkin), or its definite part (Choi and Ko, "Stable but
// responsive cloth", 2002: each compressed spring's negative transverse
// stiffness k (1 - L/l) dropped), used in the matrix and the right-hand side
// alike. A compressed spring's negative stiffness makes M - h^2 K smaller
// than M along its sideways direction (indefinite where it outweighs the
// mass over the step), and the linear step can amplify such a motion from
// step to step: on a folding cloth at a frame step the energy starts to
// alternate with growing amplitude until the run blows up (the step-energy
// experiment). The definite matrix is at least M. Solved by LDL^T (exact: the matrix may be
// indefinite) or by CG preconditioned by a kept Cholesky factor (definite;
// newton_linear_solver.h).
#pragma once

#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

class LinearImplicitEuler final : public VelocityImplicitMethod {
 public:
  LinearImplicitEuler();
  std::vector<std::string> options_read() const override { return {"stiffness"}; }

 protected:
  StepResult do_step(double h) override;

 private:
  Vector f0_, dv_;
};

}  // namespace springlab
