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
//
// The step writes (x_{n+1}, v_{n+1}) into the buffers of the step before
// and keeps (t_n, x_n, v_n) as its PreviousState (integrator.h): the run
// driver needs no copy of each good state.
#pragma once

#include "integrators/integrator.h"

namespace springlab {

class SymplecticEuler final : public Integrator {
 public:
  SymplecticEuler();
  const PreviousState* previous_state() const override { return &start_; }

 protected:
  StepResult do_step(double h) override;

 private:
  Vector f_;
  PreviousState start_;  // (t_n, x_n, v_n) of the last step
};

}  // namespace springlab
