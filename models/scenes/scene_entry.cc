// Building a scene's registry entry (scene_entry.h).
#include "models/scenes/scene_entry.h"

#include <algorithm>
#include <stdexcept>

namespace springlab {

SceneEntry scene_entry(std::string name, std::string description, std::vector<ParameterSpec> specs,
                       Scene (*build)(const SceneValues&),
                       SceneCounts (*counts)(const SceneValues&), const char* size_parameter) {
  SceneEntry entry;
  entry.name = std::move(name);
  entry.description = std::move(description);
  for (const ParameterSpec& spec : specs) entry.parameters.push_back(spec.parameter);
  entry.specs = std::move(specs);
  entry.build = build;
  entry.counts = counts;
  entry.size_parameter = size_parameter;
  return entry;
}

ParameterSpec param(const char* name, double value, const char* meaning, Range range, double min,
                    double max) {
  return {{name, value, meaning, {}}, range, min, max};
}

ParameterSpec choice(const char* name, const std::string& value, const std::string& meaning,
                     std::vector<std::string> choices) {
  const auto at = std::find(choices.begin(), choices.end(), value);
  if (at == choices.end()) throw std::logic_error("a choice's default must be one of its choices");
  const auto index = static_cast<double>(at - choices.begin());
  const auto last = static_cast<double>(choices.size()) - 1.0;
  return {{name, index, meaning, std::move(choices)}, Range::kChoice, 0.0, last};
}

std::vector<ParameterSpec> with(std::vector<ParameterSpec> a, const std::vector<ParameterSpec>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace springlab
