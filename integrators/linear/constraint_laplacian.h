// The Laplacian of distance constraints and projective elements: the
// stiffness part of projective dynamics' global matrix M + h^2 L and of
// quasi-Newton's initial Hessian (Liu et al. 2013, 2017). Linear algebra
// on the constraints a system hands out (models/core/fast_solver_views.h).
#pragma once

#include <vector>

#include "models/core/fast_solver_views.h"
#include "models/core/mechanical_system.h"

namespace springlab {

// The local/global matrix's stiffness part L = sum_c k_c (e_a - e_b)(e_a - e_b)^T
// (an anchored constraint: k_c on e_a's diagonal), particles x particles, with
// the full diagonal stored (M or contact terms are added to it in place):
// projective dynamics' global matrix M + h^2 L and quasi-Newton's initial
// Hessian (quasi_newton.cc).
SparseMatrix constraint_laplacian(const std::vector<DistanceConstraint>& constraints,
                                  Eigen::Index particles);
// The same with projective elements (projective dynamics): each adds
// w g_i . g_j to entry (i, j) of its free nodes i, j.
SparseMatrix constraint_laplacian(const std::vector<DistanceConstraint>& constraints,
                                  const std::vector<ProjectiveElement>& elements,
                                  Eigen::Index particles);

}  // namespace springlab
