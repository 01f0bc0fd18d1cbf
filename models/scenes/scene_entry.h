// One built-in scene as the scene registry holds it (builtin_scenes.cc lists
// them, one line each; models/core/registry.h is the idiom every registry
// shares). A scene's file defines its generator and its entry:
//
//   const SceneEntry& spring_scene() {
//     static const SceneEntry entry = scene_entry("spring", "the course's example ...",
//         {param("k", 100, "spring stiffness [N/m]", Range::kPositive), ...}, build_spring);
//     return entry;
//   }
//
// Adding a scene is that function in its file plus one line in the list.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "models/core/scene.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab {

// A scene's parameter values by name, after the defaults and the `-p`
// overrides; a choice parameter holds the index of its choice.
using SceneValues = std::map<std::string, double>;

// How a parameter's value is restricted (every value must be finite).
// kChoice: one of SceneParameter::choices by name, or its index.
enum class Range { kAny, kNonNegative, kPositive, kWhole, kZeroOrOne, kChoice };

struct ParameterSpec {
  SceneParameter parameter;
  Range range = Range::kAny;
  double min = 0.0;  // kWhole only: inclusive bounds
  double max = 0.0;
};

// How many particles and springs a generator would make: compared with the
// caps of scene.h before anything is allocated.
struct SceneCounts {
  double particles = 0.0;
  double springs = 0.0;
};

struct SceneEntry : BuiltinScene {
  std::vector<ParameterSpec> specs;
  Scene (*build)(const SceneValues&) = nullptr;
  SceneCounts (*counts)(const SceneValues&) = nullptr;  // nullptr: a fixed, small scene
  const char* size_parameter = nullptr;                 // the parameter the counts grow with
};

// An entry, its BuiltinScene::parameters drawn from the specs.
SceneEntry scene_entry(std::string name, std::string description, std::vector<ParameterSpec> specs,
                       Scene (*build)(const SceneValues&),
                       SceneCounts (*counts)(const SceneValues&) = nullptr,
                       const char* size_parameter = nullptr);

ParameterSpec param(const char* name, double value, const char* meaning, Range range,
                    double min = 0.0, double max = 0.0);

// A choice among `choices` (given by name or by index), `value` its default.
ParameterSpec choice(const char* name, const std::string& value, const std::string& meaning,
                     std::vector<std::string> choices);

// a followed by b.
std::vector<ParameterSpec> with(std::vector<ParameterSpec> a, const std::vector<ParameterSpec>& b);

}  // namespace springlab
