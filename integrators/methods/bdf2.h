// bdf2 — the two-step backward differentiation formula as cloth codes use
// it (Choi and Ko, "Stable but responsive cloth", SIGGRAPH 2002), applied to
// both halves of the state:
//
//   x_{n+1} = x_n + c0 (x_n - x_{n-1}) + b h v_{n+1}
//   v_{n+1} = v_n + c0 (v_n - v_{n-1}) + b h M^-1 F(t_{n+1}, x_{n+1}, v_{n+1})
//
// with the variable-step coefficients of the ratio w = h_n / h_{n-1}:
// c0 = w^2 / (1 + 2 w), b = (1 + w) / (1 + 2 w) (w = 1: the familiar
// x_{n+1} = 4/3 x_n - 1/3 x_{n-1} + 2/3 h v_{n+1}). The first step is one
// implicit Euler step. Each step is the velocity-implicit system of
// velocity_step.h with weight b, inertial centre
// v_n + c0 (v_n - v_{n-1}) and offset c0 (x_n - x_{n-1}): where the forces
// derive from potentials, the minimum of an incremental potential, solved by
// the same Newton as implicit Euler (--newton-tol, --max-newton).
//
// A step whose Newton fails is solved again in 2, 4 or 8 substeps
// (VelocityImplicitMethod::retry_in_substeps, a run warning), each a step
// of the same variable-step formula: the first of the ratio (h/n) / h_n-1
// (1/n on a uniform grid; on a run's first step, implicit Euler), the rest
// of 1. The history is then set back on the grid of h, (x_n, v_n) before
// (x_n+1, v_n+1), so that the next step is again of the ratio 1 (a jump of
// the ratio to n = 8 would extrapolate with c0 = 64/17). At 1/60 s on the
// default dam break Newton can fail at the impact on the far wall,
// converging only linearly at a rate near 1 (in one build with --dt
// 0.0166667, at t = 0.30 s; not with --dt 0.016666666666666666): that
// step is then solved in substeps.
//
// Order 2. L-stable (A-stable, and the roots of its characteristic
// polynomial go to 0 as w h -> infinity), with less damping of the low
// modes than implicit Euler at the same step.
#pragma once

#include <string>
#include <vector>

#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

class Bdf2 final : public VelocityImplicitMethod {
 public:
  Bdf2();

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  // One step of the formula above from the history as it is. When it
  // fails, the state and the history are as they were.
  StepResult formula_step(double h);

  // The previous step: its start (x, v) and its size h.
  struct History {
    bool have = false;
    Vector x, v;
    double h = 0.0;
  };
  History previous_;
  // At a step solved in substeps: previous_ then, and the step's start.
  History kept_, start_;
  Vector v_c_, x_o_, v_new_;
};

}  // namespace springlab
