// Compressible neo-Hookean (Bonet and Wood, "Nonlinear continuum mechanics
// for finite element analysis", 2008, eq. 6.27), with d the element's own
// dimension (the columns of F):
//   Psi = mu/2 (I_C - d) - mu ln J + lambda/2 (ln J)^2,
//   P = mu F + (lambda ln J - mu) (dJ/dF) / J.
// J <= 0 (an inverted or flattened element) has no energy: Psi = +infinity
// and P is not a number there (docs/physics.md "Finite elements": the run ends as diverged; the
// implicit solvers' line search keeps J > 0 because the incremental
// potential is +infinity beyond it).
#include <cmath>
#include <limits>

#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct NeoHookean {
  static constexpr MaterialFacts facts = {
      .name = "neo-hookean",
      .formula = "mu/2 (I_C - d) - mu ln J + lambda/2 (ln J)^2",
      .finite_everywhere = false,
      // Uniform compression s: d mu/2 (s^2 - 1) - d mu ln s + lambda d^2/2 (ln s)^2,
      // falling to -infinity as s -> 0 when lambda < 0 (nu < 0).
      .min_poisson = 0.0,
      .unstable_why = "with lambda < 0 its energy falls to -infinity as an element is compressed "
                      "(lambda/2 (ln J)^2 outgrows -mu ln J as J -> 0)",
  };
  // ln J, the one transcendental function here: the tetrahedra keep it
  // between calls at one state (tet_kernel.h), so that the energy, the force
  // and dF/dx take one logarithm (a second one made the force + dF/dx of a
  // tetrahedron 12 ns slower, 154 against 142 ns, benchmarks/README).
  static constexpr Keeps keeps = Keeps::log_J;

  // NaN where J <= 0, where it is not used (as tet_kernel.h's derive_log_J).
  static double log_J(double J) { return J > 0.0 ? std::log(J) : kNaN; }

  // Psi, P and the blocks given J's volume() and ln J.
  template <typename Matrix, typename VolumeOfF>
  static double Psi_given(const Matrix& F, const VolumeOfF& v, double lnJ, const Lame& m) {
    if (!(v.J > 0.0)) return kInfinity;
    const double d = static_cast<double>(F.cols());
    return 0.5 * m.mu * (F.squaredNorm() - d) - m.mu * lnJ + 0.5 * m.lambda * lnJ * lnJ;
  }

  template <typename Matrix, typename VolumeOfF>
  static Matrix P_given(const Matrix& F, const VolumeOfF& v, double lnJ, const Lame& m) {
    if (!(v.J > 0.0)) return Matrix::Constant(F.rows(), F.cols(), kNaN);
    const double inverse_J = 1.0 / v.J;  // (computed alongside the logarithm)
    return m.mu * F + ((m.lambda * lnJ - m.mu) * inverse_J) * v.g;
  }

  static double Psi(const Mat& F, const Lame& m) {
    const Volume v = volume(F);
    return Psi_given(F, v, log_J(v.J), m);
  }
  static double Psi(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
    return Psi_given(F, volume(F), d.log_J, m);
  }

  template <typename Matrix>
  static Matrix P(const Matrix& F, const Lame& m) {
    const auto v = volume(F);
    return P_given(F, v, log_J(v.J), m);
  }
  static Eigen::Matrix3d P(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
    return P_given(F, volume(F), d.log_J, m);
  }

  // dP = mu dF + lambda (dJ/J) g/J + (lambda ln J - mu) (dg/J - dJ g/J^2), dJ = g:dF.
  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
    const Volume v = volume(F);
    if (!(v.J > 0.0)) return Mat::Constant(F.rows(), F.cols(), kNaN);
    const double dJ = contract(v.g, dF);
    const double a = m.lambda * log_J(v.J) - m.mu;
    return m.mu * dF + (m.lambda * dJ / (v.J * v.J)) * v.g +
           a * (volume_differential(F, dF) / v.J - dJ / (v.J * v.J) * v.g);
  }

  // dPdF = mu I + (lambda - a)/J^2 g g^T + a/J H_J, a = lambda ln J - mu
  // (g = vec(dJ/dF), H_J its derivative), so (tangent3.h, G the cofactor matrix)
  //   A(a, b) = mu (a . b) I + (lambda - a)/J^2 (G a)(G b)^T - a/J [F (a x b)]x.
  static Tangent3 blocks(const Eigen::Matrix3d& F, const Derived3& d, const Eigen::Matrix3d& D,
                         const Lame& m) {
    const Volume3 v = volume(F);
    if (!(v.J > 0.0)) return Tangent3::Constant(kNaN);
    const double inverse_J = 1.0 / v.J;
    const double a = m.lambda * d.log_J - m.mu;
    return volumetric_blocks(F, v.g, D, m.mu, (m.lambda - a) * inverse_J * inverse_J,
                             a * inverse_J);
  }
};

}  // namespace

SPRINGLAB_MATERIAL(NeoHookean, neo_hookean)

}  // namespace springlab
