// explicit-euler — forward Euler.
//
//   x_{n+1} = x_n + h v_n
//   v_{n+1} = v_n + h M^-1 F(t_n, x_n, v_n)
//
// Order 1. Stability function R(z) = 1 + z. On the undamped oscillator
// (z = i w h) |R|^2 = 1 + w^2 h^2 > 1: the energy grows by that factor every
// step, at every step size. It is never stable without damping; how soon it
// blows up shrinks with the simulated time.
#pragma once

#include <memory>

#include "integrators/core/integrator.h"

namespace springlab {

class ExplicitEuler final : public Integrator {
 public:
  ExplicitEuler();

 protected:
  StepResult do_step(double h) override;

 private:
  Vector a_;
};

}  // namespace springlab
