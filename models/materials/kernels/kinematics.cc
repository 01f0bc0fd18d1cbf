#include "models/materials/kernels/kinematics.h"

#include <Eigen/Dense>
#include <cmath>

#include "models/materials/kernels/lanes.h"

namespace springlab {
namespace {

using V3 = Eigen::Vector3d;

V3 column(const Mat& F, int c) { return F.col(c); }

}  // namespace

Volume volume(const Mat& F) {
  Volume out;
  out.g = Mat::Zero(F.rows(), F.cols());
  if (F.rows() == 2 && F.cols() == 2) {
    out.J = F(0, 0) * F(1, 1) - F(0, 1) * F(1, 0);
    out.g << F(1, 1), -F(1, 0), -F(0, 1), F(0, 0);
  } else if (F.cols() == 3) {
    const Eigen::Matrix3d g = cofactor(F);
    out.J = column(F, 0).dot(g.col(0));
    out.g = g;
  } else {  // 3 x 2, a membrane: J = |f0 x f1|
    const V3 f0 = column(F, 0), f1 = column(F, 1);
    const V3 n = f0.cross(f1);
    out.J = n.norm();
    if (out.J > 0.0) {
      const V3 u = n / out.J;
      out.g.col(0) = f1.cross(u);
      out.g.col(1) = u.cross(f0);
    }
  }
  return out;
}

Mat volume_differential(const Mat& F, const Mat& dF) {
  Mat dg = Mat::Zero(F.rows(), F.cols());
  if (F.rows() == 2 && F.cols() == 2) {
    dg << dF(1, 1), -dF(1, 0), -dF(0, 1), dF(0, 0);  // the cofactor is linear in F
  } else if (F.cols() == 3) {
    const V3 f0 = column(F, 0), f1 = column(F, 1), f2 = column(F, 2);
    const V3 d0 = column(dF, 0), d1 = column(dF, 1), d2 = column(dF, 2);
    dg.col(0) = d1.cross(f2) + f1.cross(d2);
    dg.col(1) = d2.cross(f0) + f2.cross(d0);
    dg.col(2) = d0.cross(f1) + f0.cross(d1);
  } else {
    const V3 f0 = column(F, 0), f1 = column(F, 1);
    const V3 d0 = column(dF, 0), d1 = column(dF, 1);
    const V3 n = f0.cross(f1);
    const double J = n.norm();
    if (J > 0.0) {
      const V3 u = n / J;
      const V3 dn = d0.cross(f1) + f0.cross(d1);
      const V3 du = (dn - u * u.dot(dn)) / J;  // d(n/|n|)
      dg.col(0) = d1.cross(u) + f1.cross(du);
      dg.col(1) = du.cross(f0) + u.cross(d0);
    }
  }
  return dg;
}

namespace {

// R = U V^T from the SVD F = U Sigma V^T; a reflection (det < 0: an
// inverted element) is turned into a rotation by flipping U's last column,
// so S = R^T F keeps a negative eigenvalue instead (Irving et al. 2004).
Eigen::Matrix3d rotation_by_svd(const Eigen::Matrix3d& F) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * V.transpose();
}

// det F > 0: R is F's orthogonal polar factor (then a rotation), the limit
// of Higham's scaled Newton iteration from X = F,
//   X <- (gamma X + X^-T / gamma) / 2,  gamma = (|X^-1|_F / |X|_F)^(1/2),
// (Higham, "Computing the polar decomposition -- with applications", SIAM
// J. Sci. Stat. Comput. 7, 1986), with X^-T = cofactor(X) / det X. The
// scaling speeds up the first steps; once a step changes X by less than
// 1e-2, gamma = 1 (Higham's advice), and the iteration converges
// quadratically: a step that changes X by less than 1e-9 leaves it exact to
// rounding. Elements near rest take three or four steps, a fraction of an
// SVD. Returns false if X degenerates or has not converged after 40 steps
// (then the SVD decides).
bool rotation_by_newton(const Eigen::Matrix3d& F, Eigen::Matrix3d& R) {
  Eigen::Matrix3d X = F;
  bool scaled = true;
  for (int step = 0; step < 40; ++step) {
    const Eigen::Matrix3d C = cofactor(X);  // det X X^-T
    const double det = X.col(0).dot(C.col(0));
    if (!(det > 0.0) || !std::isfinite(det)) return false;
    // gamma and beta = 1 / (gamma det), the weights of X and X^-T det, as
    //   gamma = (|C| / (|X| det))^1/2,  beta = (|X| / (|C| det))^1/2
    // from t = |C| |X| det: a square root, a division and a square root
    // in sequence (the iteration's latency is its cost), where the direct
    // form takes three divisions and two square roots.
    double gamma = 1.0, beta = 1.0 / det;
    if (scaled) {
      const double C2 = C.squaredNorm(), X2 = X.squaredNorm();
      const double inverse_t = 1.0 / (std::sqrt(C2 * X2) * det);
      gamma = std::sqrt(C2 * inverse_t);
      beta = std::sqrt(X2 * inverse_t);
    }
    const Eigen::Matrix3d next = (0.5 * gamma) * X + (0.5 * beta) * C;
    const double change2 = (next - X).squaredNorm();
    X = next;
    if (change2 < 1e-18) {
      R = X;
      return true;
    }
    scaled = scaled && change2 > 1e-4;
  }
  return false;
}

// det F > 0 and F near a rotation, |F^T F - I|_F < 0.6 (each singular value
// within about 25 % of 1, as in a solid that moves as a solid): R is also
// the limit of
//   X <- X (I - E/2 + 3/8 E^2),  E = X^T X - I,
// the binomial series of (X^T X)^-1/2 = (I + E)^-1/2 cut after E^2 (Bjorck
// and Bowie, "An iterative algorithm for computing the best estimate of an
// orthogonal matrix", SIAM J. Numer. Anal. 8, 1971; Higham, "Functions of
// matrices", SIAM 2008, ch. 8). A singular value s, with e = s^2 - 1, goes
// to one with e' = 5/8 e^3 + O(e^4): from e = 0.1 three steps leave X
// orthogonal to rounding (the last one taken at |E|_F < 3e-6, where
// e' < 2e-17). A step is products only, no division or square root, so it
// is a short chain of multiplications where Higham's Newton step (above)
// waits on a square root, a division and a square root in turn: near rest
// it takes about 52 ns where Higham's iteration takes 94, and eight
// matrices in lanes (lanes.h, rotation3_lanes) about 16 ns each
// (benchmarks/README).
//
// For one element (T = double, M = bool) or kLanes (T = Lanes, M = Mask):
// F and X are row-major, F[3 r + c]. Where `proper` (det F > 0) the
// iteration runs until E is small; `converged` tells where it got there
// (false: F out of range, then Higham's iteration decides). A lane that
// has converged stays as it is while the others go on, so that each lane's
// steps are those of its element alone.
template <typename T, typename M>
SPRINGLAB_LANES_INLINE void rotation_by_series(const T (&F)[9], const M& proper, T (&x)[9],
                                               M& converged) {
  for (int k = 0; k < 9; ++k) x[k] = F[k];
  M active = proper;
  converged = proper ^ proper;  // nowhere yet
  for (int step = 0; step < 12; ++step) {
    T E[3][3];  // X^T X - I
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) {
        const T XtX = x[a] * x[b] + x[3 + a] * x[3 + b] + x[6 + a] * x[6 + b];
        E[a][b] = XtX - (a == b ? 1.0 : 0.0);
        E[b][a] = E[a][b];
      }
    }
    // |E|_F^2 (E is symmetric), summed as a short tree: in lanes the next
    // X waits on it (a lane stops where it is small).
    const T diagonal = (E[0][0] * E[0][0] + E[1][1] * E[1][1]) + E[2][2] * E[2][2];
    const T off_diagonal = (E[0][1] * E[0][1] + E[0][2] * E[0][2]) + E[1][2] * E[1][2];
    const T error2 = diagonal + 2.0 * off_diagonal;
    if (step == 0) active = active & (error2 < 0.36);
    T S[3][3];  // I - E/2 + 3/8 E^2
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) {
        const T E2 = E[a][0] * E[0][b] + E[a][1] * E[1][b] + E[a][2] * E[2][b];
        S[a][b] = (a == b ? 1.0 : 0.0) - 0.5 * E[a][b] + 0.375 * E2;
        S[b][a] = S[a][b];
      }
    }
    T next[9];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        next[3 * r + c] = x[3 * r] * S[0][c] + x[3 * r + 1] * S[1][c] + x[3 * r + 2] * S[2][c];
      }
    }
    for (int k = 0; k < 9; ++k) assign_where(x[k], active, next[k]);
    const M last = active & (error2 < 1e-11);
    converged = converged | last;
    active = active ^ last;  // last is within active
    if (!any(active)) break;
  }
}

}  // namespace

