// The Newmark-beta methods (Newmark 1959; Hughes 1987, ch. 9.1): the family
// of newmark_family.h with alpha_m = alpha_f = 0,
//
//   x_{n+1} = x_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
//   v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1}),   M a_{n+1} = F_{n+1}.
//
// Named members (all gamma = 1/2: second order, no numerical damping):
//   newmark              beta 1/4, average acceleration = the trapezoidal
//                        rule: A-stable, conserves a linear system's energy;
//                        --beta and --gamma select any other member;
//   central-difference   beta 0: explicit, velocity Verlet's step, w h <= 2
//                        (Verlet's code under this name: see below);
//   linear-acceleration  beta 1/6: w h <= 2 sqrt(3) = 3.464;
//   fox-goodwin          beta 1/12: w h <= sqrt(6) = 2.449, the smallest
//                        period error of the family, O((w h)^4); where F
//                        depends on x alone its positions are Numerov's
//                        method, of order 4 (its velocities of order 2).
// With gamma = 1/2 the limit is w h <= 1 / sqrt(1/4 - beta) (Hughes 9.1.2).
// gamma > 1/2 damps every mode (and the method is first order).
#pragma once

#include "integrators/methods/newmark_family.h"
#include "integrators/methods/verlet.h"

namespace springlab {

class Newmark final : public NewmarkFamily {
 public:
  Newmark();
  NewmarkParameters parameters(const IntegratorOptions& options) const override;
  std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const override;
  // The member --beta and --gamma select: unconditionally stable for
  // beta >= gamma / 2 (gamma >= 1/2), else stable for
  // w h <= 1 / sqrt(gamma/2 - beta) (Hughes 9.1.2, undamped), with the
  // energy swing of a gamma = 1/2 member (newmark_excursion); R(z) only for
  // average acceleration (the trapezoidal rule).
  IntegratorInfo info_for(const IntegratorOptions& options) const override;

 protected:
  std::vector<std::string> parameter_options() const override { return {"beta", "gamma"}; }
};

// beta = 0: x' = x + h v + h^2/2 a is explicit and the step is exactly
// velocity Verlet's (kick h/2, drift h, kick h/2, the closing kick solved
// for v' where F depends on v), so it is Verlet's code under this name;
// `newmark --beta 0` takes the family's own path to the same step.
class CentralDifference final : public VelocityVerlet {
 public:
  CentralDifference();
};

class LinearAcceleration final : public NewmarkFamily {
 public:
  LinearAcceleration();
  NewmarkParameters parameters(const IntegratorOptions&) const override {
    return {.beta = 1.0 / 6.0, .gamma = 0.5};
  }
};

class FoxGoodwin final : public NewmarkFamily {
 public:
  FoxGoodwin();
  NewmarkParameters parameters(const IntegratorOptions&) const override {
    return {.beta = 1.0 / 12.0, .gamma = 0.5};
  }
};

}  // namespace springlab
