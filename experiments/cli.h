// The `springlab` command line (README "The command line"). Kept out of main() so the
// commands' pieces can be reused by later tools (experiments, bindings).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "models/scene.h"

namespace springlab {

// SCENE is a scene file's path or a built-in scene's name; `-p key=value`
// applies to built-ins only. Throws SceneError with a one-line message.
Scene resolve_scene(const std::string& scene_arg, const std::vector<std::string>& parameters);

int run_cli(int argc, char** argv);

}  // namespace springlab
