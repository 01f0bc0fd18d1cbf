// Plug-ins: integrators built outside the tree (docs/your-own-integrator.md),
// loaded while springlab runs. A plug-in is a shared library whose methods
// each end with SPRINGLAB_PLUGIN_INTEGRATOR(Class)
// (integrators/core/your_integrator.h); loading it runs those lines, which
// offer the methods, and the loader registers them by name beside the
// built-ins, so every command, experiment and test that takes a method by
// name takes them too.
//
// The library is loaded into this process (dlopen): its code calls the
// springlab it runs in (the executable exports its symbols), so it is built
// against the headers only (springlab_add_plugin in the CMake package) and
// never carries a second copy of the library.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace springlab {

// Loads the plug-in at `path` (a path as given: a plain file name is taken
// in the current folder, not searched for) and registers its methods.
// Returns their names, in the order the library offered them. Loading the
// same file again registers nothing new and returns the same names.
// Throws std::invalid_argument, one line naming `path`, when the library
// cannot be loaded (the loader's reason), offers no method, or offers a
// name that is already registered.
std::vector<std::string> load_plugin(const std::string& path);

// The plug-ins loaded so far (as given) with the methods each registered.
struct LoadedPlugin {
  std::string path;
  std::vector<std::string> integrators;
};
std::vector<LoadedPlugin> loaded_plugins();

}  // namespace springlab
