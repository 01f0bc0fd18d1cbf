// What Newton's loop (newton_loop.h) is given to solve: a system of
// equations r(v) = 0 with its matrix J = dr/dv, and, where r is the
// gradient of a potential Phi (r = grad Phi, J its Hessian), that potential,
// which Newton then minimizes. A velocity-implicit step is one
// (velocity_step.h); a residual that is no gradient is solved alike, with
// ||r|| as the line search's merit.
#pragma once

#include <limits>

#include "integrators/newton/newton_linear_solver.h"

namespace springlab {

class NewtonProblem {
 public:
  virtual ~NewtonProblem() = default;

  // Where the iteration starts (the step's v_n); ||start||_inf also sets
  // the scale of v's round-off.
  virtual const Vector& start() const = 0;
  // The velocity whose effect on the states the forces are evaluated at is
  // one unit of their round-off: ||x_n||_inf / (h |b|) for a stage
  // x_n + h b v (velocity_step.h). An update below round-off units of it
  // moves no position by more than round-off, so the loop stops there
  // whatever its tolerance (newton_loop.cc). 0: none.
  virtual double position_resolution() const { return 0.0; }
  // Another start, where r(start()) is not finite (a state with no
  // energy); false when there is none.
  virtual bool fallback_start(Vector& v) const = 0;
  // A start whose state is the one the last step accepted, where the
  // fallback's is not either (BDF2's extrapolated stage through a
  // barrier's gap); false when there is none.
  virtual bool accepted_start(Vector& /*v*/) const { return false; }

  // r(v). potential(), matrix() and allowed() then refer to this v.
  virtual void residual(const Vector& v, Vector& r) = 0;
  // Whether r is the gradient of a potential.
  virtual bool has_potential() const = 0;
  // Phi at the v of the last residual(), and the sum of its parts'
  // magnitudes (its round-off scale).
  virtual double potential(const Vector& v, double& magnitude) = 0;
  // J(v), or the matrix of the definite Jacobians, into linear.matrix().
  virtual void matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) = 0;

  // A rank-one term u z^T of J beyond linear.matrix(), from the last
  // matrix(); nullptr when there is none (newton_loop.cc: Sherman-Morrison).
  struct RankOne {
    const Vector* u = nullptr;
    const Vector* z = nullptr;
  };
  virtual RankOne rank_one() const { return {}; }

  // States with no energy (a barrier's closed gap): the line search keeps
  // out of them (line_search.h).
  virtual bool has_forbidden_states() const { return false; }
  // The fraction of dv from v at which the first such state is reached
  // (+infinity: none).
  virtual double admissible_fraction(const Vector& /*v*/, const Vector& /*dv*/) {
    return std::numeric_limits<double>::infinity();
  }
  // The fraction of dv from v beyond which an update moves some part of
  // the state further than the problem's trust region (+infinity: none;
  // MechanicalSystem::trusted_fraction): the line search starts there.
  virtual double trusted_fraction(const Vector& /*v*/, const Vector& /*dv*/) {
    return std::numeric_limits<double>::infinity();
  }
  // Whether the v of the last residual() is allowed beyond r being finite.
  virtual bool allowed() { return true; }
  // The iteration has moved to v (an iterate the line search accepted): a
  // problem whose equations are set up around where the iteration is (the
  // contacts a step keeps, found again there) sets them up around v. True
  // when r and Phi changed (the loop then evaluates them again at v); never
  // where v would then leave the allowed states.
  virtual bool follow(const Vector& /*v*/) { return false; }
};

}  // namespace springlab
