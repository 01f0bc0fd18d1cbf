// Gravity in a scene (docs/physics.md "The physics", "Scene files" key "gravity"): the block of
// scene data of the "gravity" element kind (gravity_force.cc).
#pragma once

#include <Eigen/Core>

namespace springlab {

// F_i = m_i g on every free particle; `scene.block<Gravity>()`. Components
// past the scene's dimension are 0.
struct Gravity {
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // g [m/s^2]
};

}  // namespace springlab
