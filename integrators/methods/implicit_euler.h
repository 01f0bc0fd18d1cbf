// implicit-euler — backward Euler, the course's method (lecture eq. 12):
//
//   v_{n+1} = v_n + h M^-1 F(t_{n+1}, x_{n+1}, v_{n+1})
//   x_{n+1} = x_n + h v_{n+1}
//
// Substituting x_{n+1} leaves a nonlinear system in v_{n+1} alone: where the
// forces derive from potentials, the condition for a minimum of the step's
// incremental potential |v - v_n|^2_M / 2 + V(x_n + h v) + h W(v). Solved by
// Newton-Raphson with J = M - h dF/dv - h^2 dF/dx, CG preconditioned by a
// kept Cholesky factor and a line search, to --newton-tol (m/s) in at most
// --max-newton iterations (newton_loop.h). A Newton failure ends
// the run as a result.
//
// --solver quasi-newton minimizes the same potential by L-BFGS with the
// local/global matrix as its initial Hessian (quasi_newton.cc).
//
// Order 1. R(z) = 1 / (1 - z): A-stable and L-stable; on the undamped
// oscillator the energy shrinks by 1 / (1 + w^2 h^2) every step — artificial
// damping that grows with h.
#pragma once

#include <string>
#include <vector>

#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

class ImplicitEuler final : public VelocityImplicitMethod {
 public:
  ImplicitEuler();
  std::vector<std::string> options_read() const override;

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  Vector v_new_;
};

}  // namespace springlab
