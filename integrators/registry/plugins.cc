#include "integrators/registry/plugins.h"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>

#include "integrators/core/your_integrator.h"
#include "integrators/registry/registry.h"

namespace springlab {
namespace {

struct Loaded {
  std::string canonical;
  LoadedPlugin plugin;
};

std::mutex& plugins_mutex() {
  static std::mutex m;
  return m;
}
std::vector<Loaded>& plugins() {
  static std::vector<Loaded> list;
  return list;
}

}  // namespace

std::vector<std::string> load_plugin(const std::string& path) {
  std::lock_guard<std::mutex> lock(plugins_mutex());
  std::error_code ec;
  if (path.empty()) throw std::invalid_argument("--plugin: the file name is empty");
  if (!std::filesystem::exists(path, ec)) {
    throw std::invalid_argument(path + ": no such plug-in file");
  }
  const std::string canonical = std::filesystem::canonical(path, ec).string();
  for (const Loaded& l : plugins()) {
    if (l.canonical == canonical) return l.plugin.integrators;
  }
  // A plain name would be searched on the library path: take it here.
  const std::string as_path = path.find('/') == std::string::npos ? "./" + path : path;
  take_offered_integrators();  // nothing left over from elsewhere
  // RTLD_NOW: a symbol the plug-in needs and springlab lacks is refused
  // now, by name, not at its first call.
  void* handle = ::dlopen(as_path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = ::dlerror();
    throw std::invalid_argument(path + ": cannot load the plug-in: " +
                                (why != nullptr ? why : "unknown reason"));
  }
  const std::vector<const IntegratorEntry*> offered = take_offered_integrators();
  if (offered.empty()) {
    throw std::invalid_argument(path + ": the plug-in registers no integrator (a line "
                                "SPRINGLAB_PLUGIN_INTEGRATOR(YourClass) is missing)");
  }
  LoadedPlugin plugin{path, {}};
  for (const IntegratorEntry* entry : offered) {
    if (integrator_registry().find(entry->name) != nullptr) {
      throw std::invalid_argument(path + ": integrator '" + entry->name +
                                  "' is already registered: give your method another name");
    }
  }
  for (const IntegratorEntry* entry : offered) {
    register_integrator(*entry);
    plugin.integrators.push_back(entry->name);
  }
  // The library stays loaded for the life of the process: its entries and
  // code are in use by the registry.
  plugins().push_back({canonical, plugin});
  return plugin.integrators;
}

std::vector<LoadedPlugin> loaded_plugins() {
  std::lock_guard<std::mutex> lock(plugins_mutex());
  std::vector<LoadedPlugin> out;
  for (const Loaded& l : plugins()) out.push_back(l.plugin);
  return out;
}

}  // namespace springlab
