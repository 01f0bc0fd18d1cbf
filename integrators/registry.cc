#include "integrators/registry.h"

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "integrators/bdf2.h"
#include "integrators/discrete_gradient.h"
#include "integrators/explicit_euler.h"
#include "integrators/generalized_alpha.h"
#include "integrators/implicit_euler.h"
#include "integrators/implicit_midpoint.h"
#include "integrators/linear_implicit_euler.h"
#include "integrators/newmark.h"
#include "integrators/projective_dynamics.h"
#include "integrators/rk4.h"
#include "integrators/symplectic_euler.h"
#include "integrators/tr_bdf2.h"
#include "integrators/vbd.h"
#include "integrators/verlet.h"
#include "integrators/xpbd.h"
#include "integrators/yoshida.h"
// SUNDIALS's adaptive methods: absent from the web build (web/), which has
// no SUNDIALS.
#ifndef SPRINGLAB_NO_SUNDIALS
#include "integrators/arkode_ark.h"
#include "integrators/arkode_erk.h"
#include "integrators/cvode_integrator.h"
#include "integrators/ida_integrator.h"
#endif

namespace springlab {
namespace {

struct Entry {
  std::string name;
  std::function<std::unique_ptr<Integrator>()> make;
};

// The name comes from the method's own IntegratorInfo, so it is written once.
template <class Method>
Entry entry() {
  return {Method().name(), [] { return std::unique_ptr<Integrator>(new Method()); }};
}

// One line per method, sorted by name (hand-written methods, then SUNDIALS's;
// integrator_names() sorts them all).
const std::vector<Entry>& registry() {
  static const std::vector<Entry> entries = {
      entry<Bdf2>(),
      entry<CentralDifference>(),
      entry<DiscreteGradient>(),
      entry<ExplicitEuler>(),
      entry<FoxGoodwin>(),
      entry<GeneralizedAlpha>(),
      entry<HhtAlpha>(),
      entry<ImplicitEuler>(),
      entry<ImplicitMidpoint>(),
      entry<LinearAcceleration>(),
      entry<LinearImplicitEuler>(),
      entry<Newmark>(),
      entry<ProjectiveDynamics>(),
      entry<RungeKutta4>(),
      entry<SymplecticEuler>(),
      entry<TrBdf2>(),
      entry<Vbd>(),
      entry<VelocityVerlet>(),
      entry<Xpbd>(),
      entry<Yoshida4>(),
      entry<Yoshida6>(),
#ifndef SPRINGLAB_NO_SUNDIALS
      entry<ArkodeDirk>(),
      entry<ArkodeErk>(),
      entry<ArkodeImex>(),
      entry<CvodeAdams>(),
      entry<CvodeBdf>(),
      entry<IdaIntegrator>(),
#endif
  };
  return entries;
}

}  // namespace

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const Entry& e : registry()) names.push_back(e.name);
  std::sort(names.begin(), names.end());
  return names;
}

bool is_integrator(const std::string& name) {
  const auto& r = registry();
  return std::any_of(r.begin(), r.end(), [&](const Entry& e) { return name == e.name; });
}

std::unique_ptr<Integrator> make_integrator(const std::string& name) {
  for (const Entry& e : registry()) {
    if (name == e.name) return e.make();
  }
  std::string valid;
  for (const std::string& n : integrator_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown integrator '" + name + "' (integrators: " + valid + ")");
}

}  // namespace springlab
