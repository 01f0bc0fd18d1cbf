// Several elements at once, one per vector lane (a SIMD kernel written as
// plain arithmetic). A kernel is written once as a template on its number
// type T: with T = double it computes one element (the plain version, which
// the rest of the code calls), with T = Lanes it computes kLanes elements in
// one pass, entry k of lane l being element l's. Both run the same
// operations in the same order, and each lane's operations are IEEE
// arithmetic on that lane alone, so lane l's result is the plain version's
// for element l bit for bit (the shared tests check it). That needs no
// fused multiply-add in one and not the other: the build turns contraction
// off (-ffp-contract=off, CMakeLists.txt; the default x86-64 target has no
// fused multiply-add to contract to anyway).
//
// Lanes is a GCC and Clang vector type: + - * / and comparisons act lane by
// lane (a comparison gives a Mask, -1 in a lane where it holds, 0
// elsewhere; & | ^ ~ combine masks, as & | ^ combine bools, promoted to
// int, for one element). A function whose kernel runs on Lanes is compiled twice
// (SPRINGLAB_LANES_CLONES): for x86-64-v4 (AVX-512, one instruction for all
// eight lanes) and for the default target (four SSE2 instructions for
// eight lanes), and the loader picks the one the processor runs
// (SPRINGLAB_NO_LANES_CLONES builds the default one only: the sanitizer
// preset does, so that its tests run that copy). A Lanes
// value is passed by reference only: passing a 64-byte vector by value
// from code built for the default target changes the calling convention,
// which Clang refuses.
#pragma once

#include <cstring>

namespace springlab {

inline constexpr int kLanes = 8;
// Aligned to its size everywhere: code built for the default target would
// otherwise give it 16 bytes (its widest vector register), while the
// x86-64-v4 copy loads and stores it with 64-byte aligned instructions.
using Lanes = double __attribute__((vector_size(8 * kLanes), aligned(8 * kLanes)));
using Mask = decltype(Lanes{} < Lanes{});

#if defined(__x86_64__) && !defined(SPRINGLAB_NO_LANES_CLONES)
#define SPRINGLAB_LANES_CLONES __attribute__((target_clones("arch=x86-64-v4", "default")))
#else
#define SPRINGLAB_LANES_CLONES
#endif

// A kernel template is always inlined, so that each clone of the function
// that runs it compiles it for its own target (a call would run the
// default target's code).
#define SPRINGLAB_LANES_INLINE [[gnu::always_inline]] inline

// x = where ? a : x, lane by lane (for one element, a bool).
SPRINGLAB_LANES_INLINE void assign_where(double& x, bool where, const double& a) {
  if (where) x = a;
}
SPRINGLAB_LANES_INLINE void assign_where(Lanes& x, const Mask& where, const Lanes& a) {
  Mask bits_x, bits_a;
  std::memcpy(&bits_x, &x, sizeof x);
  std::memcpy(&bits_a, &a, sizeof a);
  bits_x = (bits_a & where) | (bits_x & ~where);
  std::memcpy(&x, &bits_x, sizeof x);
}
// Whether any lane holds.
inline bool any(bool m) { return m; }
inline bool any(const Mask& m) {
  bool out = false;
  for (int l = 0; l < kLanes; ++l) out = out || m[l] != 0;
  return out;
}

}  // namespace springlab
