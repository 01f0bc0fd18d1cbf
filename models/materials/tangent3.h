// Pieces of the closed-form tangents dPdF of 3 x 3 deformation gradients
// (material.h: the tetrahedra's fast path), on vec(F) column-major (entry
// (r, c) of F at r + 3 c), so that dP = dPdF vec(dF). Each model writes its
// dPdF from these in its own file; the shared tests check every one against
// the dPdF assembled from its dP.
//
// With f_c the columns of F, J = det F = f0 . (f1 x f2) and
// g = dJ/dF = [f1 x f2, f2 x f0, f0 x f1] (kinematics.h), the Hessian of J
// is the 3 x 3 grid of 3 x 3 blocks ([a]x the cross-product matrix)
//   H_J = [[0, -[f2]x, [f1]x], [[f2]x, 0, -[f0]x], [-[f1]x, [f0]x, 0]]
// (block (c, c') = dg_c / df_c'), so that dg = H_J vec(dF). Smith et al.,
// "Analytic eigensystems for isotropic distortion energies", ACM TOG 2019,
// §4.2.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>        // determinant

#include "models/materials/kinematics.h"  // cofactor
#include "models/materials/material.h"

namespace springlab {

// vec(A): the columns of A stacked.
inline Eigen::Matrix<double, 9, 1> vec(const Eigen::Matrix3d& A) {
  return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(A.data());
}

// [a]x, with [a]x b = a x b.
inline Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// H_J = d^2 J / dF^2 (above).
inline Tangent3 volume_hessian(const Eigen::Matrix3d& F) {
  Tangent3 H = Tangent3::Zero();
  const Eigen::Matrix3d x0 = cross_matrix(F.col(0)), x1 = cross_matrix(F.col(1)),
                        x2 = cross_matrix(F.col(2));
  H.block<3, 3>(0, 3) = -x2;
  H.block<3, 3>(0, 6) = x1;
  H.block<3, 3>(3, 0) = x2;
  H.block<3, 3>(3, 6) = -x0;
  H.block<3, 3>(6, 0) = -x1;
  H.block<3, 3>(6, 3) = x0;
  return H;
}

}  // namespace springlab
