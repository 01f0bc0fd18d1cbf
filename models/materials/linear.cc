// Linear elasticity (small strain): eps = (F + F^T)/2 - I,
//   Psi = mu eps:eps + lambda/2 (tr eps)^2,  P = 2 mu eps + lambda tr(eps) I.
// Not invariant under rotation: a rotated element stores energy (the
// lecture's reason for corotated models). Square F only: refused for
// membranes (docs/physics.md "Finite elements"). Sifakis and Barbic, "FEM simulation of 3D
// deformable solids", SIGGRAPH course 2012, §3.
#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

struct Linear {
  static constexpr MaterialFacts facts = {
      .name = "linear",
      .formula = "mu eps:eps + lambda/2 (tr eps)^2, eps = (F + F^T)/2 - I",
      .membranes = false,
  };

  template <typename Matrix>
  static Matrix strain(const Matrix& F) {
    return 0.5 * (F + F.transpose()) - Matrix::Identity(F.rows(), F.cols());
  }

  static double Psi(const Mat& F, const Lame& m) {
    const Mat eps = strain(F);
    const double tr = eps.trace();
    return m.mu * eps.squaredNorm() + 0.5 * m.lambda * tr * tr;
  }

  template <typename Matrix>
  static Matrix P(const Matrix& F, const Lame& m) {
    const Matrix eps = strain(F);
    return 2.0 * m.mu * eps + m.lambda * eps.trace() * Matrix::Identity(F.rows(), F.cols());
  }

  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
    return m.mu * (dF + dF.transpose()) +
           m.lambda * dF.trace() * Mat::Identity(F.rows(), F.cols());
  }

  // dPdF = mu (I_9 + K) + lambda vec(I) vec(I)^T, K the transpose on vec(F):
  // dP_rc/dF_ab = mu (d_ra d_cb + d_rb d_ca) + lambda d_rc d_ab. Constant.
  // Contracted (tangent3.h): A(a, b) = mu (a . b) I + mu b a^T + lambda a b^T.
  static Tangent3 blocks(const Eigen::Matrix3d&, const Eigen::Matrix3d& D, const Lame& m) {
    return symmetric_blocks([&](int i, int j) {
      const Eigen::Vector3d a = D.row(i), b = D.row(j);
      return Block3().identity(m.mu * a.dot(b)).outer(m.mu, b, a).outer(m.lambda, a, b);
    });
  }
};

}  // namespace

SPRINGLAB_MATERIAL(Linear, linear)

}  // namespace springlab
