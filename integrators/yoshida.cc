#include "integrators/yoshida.h"

#include <cmath>

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
                          .stability_limit = 1.57340194743454},
                         yoshida4_weights()) {}

Yoshida6::Yoshida6()
    : YoshidaComposition({.name = "yoshida6",
                          .scheme = "seven Verlet steps w3 w2 w1 w0 w1 w2 w3 (Yoshida 1990, "
                                    "solution A)",
                          .order = 6,
                          .symplectic = true,
                          .stability = StabilityKind::kConditional,
                          .stability_limit = 2.269057996397671},
                         yoshida6_weights()) {}

}  // namespace springlab
