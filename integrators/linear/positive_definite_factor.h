// The sparse Cholesky factorization LL^T behind SparseDirectSolver's
// kPositiveDefinite matrices (sparse_direct_solver.h). The build picks one
// of two implementations of this class:
//   - positive_definite_factor_cholmod.cc: CHOLMOD (SuiteSparse), supernodal
//     or simplicial by FactorUse, its dense blocks in OpenBLAS: the native
//     build;
//   - positive_definite_factor_eigen.cc: Eigen's SimplicialLLT with the same
//     AMD ordering: the WebAssembly build (web/), which has neither CHOLMOD
//     nor a BLAS.
// Both read the lower triangle of a compressed matrix that stores both,
// analyse its pattern at the first factorization (again after reset()) and
// repeat only the numeric factorization after that.
#pragma once

#include <memory>
#include <string>

#include "integrators/linear/sparse_direct_solver.h"

namespace springlab {

class PositiveDefiniteFactor {
 public:
  enum class Status { kOk, kNotPositiveDefinite, kOutOfMemory };

  explicit PositiveDefiniteFactor(FactorUse use);
  ~PositiveDefiniteFactor();
  PositiveDefiniteFactor(const PositiveDefiniteFactor&) = delete;
  PositiveDefiniteFactor& operator=(const PositiveDefiniteFactor&) = delete;

  // LL^T of `a` (compressed). kOutOfMemory names the step that ran out in
  // failed_step() ("CHOLMOD's analysis").
  Status factorize(const SparseMatrix& a);
  // A^-1 B for B of `rows` x `cols` (column-major) with the last factor:
  // the solution, same layout, held here until the next call; nullptr when
  // the solve fails.
  const double* solve(const double* b, Eigen::Index rows, Eigen::Index cols);
  // Forgets the factor and the analysis of the pattern.
  void reset();

  double nonzeros() const;  // nnz(L) of the last factor
  double flops() const;     // of the last numeric factorization (0: not counted)
  // Whether factorizations call BLAS (and so need its work buffer:
  // kBlasBufferBytes).
  bool uses_blas() const;
  const std::string& failed_step() const { return failed_step_; }

 private:
  struct Impl;  // the library's objects stay in the implementation's file
  std::unique_ptr<Impl> impl_;
  std::string failed_step_;
};

}  // namespace springlab
