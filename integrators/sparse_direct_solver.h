// Sparse direct solves for the implicit methods' matrices, all on the
// model's one fixed pattern, so the symbolic analysis (fill-reducing
// ordering, elimination tree, supernodes) is done once per run and only the
// numeric factorization is repeated. Three kinds of matrix, three methods:
//   - kPositiveDefinite (the Newton matrix made of the definite part of the
//     Jacobians, M - h c D - h^2 b K~ with K~ negative semidefinite):
//     CHOLMOD's LL^T (SuiteSparse). Supernodal for a factor made often,
//     its dense blocks in BLAS (OpenBLAS): ~4 x faster than a simplicial
//     LDL^T on cloth 64 and ~8 x on cloth 128 (benchmarks/README.md);
//     simplicial for one solved often (FactorUse below). Only such a factor may
//     precondition conjugate gradients (it is symmetric positive definite).
//     A matrix that turns out not to be positive definite after all is
//     factored as kSymmetric instead;
//   - kSymmetric (the exact Jacobian, indefinite where springs are
//     compressed): LDL^T without pivoting (Eigen's SimplicialLDLT), which
//     factors an indefinite matrix unless a pivot is exactly zero;
//   - kGeneral (spring damping makes dF/dx non-symmetric), or a zero pivot
//     in LDL^T: sparse LU with partial pivoting (Eigen's SparseLU).
//
// BLAS threads: CHOLMOD calls BLAS on each supernode, blocks of a few
// hundred columns at most for these meshes. On the 2-core machine the
// benchmarks run on, one OpenBLAS thread factors cloth 64 and 128 as fast as
// two when the machine is idle and much faster when it is not (OpenBLAS's
// threads spin while they wait), and keeps `experiment --jobs N`'s tasks off
// each other's cores; one thread is also deterministic run to run. The
// solver therefore sets one BLAS thread (see benchmarks/README.md for the
// figures), and with it keeps CHOLMOD's own OpenMP loops on the calling
// thread (sparse_direct_solver.cc); the environment variable
// SPRINGLAB_BLAS_THREADS overrides both.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <memory>
#include <string>

#include "models/mechanical_system.h"

namespace springlab {

enum class MatrixKind { kPositiveDefinite, kSymmetric, kGeneral };

// How a positive definite factor is used, which picks CHOLMOD's layout:
//   - kRefactoredOften (Newton: a new factor every iteration or step, a few
//     solves each): supernodal, the factorization in dense BLAS blocks;
//   - kSolvedOften (projective dynamics' and quasi-Newton's M + h^2 L: one
//     factor per step size, one solve of three right-hand sides per
//     iteration): simplicial LL^T, whose triangular solves run column by
//     column without a BLAS call per supernode. Measured in one binary at
//     1/60 over 2 s (an n_particles x n_particles Laplacian): quasi-Newton
//     at 1e-3 m/s on cloth 64 44.6 -> 36.6 ms per step, projective
//     dynamics 7.0 -> 5.7 ms on cloth 64 and 34 -> 31 ms on cloth 128.
enum class FactorUse { kRefactoredOften, kSolvedOften };

class SparseDirectSolver {
 public:
  explicit SparseDirectSolver(FactorUse use = FactorUse::kRefactoredOften);
  ~SparseDirectSolver();
  SparseDirectSolver(const SparseDirectSolver&) = delete;
  SparseDirectSolver& operator=(const SparseDirectSolver&) = delete;

  // False, with error() set, when the matrix is numerically singular (or
  // too large for the factorization's index type).
  bool factorize(const SparseMatrix& a, MatrixKind kind);
  // Forgets the symbolic analyses and the factorization: the next matrix may
  // have another pattern.
  void reset();
  // x = A^-1 b with the last factorization; false when x is not finite.
  bool solve(const Vector& b, Vector& x);
  // X = A^-1 B for several right-hand sides at once (one pass over the
  // factor: CHOLMOD then works with matrix-matrix kernels).
  bool solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X);
  // Whether the last factorization is a Cholesky factor of a positive
  // definite matrix (and so a valid preconditioner for conjugate gradients).
  bool positive_definite() const { return method_ == Method::kCholesky; }
  bool has_factor() const { return method_ != Method::kNone; }
  // Nonzeros of the last factor's L (LL^T and LDL^T; 0 for LU).
  double factor_nonzeros() const { return factor_nonzeros_; }
  // Floating-point operations of the last numeric factorization (CHOLMOD's
  // own count; 0 for the other methods).
  double factor_flops() const { return factor_flops_; }
  const std::string& error() const { return error_; }

 private:
  enum class Method { kNone, kCholesky, kLdlt, kLu };
  bool factorize_cholesky(const SparseMatrix& a);
  bool factorize_ldlt(const SparseMatrix& a);
  bool factorize_lu(const SparseMatrix& a);

  struct Cholmod;  // CHOLMOD's common block and factor (cholmod.h stays in the .cc)
  std::unique_ptr<Cholmod> cholmod_;
  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
  Eigen::SparseLU<SparseMatrix> lu_;
  bool ldlt_analyzed_ = false;
  bool lu_analyzed_ = false;
  Method method_ = Method::kNone;
  double factor_nonzeros_ = 0.0;
  double factor_flops_ = 0.0;
  std::string error_;
};

}  // namespace springlab
