#include "integrators/linear/preconditioned_minres.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springlab {

CgResult preconditioned_minres(const SparseMatrix& a, SparseDirectSolver& p, const Vector& b,
                               double rtol, int max_iterations, Vector& d, MinresScratch& s) {
  return preconditioned_minres([&a](const Vector& x, Vector& q) { q.noalias() = a * x; }, p, b,
                               rtol, max_iterations, d, s);
}

CgResult preconditioned_minres(const LinearProduct& a, SparseDirectSolver& p, const Vector& b,
                               double rtol, int max_iterations, Vector& d, MinresScratch& s) {
  CgResult result;
  const Eigen::Index n = b.size();
  d.setZero(n);
  s.r1 = b;
  if (!p.solve(s.r1, s.y)) {
    result.finite = false;
    return result;
  }
  const double beta1_squared = s.r1.dot(s.y);
  if (!(beta1_squared > 0.0)) {  // b = 0 (or P not positive definite)
    result.converged = beta1_squared == 0.0;
    result.finite = std::isfinite(beta1_squared);
    return result;
  }
  const double beta1 = std::sqrt(beta1_squared);
  const double eps = std::numeric_limits<double>::epsilon();
  double beta = beta1, old_beta = 0.0;
  double dbar = 0.0, epsilon = 0.0, phibar = beta1;
  double cs = -1.0, sn = 0.0;
  s.r2 = s.r1;
  s.w.setZero(n);
  s.w2.setZero(n);
  while (result.iterations < max_iterations) {
    ++result.iterations;
    // Lanczos: v_k = y / beta_k, the next P^-1-orthogonal direction.
    s.v = s.y / beta;
    a(s.v, s.y);
    if (result.iterations >= 2) s.y -= (beta / old_beta) * s.r1;
    const double alpha = s.v.dot(s.y);
    s.y -= (alpha / beta) * s.r2;
    s.r1.swap(s.r2);
    s.r2 = s.y;
    if (!p.solve(s.r2, s.y)) {
      result.finite = false;
      return result;
    }
    old_beta = beta;
    const double beta_squared = s.r2.dot(s.y);
    if (!(beta_squared >= 0.0)) {  // P not positive definite, or not finite
      result.finite = std::isfinite(beta_squared);
      return result;
    }
    beta = std::sqrt(beta_squared);
    // Apply the previous plane rotation, then make the next one.
    const double old_epsilon = epsilon;
    const double delta = cs * dbar + sn * alpha;
    const double gbar = sn * dbar - cs * alpha;
    epsilon = sn * beta;
    dbar = -cs * beta;
    const double gamma = std::max(std::hypot(gbar, beta), eps);
    cs = gbar / gamma;
    sn = beta / gamma;
    const double phi = cs * phibar;
    phibar *= sn;
    // Update the solution.
    s.w1.swap(s.w2);
    s.w2.swap(s.w);
    s.w = (s.v - old_epsilon * s.w1 - delta * s.w2) / gamma;
    d += phi * s.w;
    if (!std::isfinite(phibar)) {
      result.finite = false;
      return result;
    }
    if (phibar <= rtol * beta1 || beta == 0.0) {
      result.converged = true;
      return result;
    }
  }
  return result;
}

}  // namespace springlab
