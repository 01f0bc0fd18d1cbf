// libFuzzer target over the experiment-definition loader: any input must
// either load or be refused with a DefinitionError or a SceneError (a scene
// named by the definition). Any other exception, a crash, a sanitizer
// report, a hang or an out-of-memory is a bug. No task is run: only what
// `springlab experiment` does before its first task (tables, task count,
// the settings it would write).
#include <cstddef>
#include <cstdint>
#include <string>

#include "experiments/kinds/definition.h"
#include "experiments/kinds/experiment.h"
#include "models/core/scene.h"

namespace {
volatile std::size_t sink;  // keeps the computed values from being optimized away
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const springlab::LoadedExperiment loaded = springlab::parse_experiment(text, "fuzz.json");
    sink = loaded.experiment->task_count() + loaded.experiment->tables().size() +
           loaded.experiment->settings().dump().size();
  } catch (const springlab::DefinitionError&) {
  } catch (const springlab::SceneError&) {
  }
  return 0;
}
