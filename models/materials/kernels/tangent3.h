// Pieces of the closed-form tangents of 3 x 3 deformation gradients
// (tet_kernel.h: the tetrahedra's fast path). dPdF is on vec(F) column-major
// (entry (r, c) of F at r + 3 c), so that dP = dPdF vec(dF); the fast path
// needs it only contracted with two rest-shape gradients a, b (rows of
// Dm^-1),
//   A(a, b)_rs = sum_cd a_c (dP_rc / dF_sd) b_d,
// and each piece of a tangent has a 3 x 3 contraction of a few flops
// (below), which is what makes the fast path fast. Each model writes its
// blocks from these in its own file; the shared tests check every one
// against the contraction of the dPdF assembled from its dP.
//
// With f_c the columns of F, J = det F = f0 . (f1 x f2) and
// g = dJ/dF = [f1 x f2, f2 x f0, f0 x f1] (kinematics.h), the Hessian of J
// is the 3 x 3 grid of 3 x 3 blocks ([a]x the cross-product matrix)
//   H_J = [[0, -[f2]x, [f1]x], [[f2]x, 0, -[f0]x], [-[f1]x, [f0]x, 0]]
// (block (c, c') = dg_c / df_c'), so that dg = H_J vec(dF). Smith et al.,
// "Analytic eigensystems for isotropic distortion energies", ACM TOG 2019,
// §4.2. Contracted (block (c, d) of H_J is -eps_cde [f_e]x):
//   H_J(a, b) = -[F (a x b)]x.
// The other pieces the models use, contracted (I the 3 x 3 identity):
//   identity I_9                   -> (a . b) I
//   transpose, vec(dF^T)           -> b a^T
//   rank one vec(U) vec(U)^T       -> (U a)(U b)^T
//   Kronecker, vec(B dF A^T)       -> (a^T A b) B
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>        // determinant

#include "models/materials/kernels/kinematics.h"  // cofactor
#include "models/materials/material.h"

namespace springlab {

// [a]x, with [a]x b = a x b.
inline Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// One block A(a, b) summed from the pieces above, entry by entry. (Plain
// scalar sums, which the compiler keeps in registers; Eigen's 3 x 3
// expressions would pass partial packets through memory here.)
struct Block3 {
  double e[3][3] = {};
  // c I
  Block3& identity(double c) {
    for (int r = 0; r < 3; ++r) e[r][r] += c;
    return *this;
  }
  // c u v^T
  Block3& outer(double c, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) e[r][s] += c * u[r] * v[s];
    return *this;
  }
  // c M
  Block3& matrix(double c, const Eigen::Matrix3d& M) {
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) e[r][s] += c * M(r, s);
    return *this;
  }
  // c [w]x
  Block3& cross(double c, const Eigen::Vector3d& w) {
    e[0][1] -= c * w.z();
    e[0][2] += c * w.y();
    e[1][0] += c * w.z();
    e[1][2] -= c * w.x();
    e[2][0] -= c * w.y();
    e[2][1] += c * w.x();
    return *this;
  }
  // c H_J(a, b) = -c [F (a x b)]x, the volume Hessian contracted (above).
  Block3& volume_hessian(double c, const Eigen::Matrix3d& F, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b) {
    return cross(-c, F * a.cross(b));
  }
};

// The 9 x 9 matrix of blocks (i, j) = A(d_i, d_j), d_i the rows of D, from
// block(i, j) (a Block3) for i <= j: a hyperelastic tangent is symmetric (a
// Hessian), so block (j, i) is the transpose of block (i, j).
template <typename Block>
Tangent3 symmetric_blocks(Block block) {
  Tangent3 K;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      const Block3 b = block(i, j);
      for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) {
          K(3 * i + r, 3 * j + s) = b.e[r][s];
          K(3 * j + s, 3 * i + r) = b.e[r][s];
        }
      }
    }
  }
  return K;
}

// The blocks of the tangent the neo-Hookean models share,
//   dPdF = mu I_9 + c g g^T + h H_J  (g = vec(dJ/dF), G its matrix),
// contracted: A(a, b) = mu (a . b) I + c (G a)(G b)^T - h [F (a x b)]x.
// G is the caller's cofactor(F) (it has computed J = det F from it).
inline Tangent3 volumetric_blocks(const Eigen::Matrix3d& F, const Eigen::Matrix3d& G,
                                  const Eigen::Matrix3d& D, double mu, double c, double h) {
  const Eigen::Matrix3d GD = G * D.transpose();  // column i: G d_i
  return symmetric_blocks([&](int i, int j) {
    const Eigen::Vector3d a = D.row(i), b = D.row(j);
    Block3 block = Block3().identity(mu * a.dot(b)).outer(c, GD.col(i), GD.col(j));
    return i == j ? block : block.volume_hessian(h, F, a, b);  // H_J(a, a) = 0 (a x a = 0)
  });
}

// The blocks A(d_i, d_j) of any tangent T on vec(F), by the definition
// (what the closed forms are checked against): with B = D^T (x) I3,
// the 9 x 9 matrix B^T T B.
Tangent3 tangent_blocks(const Tangent3& T, const Eigen::Matrix3d& D);

}  // namespace springlab
