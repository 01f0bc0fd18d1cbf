// The alpha methods: Newmark with the equation of motion taken between the
// step's ends (newmark_family.h), which damps the high modes while keeping
// second order and the low modes nearly undamped.
//
//   hht-alpha          Hilber, Hughes and Taylor (1977): alpha in [-1/3, 0]
//                      (--alpha, default -0.1), alpha_m = 0, alpha_f = -alpha,
//                      gamma = 1/2 - alpha, beta = (1 - alpha)^2 / 4;
//                      spectral radius at infinity (1 + alpha) / (1 - alpha).
//   generalized-alpha  Chung and Hulbert (1993): the spectral radius at
//                      infinity rho_inf in [0, 1] (--rho-inf, default 0.5)
//                      chooses alpha_m = (2 rho - 1)/(rho + 1),
//                      alpha_f = rho/(rho + 1), gamma = 1/2 - alpha_m + alpha_f,
//                      beta = (1 - alpha_m + alpha_f)^2 / 4: for a given
//                      high-frequency damping, the least low-frequency
//                      damping (their eqs. 25-27). rho_inf = 1 is the
//                      average acceleration method's undamped step,
//                      rho_inf = 0 annihilates the highest modes in one step.
// Both are A-stable (unconditionally stable on the undamped oscillator).
#pragma once

#include "integrators/methods/newmark_family.h"

namespace springlab {

class HhtAlpha final : public NewmarkFamily {
 public:
  HhtAlpha();
  NewmarkParameters parameters(const IntegratorOptions& options) const override;
  std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const override;

 protected:
  std::vector<std::string> parameter_options() const override { return {"alpha"}; }
};

class GeneralizedAlpha final : public NewmarkFamily {
 public:
  GeneralizedAlpha();
  NewmarkParameters parameters(const IntegratorOptions& options) const override;
  std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const override;

 protected:
  std::vector<std::string> parameter_options() const override { return {"rho-inf"}; }
};

}  // namespace springlab
