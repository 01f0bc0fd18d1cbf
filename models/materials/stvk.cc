// St. Venant-Kirchhoff: the Green strain G = (C - I)/2, C = F^T F,
//   Psi = mu G:G + lambda/2 (tr G)^2,  P = F S,  S = 2 mu G + lambda tr(G) I
// (S the second Piola-Kirchhoff stress). Rotation invariant, but it softens
// under compression and has no resistance to inversion. Sifakis and Barbic
// 2012, §3.
#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

struct StVK {
  static constexpr MaterialFacts facts = {
      .name = "stvk",
      .formula = "mu G:G + lambda/2 (tr G)^2, G = (F^T F - I)/2",
  };

  template <typename Matrix>
  static Matrix green(const Matrix& F) {
    return 0.5 * (F.transpose() * F - Matrix::Identity(F.cols(), F.cols()));
  }

  template <typename Matrix>
  static Matrix second_pk(const Matrix& G, const Lame& m) {
    return 2.0 * m.mu * G + m.lambda * G.trace() * Matrix::Identity(G.rows(), G.cols());
  }

  static double Psi(const Mat& F, const Lame& m) {
    const Mat G = green(F);
    const double tr = G.trace();
    return m.mu * G.squaredNorm() + 0.5 * m.lambda * tr * tr;
  }

  template <typename Matrix>
  static Matrix P(const Matrix& F, const Lame& m) {
    return F * second_pk(green(F), m);
  }

  // dP = dF S + F dS, dS = 2 mu dG + lambda tr(dG) I, dG = (dF^T F + F^T dF)/2.
  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) {
    const Mat dG = 0.5 * (dF.transpose() * F + F.transpose() * dF);
    return dF * second_pk(green(F), m) + F * second_pk(dG, m);
  }

  // dP_ij/dF_ab = d_ia S_bj + mu (F_ib F_aj + (F F^T)_ia d_jb) + lambda F_ij F_ab
  // (the differential above with dF = E_ab): a Kronecker piece (S), a
  // transposed rank one (F_ib F_aj), another Kronecker piece (F F^T) and a
  // rank one (F), so (tangent3.h)
  //   A(a, b) = (a^T S b) I + mu (F b)(F a)^T + mu (a . b) F F^T + lambda (F a)(F b)^T.
  static Tangent3 blocks(const Eigen::Matrix3d& F, const Eigen::Matrix3d& D, const Lame& m) {
    const Eigen::Matrix3d S = second_pk(green(F), m);
    const Eigen::Matrix3d FFt = F * F.transpose();
    const Eigen::Matrix3d FD = F * D.transpose();  // column i: F d_i
    return symmetric_blocks([&](int i, int j) {
      const Eigen::Vector3d a = D.row(i), b = D.row(j);
      return Block3()
          .identity(a.dot(S * b))
          .outer(m.mu, FD.col(j), FD.col(i))
          .matrix(m.mu * a.dot(b), FFt)
          .outer(m.lambda, FD.col(i), FD.col(j));
    });
  }
};

}  // namespace

SPRINGLAB_MATERIAL(StVK, stvk)

}  // namespace springlab
