// The fixed corotated material's tangent blocks (corotated.cc), the
// closed form the tetrahedra's kernel runs for one element and for kLanes
// at once (tet_kernel.h, lanes.h).
//
// dPdF = 2 mu (I - dR/dF) + lambda g g^T + lambda (J - 1) H_J (tangent3.h).
// dR/dF from F = R S: along dF, R^T dF - dF^T R = W S + S W
// (polar_differential in kinematics.cc) gives W = R^T dR = [w]x with
// w = M^-1 u, M = tr(S) I - S, u_k = <R [e_k]x, dF>; so
//   dR/dF = sum_kl (M^-1)_kl vec(R [e_k]x) vec(R [e_l]x)^T,
// three rank-one pieces with R [e_k]x a = -R [a]x e_k. Contracted:
//   A(a, b) = 2 mu (a . b) I - 2 mu R [a]x M^-1 [b]x^T R^T
//             + lambda (G a)(G b)^T - lambda (J - 1) [F (a x b)]x.
// The twist term needs no inverse. M is symmetric, so M^-1 = cof(M) / det M,
// and cof(M) (x x y) = (M x) x (M y) with the Binet-Cauchy identity
// (u x v) . (w x z) = (u . w)(v . z) - (u . z)(v . w) give, entry (p, q)
// being (e_p x a)^T cof(M) (e_q x b),
//   [a]x cof(M) [b]x^T = (a^T M b) M - (M b)(M a)^T.
// Turned by R (R M R^T = tr(S) I - F R^T, since R S R^T = F R^T):
//   R [a]x M^-1 [b]x^T R^T = ((a^T M b)(tr(S) I - F R^T) - c_b c_a^T) / det M,
// with c_a = R M a. det M = (s1 + s2)(s2 + s3)(s3 + s1) for the singular
// values s_i, so the term is singular where an inverted element has
// s2 + s3 = 0, as M^-1 is.
//
// Written once on row-major 3 x 3 arrays (F[3 r + c]; D's rows are d_1,
// d_2, d_3) for a number type T: the kernel (tet_kernel.h) runs it for one
// element (T = double) and for kLanes in vector lanes (T = Lanes, lanes.h).
// K is the 9 x 9 matrix of blocks column-major, entry (3 i + r, 3 j + s) at
// index 3 i + r + 9 (3 j + s), as in a Tangent3: store(index, value) writes it.
#pragma once

#include "models/materials/kernels/kinematics.h"  // stretch, determinant, cofactor
#include "models/materials/kernels/lanes.h"

namespace springlab {

template <typename T, typename Store>
SPRINGLAB_LANES_INLINE void corotated_blocks(const T (&F)[9], const T (&R)[9], const T& /*log_J*/,
                                             const T (&D)[9], const T& mu, const T& lambda,
                                             const Store& store) {
  T S[9];  // F = R S
  stretch(R, F, S);
  const T trS = S[0] + S[4] + S[8];
  T M[9];  // tr(S) I - S
  for (int k = 0; k < 9; ++k) M[k] = k % 4 == 0 ? trS - S[k] : -S[k];
  T det_M;
  determinant(M, det_M);
  const T two_mu_over_det_M = 2.0 * mu / det_M;
  T G[9];  // the cofactor matrix dJ/dF (kinematics.h)
  cofactor(F, G);
  const T h = lambda * (F[0] * G[0] + F[3] * G[3] + F[6] * G[6] - 1.0);  // lambda (J - 1)
  T MD[3][3], c[3][3], GD[3][3];  // M d_i, c_i = R M d_i and G d_i
  for (int i = 0; i < 3; ++i) {
    for (int r = 0; r < 3; ++r) {
      MD[i][r] = M[3 * r] * D[3 * i] + M[3 * r + 1] * D[3 * i + 1] + M[3 * r + 2] * D[3 * i + 2];
      GD[i][r] = G[3 * r] * D[3 * i] + G[3 * r + 1] * D[3 * i + 1] + G[3 * r + 2] * D[3 * i + 2];
    }
    for (int r = 0; r < 3; ++r) {
      c[i][r] = R[3 * r] * MD[i][0] + R[3 * r + 1] * MD[i][1] + R[3 * r + 2] * MD[i][2];
    }
  }
  T V[9];  // F R^T = R S R^T, the left stretch
  for (int r = 0; r < 3; ++r) {
    for (int s = 0; s < 3; ++s) {
      V[3 * r + s] =
          F[3 * r] * R[3 * s] + F[3 * r + 1] * R[3 * s + 1] + F[3 * r + 2] * R[3 * s + 2];
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      const T* a = &D[3 * i];
      const T* b = &D[3 * j];
      const T aMb = a[0] * MD[j][0] + a[1] * MD[j][1] + a[2] * MD[j][2];
      const T ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
      const T beta = two_mu_over_det_M * aMb;
      const T alpha = 2.0 * mu * ab - beta * trS;
      T B[3][3];
      for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) {
          B[r][s] = beta * V[3 * r + s] + two_mu_over_det_M * c[j][r] * c[i][s] +
                    lambda * GD[i][r] * GD[j][s];
        }
        B[r][r] += alpha;
      }
      if (i != j) {  // - lambda (J - 1) [F (a x b)]x; H_J(a, a) = 0 (a x a = 0)
        const T axb[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                          a[0] * b[1] - a[1] * b[0]};
        T w[3];
        for (int r = 0; r < 3; ++r) {
          w[r] = F[3 * r] * axb[0] + F[3 * r + 1] * axb[1] + F[3 * r + 2] * axb[2];
        }
        B[0][1] += h * w[2];
        B[0][2] -= h * w[1];
        B[1][0] -= h * w[2];
        B[1][2] += h * w[0];
        B[2][0] += h * w[1];
        B[2][1] -= h * w[0];
      }
      // Block (j, i) is block (i, j) transposed (a Hessian is symmetric);
      // a diagonal block is written from its upper triangle.
      for (int r = 0; r < 3; ++r) {
        for (int s = i == j ? r : 0; s < 3; ++s) {
          store(3 * i + r + 9 * (3 * j + s), B[r][s]);
          store(3 * j + s + 9 * (3 * i + r), B[r][s]);
        }
      }
    }
  }
}

}  // namespace springlab
