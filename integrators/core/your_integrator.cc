#include "integrators/core/your_integrator.h"

#include <mutex>

namespace springlab {
namespace {

std::mutex& offered_mutex() {
  static std::mutex m;
  return m;
}
std::vector<const IntegratorEntry*>& offered() {
  static std::vector<const IntegratorEntry*> entries;
  return entries;
}

}  // namespace

void offer_plugin_integrator(const IntegratorEntry& entry) noexcept {
  try {
    std::lock_guard<std::mutex> lock(offered_mutex());
    offered().push_back(&entry);
  } catch (...) {
    // Out of memory while a library loads: the loader then finds nothing
    // offered and says the plug-in registers no integrator.
  }
}

std::vector<const IntegratorEntry*> take_offered_integrators() {
  std::lock_guard<std::mutex> lock(offered_mutex());
  std::vector<const IntegratorEntry*> out;
  out.swap(offered());
  return out;
}

}  // namespace springlab