Polar3 polar3(const Eigen::Matrix3d& F) {
  // As polar() below for a solid, with fixed sizes.
  double f[9], r[9], s[9];
  for (int k = 0; k < 9; ++k) f[k] = F(k / 3, k % 3);
  const bool proper = F.determinant() > 0.0;
  bool converged = false;
  if (proper) rotation_by_series(f, proper, r, converged);
  Polar3 p;
  if (!converged) {
    if (!proper || !rotation_by_newton(F, p.R)) p.R = rotation_by_svd(F);
    for (int k = 0; k < 9; ++k) r[k] = p.R(k / 3, k % 3);
  }
  stretch(r, f, s);
  for (int k = 0; k < 9; ++k) {
    p.R(k / 3, k % 3) = r[k];
    p.S(k / 3, k % 3) = s[k];
  }
  return p;
}

SPRINGLAB_LANES_CLONES
void rotation3_lanes(const Eigen::Matrix3d* const (&F)[kLanes],
                     Eigen::Matrix3d* const (&R)[kLanes]) {
  Lanes f[9], r[9];
  for (int l = 0; l < kLanes; ++l) {
    for (int k = 0; k < 9; ++k) f[k][l] = (*F[l])(k / 3, k % 3);
  }
  // det F (in the series' range |det F| > 0.25, so its sign is F.determinant()'s).
  Lanes det;
  determinant(f, det);
  const Mask proper = det > 0.0;
  Mask converged;
  rotation_by_series(f, proper, r, converged);
  for (int l = 0; l < kLanes; ++l) {
    if (converged[l] == 0) {
      *R[l] = polar3(*F[l]).R;
      continue;
    }
    for (int k = 0; k < 9; ++k) (*R[l])(k / 3, k % 3) = r[k][l];
  }
}

