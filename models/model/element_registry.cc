// The registered element kinds (element_kind.h), in the one registration
// idiom of springlab (models/core/registry.h). Adding a kind: write its
// file (an `ElementKind` returned by a function `const ElementKind&
// NAME_kind()`) and add one line X(ElementKind, NAME_kind) to this table.
//
// The order is the order of the model's terms, and so of the summation of
// forces (keep it: floating-point sums depend on it), and within each group
// the order of keys in scene files and messages and of energy columns.
#include "models/model/element_registry.h"

#include "models/core/registry.h"

namespace springlab {

// Each in its kind's own file.
#define SPRINGLAB_ELEMENT_KINDS(X)                                     \
  X(ElementKind, spring_kind)  /* springs.cc */                        \
  X(ElementKind, spring_damping_kind)  /* spring_damping_force.cc */   \
  X(ElementKind, gravity_kind)  /* gravity_force.cc */                 \
  X(ElementKind, drag_kind)  /* drag_force.cc */                       \
  X(ElementKind, wind_kind)  /* wind_force.cc */                       \
  X(ElementKind, material_kind)  /* materials_kind.cc */               \
  X(ElementKind, triangle_kind)  /* triangles.cc */                    \
  X(ElementKind, tetrahedron_kind)  /* tetrahedra.cc */                \
  X(ElementKind, contact_kind)  /* contact_kind.cc */                  \
  X(ElementKind, plane_kind)  /* planes.cc */                          \
  X(ElementKind, friction_kind)  /* friction_force.cc */               \
  X(ElementKind, body_kind)  /* bodies.cc */                           \
  X(ElementKind, body_gravity_kind)  /* body_forces.cc */              \
  X(ElementKind, body_contact_kind)  /* body_forces.cc */              \
  X(ElementKind, body_friction_kind)  /* body_forces.cc */             \
  X(ElementKind, fluid_kind)  /* fluid_kind.cc */                      \
  X(ElementKind, fluid_viscosity_kind)  /* fluid_viscosity_force.cc */ \
  X(ElementKind, body_spring_kind)  /* body_springs.cc */              \
  X(ElementKind, body_body_contact_kind)  /* body_body_contact.cc */   \
  X(ElementKind, body_body_friction_kind)  /* body_body_friction.cc */

SPRINGLAB_REGISTRY(ElementKind, SPRINGLAB_ELEMENT_KINDS, element_registry)

std::vector<const ElementKind*> element_kinds() { return element_registry().entries(); }

std::vector<ElementCount> element_counts(const Scene& scene) {
  std::vector<ElementCount> counts;
  for (const ElementKind* kind : element_kinds()) {
    for (const SceneKey& key : kind->keys) {
      if (key.cap > 0) counts.push_back({key.name, key.count(scene), key.cap});
    }
  }
  return counts;
}

std::vector<Cell> scene_cells(const Scene& scene) {
  std::vector<Cell> cells;
  for (const ElementKind* kind : element_kinds()) {
    if (kind->cells != nullptr) kind->cells(scene, cells);
  }
  return cells;
}

}  // namespace springlab
