// Every method by name (docs/integrators.md "The integrators"), one line
// each, in the one registration idiom of springlab (models/core/registry.h):
// a method's file ends with SPRINGLAB_INTEGRATOR(Class, accessor) and its
// line here is X(IntegratorEntry, accessor). Sorted by name; SUNDIALS's
// methods after, absent from the web build (web/), which has no SUNDIALS.
#include "integrators/registry/registry.h"

#include <algorithm>
#include <stdexcept>

#include "integrators/core/integrator_entry.h"
#include "models/core/registry.h"

#define SPRINGLAB_HAND_WRITTEN_INTEGRATORS(X)           \
  X(IntegratorEntry, bdf2_integrator)                   \
  X(IntegratorEntry, central_difference_integrator)     \
  X(IntegratorEntry, discrete_gradient_integrator)      \
  X(IntegratorEntry, explicit_euler_integrator)         \
  X(IntegratorEntry, fox_goodwin_integrator)            \
  X(IntegratorEntry, generalized_alpha_integrator)      \
  X(IntegratorEntry, hht_alpha_integrator)              \
  X(IntegratorEntry, implicit_euler_integrator)         \
  X(IntegratorEntry, implicit_midpoint_integrator)      \
  X(IntegratorEntry, linear_acceleration_integrator)    \
  X(IntegratorEntry, linear_implicit_euler_integrator)  \
  X(IntegratorEntry, newmark_integrator)                \
  X(IntegratorEntry, projective_dynamics_integrator)    \
  X(IntegratorEntry, rk4_integrator)                    \
  X(IntegratorEntry, symplectic_euler_integrator)       \
  X(IntegratorEntry, tr_bdf2_integrator)                \
  X(IntegratorEntry, vbd_integrator)                    \
  X(IntegratorEntry, verlet_integrator)                 \
  X(IntegratorEntry, xpbd_integrator)                   \
  X(IntegratorEntry, yoshida4_integrator)               \
  X(IntegratorEntry, yoshida6_integrator)
#ifndef SPRINGLAB_NO_SUNDIALS
#define SPRINGLAB_SUNDIALS_INTEGRATORS(X)               \
  X(IntegratorEntry, arkode_dirk_integrator)            \
  X(IntegratorEntry, arkode_erk_integrator)             \
  X(IntegratorEntry, arkode_imex_integrator)            \
  X(IntegratorEntry, cvode_adams_integrator)            \
  X(IntegratorEntry, cvode_bdf_integrator)              \
  X(IntegratorEntry, ida_integrator)
#else
#define SPRINGLAB_SUNDIALS_INTEGRATORS(X)
#endif
#define SPRINGLAB_INTEGRATORS(X) SPRINGLAB_HAND_WRITTEN_INTEGRATORS(X) SPRINGLAB_SUNDIALS_INTEGRATORS(X)

namespace springlab {

SPRINGLAB_REGISTRY(IntegratorEntry, SPRINGLAB_INTEGRATORS, integrator_registry)

void register_integrator(const IntegratorEntry& entry) { integrator_registry().add(entry); }

std::vector<std::string> integrator_names() {
  std::vector<std::string> names = integrator_registry().names();
  std::sort(names.begin(), names.end());
  return names;
}

bool is_integrator(const std::string& name) { return integrator_registry().find(name) != nullptr; }

bool is_builtin_integrator(const std::string& name) {
#define SPRINGLAB_INTEGRATOR_NAME(ENTRY, ACCESSOR) ACCESSOR().name,
  static const std::vector<std::string> builtin = {SPRINGLAB_INTEGRATORS(SPRINGLAB_INTEGRATOR_NAME)};
#undef SPRINGLAB_INTEGRATOR_NAME
  return std::find(builtin.begin(), builtin.end(), name) != builtin.end();
}

std::unique_ptr<Integrator> make_integrator(const std::string& name) {
  if (const IntegratorEntry* e = integrator_registry().find(name)) return e->make();
  throw std::invalid_argument(integrator_registry().unknown("integrator", name));
}

}  // namespace springlab
