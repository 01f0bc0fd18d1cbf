#include "models/model/modal_analysis.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace springlab {

double max_angular_frequency(const Model& model, const Vector& x, const Vector& v,
                             Eigen::Index dense_up_to) {
  SparseMatrix dfdx;
  model.jacobians(0.0, x, v, &dfdx, nullptr);
  // A = M^-1/2 K M^-1/2 with K the symmetric part of -dF/dx: same spectrum
  // as M^-1 K, and symmetric.
  const Vector s = model.mass().cwiseSqrt().cwiseInverse();
  SparseMatrix k = -0.5 * (SparseMatrix(dfdx.transpose()) + dfdx);
  SparseMatrix a = s.asDiagonal() * k * s.asDiagonal();
  double lambda = 0.0;
  if (a.rows() <= dense_up_to) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(a),
                                                            Eigen::EigenvaluesOnly);
    lambda = eig.eigenvalues().maxCoeff();
  } else {
    // Power iteration on A + c I (c = Gershgorin bound) converges to the
    // largest eigenvalue of A even when A has negative ones.
    double c = 0.0;
    for (int j = 0; j < a.outerSize(); ++j) {
      double row = 0.0;
      for (SparseMatrix::InnerIterator it(a, j); it; ++it) row += std::abs(it.value());
      c = std::max(c, row);
    }
    Vector q = Vector::Ones(a.rows()).normalized();
    double previous = 0.0;
    for (int iteration = 0; iteration < 5000; ++iteration) {
      Vector z = a * q + c * q;
      const double estimate = q.dot(z);
      q = z.normalized();
      if (std::abs(estimate - previous) <= 1e-10 * std::abs(estimate)) break;
      previous = estimate;
    }
    lambda = q.dot(a * q);
  }
  return lambda > 0.0 ? std::sqrt(lambda) : 0.0;
}

Mode lowest_mode(const Model& model, const Vector& x, const Vector& v) {
  const Eigen::Index n = model.dofs();
  if (n > kMaxModeUnknowns) {
    throw std::invalid_argument("the lowest mode needs a dense " + std::to_string(n) + " x " +
                                std::to_string(n) + " eigensolver; at most " +
                                std::to_string(kMaxModeUnknowns) + " unknowns");
  }
  SparseMatrix dfdx;
  model.jacobians(0.0, x, v, &dfdx, nullptr);
  // K phi = w^2 M phi  <=>  (M^-1/2 K M^-1/2) psi = w^2 psi, phi = M^-1/2 psi,
  // and |psi| = 1 gives phi^T M phi = 1.
  const Vector s = model.mass().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd K = -0.5 * (Eigen::MatrixXd(dfdx) + Eigen::MatrixXd(dfdx).transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s.asDiagonal() * K * s.asDiagonal());
  Mode mode;
  const double lambda = eig.eigenvalues()[0];
  mode.w = lambda > 0.0 ? std::sqrt(lambda) : 0.0;
  mode.phi = s.asDiagonal() * eig.eigenvectors().col(0);
  Eigen::Index largest = 0;
  mode.phi.cwiseAbs().maxCoeff(&largest);
  if (mode.phi[largest] < 0.0) mode.phi = -mode.phi;
  return mode;
}

std::vector<std::complex<double>> first_order_eigenvalues(const Model& model,
                                                          const Vector& x, const Vector& v) {
  const Eigen::Index n = model.dofs();
  if (2 * n > kMaxFirstOrderUnknowns) {
    throw std::invalid_argument("the first-order eigenvalues need a dense " +
                                std::to_string(2 * n) + " x " + std::to_string(2 * n) +
                                " eigensolver; at most " +
                                std::to_string(kMaxFirstOrderUnknowns) + " unknowns");
  }
  SparseMatrix dfdx, dfdv;
  model.jacobians(0.0, x, v, &dfdx, &dfdv);
  const Vector inv_mass = model.mass().cwiseInverse();
  // J = [[0, I], [M^-1 K, M^-1 D]]
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  J.topRightCorner(n, n).setIdentity();
  J.bottomLeftCorner(n, n) = inv_mass.asDiagonal() * Eigen::MatrixXd(dfdx);
  J.bottomRightCorner(n, n) = inv_mass.asDiagonal() * Eigen::MatrixXd(dfdv);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(J, /*computeEigenvectors=*/false);
  std::vector<std::complex<double>> lambda(eig.eigenvalues().begin(), eig.eigenvalues().end());
  std::sort(lambda.begin(), lambda.end(), [](std::complex<double> a, std::complex<double> b) {
    const double ma = std::abs(a), mb = std::abs(b);
    if (ma != mb) return ma < mb;
    if (a.imag() != b.imag()) return a.imag() < b.imag();
    return a.real() < b.real();
  });
  return lambda;
}

}  // namespace springlab
