// Drag in a scene (docs/physics.md "The physics", "Scene files" key "drag"): the block of scene
// data of the "drag" element kind (drag_force.cc).
#pragma once

namespace springlab {

// The course's F^dp = -gamma v on every free particle; `scene.block<Drag>()`.
struct Drag {
  double gamma = 0.0;  // [kg/s]
};

}  // namespace springlab
