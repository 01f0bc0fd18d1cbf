// Fixed corotated elasticity (Stomakhin et al. 2012): with the polar
// decomposition F = R S (kinematics.h),
//   Psi = mu |F - R|^2 + lambda/2 (J - 1)^2 = mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2,
//   P = 2 mu (F - R) + lambda (J - 1) dJ/dF
// (the derivative of |F - R|^2 through R vanishes: R is the nearest
// rotation). An inverted solid keeps det R = 1, so its last sigma is
// negative and the element is pushed back. Kim and Eberle, "Dynamic
// Deformables", SIGGRAPH course 2022, §5.
#include "models/materials/kinematics.h"

namespace springlab {
namespace {

double Psi(const Mat& F, const Lame& m) {
  const Polar p = polar(F);
  const double J = volume(F).J;
  return m.mu * (F - p.R).squaredNorm() + 0.5 * m.lambda * (J - 1.0) * (J - 1.0);
}

Mat P(const Mat& F, const Lame& m) {
  const Polar p = polar(F);
  const Volume v = volume(F);
  return 2.0 * m.mu * (F - p.R) + m.lambda * (v.J - 1.0) * v.g;
}

Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
  const Polar p = polar(F);
  const Volume v = volume(F);
  const Mat dR = polar_differential(p, F, dF);
  return 2.0 * m.mu * (dF - dR) +
         m.lambda * (contract(v.g, dF) * v.g + (v.J - 1.0) * volume_differential(F, dF));
}

}  // namespace

const MaterialModel& corotated_material() {
  static const MaterialModel model = {
      .name = "corotated",
      .formula = "mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2",
      .Psi = Psi,
      .P = P,
      .dP = dP,
  };
  return model;
}

}  // namespace springlab