Polar polar(const Mat& F) {
  Polar p;
  if (F.rows() == 3 && F.cols() == 3) {
    const Polar3 p3 = polar3(F);
    p.R = p3.R;
    p.S = p3.S;
  } else if (F.rows() == F.cols()) {
    // R = U V^T from the SVD; a reflection (det < 0: an inverted element) is
    // turned into a rotation by flipping U's last column, so S = R^T F keeps
    // a negative eigenvalue instead (Irving et al. 2004).
    Eigen::JacobiSVD<Mat> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat U = svd.matrixU();
    const Mat V = svd.matrixV();
    if ((U * V.transpose()).determinant() < 0.0) U.col(U.cols() - 1) *= -1.0;
    p.R = U * V.transpose();
    const Mat S = p.R.transpose() * F;
    p.S = 0.5 * (S + S.transpose());
  } else {
    // A membrane: S = C^1/2, R = F S^-1 (orthonormal columns).
    const Mat C = F.transpose() * F;
    Eigen::SelfAdjointEigenSolver<Mat> eig(C);
    const Eigen::Vector2d s = eig.eigenvalues().cwiseSqrt();
    const Mat Q = eig.eigenvectors();
    p.S = Q * s.asDiagonal() * Q.transpose();
    p.R = F * (Q * s.cwiseInverse().asDiagonal() * Q.transpose());
  }
  return p;
}

