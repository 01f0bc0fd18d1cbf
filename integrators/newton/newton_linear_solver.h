// The linear solves of Newton's updates, J d = rhs (newton_loop.h), on the
// model's one sparse pattern:
//   - J symmetric (forces from potentials, no spring damping): conjugate
//     gradients (CG, preconditioned_cg.h) preconditioned by a Cholesky
//     factor of the definite Newton matrix (CHOLMOD, supernodal:
//     sparse_direct_solver.h), made at some earlier iterate and kept across
//     iterations and steps while CG converges fast with it. CG may stop at
//     negative curvature where Newton minimizes (`truncate`: its iterate
//     then still descends the potential); where a true solve of an
//     indefinite J is wanted, MINRES (preconditioned_minres.h), and LDL^T
//     where neither converges;
//   - J not symmetric (spring damping): sparse LU at every new matrix.
//
// The kept factor, refreshed by renting against buying (the ski-rental
// rule: Karlin, Manasse, Rudolph and Sleator, "Competitive snoopy caching",
// Algorithmica 3, 1988: rent until the rent paid equals the price, then
// buy; in that problem it never pays more than twice what the best choice
// in hindsight would, here a guide, the future iterations being unknown). A factorization costs about kRefreshCost CG iterations (CPU time
// in one run of cloth 32 / 64 / 128 at 1/60 s, 2026-11-27: 14 / 7.3 / 11.4
// iterations of 0.42 / 5.2 / 28 ms; a count, not a clock, so that a run is
// the same from one machine to the next). The rent is the iterations a
// kept factor costs beyond what a fresh one would: a fresh factor solves
// the definite matrix in 1 iteration, so every further one is the kept
// factor's; it solves the exact matrix (compressed springs' negative
// stiffness included) in as many as the two matrices' difference costs,
// 5-20 on cloth 128 while it buckles, which no refresh removes: that count
// is taken from the factor's first exact solve, and only iterations beyond
// it are rent. Once the rent summed since the factor was made exceeds
// kRefreshCost, the next solve has a fresh one. (The rule it replaces,
// refresh after any solve of more than 10 iterations, refreshed on cloth
// 128 after nearly every exact solve of a buckling step, whose next
// update, of the definite matrix, then took 1 iteration: 8.9
// factorizations per step over the first 0.3 s.) A solve not converged
// after kCgHardLimit is redone at once with a fresh factor. At a nonlinear
// solve's first linear solve (start_nonlinear_solve) the kept factor, made
// in an earlier step, gets kCgSoftLimit products, and after it failed
// there the next steps start with a fresh factor: at 1/60 s a factor of
// the step before preconditions poorly (BM_LinearSolver/kept-factor-cg: 34
// products to 1e-2 on cloth 64, 444 on cloth 128), a new factorization
// costs less. How many: kFreshSteps after a probe that served, twice as
// many after each further failed one, up to kMaxFreshSteps (exponential
// backoff: where every probe fails, as for linear-implicit-euler
// --stiffness definite on cloth 64 at 1/60 s, a failed probe's 10
// products every 5 steps were two thirds of its CG work).
//
// Counts linear solves, their iterations and factorizations in the method's
// statistics.
#pragma once

#include <string>

#include "integrators/newton/newton_matrix.h"
#include "integrators/linear/preconditioned_cg.h"
#include "integrators/linear/preconditioned_minres.h"
#include "integrators/linear/sparse_direct_solver.h"

namespace springlab {

class NewtonLinearSolver {
 public:
  // Where a solve stops: CG's (or MINRES's) relative residual rtol, its
  // estimated error atol, and whether CG stops at negative curvature.
  struct Tolerance {
    double rtol = 0.0;
    double atol = 0.0;
    bool truncate = false;
  };
  struct Result {
    bool ok = true;
    bool negative_curvature = false;  // CG stopped at its first product
    bool converged = false;
  };

