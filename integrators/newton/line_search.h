// Newton's line search (newton_loop.h): along the update dv from v, a step
// alpha dv whose trial v + alpha dv is accepted by the merit:
//   - on a potential Phi, Armijo's sufficient decrease: Phi falls by
//     kArmijo = 1e-4 of its first-order prediction alpha r.dv (Nocedal and
//     Wright, "Numerical Optimization", 2006, eq. 3.4); below Phi's
//     round-off, ||r|| must fall instead;
//   - on a plain residual, ||r|| falls by kArmijo alpha of itself.
// Backtracking halves alpha from the full step; with a descent direction
// of the potential and the definite matrix it cannot fail but to
// round-off (alpha down to 1e-12), otherwise it gives up at 1/1024 (the
// policy then tries another matrix: newton_policy.h).
//
// The step cap (IPC, Li et al. 2020): where a barrier forbids states, the
// search starts at kGapCap = 0.9 of the fraction of dv at which the first
// gap would close, instead of finding the closed gap by halving.
//
// The trust region (NewtonProblem::trusted_fraction: a fluid's water
// particles move at most h/2 per update, docs/physics.md "Implicit steps
// on a fluid"): the search starts at most at the fraction of dv that keeps
// every particle within it, halves from there (down to that fraction times
// the search's own floor), and a longer step along negative curvature
// stops there too.
//
// Negative curvature. Where CG stopped at its first product (dv is a
// direction along which the potential curves down: a saddle of Phi, a
// buckling cloth), the step's equations have solutions of lower Phi nearby:
// the search doubles the step while Phi keeps falling (up to kMaxEscape =
// 10 m/s), also from an update below the tolerance. Where the step's
// equations have several solutions, Newton thus prefers the lower potential.
#pragma once

#include "integrators/newton/newton_problem.h"

namespace springlab {

class LineSearch {
 public:
  // The line: from v along dv, at r(v) with norm r_norm, Phi(v) = phi with
  // its round-off scale, slope r.dv (the potential's, where minimizing) and
  // ||dv||_inf = update.
  struct Line {
    const Vector& v;
    const Vector& dv;
    double r_norm, phi, magnitude, slope, update;
    bool minimize;
  };
  // The last trial (the accepted one after a search): v, r(v), Phi(v).
  struct Trial {
    Vector v, r;
    double phi = 0.0, magnitude = 0.0;
  };

  // A nonlinear solve's start.
  void reset() { trial_.magnitude = 0.0; }
  // A new update's line (the trial's Phi is not yet known).
  void begin_line() { trial_.phi = 0.0; }
  // Backtracking from the full step (or the step cap). True, with the
  // trial and alpha, when a step is accepted.
  bool search(NewtonProblem& problem, const Line& line, bool negative_curvature, bool definite,
              double& alpha);
  // Along a direction of negative curvature: longer steps, doubling from
  // alpha while the potential keeps falling (and not visibly rising: tiny
  // steps change it below its round-off). True, with the trial at the best
  // step and alpha, when the potential fell beyond its round-off.
  bool expand(NewtonProblem& problem, const Line& line, double& alpha);
  Trial& trial() { return trial_; }

 private:
  bool accept(NewtonProblem& problem, const Line& line, double alpha);
  double noise(const Line& line) const;

  Trial trial_;
};

}  // namespace springlab
