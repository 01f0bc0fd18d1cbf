// Built-in scenes (docs/scenes.md "Built-in scenes"): the registry of the
// scenes' entries (scene_entry.h; each defined in its scene's file) and the
// reading of `-p key=value`. Every scene is checked afterwards by
// validate_scene like any scene file.
#include "models/scenes/builtin_scenes.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "models/core/decimal_text.h"
#include "models/core/registry.h"
#include "models/core/scene.h"  // printable
#include "models/model/scene_file.h"
#include "models/springs/springs.h"  // kMaxSceneSprings
#include "models/scenes/scene_entry.h"

namespace springlab {

// The built-in scenes, one line each (models/core/registry.h), by file:
// builtin_springs.cc, builtin_solids.cc, builtin_contact.cc,
// builtin_bodies.cc, builtin_fluids.cc.
#define SPRINGLAB_SCENES(X)               \
  X(SceneEntry, spring_scene)             \
  X(SceneEntry, oscillator_scene)         \
  X(SceneEntry, chain_scene)              \
  X(SceneEntry, cloth_scene)              \
  X(SceneEntry, beam_scene)               \
  X(SceneEntry, membrane_scene)           \
  X(SceneEntry, block_scene)              \
  X(SceneEntry, slope_scene)              \
  X(SceneEntry, tumbling_box_scene)       \
  X(SceneEntry, box_on_slope_scene)       \
  X(SceneEntry, box_chain_scene)          \
  X(SceneEntry, box_pile_scene)           \
  X(SceneEntry, box_tower_scene)          \
  X(SceneEntry, box_drop_scene)           \
  X(SceneEntry, dam_break_scene)          \
  X(SceneEntry, dam_break_obstacle_scene) \
  X(SceneEntry, tank_scene)               \
  X(SceneEntry, sloshing_scene)

SPRINGLAB_REGISTRY(SceneEntry, SPRINGLAB_SCENES, scene_registry)

namespace {

std::string format_number(double value) { return shortest_decimal(value); }

// The whole text must be one finite decimal number: "", "1x", "nan", "inf",
// " 1" are refused (strtod would accept some of them, or a prefix).
std::optional<double> parse_number(const std::string& text) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+' && last - first > 1 && first[1] != '-') ++first;
  double value = 0.0;
  const char* end = read_decimal(first, last, value);
  if (end != last || !std::isfinite(value)) return std::nullopt;
  return value;
}

// A count as a whole number (format_number would write 1e+07).
std::string format_count(double value) {
  return value == std::floor(value) && std::abs(value) < 1e15
             ? std::to_string(static_cast<long long>(value))
             : format_number(value);
}

// Refuses a scene over the caps of scene.h before it is built.
void check_counts(const std::string& label, const SceneEntry& g, const SceneValues& values) {
  if (g.counts == nullptr) return;
  const SceneCounts counts = g.counts(values);
  auto check = [&](double count, std::size_t cap, const char* what) {
    if (count > static_cast<double>(cap)) {
      const std::string parameter = g.size_parameter;
      throw SceneError(label + ": parameter '" + parameter + "' = " +
                       format_count(values.at(parameter)) + " would make " +
                       format_count(count) + " " + what + ", over the cap of " +
                       std::to_string(cap) + " per scene");
    }
  };
  check(counts.particles, kMaxSceneParticles, "particles");
  check(counts.springs, kMaxSceneSprings, "springs");
}

void check_range(const std::string& label, const ParameterSpec& spec, double value) {
  const std::string prefix = label + ": parameter '" + spec.parameter.name + "' must be ";
  const std::string got = " (got " + format_number(value) + ")";
  switch (spec.range) {
    case Range::kAny:
      break;
    case Range::kNonNegative:
      if (value < 0) throw SceneError(prefix + ">= 0" + got);
      break;
    case Range::kPositive:
      if (value <= 0) throw SceneError(prefix + "> 0" + got);
      break;
    case Range::kWhole:
      if (value != std::floor(value) || value < spec.min || value > spec.max) {
        throw SceneError(prefix + "a whole number in [" +
                         std::to_string(static_cast<long long>(spec.min)) + ", " +
                         std::to_string(static_cast<long long>(spec.max)) + "]" + got);
      }
      break;
    case Range::kZeroOrOne:
      if (value != 0 && value != 1) throw SceneError(prefix + "0 or 1" + got);
      break;
    case Range::kChoice:
      break;  // read_choice
  }
}

// "a, b, c".
std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// A choice parameter's value: one of its names, or the index of one.
double read_choice(const std::string& label, const ParameterSpec& spec, const std::string& text) {
  const std::vector<std::string>& choices = spec.parameter.choices;
  const auto at = std::find(choices.begin(), choices.end(), text);
  if (at != choices.end()) return static_cast<double>(at - choices.begin());
  const std::optional<double> index = parse_number(text);
  if (index && *index == std::floor(*index) && *index >= spec.min && *index <= spec.max) {
    return *index;
  }
  throw SceneError(label + ": parameter '" + spec.parameter.name + "' must be one of " +
                   joined(choices) +
                   " or its number 0 to " + std::to_string(choices.size() - 1) + " (got '" +
                   text + "')" + did_you_mean(text, choices));
}



}  // namespace

const std::vector<BuiltinScene>& builtin_scenes() {
  static const std::vector<BuiltinScene> scenes = [] {
    std::vector<BuiltinScene> out;
    for (const SceneEntry* e : scene_registry().entries()) out.push_back(*e);
    std::sort(out.begin(), out.end(),
              [](const BuiltinScene& a, const BuiltinScene& b) { return a.name < b.name; });
    return out;
  }();
  return scenes;
}

bool is_builtin_scene(const std::string& name) { return scene_registry().find(name) != nullptr; }

Scene make_builtin_scene(const std::string& name,
                         const std::vector<std::pair<std::string, std::string>>& overrides) {
  const SceneEntry* entry = scene_registry().find(name);
  if (entry == nullptr) {
    throw SceneError(scene_registry().unknown("built-in scene", printable(name)));
  }
  const std::string label = "scene '" + name + "'";
  SceneValues values;
  for (const ParameterSpec& spec : entry->specs)
    values[spec.parameter.name] = spec.parameter.default_value;

  // Each value is checked as given; a key given twice keeps the last value.
  for (const auto& [key_binding, text] : overrides) {
    const std::string& key = key_binding;  // clang 14 cannot capture a structured binding
    const auto spec = std::find_if(entry->specs.begin(), entry->specs.end(),
                                   [&](const ParameterSpec& s) { return s.parameter.name == key; });
    if (spec == entry->specs.end()) {
      std::vector<std::string> names;
      for (const ParameterSpec& s : entry->specs) names.push_back(s.parameter.name);
      throw SceneError(label + ": unknown parameter '" + key + "'" + did_you_mean(key, names) +
                       " (parameters: " + joined(names) + ")");
    }
    if (spec->range == Range::kChoice) {
      values[key] = read_choice(label, *spec, text);
      continue;
    }
    const std::optional<double> value = parse_number(text);
    if (!value)
      throw SceneError(label + ": parameter '" + key + "' must be a finite number (got '" + text +
                       "')");
    check_range(label, *spec, *value);
    values[key] = *value;
  }

  check_counts(label, *entry, values);
  Scene scene = entry->build(values);
  scene.name = name;
  validate_scene(scene, label);  // a safety net: a generator bug is reported, not simulated
  return scene;
}

}  // namespace springlab
