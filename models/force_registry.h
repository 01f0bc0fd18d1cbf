// The list of force kinds a scene can name. Adding a force: write its .cc
// (a ForceTerm plus a `make_...` factory) and add one line to the table in
// force_registry.cc.
#pragma once

#include <memory>
#include <vector>

#include "models/force_term.h"
#include "models/scene.h"

namespace springlab {

// How scene particle indices map to the model's internal order (free first).
struct ParticleOrder {
  int dim = 2;
  int free_particles = 0;
  std::vector<int> internal_of_scene;  // scene index -> internal index
  std::vector<int> scene_of_internal;  // internal index -> scene index
};

// Builds the term from the scene, or returns nullptr when the scene does not
// name this force (an absent force costs nothing).
using ForceFactory = std::unique_ptr<ForceTerm> (*)(const Scene&, const ParticleOrder&);

struct ForceKind {
  const char* name;
  ForceFactory make;
};

const std::vector<ForceKind>& force_kinds();

}  // namespace springlab
