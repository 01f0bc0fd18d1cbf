// The element kinds' registry (element_registry.cc): every kind, one line
// each, and what is read off the whole list. It sits above every kind's
// wing; the kinds themselves see only their interface (element_kind.h).
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "models/core/element_kind.h"
#include "models/core/registry.h"

namespace springlab {

// The registry itself (the idiom of models/core/registry.h).
Registry<ElementKind>& element_registry();

// Every registered kind, in registry order (element_registry.cc): the order
// of keys in files and messages, of energy columns, and of the model's terms.
std::vector<const ElementKind*> element_kinds();

// The element arrays of a scene ("springs", ...) with their counts and caps,
// in registry order.
struct ElementCount {
  std::string_view key;
  std::size_t count = 0;
  std::size_t cap = 0;
};
std::vector<ElementCount> element_counts(const Scene& scene);

// Every element of the scene as a cell, kinds in registry order.
std::vector<Cell> scene_cells(const Scene& scene);

}  // namespace springlab
