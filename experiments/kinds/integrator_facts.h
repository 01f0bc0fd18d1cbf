// The facts of one integrator as JSON, the same for a built-in (`springlab
// list --json`, experiments/cli/integrator_table.h) and for a method an
// experiment brought with it (a plug-in's or a Python class's: the settings
// file lists those under "own_integrators", so the report groups and labels
// them like the built-ins without a second `list`).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "integrators/core/integrator.h"

namespace springlab {

// "explicit", "symplectic", "implicit" (fixed step) or "adaptive".
std::string integrator_family(const IntegratorInfo& info);

// {"name", "family", "order", "position_order", "adaptive", "implicit",
//  "symplectic", "iterates_to_tolerance", "scheme", "stability": {"kind",
//  "text", "limit_wh", "alpha_degrees", "note", "rho_inf"}}
nlohmann::ordered_json integrator_facts_json(const std::string& name, const IntegratorInfo& info);

}  // namespace springlab
