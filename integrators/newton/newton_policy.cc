#include "integrators/newton/newton_policy.h"

namespace springlab {

void NewtonPolicy::start(bool has_potential, NewtonMode& mode) {
  mode.minimize = has_potential;
  mode.definite = definite_only_ && symmetric_;
  mode.careful = false;
}

bool NewtonPolicy::retry_not_descending(NewtonMode& mode) {
  if (mode.definite) return false;
  mode.definite = true;
  return true;
}

bool NewtonPolicy::retry_search_failed(NewtonMode& mode, NewtonProblem& problem,
                                       NewtonIterate& it) {
  if (!mode.minimize && !mode.careful && symmetric_) {
    mode.careful = true;  // an accurate Newton update descends ||r||: retry with one
  } else if (!mode.definite && symmetric_) {
    mode.definite = true;  // its update descends: retry from the same v
  } else {
    return false;
  }
  problem.residual(it.v, it.r);  // the state of the residual at v again
  return true;
}

void NewtonPolicy::step_taken(NewtonMode& mode, double alpha) {
  // The definite matrix after a line search, the exact one after a full
  // update (quadratic convergence near the solution).
  if (symmetric_) mode.definite = alpha < 1.0 || definite_only_;
}

}  // namespace springlab
