#include "models/core/verdict.h"

namespace springlab {

std::string_view to_string(VerdictRule rule) {
  switch (rule) {
    case VerdictRule::kNonFinite: return "non-finite";
    case VerdictRule::kEnergy: return "energy";
    case VerdictRule::kForbidden: return "forbidden-state";
    case VerdictRule::kFluidOutside: return "fluid-outside";
    case VerdictRule::kFluidDensity: return "fluid-density";
    case VerdictRule::kBodyStrain: return "body-strain";
    case VerdictRule::kBodyEnergy: return "body-energy";
  }
  return "unknown";
}

}  // namespace springlab
