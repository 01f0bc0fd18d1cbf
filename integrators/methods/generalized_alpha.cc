#include "integrators/methods/generalized_alpha.h"

#include <charconv>
#include <cmath>
#include <sstream>
#include <string>

#include "integrators/core/integrator_entry.h"
#include "models/core/decimal_text.h"

namespace springlab {
namespace {

constexpr double kDefaultAlpha = -0.1;
constexpr double kDefaultRhoInf = 0.5;

}  // namespace

HhtAlpha::HhtAlpha()
    : NewmarkFamily({.name = "hht-alpha",
                     .scheme = "Newmark with M a' = F((1 + alpha) y' - alpha y), y = (t, x, v), "
                               "gamma = 1/2 - alpha, beta = (1 - alpha)^2/4",
                     .order = 2,
                     .implicit = true,
                     .iterates_to_tolerance = true,
                     .stability = StabilityKind::kA,
                     .stability_limit = kInfinity,
                     .stability_note = "at the default --alpha -0.1",
                     .spectral_radius_infinity = (1.0 + kDefaultAlpha) / (1.0 - kDefaultAlpha)}) {}

NewmarkParameters HhtAlpha::parameters(const IntegratorOptions& o) const {
  return hht_parameters(std::isnan(o.alpha) ? kDefaultAlpha : o.alpha);
}

std::string HhtAlpha::check_options(const IntegratorOptions& o, Eigen::Index) const {
  if (std::isnan(o.alpha) || (o.alpha >= -1.0 / 3.0 && o.alpha <= 0.0)) return {};
  std::ostringstream why;
  why << "--alpha: must be in [-1/3, 0] (Hilber, Hughes and Taylor's range), got "
      << shortest_decimal(o.alpha);
  return why.str();
}

GeneralizedAlpha::GeneralizedAlpha()
    : NewmarkFamily({.name = "generalized-alpha",
                     .scheme = "Newmark with M ((1 - am) a' + am a) = F at (1 - af) x' + af x, "
                               "am, af from rho_inf (Chung and Hulbert 1993)",
                     .order = 2,
                     .implicit = true,
                     .iterates_to_tolerance = true,
                     .stability = StabilityKind::kA,
                     .stability_limit = kInfinity,
                     .stability_note = "at the default --rho-inf 0.5",
                     .spectral_radius_infinity = kDefaultRhoInf}) {}

NewmarkParameters GeneralizedAlpha::parameters(const IntegratorOptions& o) const {
  return generalized_alpha_parameters(std::isnan(o.rho_inf) ? kDefaultRhoInf : o.rho_inf);
}

std::string GeneralizedAlpha::check_options(const IntegratorOptions& o, Eigen::Index) const {
  if (std::isnan(o.rho_inf) || (o.rho_inf >= 0.0 && o.rho_inf <= 1.0)) return {};
  std::ostringstream why;
  why << "--rho-inf: must be in [0, 1] (the spectral radius at infinity), got "
      << shortest_decimal(o.rho_inf);
  return why.str();
}

SPRINGLAB_INTEGRATOR(GeneralizedAlpha, generalized_alpha_integrator)

SPRINGLAB_INTEGRATOR(HhtAlpha, hht_alpha_integrator)

}  // namespace springlab
