// The stage of the spring force loop that bounds its cost:
//   scale[j] = k[j] (1 - rest[j] / sqrt(l2[j])),  j < m,
// the square roots and divisions (hooke_force, spring_force.h, is the same
// formula for one spring, written plainly). A portable version (Eigen's
// packets) and, on x86-64, AVX and AVX-512 versions picked at run time.
// Every variant rounds each lane exactly as the scalar formula does (IEEE
// sqrt, div, sub, mul; no fused multiply-add), so forces are the same bit
// for bit whichever variant the CPU runs.
#pragma once

namespace springlab {

using ScaleKernel = void (*)(const double* k, const double* rest, const double* l2,
                             double* scale, int m);

// The plain version, and the fastest this CPU runs.
void spring_scales_portable(const double* k, const double* rest, const double* l2,
                            double* scale, int m);
ScaleKernel pick_scale_kernel();

}  // namespace springlab
