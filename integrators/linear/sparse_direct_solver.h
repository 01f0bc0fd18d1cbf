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
//
// Memory (issue 38.1). A factor's size is known before any numeric work:
// CHOLMOD's symbolic analysis of the pattern (AMD ordering, column counts)
// gives nnz(L) exactly for that ordering, in O(nnz(A)) time and memory.
// The rule: a factorization is attempted only when its estimated bytes,
// kFactorBytesPerNonzero x nnz(L), fit in memory_limit_bytes(); otherwise
// factorize() fails with out_of_memory() set and a message quoting both
// numbers, and so does every allocation that fails anyway (CHOLMOD's
// OUT_OF_MEMORY or TOO_LARGE status, std::bad_alloc from Eigen): no
// fallback to another method, which would need as much again.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <memory>
#include <string>

#include "models/core/mechanical_system.h"

namespace springlab {

enum class MatrixKind { kPositiveDefinite, kSymmetric, kGeneral };
class PositiveDefiniteFactor;

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

// A factor's size, from the symbolic analysis only.
struct FactorEstimate {
  double nonzeros = 0.0;  // nnz(L), AMD ordering
  double bytes = 0.0;     // kFactorBytesPerNonzero * nonzeros
};
// Bytes per nonzero of L: its value (8) and row index (4), plus a third
// again for what a factorization holds beside L (supernodal padding,
// CHOLMOD's update workspace, Eigen's column copies). Measured on block
// n = 20 / 30 with implicit-euler (docs/reliability.md).
constexpr double kFactorBytesPerNonzero = 16.0;
// A supernodal factorization's first BLAS call makes OpenBLAS's work buffer
// (128 MB in Debian's build), and OpenBLAS retries a failed one forever
// (issue 38.1: "spun > 120 s inside blas_memory_alloc"): the rule counts it.
constexpr double kBlasBufferBytes = 256e6;
FactorEstimate estimate_factor(const SparseMatrix& a);
// Bytes this process may still allocate: physical memory
// (sysconf(_SC_PHYS_PAGES) * _SC_PAGE_SIZE), or, when RLIMIT_AS is set and
// tighter, that limit less the address space already mapped
// (/proc/self/statm). Infinity when neither is known.
double memory_limit_bytes();
// "1.5 GB": bytes in the unit that suits them.
std::string format_bytes(double bytes);
// Empty when a factor of `a` fits in `limit` bytes; otherwise one line with
// the estimate and the limit ("the factor of the 89373 x 89373 Newton matrix
// needs about 2.1 GB (3.1e8 nonzeros), over the 1.2 GB this process may
// allocate"), without advice: the caller says what to try.
// `extra`: bytes needed beside the factor (kBlasBufferBytes when supernodal).
std::string factor_fit_error(const SparseMatrix& a, double limit = memory_limit_bytes(),
                             double extra = kBlasBufferBytes);

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
  // The last factorize() failed because the factor did not fit in memory
  // (estimated or an allocation failed): trying another method or a smaller
  // step will not help.
  bool out_of_memory() const { return out_of_memory_; }
  // The limit factorize() checks its estimate against (memory_limit_bytes()
  // when not set; infinity skips the check, for tests of the allocation
  // failures themselves).
  void set_memory_limit(double bytes) { memory_limit_ = bytes; }

 private:
  enum class Method { kNone, kCholesky, kLdlt, kLu };
  bool factorize_cholesky(const SparseMatrix& a);
  bool factorize_ldlt(const SparseMatrix& a);
  bool factorize_lu(const SparseMatrix& a);
  bool fits(const SparseMatrix& a);
  bool fail_out_of_memory(const SparseMatrix& a, const std::string& where);

  // LL^T: CHOLMOD natively, Eigen's in the web build (positive_definite_factor.h).
  std::unique_ptr<PositiveDefiniteFactor> cholesky_;
  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
  Eigen::SparseLU<SparseMatrix> lu_;
  bool ldlt_analyzed_ = false;
  bool lu_analyzed_ = false;
  bool fit_checked_ = false;
  bool out_of_memory_ = false;
  double memory_limit_ = -1.0;  // < 0: memory_limit_bytes()
  Method method_ = Method::kNone;
  double factor_nonzeros_ = 0.0;
  double factor_flops_ = 0.0;
  std::string error_;
};

}  // namespace springlab
