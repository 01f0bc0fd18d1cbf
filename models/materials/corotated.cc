// Fixed corotated elasticity (Stomakhin et al. 2012): with the polar
// decomposition F = R S (kinematics.h),
//   Psi = mu |F - R|^2 + lambda/2 (J - 1)^2 = mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2,
//   P = 2 mu (F - R) + lambda (J - 1) dJ/dF
// (the derivative of |F - R|^2 through R vanishes: R is the nearest
// rotation). An inverted solid keeps det R = 1, so its last sigma is
// negative and the element is pushed back. Kim and Eberle, "Dynamic
// Deformables", SIGGRAPH course 2022, §5.

#include "models/materials/kernels/corotated_blocks.h"
#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

struct Corotated {
  static constexpr MaterialFacts facts = {
      .name = "corotated",
      .formula = "mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2",
      // Uniform stretch s: d mu (s - 1)^2 + lambda/2 (s^d - 1)^2, below 0 and
      // falling without bound as s grows when lambda < 0 (nu < 0).
      .min_poisson = 0.0,
      .unstable_why = "with lambda < 0 its energy falls without bound as an element stretches "
                      "(lambda/2 (J - 1)^2 outgrows mu sum_i (sigma_i - 1)^2)",
  };
  // Psi, P and the blocks need the rotation R of F = R S (about 50 ns):
  // the tetrahedra keep each element's and derive it in lanes (tet_kernel.h).
  static constexpr Keeps keeps = Keeps::rotation;

  template <typename Matrix>
  static double Psi_of_rotation(const Matrix& F, const Matrix& R, const Lame& m) {
    const double J = volume(F).J;
    return m.mu * (F - R).squaredNorm() + 0.5 * m.lambda * (J - 1.0) * (J - 1.0);
  }
  static double Psi(const Mat& F, const Lame& m) { return Psi_of_rotation(F, polar(F).R, m); }
  static double Psi(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
    return Psi_of_rotation(F, d.R, m);
  }

  template <typename Matrix>
  static Matrix P_of_rotation(const Matrix& F, const Matrix& R, const Lame& m) {
    const auto v = volume(F);
    return 2.0 * m.mu * (F - R) + m.lambda * (v.J - 1.0) * v.g;
  }
  template <typename Matrix>
  static Matrix P(const Matrix& F, const Lame& m) {
    return P_of_rotation(F, Matrix(polar(F).R), m);
  }
  static Eigen::Matrix3d P(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
    return P_of_rotation(F, d.R, m);
  }

  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
    const Polar p = polar(F);
    const Volume v = volume(F);
    const Mat dR = polar_differential(p, F, dF);
    return 2.0 * m.mu * (dF - dR) +
           m.lambda * (contract(v.g, dF) * v.g + (v.J - 1.0) * volume_differential(F, dF));
  }

  // dPdF = 2 mu (I - dR/dF) + lambda g g^T + lambda (J - 1) H_J, contracted
  // with the rows of D in closed form: written once for one element and for
  // vector lanes in kernels/corotated_blocks.h, with its derivation.
  template <typename T, typename Store>
  SPRINGLAB_LANES_INLINE static void blocks(const T (&F)[9], const T (&R)[9], const T& log_J,
                                            const T (&D)[9], const T& mu, const T& lambda,
                                            const Store& store) {
    corotated_blocks(F, R, log_J, D, mu, lambda, store);
  }
};

}  // namespace

SPRINGLAB_MATERIAL(Corotated, corotated)

}  // namespace springlab
