// Natural frequencies of a model linearized at a state: the eigenvalues
// w^2 of M^-1 K, K = -dF/dx (symmetric part). The largest, w_max, sets every
// explicit method's stability limit (2/w_max for symplectic Euler and
// Verlet, 2 sqrt 2/w_max for RK4): the course's "explicit solvers don't work
// so well on springs" in one number.
//
// With damping the modes are the eigenvalues lambda of the first-order
// system y = (x, v), y' = J y, J = [[0, I], [M^-1 K, M^-1 D]] (K = dF/dx,
// D = dF/dv): lambda = +-i w for an undamped mode, Re lambda < 0 for a damped
// one. A one-step method whose step is R(h J) is stable when every h lambda
// lies in its stability region |R(z)| <= 1.
#pragma once

#include <complex>
#include <vector>

#include "models/model/model.h"

namespace springlab {

// w_max in rad/s at (x, v), t = 0. Dense symmetric eigensolver up to
// `dense_up_to` unknowns (its cost grows as n^3; the lab page asks for less),
// power iteration on M^-1/2 K M^-1/2 above. 0 when K has no positive
// eigenvalue.
inline constexpr Eigen::Index kDenseFrequencyUnknowns = 3000;
double max_angular_frequency(const Model& model, const Vector& x, const Vector& v,
                             Eigen::Index dense_up_to = kDenseFrequencyUnknowns);
inline double max_angular_frequency(const Model& model,
                                    Eigen::Index dense_up_to = kDenseFrequencyUnknowns) {
  return max_angular_frequency(model, model.initial_positions(), model.initial_velocities(),
                               dense_up_to);
}

// The eigenvalues of J at (x, v), t = 0, in a fixed order: by |lambda|, then
// by imaginary part (a conjugate pair: negative first). Dense eigensolver;
// throws std::invalid_argument above kMaxFirstOrderUnknowns unknowns (2 n).
inline constexpr int kMaxFirstOrderUnknowns = 4000;
std::vector<std::complex<double>> first_order_eigenvalues(const Model& model,
                                                          const Vector& x, const Vector& v);

// The slowest vibration mode at (x, v), t = 0: the smallest eigenvalue w^2
// of M^-1 K (K the symmetric part of -dF/dx) and its shape phi, normalized
// so that phi^T M phi = 1, with the sign that makes its largest component
// positive. Dense symmetric eigensolver on M^-1/2 K M^-1/2; throws
// std::invalid_argument above kMaxModeUnknowns unknowns (about 10 s). w is 0 when the
// smallest eigenvalue is not positive (a free body has rigid modes).
inline constexpr int kMaxModeUnknowns = 1500;
struct Mode {
  double w = 0.0;  // rad/s
  Vector phi;      // one entry per unknown
};
Mode lowest_mode(const Model& model, const Vector& x, const Vector& v);

}  // namespace springlab
