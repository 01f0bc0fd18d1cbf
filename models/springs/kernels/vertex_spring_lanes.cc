#include "models/springs/kernels/vertex_spring_lanes.h"

#include <cmath>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace springlab {
namespace {

// The exact blocks of 3-D springs, two springs at once in the lanes of a
// two-double vector (GCC's and Clang's vector extension: SSE2 on the
// default target, WebAssembly's SIMD or scalars elsewhere): the same
// formulas, each lane rounded as add_vertex_spring rounds it, the lanes
// summed at the end (so the sums differ from the plain loop's in the last
// bits), T folded into A's diagonal. vbd's sweeps spend most of their
// time here: built from registers (not an Eigen::Array2d filled through
// memory, which made each vector load wait for the two scalar stores
// before it: perf, cloth 64), 61 -> 39 instructions per spring.
using Pair2 = double __attribute__((vector_size(16)));
inline Pair2 sqrt2(Pair2 v) {
#if defined(__x86_64__)
  return _mm_sqrt_pd(v);
#else
  return Pair2{std::sqrt(v[0]), std::sqrt(v[1])};
#endif
}

}  // namespace

void add_vertex_blocks_lanes3(const double* x, const int* particles, int count,
                              const int* vertex_first, const VertexSpring* springs,
                              const VertexBlocks& out) {
  const Pair2 zero = {0.0, 0.0};
  for (int n = 0; n < count; ++n) {
    const int p = particles[n];
    const double xp[3] = {x[p * 3], x[p * 3 + 1], x[p * 3 + 2]};
    const Pair2 xp0 = {xp[0], xp[0]}, xp1 = {xp[1], xp[1]}, xp2 = {xp[2], xp[2]};
    Pair2 f0 = zero, f1 = zero, f2 = zero;
    Pair2 a00 = zero, a01 = zero, a02 = zero, a11 = zero, a12 = zero, a22 = zero;
    double f[3] = {};
    double A[3][3] = {};
    double T = 0.0;
    int e = vertex_first[p];
    const int end = vertex_first[p + 1];
    for (; e + 2 <= end; e += 2) {
      const VertexSpring& s = springs[e];
      const VertexSpring& u = springs[e + 1];
      const double* xs = x + s.other;
      const double* xu = x + u.other;
      const Pair2 d0 = xp0 - Pair2{xs[0], xu[0]};
      const Pair2 d1 = xp1 - Pair2{xs[1], xu[1]};
      const Pair2 d2 = xp2 - Pair2{xs[2], xu[2]};
      const Pair2 l2 = d0 * d0 + d1 * d1 + d2 * d2;
      if (!(l2[0] > 0.0 && l2[1] > 0.0)) {  // a spring without direction: one at a time
        add_vertex_spring<3, false>(x, xp, s, f, A, T);
        add_vertex_spring<3, false>(x, xp, u, f, A, T);
        continue;
      }
      const Pair2 inv_l = 1.0 / sqrt2(l2);
      const Pair2 kL = {s.kL, u.kL};
      const Pair2 t = Pair2{s.k, u.k} - kL * inv_l;
      f0 -= t * d0;
      f1 -= t * d1;
      f2 -= t * d2;
      const Pair2 a = kL * (inv_l * inv_l) * inv_l;
      const Pair2 ad0 = a * d0, ad1 = a * d1, ad2 = a * d2;
      a00 += ad0 * d0 + t;
      a01 += ad0 * d1;
      a02 += ad0 * d2;
      a11 += ad1 * d1 + t;
      a12 += ad1 * d2;
      a22 += ad2 * d2 + t;
    }
    if (e < end) add_vertex_spring<3, false>(x, xp, springs[e], f, A, T);
    f[0] += f0[0] + f0[1];
    f[1] += f1[0] + f1[1];
    f[2] += f2[0] + f2[1];
    A[0][0] += a00[0] + a00[1];
    A[0][1] += a01[0] + a01[1];
    A[0][2] += a02[0] + a02[1];
    A[1][1] += a11[0] + a11[1];
    A[1][2] += a12[0] + a12[1];
    A[2][2] += a22[0] + a22[1];
    write_vertex_block<3>(f, A, T, out.f + n * 3, out.dfdx + n * 9);
  }
}

}  // namespace springlab
