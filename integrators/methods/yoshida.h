// yoshida4, yoshida6 — symmetric compositions of velocity Verlet steps
// (Yoshida, "Construction of higher order symplectic integrators", Phys.
// Lett. A 150, 262-268, 1990): one step of size h is the Verlet steps
// w_1 h, w_2 h, ..., w_s h (sum w_i = 1, symmetric), whose error terms
// cancel to the method's order. Explicit and symplectic for forces of x
// alone, like Verlet; some w_i are negative (a step backwards in time).
//
//   yoshida4 (Forest and Ruth 1990; Yoshida eq. 4.4): w_1 = w_3 = 1/(2 - 2^(1/3)),
//     w_2 = -2^(1/3)/(2 - 2^(1/3)); 3 force evaluations per step.
//   yoshida6 (Yoshida's Table 1, solution A): the seven weights
//     w_3 w_2 w_1 w_0 w_1 w_2 w_3, w_1 = -1.17767998417887,
//     w_2 = 0.235573213359357, w_3 = 0.784513610477560,
//     w_0 = 1 - 2 (w_1 + w_2 + w_3); 7 force evaluations per step.
//
// Stability on the undamped oscillator: the step's matrix is the product of
// the Verlet matrices [[1 - s^2/2, s], [-s + s^3/4, 1 - s^2/2]] / w (s = w_i w h),
// stable while |trace| <= 2. Its first crossing is w h = 1.5734 (yoshida4)
// and 2.2691 (yoshida6): a higher order buys accuracy, not a larger step
// per force evaluation (Verlet: 2 per evaluation).
#pragma once

#include <vector>

#include "integrators/methods/verlet.h"

namespace springlab {

class YoshidaComposition : public VelocityVerlet {
 protected:
  YoshidaComposition(IntegratorInfo info, std::vector<double> weights)
      : VelocityVerlet(std::move(info)), weights_(std::move(weights)) {}
  StepResult do_step(double h) override;

 private:
  std::vector<double> weights_;
};

class Yoshida4 final : public YoshidaComposition {
 public:
  Yoshida4();
};

class Yoshida6 final : public YoshidaComposition {
 public:
  Yoshida6();
};

// The weights of one step, in order (exposed for the tests).
std::vector<double> yoshida4_weights();
std::vector<double> yoshida6_weights();

}  // namespace springlab
