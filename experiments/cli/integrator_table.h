// What `springlab list` says about each registered integrator: the facts of
// its IntegratorInfo (order, kind, stability property), the family the report
// groups it in, and the colour and marker every figure of every report draws
// it with. `springlab list --json` writes this table; the report target saves
// it as report-data/integrators.json and the report reads nothing else about
// integrators, so a method looks the same in every figure of every report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/kinds/integrator_facts.h"  // integrator_family, the facts of one
#include "integrators/core/integrator.h"

namespace springlab {

// How the report draws a method: a matplotlib colour "#rrggbb" and marker.
struct IntegratorStyle {
  std::string colour;
  std::string marker;
};

// The method's own entry of the style table; a method without one gets a
// colour and marker picked from a reserve by a hash of its name (the same in
// every run and report, but possibly shared: give a new method its entry).
IntegratorStyle integrator_style(const std::string& name);

// {"integrators": [{"name", "family", "order", "adaptive", "implicit",
//   "symplectic", "iterates_to_tolerance", "scheme", "stability": {"kind",
//   "text", "limit_wh", "alpha_degrees", "note"}, "colour", "marker"}, ...],
//  "scenes": [{"name", "description", "parameters": [...]}, ...]}
nlohmann::ordered_json integrator_table_json();

}  // namespace springlab
