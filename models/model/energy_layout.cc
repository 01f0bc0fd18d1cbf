// The energy columns of a scene or of several (energies.h), read off the
// element kinds' registry: the always-reported columns, then those of the
// kinds a scene has, in registry order.
#include "models/model/energy_layout.h"

#include <algorithm>

#include "models/model/element_registry.h"

namespace springlab {
namespace {

// Whether the scene has any element of this kind (an optional column is
// reported only then).
bool has_elements(const ElementKind& kind, const Scene& scene) {
  if (kind.energy.present != nullptr) return kind.energy.present(scene);
  return std::any_of(kind.keys.begin(), kind.keys.end(), [&](const SceneKey& key) {
    return key.count != nullptr && key.count(scene) > 0;
  });
}

}  // namespace

EnergyLayout energy_layout(const Scene& scene) { return energy_layout({&scene}); }

EnergyLayout energy_layout(const std::vector<const Scene*>& scenes) {
  std::vector<const EnergyColumn*> always, present, works;
  auto add_once = [](std::vector<const EnergyColumn*>& list, const EnergyColumn& c) {
    const bool known = std::any_of(list.begin(), list.end(),
                                   [&](const EnergyColumn* seen) { return seen->name == c.name; });
    if (!known) list.push_back(&c);
  };
  for (const ElementKind* kind : element_kinds()) {
    const EnergyColumn& c = kind->energy;
    if (c.name.empty()) continue;
    if (c.work) {
      if (std::any_of(scenes.begin(), scenes.end(),
                      [&](const Scene* s) { return has_elements(*kind, *s); })) {
        add_once(works, c);
      }
    } else if (c.always) {
      add_once(always, c);
    } else if (std::any_of(scenes.begin(), scenes.end(),
                           [&](const Scene* s) { return has_elements(*kind, *s); })) {
      add_once(present, c);
    }
  }
  EnergyLayout layout;
  auto add_potential = [&](const EnergyColumn* c) {
    if (c->counts_with_spring) layout.counts_with_spring.push_back(layout.columns.size());
    layout.potentials.push_back(layout.columns.size());
    layout.columns.emplace_back(c->name);
  };
  layout.kinetic = 0;
  layout.columns.push_back("kinetic");
  for (const EnergyColumn* c : always) add_potential(c);
  layout.total = layout.columns.size();
  layout.columns.push_back("total");
  for (const EnergyColumn* c : present) add_potential(c);
  for (const EnergyColumn* c : works) {
    layout.works.push_back(layout.columns.size());
    layout.columns.emplace_back(c->name);
  }
  return layout;
}

}  // namespace springlab
