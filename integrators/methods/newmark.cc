#include "integrators/methods/newmark.h"

#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>

#include "integrators/core/integrator_entry.h"
#include "models/core/decimal_text.h"

namespace springlab {
namespace {

// The trapezoidal rule's R(z) on y' = lambda y: average acceleration is the
// trapezoidal rule applied to (x, v)' = (v, M^-1 F).
std::complex<double> trapezoidal(std::complex<double> z) { return (1.0 + z / 2.0) / (1.0 - z / 2.0); }

// Stable for w h <= 1 / sqrt(gamma/2 - beta) on the undamped oscillator
// (Hughes 9.1.2: Omega_crit at xi = 0), when 2 beta < gamma.
double newmark_limit(double beta, double gamma = 0.5) { return 1.0 / std::sqrt(gamma / 2.0 - beta); }

// With gamma = 1/2 the method conserves (v^2 + w^2 x^2 (1 + (beta - 1/4) (w h)^2))/2
// on the undamped oscillator (Hughes 9.1.2), so E swings up to
// 1 / (1 - (w h / limit)^2) times its least value along a stable orbit.
std::function<double(double)> newmark_excursion(double beta) {
  const double limit = newmark_limit(beta);
  return [limit](double wh) { return 1.0 / (1.0 - (wh / limit) * (wh / limit)); };
}

}  // namespace

Newmark::Newmark()
    : NewmarkFamily({.name = "newmark",
                     .scheme = "x' = x + h v + h^2/4 (a + a'),  v' = v + h/2 (a + a'),  M a' = F(x', v')",
                     .order = 2,
                     .implicit = true,
                     .iterates_to_tolerance = true,
                     .stability = StabilityKind::kA,
                     .stability_limit = kInfinity,
                     .stability_note = "average acceleration, the default beta 1/4, gamma 1/2; "
                                       "--gamma > 1/2 damps every mode and is first order",
                     .stability_function = trapezoidal,
                     .spectral_radius_infinity = 1.0}) {}

NewmarkParameters Newmark::parameters(const IntegratorOptions& o) const {
  return {.beta = std::isnan(o.beta) ? 0.25 : o.beta, .gamma = std::isnan(o.gamma) ? 0.5 : o.gamma};
}

IntegratorInfo Newmark::info_for(const IntegratorOptions& o) const {
  const NewmarkParameters p = parameters(o);
  IntegratorInfo info = this->info();
  if (p.beta == 0.25 && p.gamma == 0.5) return info;
  std::ostringstream note;
  note << "at --beta " << p.beta << " --gamma " << p.gamma;
  info.stability_note = note.str();
  info.stability_function = {};
  info.spectral_radius_infinity = std::numeric_limits<double>::quiet_NaN();
  if (p.gamma > 0.5) info.order = 1;
  if (p.beta >= 0.5 * p.gamma) return info;  // A-stable (Hughes 9.1.2)
  info.stability = StabilityKind::kConditional;
  info.stability_limit = 1.0 / std::sqrt(0.5 * p.gamma - p.beta);
  if (p.gamma == 0.5) info.energy_excursion = newmark_excursion(p.beta);
  return info;
}

std::string Newmark::check_options(const IntegratorOptions& o, Eigen::Index) const {
  const NewmarkParameters p = parameters(o);
  std::ostringstream why;
  if (!(p.gamma >= 0.5 && p.gamma <= 1.0)) {
    why << "--gamma: must be in [0.5, 1] (below 1/2 the method amplifies every mode), got "
        << shortest_decimal(p.gamma);
  } else if (!(p.beta >= 0.0 && p.beta <= 0.5)) {
    why << "--beta: must be in [0, 0.5], got " << shortest_decimal(p.beta);
  }
  return why.str();
}

CentralDifference::CentralDifference()
    : VelocityVerlet({.name = "central-difference",
                     .scheme = "x' = x + h v + h^2/2 a,  v' = v + h/2 (a + a'),  M a' = F(x', v')",
                     .order = 2,
                     .symplectic = true,
                     .stability = StabilityKind::kConditional,
                     .stability_limit = newmark_limit(0.0),
                     .energy_excursion = newmark_excursion(0.0)}) {}

LinearAcceleration::LinearAcceleration()
    : NewmarkFamily({.name = "linear-acceleration",
                     .scheme = "x' = x + h v + h^2 (a/3 + a'/6),  v' = v + h/2 (a + a'),  M a' = F(x', v')",
                     .order = 2,
                     .implicit = true,
                     .iterates_to_tolerance = true,
                     .stability = StabilityKind::kConditional,
                     .stability_limit = newmark_limit(1.0 / 6.0),
                     .energy_excursion = newmark_excursion(1.0 / 6.0)}) {}

FoxGoodwin::FoxGoodwin()
    : NewmarkFamily({.name = "fox-goodwin",
                     .scheme = "x' = x + h v + h^2 (5a/12 + a'/12),  v' = v + h/2 (a + a'),  M a' = F(x', v')",
                     .order = 2,
                     .position_order = 4,
                     .implicit = true,
                     .iterates_to_tolerance = true,
                     .stability = StabilityKind::kConditional,
                     .stability_limit = newmark_limit(1.0 / 12.0),
                     .energy_excursion = newmark_excursion(1.0 / 12.0)}) {}

SPRINGLAB_INTEGRATOR(CentralDifference, central_difference_integrator)

SPRINGLAB_INTEGRATOR(FoxGoodwin, fox_goodwin_integrator)

SPRINGLAB_INTEGRATOR(LinearAcceleration, linear_acceleration_integrator)

SPRINGLAB_INTEGRATOR(Newmark, newmark_integrator)

}  // namespace springlab
