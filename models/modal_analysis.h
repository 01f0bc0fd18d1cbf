// Natural frequencies of a model linearized at a state: the eigenvalues
// w^2 of M^-1 K, K = -dF/dx (symmetric part). The largest, w_max, sets every
// explicit method's stability limit (2/w_max for symplectic Euler and
// Verlet, 2 sqrt 2/w_max for RK4): the course's "explicit solvers don't work
// so well on springs" in one number.
#pragma once

#include "models/mass_spring_model.h"

namespace springlab {

// w_max in rad/s at (x, v), t = 0. Dense symmetric eigensolver up to 3000
// unknowns, power iteration on M^-1/2 K M^-1/2 above. 0 when K has no
// positive eigenvalue.
double max_angular_frequency(const MassSpringModel& model, const Vector& x, const Vector& v);
inline double max_angular_frequency(const MassSpringModel& model) {
  return max_angular_frequency(model, model.initial_positions(), model.initial_velocities());
}

}  // namespace springlab
