// A model's memory, summed from its parts (memory_estimate.h).
#include "models/core/memory_estimate.h"

#include <algorithm>

namespace springlab {
namespace {

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

}  // namespace springlab
