#include "integrators/methods/reference_backward_euler.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

namespace springlab {
namespace {

constexpr Eigen::Index kDenseLimit = 600;

// dv = -J^-1 r; false when J is singular or dv not finite.
bool newton_update(const SparseMatrix& jacobian, const Vector& r, Vector& dv) {
  if (jacobian.rows() <= kDenseLimit) {
    const Eigen::MatrixXd dense(jacobian);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(dense);
    if (!lu.isInvertible()) return false;
    dv = -lu.solve(r);
  } else {
    Eigen::SimplicialLDLT<SparseMatrix> ldlt(jacobian);
    if (ldlt.info() != Eigen::Success) return false;
    dv = -ldlt.solve(r);
  }
  return dv.allFinite();
}

}  // namespace

ReferenceStepResult reference_backward_euler_step(const MechanicalSystem& system, double t,
                                                  double h, double tol, int max_iterations,
                                                  Vector& x, Vector& v) {
  ReferenceStepResult result;
  system.lag_normal_forces(&x, &v, h);
  const Vector v_n = v;
  const double t1 = t + h;
  Vector f, r, dv, x1;
  SparseMatrix dfdx, dfdv;
  for (; result.iterations < max_iterations; ++result.iterations) {
    x1 = x + h * v;
    system.force(t1, x1, v, f);
    r = system.mass().cwiseProduct(v - v_n) - h * f;
    system.jacobians(t1, x1, v, &dfdx, &dfdv);
    SparseMatrix jacobian = -h * dfdv - h * h * dfdx;
    jacobian.diagonal() += system.mass();
    if (!newton_update(jacobian, r, dv)) {
      result.message = "the Newton matrix is singular, or the update not finite";
      break;
    }
    v += dv;
    if (dv.lpNorm<Eigen::Infinity>() <= tol) {
      ++result.iterations;
      result.ok = true;
      break;
    }
  }
  system.lag_normal_forces(nullptr, nullptr, 0.0);
  if (!result.ok && result.message.empty()) result.message = "no convergence";
  if (result.ok) x += h * v;
  return result;
}

}  // namespace springlab
