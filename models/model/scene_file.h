// Scene files (docs/physics.md "Scene files"): reading, checking and writing
// a whole scene. Each element kind reads, checks and writes its own keys
// (models/core/element_kind.h); these functions walk the registry
// (element_registry.h) in its order, so they sit above every kind.
#pragma once

#include <string>

#include "models/core/scene.h"

namespace springlab {

// Parses and validates a scene (docs/physics.md "Scene files"). `source` names the file in
// messages. Throws SceneError on any violation; never returns a half-valid scene.
Scene parse_scene(const std::string& json_text, const std::string& source);
// `source` names the file in messages (default: the path). A FIFO or a
// pipe (/dev/stdin) is read like a file, within the same size cap.
Scene load_scene_file(const std::string& path, const std::string& source = "");

// The scene as a scene file (round-trips through parse_scene).
std::string scene_to_json(const Scene& scene);

// Runs every docs/physics.md "Scene files" check on an already-built scene (used for built-ins
// too).
void validate_scene(const Scene& scene, const std::string& source);

}  // namespace springlab
