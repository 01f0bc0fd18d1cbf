// The rigid bodies in `run --json` (docs/command-line.md, docs/physics.md
// "Rigid bodies (affine bodies)"): per body, in scene order, its centre of
// mass p, its A (rows), their rates, linear momentum P = m dp/dt and angular
// momentum L about the origin and L_c about the centre of mass (bodies.h).
#pragma once

#include <nlohmann/json.hpp>

#include "models/model/model.h"

namespace springlab {

// An array of one object per body; an empty array when the scene has none.
nlohmann::ordered_json bodies_json(const Model& model, const Vector& x, const Vector& v);

}  // namespace springlab
