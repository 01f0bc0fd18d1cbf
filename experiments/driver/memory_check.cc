// The memory checks of memory_check.h.
#include "experiments/driver/memory_check.h"

#include "integrators/linear/sparse_direct_solver.h"
#include "models/model/model_memory.h"

namespace springlab {
namespace {

// "about 21.5 GB, 20.3 GB of it for its 974169 fluid particles"
std::string estimate_text(const MemoryEstimate& e, bool jacobians) {
  std::string text = "about " + format_bytes(e.bytes(jacobians));
  if (const MemoryPart* part = e.largest(jacobians)) {
    text += ", " + format_bytes(e.part_bytes(*part, jacobians)) + " of it for its " + part->what;
  }
  return text;
}

}  // namespace

void check_scene_memory(const Scene& scene, const std::string& label) {
  check_scene_memory(scene, label, memory_limit_bytes());
}

void check_scene_memory(const Scene& scene, const std::string& label, double limit) {
  const MemoryEstimate e = estimate_model_memory(scene);
  if (!(e.bytes(false) > limit)) return;
  throw MemoryRefused(label + ": the model would need " + estimate_text(e, false) +
                      ", more than the " + format_bytes(limit) +
                      " this process may use: make the scene smaller");
}

void check_jacobian_memory(const Model& model, const Integrator& integrator,
                           const std::string& label) {
  check_jacobian_memory(model, integrator, label, memory_limit_bytes());
}

void check_jacobian_memory(const Model& model, const Integrator& integrator,
                           const std::string& label, double limit) {
  if (!integrator.assembles_jacobians(model)) return;
  const MemoryEstimate e = estimate_model_memory(model.scene());
  if (!(e.bytes(true) > limit)) return;
  throw MemoryRefused("--integrator " + integrator.name() + ": " + label +
                      "'s model and Jacobian pattern would need " + estimate_text(e, true) +
                      ", more than the " + format_bytes(limit) +
                      " this process may use: make the scene smaller, or use a method that "
                      "assembles no Jacobian (e.g. symplectic-euler, rk4, xpbd)");
}

}  // namespace springlab
