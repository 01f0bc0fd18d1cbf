// The energy columns a scene reports (energies.h), from the element kinds'
// registry (element_registry.h).
#pragma once

#include <vector>

#include "models/core/energies.h"
#include "models/core/scene.h"

namespace springlab {

// The layout of a scene: the always-reported columns and those of the kinds
// whose element arrays are not empty in it. Over several scenes (one table
// of an experiment): the union, each scene's missing columns being 0.
EnergyLayout energy_layout(const Scene& scene);
EnergyLayout energy_layout(const std::vector<const Scene*>& scenes);

}  // namespace springlab
