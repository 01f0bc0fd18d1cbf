// Wind in a scene (docs/physics.md "The physics", "Scene files" key "wind"): the block of scene
// data of the "wind" element kind (wind_force.cc).
#pragma once

#include <Eigen/Core>

namespace springlab {

// w(t) = w0 (1 + gust sin(2 pi f t)); F_i = coefficient (w(t) - v_i) on every
// free particle. `scene.block<Wind>()`; a scene without one has no wind.
struct Wind {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // w0 [m/s]
  double coefficient = 0.0;                            // c_w [kg/s]
  double gust = 0.0;                                   // relative amplitude
  double frequency = 0.0;                              // f [Hz]
};

}  // namespace springlab
