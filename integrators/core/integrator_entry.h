// How a method is registered by name (models/core/registry.h): the entry a
// method's file defines, one line at its end,
//
//   SPRINGLAB_INTEGRATOR(ImplicitEuler, implicit_euler_integrator)
//
// and the one line X(IntegratorEntry, implicit_euler_integrator) in
// integrators/registry/registry.cc. A plug-in registers its own at load time
// (register_integrator, integrators/registry/registry.h).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "integrators/core/integrator.h"

namespace springlab {

struct IntegratorEntry {
  std::string name;  // as the method's IntegratorInfo says
  std::function<std::unique_ptr<Integrator>()> make;
};

// The entry of a method class: its name from its own IntegratorInfo, so it
// is written once.
template <class Method>
IntegratorEntry integrator_entry() {
  return {Method().name(), [] { return std::unique_ptr<Integrator>(new Method()); }};
}

}  // namespace springlab

// Defines `const IntegratorEntry& ACCESSOR()` for the method class CLASS.
// Inside namespace springlab.
#define SPRINGLAB_INTEGRATOR(CLASS, ACCESSOR)                           \
  const IntegratorEntry& ACCESSOR() {                                   \
    static const IntegratorEntry entry = integrator_entry<CLASS>();     \
    return entry;                                                       \
  }
