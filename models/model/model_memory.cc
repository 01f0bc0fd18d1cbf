// The model's memory from the scene (model_memory.h).
#include "models/model/model_memory.h"

#include "models/bodies/bodies.h"
#include "models/core/element_kind.h"
#include "models/model/element_registry.h"

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

}  // namespace

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
