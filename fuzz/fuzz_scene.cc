// libFuzzer target over the scene loader (docs/physics.md "Scene files"): any input must either
// parse or be refused with a SceneError. Any other exception, a crash, a
// sanitizer report, a hang or an out-of-memory is a bug. A scene that parses
// must also pass validate_scene, print with scene_to_json and read back to
// the same file (every element kind's writer and reader agree), and build a
// model whose initial energies are computed.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "models/model/model.h"
#include "models/core/scene.h"
#include "models/model/scene_file.h"

namespace {
volatile double sink;  // keeps the computed values from being optimized away
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  springlab::Scene scene;
  try {
    scene = springlab::parse_scene(text, "fuzz.json");
  } catch (const springlab::SceneError&) {
    return 0;  // refused with a message: the expected outcome for most inputs
  }
  // A scene that parsed is valid and round-trips through a scene file; these
  // throw (and so abort the fuzzer) if not.
  springlab::validate_scene(scene, "fuzz.json");
  const springlab::Scene again = springlab::parse_scene(springlab::scene_to_json(scene), "again");
  if (again.particles.size() != scene.particles.size() || again.dimension != scene.dimension ||
      springlab::scene_to_json(again) != springlab::scene_to_json(scene)) {
    std::abort();
  }
  const springlab::Model model(scene);
  const springlab::Energies e =
      model.energies(model.initial_positions(), model.initial_velocities());
  sink = e.total() + model.energy_scale();
  return 0;
}
