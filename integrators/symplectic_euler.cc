#include "integrators/symplectic_euler.h"

namespace springlab {

SymplecticEuler::SymplecticEuler()
    : Integrator({.name = "symplectic-euler",
                  .scheme = "v' = v + h M^-1 F(t, x, v),  x' = x + h v'",
                  .order = 1,
                  .symplectic = true,
                  .stability_limit = 2.0}) {}

StepResult SymplecticEuler::do_step(double h) {
  eval_acceleration(t_, x_, v_, a_);
  v_ += h * a_;
  x_ += h * v_;
  return StepResult::success();
}

}  // namespace springlab
