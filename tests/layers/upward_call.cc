// Probe of the wings (tests/CMakeLists.txt, layers_are_enforced): a call
// from models/core into the element registry (models/model, above it),
// through a declaration written by hand so that it compiles. Linked like a
// wing (a shared object, -Wl,--no-undefined, against models/core alone), it
// must fail to link, naming element_kinds.
#include <vector>

#include "models/core/element_kind.h"

namespace springlab {
const std::vector<const ElementKind*>& element_kinds();
std::size_t probe_kind_count() { return element_kinds().size(); }
}  // namespace springlab
