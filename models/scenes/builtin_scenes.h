// Built-in scenes (docs/scenes.md "Built-in scenes"): generators that return a Scene, parameterised
// by `-p key=value`. Each is printable as a scene file (`springlab scene NAME`).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "models/core/scene.h"

namespace springlab {

struct SceneParameter {
  std::string name;
  double default_value;  // a choice parameter: the index of its default choice
  std::string meaning;   // with units, shown by `springlab list`
  // A choice parameter (a finite-element scene's `model`): given by name,
  // `-p model=corotated`, or by its index here, `-p model=1`. Empty for a
  // number.
  std::vector<std::string> choices;
};

struct BuiltinScene {
  std::string name;
  std::string description;
  std::vector<SceneParameter> parameters;
};

// Sorted by name. The registry (builtin_scenes.cc) lists each scene's entry,
// defined in the scene's file (scene_entry.h).
const std::vector<BuiltinScene>& builtin_scenes();
bool is_builtin_scene(const std::string& name);

// Builds a built-in scene. `overrides` are the `-p key=value` pairs as typed.
// Throws SceneError naming the parameter on an unknown key, a value that is
// not a finite number (nor one of a choice parameter's names), or a value
// outside the parameter's range.
Scene make_builtin_scene(const std::string& name,
                         const std::vector<std::pair<std::string, std::string>>& overrides = {});

}  // namespace springlab
