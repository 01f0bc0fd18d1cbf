// Fixed corotated elasticity (Stomakhin et al. 2012): with the polar
// decomposition F = R S (kinematics.h),
//   Psi = mu |F - R|^2 + lambda/2 (J - 1)^2 = mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2,
//   P = 2 mu (F - R) + lambda (J - 1) dJ/dF
// (the derivative of |F - R|^2 through R vanishes: R is the nearest
// rotation). An inverted solid keeps det R = 1, so its last sigma is
// negative and the element is pushed back. Kim and Eberle, "Dynamic
// Deformables", SIGGRAPH course 2022, §5.
#include <Eigen/LU>

#include "models/materials/kinematics.h"
#include "models/materials/tangent3.h"

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

// dPdF = 2 mu (I - dR/dF) + lambda g g^T + lambda (J - 1) H_J (tangent3.h),
// with dR/dF column by column: along E_ab, R^T dF - dF^T R = W S + S W
// (polar_differential in kinematics.cc) gives W = [w]x,
// w = (tr(S) I - S)^-1 u, one inverse for all nine columns.
Tangent3 dPdF3(const Eigen::Matrix3d& F, const Lame& m) {
  const Polar3 p = polar3(F);
  const Eigen::Matrix3d M_inv =
      (p.S.trace() * Eigen::Matrix3d::Identity() - p.S).inverse();
  const Eigen::Matrix<double, 9, 1> g = vec(cofactor(F));
  Tangent3 T = 2.0 * m.mu * Tangent3::Identity() + m.lambda * g * g.transpose() +
               m.lambda * (F.determinant() - 1.0) * volume_hessian(F);
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) {
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();  // R^T E_ab
      A.col(b) = p.R.row(a).transpose();
      const Eigen::Matrix3d K = A - A.transpose();
      const Eigen::Vector3d w = M_inv * Eigen::Vector3d(K(2, 1), K(0, 2), K(1, 0));
      T.col(a + 3 * b) -= 2.0 * m.mu * vec(p.R * cross_matrix(w));
    }
  }
  return T;
}

}  // namespace

const MaterialModel& corotated_material() {
  static const MaterialModel model = {
      .name = "corotated",
      .formula = "mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2",
      .Psi = Psi,
      .P = P,
      .dP = dP,
      .dPdF3 = dPdF3,
  };
  return model;
}

}  // namespace springlab
