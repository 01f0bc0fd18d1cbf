// Is a step's answer a minimizer of its incremental potential? (issue 38,
// finding 2: backward Euler gaining energy while "completed").
//
// Where every force derives from a potential, a velocity-implicit step
// minimizes (velocity_step.h)
//
//   Phi(v) = |v - v_c|^2_M / 2 + (w / b) V(x*(v)) + (h w / c) W(v*(v)),
//
// and for backward Euler Phi(0) = |v_n|^2_M / 2 + V(x_n) is the energy the
// step starts with: a minimizer v* has Phi(v*) <= Phi(0), so
// V(x_{n+1}) + |v_{n+1} - v_n|^2_M / 2 <= K_n + V_n (Kane et al. 2000; for a
// convex V also K_{n+1} + V_{n+1} <= K_n + V_n). Two feasible states are
// known before the solve: v_n (Newton's start) and v_kept, the v that keeps
// the stage at x_n (a v_n + b v = 0, minus the position offset: v = 0 for
// backward Euler). An answer v whose Phi lies above the lower of the two by
// more than the solve can resolve is no minimizer -- a point where the
// iteration stopped, or a higher stationary point -- and not a solution of
// the step.
//
// What the solve resolves. With the stopping tolerance tol on the error of
// v (max norm, m/s; at least v's round-off), Phi's quadratic model at v*
// gives
//   Phi(v) - Phi(v*) ~ r(v).(v - v*) / 2 <= ||r(v)||_1 tol / 2,
// r = grad Phi, evaluated at the answer, and the kinetic energy of a
// velocity error of tol, tol^2 sum(m) / 2: no check can see below it (a
// turned neo-Hookean block at rest: Phi 1.4e-15 J -> 3.6e-15 J, round-off
// of the stored energy's terms mu W ~ 300 J inside each element, against
// tol^2 sum(m) / 2 = 4e-8 J). (Half the bound convexity gives,
// r.(v - v*): with it, block n=3 at poisson 0.49999999999 took an L-BFGS
// answer that raised its energy from 52 J to 318 J); plus Phi's own round-off,
// kRoundoff x the magnitudes of the terms compared: those of the lower
// guess, of v_kept (the answer's terms carry the round-off of the kinetic
// energy v_kept holds: a strain-free spin has Phi(v_n) ~ 1e-29 J against
// K_n ~ 1 J), and of the answer. The magnitude of v_n when it is not the
// lower guess is left out: on one near-incompressible tetrahedron
// (lambda ~ 3e20 Pa) v_n's stage is strained, Phi(v_n) = 1e14 J, and its
// round-off (2e4 J) hid answers 160 J above Phi(v_kept) = 3 J.
//
// Backward Euler on a conservative system (no velocity-dependent force)
// asks more of L-BFGS's answers: its minimizer loses energy where V is
// convex (K_{n+1} + V_{n+1} + |v_{n+1} - v_n|^2_M / 2 <= K_n + V_n), and an
// answer whose Phi is low may still gain it (one near-incompressible
// tetrahedron at 1 ms: Phi(v) far below Phi(0) every step while its
// energy rose from 3 J to 134 J in 95 steps, its volume's strain never
// resolved). Its energy H(v) = |v|^2_M / 2 + V(x_n + h v) must not exceed
// H_n = Phi(0) by more than the tolerance resolves, grad H = M v_n + r:
// (||M v_n||_1 + ||r||_1) tol / 2. A refused L-BFGS answer only hands the step
// to Newton; where V is not convex Newton may take a step that L-BFGS's
// would have matched.
//
// Newton's own start needs no check: its line search makes Phi fall from
// there (to round-off), and near the start's potential the stored energy's
// round-off is not that of Phi's parts (a turned neo-Hookean block at rest:
// 2.3e-14 J against terms of mu W ~ 300 J inside each element). So Newton's
// answer is judged against v_kept only, and only where v_kept lies lower
// than v_n by more than round-off and tol^2 sum(m) / 2; L-BFGS, which
// starts elsewhere, against the lower of the two.
#pragma once

#include <string>

#include "integrators/velocity_step.h"

namespace springlab {

class IncrementalPotentialCheck {
 public:
  // Before the solve of the step begun in `step`: Phi at the two guesses
  // when the step minimizes Phi (has_potential, not the discrete gradient).
  // `quasi_newton`: L-BFGS solves the step first (its answers are judged
  // always; Newton's only where judges_newton()).
  void begin(VelocityStep& step, bool quasi_newton, double tol);
  // Whether Newton's answers are judged in this step: v_kept lies lower
  // than Newton's start by more than round-off.
  bool judges_newton() const { return judges_newton_; }
  // v_kept (after begin(), where judges_newton()): Newton's second start.
  const Vector& kept() const { return v_kept_; }
  // After the solve: "" when v is accepted; otherwise the potentials, as
  // "raised the incremental potential from A J to B J (more than the C J
  // the tolerance leaves)". `tol`: the solve's stopping tolerance (m/s); `r`
  // scratch for the residual. `energy`: also backward Euler's energy test
  // (L-BFGS's answers, where it applies).
  std::string judge(VelocityStep& step, const Vector& v, double tol, Vector& r,
                    bool energy = false) const;

 private:
  bool active_ = false, judges_newton_ = false, judges_energy_ = false;
  double phi_start_ = 0.0, phi_kept_ = 0.0, noise_scale_ = 0.0, resolution_ = 0.0;
  Vector v_kept_;
};

}  // namespace springlab
