// Reading a spring entry of a scene file (springs.cc), shared by the
// particle springs (springs.cc) and the springs to body points
// (body_springs.cc). Apart from springs.h, which is the plain data.
#pragma once

#include <string>

#include "models/core/scene_io.h"

namespace springlab {

// Whether an entry has an end {"body": b, "X": [...]} instead of a particle
// index (the body-spring kind reads those, once the bodies are).
bool is_body_spring(const Json& j);
// Its "k" and optional "rest", each a number >= 0; true when "rest" is given
// (else the caller takes the ends' distance at rest).
bool read_stiffness_and_rest(const Reporter& r, const std::string& where, const Json& j,
                             double& k, double& rest);

}  // namespace springlab
