#include "experiments/kinds/definition_methods.h"

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <sstream>

#include "integrators/registry/plugins.h"

namespace springlab {
namespace {

namespace fs = std::filesystem;

std::mutex& loader_mutex() {
  static std::mutex m;
  return m;
}
PythonMethodLoader& python_loader() {
  static PythonMethodLoader loader;
  return loader;
}

std::vector<std::string> paths(const DefinitionObject& top, const char* key) {
  std::vector<std::string> out;
  const nlohmann::json& list = top.raw(key);
  if (!list.is_array() || list.empty()) top.fail(key, "must be a non-empty array of file names");
  for (const nlohmann::json& item : list) {
    if (!item.is_string() || item.get<std::string>().empty()) {
      top.fail(key, "must be a non-empty array of file names");
    }
    out.push_back(item.get<std::string>());
  }
  return out;
}

// The plug-in file: beside the definition, or (a plain name) on
// SPRINGLAB_PLUGIN_PATH.
std::string find_plugin(const DefinitionObject& top, const fs::path& base, const std::string& name,
                        std::size_t index) {
  std::error_code ec;
  const fs::path here = fs::path(name).is_absolute() ? fs::path(name) : base / name;
  if (fs::exists(here, ec)) return here.string();
  std::string searched = base.empty() ? "." : base.string();
  if (fs::path(name).filename() == fs::path(name)) {
    if (const char* env = std::getenv("SPRINGLAB_PLUGIN_PATH")) {
      std::stringstream folders(env);
      std::string folder;
      while (std::getline(folders, folder, ':')) {
        if (folder.empty()) continue;
        if (fs::exists(fs::path(folder) / name, ec)) return (fs::path(folder) / name).string();
      }
      searched += " and SPRINGLAB_PLUGIN_PATH";
    }
  }
  top.fail("plugins[" + std::to_string(index) + "]",
           "no plug-in file '" + name + "' (looked in " + searched + ")");
}

}  // namespace

void set_python_method_loader(PythonMethodLoader loader) {
  std::lock_guard<std::mutex> lock(loader_mutex());
  python_loader() = std::move(loader);
}

void load_definition_methods(const DefinitionObject& top) {
  const fs::path base = fs::path(top.file()).parent_path();
  if (top.has("plugins")) {
    const std::vector<std::string> plugins = paths(top, "plugins");
    for (std::size_t i = 0; i < plugins.size(); ++i) {
      const std::string file = find_plugin(top, base, plugins[i], i);
      try {
        load_plugin(file);
      } catch (const std::invalid_argument& e) {
        top.fail("plugins[" + std::to_string(i) + "]", e.what());
      }
    }
  }
  if (top.has("python")) {
    const std::vector<std::string> files = paths(top, "python");
    PythonMethodLoader loader;
    {
      std::lock_guard<std::mutex> lock(loader_mutex());
      loader = python_loader();
    }
    if (!loader) {
      top.fail("python", "methods written in Python run from Python: "
                         "springlab.experiment(\"" + top.file() + "\", out=...) "
                         "(docs/your-own-integrator.md)");
    }
    std::error_code ec;
    for (std::size_t i = 0; i < files.size(); ++i) {
      const fs::path file = fs::path(files[i]).is_absolute() ? fs::path(files[i]) : base / files[i];
      if (!fs::exists(file, ec)) {
        top.fail("python[" + std::to_string(i) + "]", "no such file '" + file.string() + "'");
      }
      loader(file.string());
    }
  }
}

}  // namespace springlab