  // A new run: forget the symbolic analyses and the kept factorization;
  // count in `stats`.
  void reset(IntegratorStats& stats);
  // The matrix J of the next solves, for the caller to assemble (with
  // `definite`: whether it is the definite matrix; `symmetric`: whether J
  // is; `source`: where the definite matrix of the same point is, for a
  // fresh preconditioner). The pattern is the same from call to call.
  SparseMatrix& matrix(bool definite, bool symmetric, DefiniteMatrixSource& source);
  // Or J given by its products (source.product), not assembled: the
  // Krylov solves multiply by products, and J is assembled only where a
  // solve needs its matrix (a direct factorization of J; the preconditioner
  // is made from source.assemble_definite as ever). Where J reaches
  // further than the products do (a fluid's pressure Hessian), this saves
  // an assembly at every Newton iteration.
  void defer(bool definite, bool symmetric, DefiniteMatrixSource& source);
  // The next solve is a nonlinear solve's first (see above).
  void start_nonlinear_solve() { first_solve_ = true; }
  // d ~ J^-1 rhs. False `ok`, with `error`, when J (or the definite matrix)
  // is singular, its factor does not fit in memory, or d is not finite.
  Result solve(const Vector& rhs, const Tolerance& tolerance, Vector& d, std::string& error);
  // d = J^-1 rhs by one factorization of J, indefinite or not symmetric
  // (LDL^T, LU): linear-implicit-euler's exact stiffness.
  bool solve_directly(const Vector& rhs, Vector& d, std::string& error);
  bool out_of_memory() const { return direct_.out_of_memory() || preconditioner_.out_of_memory(); }

  static constexpr int kRefreshCost = 10;
  static constexpr int kCgSoftLimit = 10;
  static constexpr int kCgHardLimit = 30;
  static constexpr int kFreshSteps = 4;
  static constexpr int kMaxFreshSteps = 64;

 private:
  Result solve_with_limit(const Vector& rhs, const Tolerance& tolerance, Vector& d,
                          std::string& error, int max_iterations);
  Result solve_factored(MatrixKind kind, const Vector& rhs, Vector& d, std::string& error);
  // Makes the kept preconditioner the Cholesky factor of the definite
  // Newton matrix (jacobian_ itself when it is that matrix). False, with
  // `error`, when that matrix is singular.
  bool refresh_preconditioner(std::string& error);
  // The kept factor at a nonlinear solve's start.
  struct Start {
    bool probe = false;
    long factorizations = 0;
  };
  Start begin_first_solve();
  void end_first_solve(const Start& start);

  IntegratorStats* stats_ = nullptr;
  DefiniteMatrixSource* source_ = nullptr;
  bool definite_ = false;   // jacobian_ is the definite matrix
  bool deferred_ = false;   // J is given by the source's products (defer)
  bool assembled_ = true;   // jacobian_ holds J (false while deferred and not yet needed)
  // jacobian_, assembled first where it is deferred.
  const SparseMatrix& assembled_matrix();
  // matrix() and defer(): the next solves' J, assembled by the caller or not.
  void next_matrix(bool definite, bool symmetric, DefiniteMatrixSource& source, bool deferred);
  bool symmetric_ = false;  // jacobian_ is symmetric
  bool first_solve_ = false;
  SparseMatrix jacobian_, preconditioner_matrix_;
  SparseDirectSolver direct_;          // factorizations of jacobian_ itself
  SparseDirectSolver preconditioner_;  // the kept Cholesky factor
  // The pattern version each solver analysed (-1: none yet). A system whose
  // pattern varies (fluids) may hand a new one at any evaluation; a solver
  // given a matrix of another pattern forgets its analysis first. With one
  // pattern (springs, elements) these stay 0 after the first factorization.
  long direct_version_ = -1, preconditioner_version_ = -1;
  // factorize() of `solver` for the source's current pattern.
  bool factorize_on(SparseDirectSolver& solver, long& analysed, const SparseMatrix& a,
                    MatrixKind kind);
  bool preconditioner_valid_ = false;
  // Nonlinear solves left to start with a fresh factor.
  int fresh_steps_ = 0;
  // How many steps start with a fresh factor after the next failed probe.
  int fresh_run_ = 0;
  bool direct_current_ = false;  // direct_ holds a factorization of jacobian_ as it is
  int cg_slow_ = 0;              // the kept factor is to be refreshed before the next solve
  // The rent paid on the kept factor (see above): the iterations beyond a
  // fresh factor's summed since it was made, and its first exact solve's
  // count (-1: none yet).
  int rent_ = 0;
  int exact_iterations_ = -1;
  // Adds a solve of `iterations` with the kept factor to its rent.
  void pay_rent(int iterations);
  CgScratch cg_;
  MinresScratch minres_;
};

// A factor that does not fit in memory (issue 38.1): the solver's line and
// what to try; no other method, no second attempt (each needs as much).
std::string out_of_memory_text(const SparseDirectSolver& solver);

}  // namespace springlab
