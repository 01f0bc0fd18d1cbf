#include "integrators/linear/preconditioned_cg.h"

#include <algorithm>
#include <cmath>

namespace springlab {

CgResult preconditioned_cg(const SparseMatrix& a, SparseDirectSolver& p, const Vector& b,
                           double rtol, double atol, int max_iterations, Vector& d,
                           CgScratch& s) {
  return preconditioned_cg([&a](const Vector& x, Vector& q) { q.noalias() = a * x; }, p, b, rtol,
                           atol, max_iterations, d, s);
}

CgResult preconditioned_cg(const LinearProduct& a, SparseDirectSolver& p, const Vector& b,
                           double rtol, double atol, int max_iterations, Vector& d,
                           CgScratch& s) {
  CgResult result;
  d.setZero(b.size());
  s.r = b;  // r = b - A d
  if (!p.solve(s.r, s.z)) {
    result.finite = false;
    return result;
  }
  s.p = s.z;
  double rz = s.r.dot(s.z);
  while (result.iterations < max_iterations) {
    a(s.p, s.q);
    ++result.iterations;
    const double curvature = s.p.dot(s.q);
    if (!std::isfinite(curvature)) {
      result.finite = false;
      return result;
    }
    if (curvature <= 0.0) {
      // A is not positive definite along p: keep what descends (header).
      result.negative_curvature = true;
      if (result.iterations == 1) d = s.z;
      return result;
    }
    const double alpha = rz / curvature;
    d += alpha * s.p;
    s.r -= alpha * s.q;
    if (!p.solve(s.r, s.z)) {
      result.finite = false;
      return result;
    }
    if (s.z.lpNorm<Eigen::Infinity>() <= std::max(rtol * d.lpNorm<Eigen::Infinity>(), atol)) {
      result.converged = true;
      return result;
    }
    const double rz_next = s.r.dot(s.z);
    s.p = s.z + (rz_next / rz) * s.p;
    rz = rz_next;
  }
  return result;
}

}  // namespace springlab
