// What the model of a scene will hold, estimated from the scene alone
// before anything large is built (issue 46.5-7): its own arrays, then each
// registered kind's parts (ElementKind::memory, models/core/memory_estimate.h).
#pragma once

#include "models/core/memory_estimate.h"
#include "models/core/scene.h"

namespace springlab {

// The model of `scene` and a run's state vectors: the particles' own arrays,
// then each registered kind's parts, in registry order.
MemoryEstimate estimate_model_memory(const Scene& scene);

}  // namespace springlab
