#include "integrators/sparse_direct_solver.h"

namespace springlab {

bool SparseDirectSolver::factorize(const SparseMatrix& a, bool symmetric) {
  error_.clear();
  if (symmetric) {
    if (!ldlt_analyzed_) {
      ldlt_.analyzePattern(a);
      ldlt_analyzed_ = true;
    }
    ldlt_.factorize(a);
    if (ldlt_.info() == Eigen::Success) {
      using_lu_ = false;
      return true;
    }
  }
  return factorize_lu(a);
}

bool SparseDirectSolver::factorize_lu(const SparseMatrix& a) {
  if (!lu_analyzed_) {
    lu_.analyzePattern(a);
    lu_analyzed_ = true;
  }
  lu_.factorize(a);
  using_lu_ = true;
  if (lu_.info() != Eigen::Success) {
    error_ = "sparse LU factorization failed: " + lu_.lastErrorMessage();
    return false;
  }
  return true;
}

bool SparseDirectSolver::solve(const Vector& b, Vector& x) const {
  if (using_lu_) {
    x = lu_.solve(b);
  } else {
    x = ldlt_.solve(b);
  }
  return x.allFinite();
}

}  // namespace springlab
