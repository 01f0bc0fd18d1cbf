#include "experiments/kinds/integrator_facts.h"

#include <algorithm>
#include <cmath>

namespace springlab {
namespace {

nlohmann::ordered_json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

}  // namespace

std::string integrator_family(const IntegratorInfo& info) {
  if (info.adaptive) return "adaptive";
  if (info.symplectic) return "symplectic";
  if (info.implicit) return "implicit";
  return "explicit";
}

nlohmann::ordered_json integrator_facts_json(const std::string& name, const IntegratorInfo& info) {
  using Json = nlohmann::ordered_json;
  Json stability;
  stability["kind"] = to_string(info.stability);
  stability["text"] = stability_text(info);
  // Largest stable w h undamped: null when every step is stable (A, L) or
  // there is no one number.
  stability["limit_wh"] = number_or_null(info.stability_limit);
  stability["alpha_degrees"] = number_or_null(info.stability_alpha);
  stability["note"] = info.stability_note;
  // The spectral radius as w h -> infinity, where the method states it.
  stability["rho_inf"] = number_or_null(info.spectral_radius_infinity);
  Json entry;
  entry["name"] = name;
  entry["family"] = integrator_family(info);
  entry["order"] = info.order;
  // The positions' order where F depends on x alone, where higher (fox-goodwin: 4).
  entry["position_order"] = std::max(info.order, info.position_order);
  entry["adaptive"] = info.adaptive;
  entry["implicit"] = info.implicit;
  entry["symplectic"] = info.symplectic;
  entry["iterates_to_tolerance"] = info.iterates_to_tolerance;
  entry["scheme"] = info.scheme;
  entry["stability"] = stability;
  return entry;
}

}  // namespace springlab
