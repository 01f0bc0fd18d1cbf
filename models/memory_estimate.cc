// The model's memory from the scene (memory_estimate.h).
#include "models/memory_estimate.h"

#include <algorithm>

#include "models/bodies.h"
#include "models/element_kind.h"
#include "models/scene.h"

namespace springlab {
namespace {

// Per scene particle: two copies of its Particle (the caller's scene and
// the model's) and the particle order; per unknown coordinate, the model's
// arrays (mass, x0, v0, the internal x, v, f, y, three constant forces) and
// a run's state vectors, 18 doubles. Fitted to the peak resident memory of
// symplectic Euler on the 10^6-particle chain (2-D) and the 578 x 578 cloth
// (3-D) with the springs' own bytes (spring_memory): 650 and 485 MB.
constexpr double kParticleBytes = 224.0;
constexpr double kBytesPerCoordinate = 18.0 * 8.0;
// Building the pattern, per declared block: the builder's entry (8 bytes);
// per declared entry, its triplet (16) and Eigen's intermediate (12); per
// distinct entry, the compressed pattern (12). Once built, a Newton method
// keeps four matrices on it (the pattern, dF/dx, the Newton matrix and its
// definite twin; dF/dv where forces depend on v), 12 bytes an entry each.
constexpr double kBuilderBytesPerBlock = 8.0;
constexpr double kBuildBytesPerEntry = 28.0;
constexpr double kEntryBytes = 12.0;
constexpr double kHeldMatrices = 4.0;

}  // namespace

double MemoryEstimate::part_bytes(const MemoryPart& part, bool jacobians) const {
  if (!jacobians) return part.bytes;
  const double per_block = static_cast<double>(dim * dim);
  const double build = part.pattern_blocks * (kBuilderBytesPerBlock + per_block * kBuildBytesPerEntry) +
                       part.distinct_blocks * per_block * kEntryBytes + part.slot_bytes;
  const double held = part.distinct_blocks * per_block * kEntryBytes * kHeldMatrices + part.slot_bytes;
  return part.bytes + std::max(build, held);
}

double MemoryEstimate::bytes(bool jacobians) const {
  double sum = 0.0;
  for (const MemoryPart& part : parts) sum += part_bytes(part, jacobians);
  return sum;
}

const MemoryPart* MemoryEstimate::largest(bool jacobians) const {
  const MemoryPart* best = nullptr;
  for (const MemoryPart& part : parts) {
    if (best == nullptr || part_bytes(part, jacobians) > part_bytes(*best, jacobians)) best = &part;
  }
  return best;
}

MemoryEstimate estimate_model_memory(const Scene& scene) {
  MemoryEstimate out;
  out.dim = scene.dimension;
  // The unknowns: the particles' and the bodies' four pseudo-particles (the
  // diagonal blocks are always in the pattern).
  const double particles = static_cast<double>(scene.particles.size());
  const double pseudo = 4.0 * static_cast<double>(scene.get<Bodies>().size());
  MemoryPart own;
  own.what = std::to_string(scene.particles.size()) + " particles";
  own.bytes = particles * kParticleBytes + (particles + pseudo) * scene.dimension * kBytesPerCoordinate;
  own.pattern_blocks = own.distinct_blocks = particles + pseudo;
  out.parts.push_back(own);
  for (const ElementKind* kind : element_kinds()) {
    if (kind->memory != nullptr) kind->memory(scene, out);
  }
  return out;
}

}  // namespace springlab
