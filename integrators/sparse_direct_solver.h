// Sparse direct solves for the implicit methods' matrices, all on the
// model's one fixed pattern, so the symbolic analysis (fill-reducing
// ordering, elimination tree) is done once per run and only the numeric
// factorization is repeated.
//   - symmetric matrices: LDL^T (SimplicialLDLT). No positive definiteness
//     is assumed: compressed springs make M + h^2 K indefinite, LDL^T still
//     factors it unless a pivot is exactly zero;
//   - otherwise, or when LDL^T meets a zero pivot: sparse LU with partial
//     pivoting.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <string>

#include "models/mechanical_system.h"

namespace springlab {

class SparseDirectSolver {
 public:
  // False, with error() set, when the matrix is numerically singular.
  bool factorize(const SparseMatrix& a, bool symmetric);
  // Forgets the symbolic analysis: the next matrix may have another pattern.
  void reset() { ldlt_analyzed_ = lu_analyzed_ = using_lu_ = false; }
  // False when the solution is not finite.
  bool solve(const Vector& b, Vector& x) const;
  const std::string& error() const { return error_; }

 private:
  bool factorize_lu(const SparseMatrix& a);

  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
  Eigen::SparseLU<SparseMatrix> lu_;
  bool ldlt_analyzed_ = false;
  bool lu_analyzed_ = false;
  bool using_lu_ = false;
  std::string error_;
};

}  // namespace springlab
