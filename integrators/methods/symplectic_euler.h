// symplectic-euler — semi-implicit (symplectic) Euler: velocity first, then
// position with the new velocity.
//
//   v_{n+1} = v_n + h M^-1 F(t_n, x_n, v_n)
//   x_{n+1} = x_n + h v_{n+1}
//
// Order 1. Symplectic when F depends on x only: the energy is not conserved
// exactly but oscillates within O(h) of its initial value forever (a nearby
// "modified energy" is conserved). On the undamped oscillator it is stable
// for w h <= 2 (the step map's trace reaches -2 at w h = 2).
#pragma once

#include "integrators/core/integrator.h"

namespace springlab {

class SymplecticEuler final : public Integrator {
 public:
  SymplecticEuler();

 protected:
  StepResult do_step(double h) override;

 private:
  Vector f_;
};

}  // namespace springlab
