// Probe of the wings (tests/CMakeLists.txt, layers_are_enforced): the same
// call linked against models/model, where the registry is: it must link.
#include <vector>

#include "models/model/element_registry.h"

namespace springlab {
std::size_t probe_kind_count() { return element_kinds().size(); }
}  // namespace springlab
