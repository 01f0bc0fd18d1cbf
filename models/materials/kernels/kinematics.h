// The kinematic quantities the materials share, for a d x k deformation
// gradient F (square: a solid; 3 x 2: a membrane):
//   - J, the ratio of deformed to rest area/volume: det F for a solid (its
//     sign kept, negative where the element is inverted), |f0 x f1| =
//     sqrt(det C) for a membrane (f_i the columns of F);
//   - g = dJ/dF: the cofactor matrix of a solid (columns f1 x f2, f2 x f0,
//     f0 x f1 in 3-D), (f1 x n, n x f0) for a membrane (n the unit normal);
//   - dg = (dg/dF)[dF], its change along dF;
//   - the rotation R of the polar decomposition F = R S (fixed corotated):
//     for a solid the proper rotation nearest F (an inverted element keeps
//     det R = 1, S then has a negative eigenvalue; Irving et al. 2004), for a
//     membrane R = F C^-1/2 with orthonormal columns; and its change dR.
#pragma once

#include <Eigen/Geometry>  // cross

#include "models/materials/kernels/lanes.h"  // kLanes
#include "models/materials/material.h"

namespace springlab {

struct Volume {
  double J = 0.0;
  Mat g;  // dJ/dF, the shape of F
};
Volume volume(const Mat& F);
// g = dJ/dF of a solid's 3 x 3 F: the cofactor matrix, columns f1 x f2,
// f2 x f0, f0 x f1, and det F, on row-major arrays (F[3 r + c]) for one
// matrix (T = double) or kLanes (T = Lanes, lanes.h). Written entry by
// entry, (f_a x f_b)_r = F_pa F_qb - F_qa F_pb with (r, p, q) and (c, a, b)
// cyclic.
template <typename T>
SPRINGLAB_LANES_INLINE void cofactor(const T (&F)[9], T (&G)[9]) {
  for (int r = 0; r < 3; ++r) {
    const int p = (r + 1) % 3, q = (r + 2) % 3;
    for (int c = 0; c < 3; ++c) {
      const int a = (c + 1) % 3, b = (c + 2) % 3;  // g_c = f_a x f_b
      G[3 * r + c] = F[3 * p + a] * F[3 * q + b] - F[3 * q + a] * F[3 * p + b];
    }
  }
}
template <typename T>
SPRINGLAB_LANES_INLINE void determinant(const T (&A)[9], T& det) {
  det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
        A[2] * (A[3] * A[7] - A[4] * A[6]);
}
// The cofactor matrix of an Eigen 3 x 3 F, fixed size (volume() uses it;
// so do the closed-form tangents, tangent3.h), entry by entry as above:
// Eigen's column cross products store each column as a two-double packet
// and a double, which the next whole-matrix read (packets at other
// offsets) cannot take from the store buffer on x86 (a store-forwarding
// stall per column). With the scalar form corotated's force + dF/dx ran
// about 10 % faster when Higham's iteration, a cofactor per step,
// decomposed every element (benchmarks/README).
inline Eigen::Matrix3d cofactor(const Eigen::Matrix3d& F) {
  double f[9], g[9];
  for (int k = 0; k < 9; ++k) f[k] = F(k / 3, k % 3);
  cofactor(f, g);
  Eigen::Matrix3d G;
  for (int k = 0; k < 9; ++k) G(k / 3, k % 3) = g[k];
  return G;
}
// (dg/dF)[dF] (the second derivative of J along dF).
Mat volume_differential(const Mat& F, const Mat& dF);

// A : B, the sum of the entrywise products.
inline double contract(const Mat& A, const Mat& B) { return A.cwiseProduct(B).sum(); }

struct Polar {
  Mat R;  // d x k, orthonormal columns (a rotation for a solid)
  Mat S;  // k x k symmetric, F = R S
};
Polar polar(const Mat& F);
// The same for a 3 x 3 F, fixed size (the tetrahedra's fast path).
struct Polar3 {
  Eigen::Matrix3d R, S;
};
Polar3 polar3(const Eigen::Matrix3d& F);
// polar3(F).R of kLanes matrices at once, in vector lanes (lanes.h): *R[l]
// is polar3(*F[l]).R bit for bit. (The pointers may repeat: a caller with
// fewer matrices fills the rest of F with one of them and of R with
// scratch.)
void rotation3_lanes(const Eigen::Matrix3d* const (&F)[kLanes],
                     Eigen::Matrix3d* const (&R)[kLanes]);
// S = (R^T F + F^T R) / 2 of row-major 3 x 3 arrays (R[3 r + c]), for one
// matrix (T = double) or kLanes (T = Lanes): polar3's S from its R, the
// same arithmetic as polar3 runs.
template <typename T>
SPRINGLAB_LANES_INLINE void stretch(const T (&R)[9], const T (&F)[9], T (&S)[9]) {
  T RtF[9];
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      RtF[3 * a + b] = R[a] * F[b] + R[3 + a] * F[3 + b] + R[6 + a] * F[6 + b];
    }
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) S[3 * a + b] = 0.5 * (RtF[3 * a + b] + RtF[3 * b + a]);
  }
}

// What a material derives from a 3 x 3 F first, the costly step its
// energy, stress and tangent blocks share (Keeps, tet_kernel.h):
// corotated's rotation R of F = R S (about 50 ns; S follows from R and F in
// a few dozen flops, stretch), neo-Hookean's ln J (a logarithm, about
// 12 ns). The kernel (tet_kernel.h) fills the one a material keeps; the tetrahedra keep each
// element's between calls at one state (tet_force.cc).
struct Derived3 {
  Eigen::Matrix3d R;   // F = R S (corotated)
  double log_J = 0.0;  // ln det F (neo-Hookean; det F > 0)
};

// The nearest matrix to F (Frobenius norm) whose J is 1: the volume
// constraint set of projective dynamics (Bouaziz et al., "Projective
// dynamics: fusing constraint projections for fast simulation", ACM TOG
// 2014, sec. 5). With F = U diag(s) V^T (an SVD; for a membrane U is 3 x 2),
// T = U diag(s*) V^T where s* minimizes |s - s*|^2 subject to prod s* = 1;
// its Lagrange conditions s_i - s*_i = m prod_{j != i} s*_j = m / s*_i give
//   s*_i = (s_i + sqrt(s_i^2 - 4 m)) / 2
// for one scalar m, the root of sum_i ln s*_i(m) = 0 (decreasing in m),
// found by Newton's method kept inside a bracket. Where no such m exists
// (a large growth: at the bracket's end m = s_min^2 / 4, where
// s*_min = s_min / 2, the product still exceeds 1, as when every s_i
// exceeds 2) T = F / J^(1/k), and an inverted or flattened element
// (J <= 0) is projected onto its rotation polar(F).R, a point of the set
// but not the nearest.
Mat nearest_unit_volume(const Mat& F);

// volume() and polar() of a 3 x 3 F with fixed sizes, so that a material's
// P, written once as a template on the matrix type, also has a fixed-size
// instance (the tetrahedra's P, tet_kernel.h).
struct Volume3 {
  double J = 0.0;
  Eigen::Matrix3d g;
};
inline Volume3 volume(const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d g = cofactor(F);
  return {F.col(0).dot(g.col(0)), g};
}
inline Polar3 polar(const Eigen::Matrix3d& F) { return polar3(F); }
// dR = (dR/dF)[dF] at F = R S.
Mat polar_differential(const Polar& p, const Mat& F, const Mat& dF);

}  // namespace springlab
