// One spring's part of a particle's vertex block (vertex block descent:
// models/core/vertex_blocks.h), plainly: the force on the particle and the
// diagonal block of its Jacobian, from the spring's other end.
#pragma once

#include <cmath>

namespace springlab {

// One spring as a particle's vertex block reads it: the other end's
// offset (other * dim) into x, k and k L.
struct VertexSpring {
  int other;
  double k, kL;
};

// With d = x_p - x_o, l = |d|, t = k (1 - L/l) = k - k L / l (the
// transverse stiffness, and the force's scale: F_p = -t d):
//   K = (k - t) d d^T / l^2 + t I = k L d d^T / l^3 + t I,
// summed as A = sum a d d^T (a = k L / l^3) and T = sum t,
// dF_p/dx_p = -(A + T I): one square root and one division per spring
// (1 / l). Definite: t clamped at 0, then a = k / l^2.
template <int D, bool kDefinite>
inline void add_vertex_spring(const double* x, const double (&xp)[D], const VertexSpring& s,
                              double (&f)[D], double (&A)[D][D], double& T) {
  const double* xo = x + s.other;
  double d[D];
  double l2 = 0.0;
  for (int r = 0; r < D; ++r) {
    d[r] = xp[r] - xo[r];
    l2 += d[r] * d[r];
  }
  if (!(l2 > 0.0)) {  // no direction: F = 0; K = k I if L = 0, else 0
    if (s.kL == 0.0) T += s.k;
    return;
  }
  const double inv_l = 1.0 / std::sqrt(l2);
  const double t = s.k - s.kL * inv_l;
  for (int r = 0; r < D; ++r) f[r] -= t * d[r];
  const double inv_l2 = inv_l * inv_l;
  double a = s.kL * inv_l2 * inv_l;
  if (kDefinite && t < 0.0) {
    a = s.k * inv_l2;
  } else {
    T += t;
  }
  double ad[D];
  for (int r = 0; r < D; ++r) ad[r] = a * d[r];
  for (int r = 0; r < D; ++r) {
    for (int q = r; q < D; ++q) A[r][q] += ad[r] * d[q];
  }
}

template <int D>
inline void write_vertex_block(const double (&f)[D], const double (&A)[D][D], double T,
                               double* fp, double* K) {
  for (int r = 0; r < D; ++r) {
    fp[r] += f[r];
    K[r * D + r] -= A[r][r] + T;
    for (int q = r + 1; q < D; ++q) {
      K[r * D + q] -= A[r][q];
      K[q * D + r] -= A[r][q];
    }
  }
}

}  // namespace springlab
