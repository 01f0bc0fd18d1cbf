// Memory counted before it is spent (issue 46.5-7; docs/reliability.md
// "Memory known before it is spent"): a scene whose model would not fit is
// refused before the model is built, and a model whose Jacobian pattern
// would not fit before a method that assembles Jacobians builds it, each
// with one line naming what weighs most in the scene's words (its bodies,
// fluid particles, springs ...). The estimate is the kinds' own
// (models/memory_estimate.h); the limit is what this process may still
// allocate (integrators/linear/sparse_direct_solver.h: physical memory, or
// RLIMIT_AS less what is mapped). A factor that will not fit is checked
// after the pattern exists (factor_fit_error).
#pragma once

#include <stdexcept>
#include <string>

#include "integrators/core/integrator.h"
#include "models/model/model.h"
#include "models/core/scene.h"

namespace springlab {

class MemoryRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Before `Model model(scene)`. `label` names the scene in the line
// ("box-chain", "tank.json"). Throws MemoryRefused.
void check_scene_memory(const Scene& scene, const std::string& label);
void check_scene_memory(const Scene& scene, const std::string& label, double limit);

// Before `integrator` (made, not yet initialized) runs on `model` and makes
// its first Jacobian: where the method assembles one
// (Integrator::assembles_jacobians), the model with its pattern must fit.
// Throws MemoryRefused.
void check_jacobian_memory(const Model& model, const Integrator& integrator,
                           const std::string& label);
void check_jacobian_memory(const Model& model, const Integrator& integrator,
                           const std::string& label, double limit);

}  // namespace springlab
