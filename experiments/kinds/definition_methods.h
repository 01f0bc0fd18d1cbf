// The methods an experiment definition brings beside the built-ins
// (docs/your-own-integrator.md "In the report"):
//
//   "plugins": ["libmy_methods.so", ...]   C++ plug-ins, loaded before the
//                                          definition's integrators are read
//   "python":  ["my_euler.py", ...]        Python files whose
//                                          springlab.Integrator classes are
//                                          registered, when the definition
//                                          runs from Python
//
// Both paths are relative to the definition's folder; a plug-in named by a
// plain file name that is not there is looked for in the folders of the
// environment variable SPRINGLAB_PLUGIN_PATH (':'-separated: the report's
// build sets it to where the examples' plug-ins are built).
#pragma once

#include <functional>
#include <string>

#include "experiments/kinds/definition.h"

namespace springlab {

// Loads what `top` names under "plugins" and "python"; refuses, naming the
// element, a file that is not there, a plug-in that does not load, and
// "python" outside Python (no loader set).
void load_definition_methods(const DefinitionObject& top);

// How a "python" file is loaded: set by the Python module (it imports the
// file and registers its classes); unset in the command line.
using PythonMethodLoader = std::function<void(const std::string& path)>;
void set_python_method_loader(PythonMethodLoader loader);

}  // namespace springlab
