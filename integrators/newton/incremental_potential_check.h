// Is a step's answer a minimizer of its incremental potential? (issue 38,
// finding 2: backward Euler gaining energy while "completed").
//
// Where every force derives from a potential, a velocity-implicit step
// minimizes (velocity_step.h)
//
//   Phi(v) = |v - v_c|^2_M / 2 + (w / b) V(x*(v)) + (h w / c) W(v*(v)).
//
// Two feasible states are known before the solve: v_n (Newton's start) and
// v_kept, the v that keeps the stage at x_n (a v_n + b v = 0, minus the
// position offset; v = 0 for backward Euler, where Phi(0) = K_n + V_n, the
// energy the step starts with). A minimizer lies no higher than the lower
// of the two; an answer above it by more than the solve resolves is no
// solution (a point where the iteration stopped short, or a higher
// stationary point).
//
// Backward Euler on a conservative system (no velocity-dependent force)
// asks more: where V is convex its minimizer loses energy,
// K_{n+1} + V_{n+1} + |v_{n+1} - v_n|^2_M / 2 <= K_n + V_n (from the step's
// equations and V_n >= V_{n+1} + grad V_{n+1} . (x_n - x_{n+1})), and a low
// Phi does not keep the energy from rising (one near-incompressible
// tetrahedron at 1 ms with L-BFGS: Phi far below Phi(0) every step while
// its energy rose from 3 J to 134 J). So its energy
// H(v) = |v|^2_M / 2 + V(x_n + h v) must not exceed H_n = Phi(0) either.
//
// What the solve resolves, where Phi (or H) rose beyond the round-off of
// the compared terms (kRoundoff x their magnitudes: those of the lower
// guess, of v_kept -- the answer's terms carry the round-off of the kinetic
// energy v_kept holds: a strain-free spin has Phi(v_n) ~ 1e-29 J against
// K_n ~ 1 J -- and of the answer; v_n's left out where it is not the lower:
// on the tetrahedron (lambda ~ 3e20 Pa) Phi(v_n) = 1e14 J, whose round-off
// hid answers 160 J above Phi(v_kept) = 3 J):
//   - Newton's next update d = H^-1 r at the answer (H the definite Newton
//     matrix, r = grad Phi) estimates the error v - v*. Where ||d||_inf is
//     within the tolerance tol (m/s), Phi(v) - Phi(v*) ~ r.d / 2 (Phi's
//     quadratic model; twice that allowed), and H's error (grad H =
//     M v_n + r) about (M v_n + r).d. Where it is not, v is no answer to the
//     tolerance. (The bound ||r||_1 tol / 2 does not do: a direction the
//     matrix makes stiff has a large r but a small error, and on the
//     tetrahedron it allowed 5e4 J to an answer 2,600 J above its start.)
//   - where Phi (or H) rose beyond the compared terms' round-off, that of
//     the stored energy's own terms, which its sum hides where they cancel
//     (VelocityStep::stored_magnitude, at the answer and at v_kept): a
//     cantilever's static step rose by 1.4e-13 J on -0.246 J under one
//     BLAS kernel (issue 46.15), 600 units of round-off of the sum but 2.5
//     of its terms' (+-25 J of gravity);
//   - the kinetic energy of a velocity error of tol, tol^2 sum(m) / 2: no
//     check can see below it (a turned neo-Hookean block at rest: Phi
//     1.4e-15 J -> 3.6e-15 J, the round-off of the stored energy's terms of
//     mu W ~ 300 J inside each element, against 4e-8 J).
// The matrix and its solve are paid only where the answer rose beyond
// round-off, which on the built-in scenes of the trajectory digest changes
// no result.
#pragma once

#include <string>

#include "integrators/newton/velocity_step.h"

namespace springlab {

class IncrementalPotentialCheck {
 public:
  // Before the solve of the step begun in `step`: Phi at the two guesses
  // when the step minimizes Phi (has_potential, and `solved_as_is`: Newton
  // solves the step itself, not a method's problem around it, such as the
  // discrete gradient's). `tol`: the solve's tolerance (m/s).
  void begin(VelocityStep& step, double tol, bool solved_as_is);
  // Whether this step's answers are judged (it minimizes Phi).
  bool active() const { return active_; }
  // v_kept (after begin(), where active()): Newton's second start.
  const Vector& kept() const { return v_kept_; }
  // After the solve: "" when v is accepted; otherwise the potentials, as
  // "raised the incremental potential from A J to B J (more than the C J
  // the tolerance leaves)". `tol`: the solve's stopping tolerance (m/s); `r`
  // scratch for the residual; `linear` solves with the definite Newton
  // matrix at v, only where Phi (or H) rose beyond round-off.
  std::string judge(VelocityStep& step, const Vector& v, double tol, Vector& r,
                    NewtonLinearSolver& linear);

 private:
  // Phi at v_kept and v_n (phi_kept_, phi_start_ the lower, noise_scale_);
  // false where Phi(v_kept) is not finite (nothing to compare with).
  bool start_potentials(VelocityStep& step);

  bool active_ = false, judges_energy_ = false;
  long follows_ = 0;  // VelocityStep::follows() when the above were taken
  double phi_start_ = 0.0, phi_kept_ = 0.0, noise_scale_ = 0.0, resolution_ = 0.0;
  Vector v_kept_, d_;
};

}  // namespace springlab
