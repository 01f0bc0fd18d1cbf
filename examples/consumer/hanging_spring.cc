// The course's example scene, run from another project through the installed
// springlab package: a mass on a spring under gravity and drag, integrated
// with backward Euler until it hangs still. It must come to rest at the
// static equilibrium, stretched by m g / k, which it checks (exit 1 if not).
#include <cmath>
#include <cstdio>

#include "experiments/driver/simulation.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"

int main() {
  using namespace springlab;
  const Scene scene = make_builtin_scene("spring", {{"k", "100"}, {"mass", "1"}});
  const Model model(scene);
  RunSettings settings;
  settings.integrator = "implicit-euler";
  settings.dt = 0.01;
  settings.t_end = 30.0;
  const RunResult r = simulate(model, settings);

  const double y = model.scene_positions(r.x_final)(1, 1);   // particle 1, y
  const double expected = -1.0 - 1.0 * 9.81 / 100.0;        // -(rest + m g / k)
  std::printf("%s on %s: %s, %ld steps; hangs at y = %.6f m (m g / k predicts %.6f)\n",
              r.integrator.c_str(), scene.name.c_str(), to_string(r.status), r.stats.steps, y,
              expected);
  return r.status == RunStatus::kCompleted && std::abs(y - expected) < 1e-6 ? 0 : 1;
}
