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

template <typename Matrix, typename Polar>
double Psi_of_polar(const Matrix& F, const Polar& p, const Lame& m) {
  const double J = volume(F).J;
  return m.mu * (F - p.R).squaredNorm() + 0.5 * m.lambda * (J - 1.0) * (J - 1.0);
}

double Psi(const Mat& F, const Lame& m) { return Psi_of_polar(F, polar(F), m); }

template <typename Matrix, typename Polar>
Matrix P_of_polar(const Matrix& F, const Polar& p, const Lame& m) {
  const auto v = volume(F);
  return 2.0 * m.mu * (F - p.R) + m.lambda * (v.J - 1.0) * v.g;
}

template <typename Matrix>
Matrix P(const Matrix& F, const Lame& m) {
  return P_of_polar(F, polar(F), m);
}

Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
  const Polar p = polar(F);
  const Volume v = volume(F);
  const Mat dR = polar_differential(p, F, dF);
  return 2.0 * m.mu * (dF - dR) +
         m.lambda * (contract(v.g, dF) * v.g + (v.J - 1.0) * volume_differential(F, dF));
}

// dPdF = 2 mu (I - dR/dF) + lambda g g^T + lambda (J - 1) H_J (tangent3.h).
// dR/dF from F = R S: along dF, R^T dF - dF^T R = W S + S W
// (polar_differential in kinematics.cc) gives W = R^T dR = [w]x with
// w = M^-1 u, M = tr(S) I - S, u_k = <R [e_k]x, dF>; so
//   dR/dF = sum_kl (M^-1)_kl vec(R [e_k]x) vec(R [e_l]x)^T,
// three rank-one pieces with R [e_k]x a = -R [a]x e_k. Contracted:
//   A(a, b) = 2 mu (a . b) I - 2 mu R [a]x M^-1 [b]x^T R^T
//             + lambda (G a)(G b)^T - lambda (J - 1) [F (a x b)]x.
// The twist term needs no inverse. M is symmetric, so M^-1 = cof(M) / det M,
// and cof(M) (x x y) = (M x) x (M y) with the Binet-Cauchy identity
// (u x v) . (w x z) = (u . w)(v . z) - (u . z)(v . w) give, entry (p, q)
// being (e_p x a)^T cof(M) (e_q x b),
//   [a]x cof(M) [b]x^T = (a^T M b) M - (M b)(M a)^T.
// Turned by R (R M R^T = tr(S) I - F R^T, since R S R^T = F R^T):
//   R [a]x M^-1 [b]x^T R^T = ((a^T M b)(tr(S) I - F R^T) - c_b c_a^T) / det M,
// with c_a = R M a. det M = (s1 + s2)(s2 + s3)(s3 + s1) for the singular
// values s_i, so the term is singular where an inverted element has
// s2 + s3 = 0, as M^-1 is.
Tangent3 tangent_blocks3_of_polar(const Eigen::Matrix3d& F, const Polar3& p,
                                  const Eigen::Matrix3d& D, const Lame& m) {
  const double trS = p.S.trace();
  const Eigen::Matrix3d M = trS * Eigen::Matrix3d::Identity() - p.S;
  const double two_mu_over_det_M = 2.0 * m.mu / M.determinant();
  const Eigen::Matrix3d MD = M * D.transpose();  // column i: M d_i
  const Eigen::Matrix3d c = p.R * MD;            // column i: c_i = R M d_i
  const Eigen::Matrix3d V = F * p.R.transpose(); // R S R^T, the left stretch
  const Volume3 v = volume(F);  // J and G = dJ/dF, the cofactor matrix
  const double h = m.lambda * (v.J - 1.0);
  const Eigen::Matrix3d GD = v.g * D.transpose();  // column i: G d_i
  return symmetric_blocks([&](int i, int j) {
    const Eigen::Vector3d a = D.row(i), b = D.row(j);
    const double aMb = a.dot(MD.col(j));
    Block3 block = Block3()
                       .identity(2.0 * m.mu * a.dot(b) - two_mu_over_det_M * aMb * trS)
                       .matrix(two_mu_over_det_M * aMb, V)
                       .outer(two_mu_over_det_M, c.col(j), c.col(i))
                       .outer(m.lambda, GD.col(i), GD.col(j));
    return i == j ? block : block.volume_hessian(h, F, a, b);  // H_J(a, a) = 0 (a x a = 0)
  });
}

Tangent3 tangent_blocks3(const Eigen::Matrix3d& F, const Eigen::Matrix3d& D, const Lame& m) {
  return tangent_blocks3_of_polar(F, polar3(F), D, m);
}

// The tetrahedra keep each element's R and S between calls at one state
// (material.h).
void derive3(const Eigen::Matrix3d& F, Derived3& d) { d.polar = polar3(F); }
double Psi3_derived(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
  return Psi_of_polar(F, d.polar, m);
}
Eigen::Matrix3d P3_derived(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
  return P_of_polar(F, d.polar, m);
}
Tangent3 tangent_blocks3_derived(const Eigen::Matrix3d& F, const Derived3& d,
                                 const Eigen::Matrix3d& D, const Lame& m) {
  return tangent_blocks3_of_polar(F, d.polar, D, m);
}

}  // namespace

const MaterialModel& corotated_material() {
  static const MaterialModel model = {
      .name = "corotated",
      .formula = "mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2",
      .Psi = Psi,
      .P = P<Mat>,
      .P3 = P<Eigen::Matrix3d>,
      .dP = dP,
      .tangent_blocks3 = tangent_blocks3,
      .derive3 = derive3,
      .Psi3_derived = Psi3_derived,
      .P3_derived = P3_derived,
      .tangent_blocks3_derived = tangent_blocks3_derived,
  };
  return model;
}

}  // namespace springlab
