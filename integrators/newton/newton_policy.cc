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

void DiscreteGradientPhases::start(bool has_potential, NewtonMode& mode) {
  NewtonPolicy::start(has_potential, mode);
  has_potential_ = has_potential;
  newton_phase_ = false;
  step_.freeze(mode.minimize);
  step_.set_frozen_coefficient(0.0);
}

void DiscreteGradientPhases::begin_iteration(NewtonMode& mode, NewtonIterate& it) {
  if (has_potential_) {
    mode.minimize = !newton_phase_;
    step_.freeze(mode.minimize);
    mode.careful = mode.careful || newton_phase_;
  }
  // The coefficient at this v: the potential and r of the next iterations
  // use it.
  step_.update_frozen(it.r, it.phi);
}

bool DiscreteGradientPhases::retry_not_descending(NewtonMode& mode) {
  if (NewtonPolicy::retry_not_descending(mode)) return true;
  if (!step_.frozen()) return false;
  newton_phase_ = true;  // the frozen potential is only a guide: Newton on r
  return true;
}

bool DiscreteGradientPhases::retry_search_failed(NewtonMode& mode, NewtonProblem& problem,
                                                 NewtonIterate& it) {
  if (!newton_phase_) return NewtonPolicy::retry_search_failed(mode, problem, it);
  // Back to the frozen potential, from v.
  newton_phase_ = false;
  mode.careful = false;
  step_.refreeze_at(it.v, it.r);
  it.phi = step_.potential(it.v, it.magnitude);
  return true;
}

void DiscreteGradientPhases::step_taken(NewtonMode& mode, double alpha) {
  if (has_potential_ && !newton_phase_ && alpha == 1.0 && !mode.definite) newton_phase_ = true;
  NewtonPolicy::step_taken(mode, alpha);
}

}  // namespace springlab
