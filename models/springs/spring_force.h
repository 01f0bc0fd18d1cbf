// Hooke's law for one spring, written plainly: the reference the spring
// force term's blocked SIMD loop (spring_force.cc) is tested against, bit for
// bit (tests/test_model.cc).
#pragma once

#include <Eigen/Core>

namespace springlab {

// The force on end i of a spring (i, j) of stiffness k and rest length L:
//   d = x_i - x_j,  l = |d|,  u = d / l,   F_i = -k (l - L) u,   F_j = -F_i.
// Evaluated as -k (1 - L/l) d (the same value: (l - L) u = (1 - L/l) d), one
// division and one square root, exactly -k d when L = 0, and in the fast
// loop's order of operations so the two agree to the last bit. A spring of
// zero length has no direction: F = 0. `dim` (2 or 3) components are used.
Eigen::Vector3d hooke_force(const Eigen::Vector3d& x_i, const Eigen::Vector3d& x_j, double k,
                            double rest, int dim);

}  // namespace springlab
