// implicit-euler — backward Euler, the course's method (lecture eq. 12):
//
//   v_{n+1} = v_n + h M^-1 F(t_{n+1}, x_{n+1}, v_{n+1})
//   x_{n+1} = x_n + h v_{n+1}
//
// Substituting x_{n+1} leaves a nonlinear system in v_{n+1} alone, solved by
// Newton-Raphson with a line search to --newton-tol (at most --max-newton
// iterations) using J = M - h dF/dv - h^2 dF/dx and a sparse direct solver
// (newton_velocity_solver.h). A Newton failure ends the run as a result.
//
// Order 1. R(z) = 1 / (1 - z): A-stable and L-stable; on the undamped
// oscillator the energy shrinks by 1 / (1 + w^2 h^2) every step — artificial
// damping that grows with h.
#pragma once

#include "integrators/newton_velocity_solver.h"

namespace springlab {

class ImplicitEuler final : public ImplicitIntegrator {
 public:
  ImplicitEuler();

 protected:
  StepResult do_step(double h) override;

 private:
  Vector v_new_;
};

}  // namespace springlab
