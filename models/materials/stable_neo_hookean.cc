// Stable neo-Hookean (Smith, de Goes and Kim, "Stable neo-Hookean flesh
// simulation", ACM TOG 2018, eq. 14, without its log term), with
// lambda' = lambda + mu and alpha = 1 + mu/lambda':
//   Psi = mu/2 (I_C - d) + lambda'/2 (J - alpha)^2 - mu^2/(2 lambda'),
//   P = mu F + lambda' (J - alpha) dJ/dF.
// Defined for every F, inverted ones included (no logarithm): the energy
// pushes an inverted element back instead of ending the run. The constant
// makes Psi(I) = 0 and alpha makes P(I) = 0.
#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

struct StableNeoHookean {
  static constexpr MaterialFacts facts = {
      .name = "stable-neo-hookean",
      .formula = "mu/2 (I_C - d) + lambda'/2 (J - alpha)^2 - mu^2/(2 lambda'), "
                 "lambda' = lambda + mu, alpha = 1 + mu/lambda'",
      // A tetrahedron collapsed to a point (F = 0) has Psi = lambda' nu: below
      // the rest state's 0 when nu < 0 (the minimum over J of Psi with I_C at
      // its least, 3 J^(2/3), is min(0, lambda' nu)). With d = 2 (triangles)
      // Psi(0) = lambda'/2 > 0 and Psi >= 0 for every nu.
      .min_poisson = 0.0,
      .unstable_in_tetrahedra_only = true,
      .unstable_why = "a tetrahedron collapsed to a point has the energy lambda' nu W < 0, below "
                      "its rest state's",
  };

  static double shifted_lambda(const Lame& m) { return m.lambda + m.mu; }
  static double alpha(const Lame& m) { return 1.0 + m.mu / shifted_lambda(m); }

  static double Psi(const Mat& F, const Lame& m) {
    const double J = volume(F).J;
    const double l = shifted_lambda(m), a = alpha(m);
    const double d = static_cast<double>(F.cols());
    return 0.5 * m.mu * (F.squaredNorm() - d) + 0.5 * l * (J - a) * (J - a) -
           m.mu * m.mu / (2.0 * l);
  }

  template <typename Matrix>
  static Matrix P(const Matrix& F, const Lame& m) {
    const auto v = volume(F);
    return m.mu * F + shifted_lambda(m) * (v.J - alpha(m)) * v.g;
  }

  // dP = mu dF + lambda' (dJ g + (J - alpha) dg), dJ = g:dF.
  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
    const Volume v = volume(F);
    return m.mu * dF + shifted_lambda(m) * (contract(v.g, dF) * v.g +
                                            (v.J - alpha(m)) * volume_differential(F, dF));
  }

  // dPdF = mu I + lambda' g g^T + lambda' (J - alpha) H_J, g = vec(dJ/dF), so
  // (tangent3.h, with g's matrix the cofactor matrix G)
  //   A(a, b) = mu (a . b) I + lambda' (G a)(G b)^T - lambda' (J - alpha) [F (a x b)]x.
  static Tangent3 blocks(const Eigen::Matrix3d& F, const Eigen::Matrix3d& D, const Lame& m) {
    const double l = shifted_lambda(m);
    const Volume3 v = volume(F);
    return volumetric_blocks(F, v.g, D, m.mu, l, l * (v.J - alpha(m)));
  }
};

}  // namespace

SPRINGLAB_MATERIAL(StableNeoHookean, stable_neo_hookean)

}  // namespace springlab
