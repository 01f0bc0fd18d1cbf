// Newton's matrix policy and its fallbacks (newton_loop.h): which matrix
// an update is computed with, which merit the line search asks to fall, how
// accurately the update is solved, and what to try when an update fails.
//
// The matrix. Where Newton minimizes a potential, compressed springs make
// its Hessian J indefinite and an update of it may not descend. The
// alternating policy (the default) uses the exact J after a full update
// (quadratic convergence near the solution) and the definite part of J
// (each compressed spring's negative transverse stiffness dropped:
// MechanicalSystem::definite_jacobians), positive definite, whose update
// always descends, after an update that needed a line search or did not
// descend. The definite policy ("projected Newton") uses the definite
// matrix throughout: linear convergence, but no alternation between long
// exact updates cut back by the search and definite ones near a buckling
// state (velocity_implicit_method.h: the step's second attempt). Where J is
// not symmetric (spring damping) it is exact throughout.
//
// The fallbacks, from the same iterate:
//   - an update that does not descend the potential: the definite matrix;
//   - a failed search on the potential: the definite matrix;
//   - a failed search on ||r|| (no potential): an accurate linear solve (a
//     true Newton update, which descends ||r||), then the definite matrix.
// None left: Newton fails with a message.
#pragma once

#include "integrators/newton/newton_problem.h"

namespace springlab {

// What the next update is.
struct NewtonMode {
  bool minimize = false;  // the merit is the potential (else ||r||)
  bool definite = false;  // of the definite matrix
  bool careful = false;   // an accurate linear solve (a true Newton update)
};

// The iterate, the loop's: v, r(v), and Phi(v) with its round-off scale.
struct NewtonIterate {
  Vector& v;
  Vector& r;
  double& phi;
  double& magnitude;
};

class NewtonPolicy {
 public:
  enum class Matrices { kAlternating, kDefinite };
  NewtonPolicy(Matrices matrices, bool symmetric)
      : definite_only_(matrices == Matrices::kDefinite), symmetric_(symmetric) {}
  virtual ~NewtonPolicy() = default;

  // Before the first residual: the first update's mode.
  virtual void start(bool has_potential, NewtonMode& mode);
  // Before each update (after a fallback too).
  virtual void begin_iteration(NewtonMode& /*mode*/, NewtonIterate& /*it*/) {}
  // The update does not descend the potential: true to compute another
  // from the same iterate with `mode` changed.
  virtual bool retry_not_descending(NewtonMode& mode);
  // The line search failed: true to compute another update from the same
  // iterate (r recomputed at it).
  virtual bool retry_search_failed(NewtonMode& mode, NewtonProblem& problem, NewtonIterate& it);
  // A step of alpha times the update was taken.
  virtual void step_taken(NewtonMode& mode, double alpha);

 protected:
  const bool definite_only_;
  const bool symmetric_;
};

}  // namespace springlab
