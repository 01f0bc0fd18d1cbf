// Springs in a scene (docs/physics.md "The physics", "Scene files"): the block of scene data of the
// "spring" element kind (springs.cc), whose force is spring_force.cc and whose
// `damping` the "spring-damping" kind (spring_damping_force.cc) reads.
#pragma once

#include <cstddef>
#include <vector>

namespace springlab {

struct Spring {
  int i = 0;
  int j = 0;
  double k = 0.0;
  double rest = 0.0;     // resolved: the distance of the ends' rest positions X
                         // (their initial distance without X) when the file omits it
  double damping = 0.0;  // c in F_i = -c ((v_i - v_j).d) d
};

// The scene's springs, in file order: `scene.block<Springs>()`.
using Springs = std::vector<Spring>;

// At most this many springs per scene (docs/reliability.md, "Reliability").
inline constexpr std::size_t kMaxSceneSprings = 2'000'000;

}  // namespace springlab