Mat nearest_unit_volume(const Mat& F) {
  const double J = volume(F).J;
  if (!(J > 0.0)) return polar(F).R;
  // The SVD F = U diag(s) V^T from the eigen decomposition
  // C = F^T F = V diag(s^2) V^T (k x k, closed form): U diag(s*) V^T =
  // F V diag(s* / s) V^T, no U needed (J > 0: every s_i > 0).
  using Values = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;  // on the stack
  Mat V;
  Values s;
  if (F.cols() == 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(Eigen::Matrix3d(F.transpose() * F));
    V = eig.eigenvectors();
    s = eig.eigenvalues().cwiseSqrt();
  } else {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig;
    eig.computeDirect(Eigen::Matrix2d(F.transpose() * F));
    V = eig.eigenvectors();
    s = eig.eigenvalues().cwiseSqrt();
  }
  const Eigen::Index k = s.size();
  const double s_min = s.minCoeff();
  Values star(k);
  const auto at = [&](double m, double& g, double& dg) {  // g(m), g'(m)
    double product = 1.0;
    dg = 0.0;
    for (Eigen::Index i = 0; i < k; ++i) {
      const double r = std::sqrt(std::max(0.0, s[i] * s[i] - 4.0 * m));
      star[i] = 0.5 * (s[i] + r);
      product *= star[i];
      dg -= 1.0 / (r * star[i]);
    }
    g = std::log(product);
  };
  // g(0) = ln J. For J > 1 the root lies in (0, s_min^2 / 4]; for J < 1 in
  // [-1, 0) (at m = -1 every s*_i >= 1, so g >= 0).
  double lo = J > 1.0 ? 0.0 : -1.0, hi = J > 1.0 ? 0.25 * s_min * s_min : 0.0;
  double g = 0.0, dg = 0.0;
  if (J > 1.0) {
    at(hi, g, dg);
    if (g > 0.0) {  // no root on this branch
      return F / std::pow(J, 1.0 / static_cast<double>(k));
    }
  }
  double m = 0.0;
  for (int iteration = 0; iteration < 100; ++iteration) {
    at(m, g, dg);
    if (std::abs(g) <= 1e-15 * static_cast<double>(k)) break;
    if (g > 0.0) lo = m; else hi = m;  // g decreases in m
    double next = m - g / dg;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // Newton left the bracket
    if (next == m) break;
    m = next;
  }
  at(m, g, dg);
  return F * (V * star.cwiseQuotient(s).asDiagonal() * V.transpose());
}

Mat polar_differential(const Polar& p, const Mat& F, const Mat& dF) {
  if (F.rows() == F.cols()) {
    // F = R S with W = R^T dR skew and dS symmetric gives
    // R^T dF - dF^T R = W S + S W (the symmetric part of R^T dF is dS).
    const Mat A = p.R.transpose() * dF;
    const Mat K = A - A.transpose();
    if (F.rows() == 2) {
      // W = theta [[0, -1], [1, 0]]: W S + S W = tr(S) W.
      const double theta = K(1, 0) / p.S.trace();
      Mat W(2, 2);
      W << 0.0, -theta, theta, 0.0;
      return p.R * W;
    }
    // W = [w]x: W S + S W = [(tr(S) I - S) w]x (Twigg and Kacic-Alesic 2010).
    const Eigen::Vector3d u(K(2, 1), K(0, 2), K(1, 0));
    const Eigen::Matrix3d M = p.S.trace() * Eigen::Matrix3d::Identity() - Eigen::Matrix3d(p.S);
    const Eigen::Vector3d w = M.fullPivLu().solve(u);
    Mat W(3, 3);
    W << 0.0, -w(2), w(1), w(2), 0.0, -w(0), -w(1), w(0), 0.0;
    return p.R * W;
  }
  // A membrane: S^2 = C, so S dS + dS S = dC, solved in S's eigenbasis
  // (dS'_ij = dC'_ij / (s_i + s_j)); then R = F S^-1 gives
  // dR = (dF - R dS) S^-1.
  const Mat dC = dF.transpose() * F + F.transpose() * dF;
  Eigen::SelfAdjointEigenSolver<Mat> eig(p.S);
  const Mat Q = eig.eigenvectors();
  const Eigen::Vector2d s = eig.eigenvalues();
  Mat dSp = Q.transpose() * dC * Q;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) dSp(i, j) /= s(i) + s(j);
  }
  const Mat dS = Q * dSp * Q.transpose();
  const Mat S_inv = Q * s.cwiseInverse().asDiagonal() * Q.transpose();
  return (dF - p.R * dS) * S_inv;
}

}  // namespace springlab
