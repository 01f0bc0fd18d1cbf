// The registered element kinds (element_kind.h). Adding a kind: write its
// file (an `ElementKind` returned by a function like the ones below) and add
// one line to this table.
//
// The order is the order of the model's terms, and so of the summation of
// forces (keep it: floating-point sums depend on it), and within each group
// the order of keys in scene files and messages and of energy columns.
#include "models/model/element_registry.h"

namespace springlab {

// Each in its kind's own file.
const ElementKind& spring_kind();          // springs.cc
const ElementKind& spring_damping_kind();  // spring_damping_force.cc
const ElementKind& gravity_kind();         // gravity_force.cc
const ElementKind& drag_kind();            // drag_force.cc
const ElementKind& wind_kind();            // wind_force.cc
const ElementKind& material_kind();        // materials_kind.cc
const ElementKind& triangle_kind();        // triangles.cc
const ElementKind& tetrahedron_kind();     // tetrahedra.cc
const ElementKind& contact_kind();         // contact_kind.cc
const ElementKind& plane_kind();           // planes.cc
const ElementKind& friction_kind();        // friction_force.cc
const ElementKind& body_kind();            // bodies.cc
const ElementKind& body_gravity_kind();    // body_forces.cc
const ElementKind& body_contact_kind();    // body_forces.cc
const ElementKind& body_friction_kind();   // body_forces.cc
const ElementKind& fluid_kind();           // fluid_kind.cc
const ElementKind& fluid_viscosity_kind(); // fluid_viscosity_force.cc
const ElementKind& body_spring_kind();     // body_springs.cc
const ElementKind& body_body_contact_kind();  // body_body_contact.cc
const ElementKind& body_body_friction_kind();  // body_body_friction.cc

const std::vector<const ElementKind*>& element_kinds() {
  static const std::vector<const ElementKind*> kinds = {
      &spring_kind(),
      &spring_damping_kind(),
      &gravity_kind(),
      &drag_kind(),
      &wind_kind(),
      &material_kind(),
      &triangle_kind(),
      &tetrahedron_kind(),
      &contact_kind(),
      &plane_kind(),
      &friction_kind(),
      &body_kind(),
      &body_gravity_kind(),
      &body_contact_kind(),
      &body_friction_kind(),
      &fluid_kind(),
      &fluid_viscosity_kind(),
      &body_spring_kind(),
      &body_body_contact_kind(),
      &body_body_friction_kind(),
  };
  return kinds;
}

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
