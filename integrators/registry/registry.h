// Integrators chosen by name (docs/integrators.md "The integrators"), from one registry
// (registry.cc; the idiom of models/core/registry.h). Adding a method: one
// new file pair plus one line in registry.cc; every shared test suite
// (tests/test_integrators*.cc) then covers it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/core/integrator.h"
#include "integrators/core/integrator_entry.h"
#include "models/core/registry.h"

namespace springlab {

// The registry itself: the built-ins, then what was registered at run time.
Registry<IntegratorEntry>& integrator_registry();
// Adds a method at run time (a plug-in's, docs/your-own-integrator.md);
// `entry` must outlive its use. Throws std::invalid_argument when the name
// is taken.
void register_integrator(const IntegratorEntry& entry);

// Sorted by name.
std::vector<std::string> integrator_names();
bool is_integrator(const std::string& name);
// Whether `name` is one of springlab's own methods (not a plug-in's or a
// Python class's, registered at run time).
bool is_builtin_integrator(const std::string& name);
// Throws std::invalid_argument naming the closest names and listing the
// valid ones when `name` is unknown.
std::unique_ptr<Integrator> make_integrator(const std::string& name);

}  // namespace springlab
