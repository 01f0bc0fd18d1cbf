// The scene's extent of motion (docs/command-line.md "Divergence"): the
// length d in the energy scale's gravity term, E_s = ... + sum_free m |g| d.
// d is the diameter of the box that holds
//   - the initial positions of every particle and of the kinds' own points
//     (`points`: a body's surface vertices, element_kind.h OwnUnknowns), and
//   - under gravity, where each free one of them lands when it falls along
//     g onto the nearest contact plane below it that faces up (its foot
//     there),
// so a small body dropped from high onto a plane gets the height it can
// fall, not its own size (a 1 cm box 20 m above the ground: d = 20 m, not
// 1.7 cm), and a scene without planes keeps the diameter of its initial
// positions.
#pragma once

#include <vector>

#include "models/core/element_kind.h"
#include "models/core/scene.h"

namespace springlab {

double extent_of_motion(const Scene& scene, const std::vector<StartPoint>& points);

}  // namespace springlab
