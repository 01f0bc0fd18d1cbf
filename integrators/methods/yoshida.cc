#include "integrators/methods/yoshida.h"

#include <cmath>
#include <functional>

#include "integrators/core/integrator_entry.h"

namespace springlab {

std::vector<double> yoshida4_weights() {
  const double c = std::cbrt(2.0);
  const double w1 = 1.0 / (2.0 - c), w0 = -c / (2.0 - c);
  return {w1, w0, w1};
}

std::vector<double> yoshida6_weights() {
  const double w1 = -1.17767998417887, w2 = 0.235573213359357, w3 = 0.784513610477560;
  const double w0 = 1.0 - 2.0 * (w1 + w2 + w3);
  return {w3, w2, w1, w0, w1, w2, w3};
}

StepResult YoshidaComposition::do_step(double h) {
  const double t0 = t_;
  for (double w : weights_) {
    const StepResult result = VelocityVerlet::do_step(w * h);
    if (!result.ok) {
      t_ = t0;
      return result;
    }
    t_ += w * h;  // the next substep starts here (Integrator::advance_to sets t_ exactly after)
  }
  t_ = t0;
  return StepResult::success();
}

namespace {

// The energy excursion (integrator.h) of a composition on the undamped
// oscillator, in the scaled unknowns (u, v) = (w x, v). One step is
// S = V(w_s a) ... V(w_1 a), V(s) = [[1 - s^2/2, s], [-s + s^3/4, 1 - s^2/2]]
// (yoshida.h). A stable map S = [[A, B], [C, D]] with det 1 keeps the
// quadratic form Q = [[-C, (A - D)/2], [(A - D)/2, B]] (S^T Q S = Q: for Verlet
// itself, v^2 + (1 - s^2/4) u^2); on a level set of Q the energy (u^2 + v^2)/2
// runs between its two eigenvalues' reciprocals, so it swings by their ratio.
std::function<double(double)> composition_excursion(std::vector<double> weights) {
  return [weights = std::move(weights)](double a) {
    double A = 1.0, B = 0.0, C = 0.0, D = 1.0;  // the identity
    for (const double w : weights) {
      const double s = w * a;
      const double va = 1.0 - s * s / 2.0, vb = s, vc = -s + s * s * s / 4.0, vd = va;
      const double a2 = va * A + vb * C, b2 = va * B + vb * D;
      const double c2 = vc * A + vd * C, d2 = vc * B + vd * D;
      A = a2, B = b2, C = c2, D = d2;
    }
    const double p = -C, q = B, r = (A - D) / 2.0;  // Q = [[p, r], [r, q]]
    const double mean = (p + q) / 2.0, spread = std::hypot((p - q) / 2.0, r);
    return std::abs((mean + spread) / (mean - spread));
  };
}

}  // namespace

// The limits are the first w h at which |trace| of the step's matrix
// exceeds 2 (yoshida.h), found by bisection to 1e-12;
// tests/test_stability_property.cc measures them by running.
Yoshida4::Yoshida4()
    : YoshidaComposition({.name = "yoshida4",
                          .scheme = "Verlet steps w1 h, w0 h, w1 h, w1 = 1/(2 - 2^(1/3)), "
                                    "w0 = 1 - 2 w1",
                          .order = 4,
                          .symplectic = true,
                          .stability = StabilityKind::kConditional,
                          .stability_limit = 1.57340194743454,
                          .energy_excursion = composition_excursion(yoshida4_weights())},
                         yoshida4_weights()) {}

Yoshida6::Yoshida6()
    : YoshidaComposition({.name = "yoshida6",
                          .scheme = "seven Verlet steps w3 w2 w1 w0 w1 w2 w3 (Yoshida 1990, "
                                    "solution A)",
                          .order = 6,
                          .symplectic = true,
                          .stability = StabilityKind::kConditional,
                          .stability_limit = 2.269057996397671,
                          .energy_excursion = composition_excursion(yoshida6_weights())},
                         yoshida6_weights()) {}

SPRINGLAB_INTEGRATOR(Yoshida4, yoshida4_integrator)

SPRINGLAB_INTEGRATOR(Yoshida6, yoshida6_integrator)

}  // namespace springlab
