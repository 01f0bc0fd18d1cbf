// Integrators chosen by name (docs/integrators.md "The integrators"), from one sorted registry.
// Adding a method: one new file pair plus one line in registry.cc; every
// shared test suite (tests/test_integrators*.cc) then covers it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/core/integrator.h"

namespace springlab {

// Sorted by name.
std::vector<std::string> integrator_names();
bool is_integrator(const std::string& name);
// Throws std::invalid_argument listing the valid names when `name` is unknown.
std::unique_ptr<Integrator> make_integrator(const std::string& name);

}  // namespace springlab
