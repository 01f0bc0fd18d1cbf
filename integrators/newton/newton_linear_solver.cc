#include "integrators/newton/newton_linear_solver.h"

#include <algorithm>

namespace springlab {

std::string out_of_memory_text(const SparseDirectSolver& solver) {
  return solver.error() +
         ": use a coarser mesh, --solver quasi-newton (it factors a matrix of a third of the "
         "unknowns), or a method that factors none (rk4, xpbd, projective-dynamics)";
}

void NewtonLinearSolver::reset(IntegratorStats& stats) {
  stats_ = &stats;
  direct_.reset();
  preconditioner_.reset();
  preconditioner_valid_ = false;
  direct_current_ = false;
  fresh_steps_ = 0;
  fresh_run_ = kFreshSteps;
  cg_slow_ = 0;
  rent_ = 0;
  exact_iterations_ = -1;
  direct_version_ = preconditioner_version_ = -1;
  deferred_ = false;
  assembled_ = true;
  source_ = nullptr;
  jacobian_ = SparseMatrix();
  preconditioner_matrix_ = SparseMatrix();
}

void NewtonLinearSolver::next_matrix(bool definite, bool symmetric, DefiniteMatrixSource& source,
                                     bool deferred) {
  definite_ = definite;
  symmetric_ = symmetric;
  source_ = &source;
  direct_current_ = false;
  deferred_ = deferred;
  assembled_ = !deferred;
}

SparseMatrix& NewtonLinearSolver::matrix(bool definite, bool symmetric,
                                         DefiniteMatrixSource& source) {
  next_matrix(definite, symmetric, source, /*deferred=*/false);
  return jacobian_;
}

void NewtonLinearSolver::defer(bool definite, bool symmetric, DefiniteMatrixSource& source) {
  next_matrix(definite, symmetric, source, /*deferred=*/true);
}

const SparseMatrix& NewtonLinearSolver::assembled_matrix() {
  if (!assembled_) {
    source_->assemble_matrix(definite_, jacobian_);
    assembled_ = true;
  }
  return jacobian_;
}

bool NewtonLinearSolver::factorize_on(SparseDirectSolver& solver, long& analysed,
                                      const SparseMatrix& a, MatrixKind kind) {
  const long version = source_->pattern_version();
  if (analysed != version) {
    solver.reset();  // a new pattern: a new symbolic analysis
    analysed = version;
  }
  return solver.factorize(a, kind);
}

NewtonLinearSolver::Start NewtonLinearSolver::begin_first_solve() {
  Start start;
  start.probe = fresh_steps_ == 0 && cg_slow_ == 0 && preconditioner_valid_;
  if (fresh_steps_ > 0) {
    --fresh_steps_;
    cg_slow_ = 1;  // refresh before the first solve
  }
  start.factorizations = stats_->factorizations;
  return start;
}

void NewtonLinearSolver::end_first_solve(const Start& start) {
  // The kept factor failed at a step's start: fresh ones for the next steps.
  if (!start.probe) return;
  if (stats_->factorizations > start.factorizations) {
    fresh_steps_ = fresh_run_;
    fresh_run_ = std::min(2 * fresh_run_, kMaxFreshSteps);
  } else {
    fresh_run_ = kFreshSteps;  // it served: probe again soon after a failure
  }
}

NewtonLinearSolver::Result NewtonLinearSolver::solve(const Vector& rhs,
                                                     const Tolerance& tolerance, Vector& d,
                                                     std::string& error) {
  if (!first_solve_) return solve_with_limit(rhs, tolerance, d, error, kCgHardLimit);
  first_solve_ = false;
  const Start start = begin_first_solve();
  const Result result = solve_with_limit(rhs, tolerance, d, error, kCgSoftLimit);
  end_first_solve(start);
  return result;
}

bool NewtonLinearSolver::refresh_preconditioner(std::string& error) {
  const SparseMatrix* a = &jacobian_;
  preconditioner_valid_ = false;
  if (!definite_ || !assembled_) {
    source_->assemble_definite(preconditioner_matrix_);
    a = &preconditioner_matrix_;
  }
  ++stats_->factorizations;
  preconditioner_valid_ = factorize_on(preconditioner_, preconditioner_version_, *a,
                                       MatrixKind::kPositiveDefinite) &&
                          preconditioner_.positive_definite();
  cg_slow_ = 0;
  rent_ = 0;
  exact_iterations_ = -1;
  if (!preconditioner_valid_ && preconditioner_.out_of_memory()) {
    error = out_of_memory_text(preconditioner_);
  } else if (!preconditioner_valid_) {
    error = "the definite Newton matrix is not positive definite";
    if (!preconditioner_.error().empty()) error += " (" + preconditioner_.error() + ")";
  }
  return preconditioner_valid_;
}

NewtonLinearSolver::Result NewtonLinearSolver::solve_factored(MatrixKind kind, const Vector& rhs,
                                                              Vector& d, std::string& error) {
  Result out;
  // The same matrix as the last direct solve's (a second right-hand side).
  if (!(direct_current_ && direct_.has_factor())) {
    ++stats_->factorizations;
    direct_current_ = true;
    if (!factorize_on(direct_, direct_version_, assembled_matrix(), kind)) {
      direct_current_ = false;
      error = direct_.out_of_memory()
                  ? out_of_memory_text(direct_)
                  : "the Newton matrix is singular (" + direct_.error() + ")";
      out.ok = false;
      return out;
    }
  }
  out.ok = direct_.solve(rhs, d);
  out.converged = true;
  if (!out.ok) error = "the linear solve gave a non-finite update";
  return out;
}

NewtonLinearSolver::Result NewtonLinearSolver::solve_with_limit(const Vector& rhs,
                                                                const Tolerance& tolerance,
                                                                Vector& d, std::string& error,
                                                                int max_iterations) {
  ++stats_->linear_solves;
  // Spring damping makes the Jacobian non-symmetric: no CG, LU.
  if (!symmetric_) {
    return solve_factored(MatrixKind::kGeneral, rhs, d, error);
  }
  auto no_preconditioner = [&] {
    if (preconditioner_.out_of_memory()) return Result{.ok = false};
    // No positive definite matrix to precondition with (a negative mass,
    // say, cannot happen; round-off in a nearly singular one can).
    return solve_factored(MatrixKind::kSymmetric, rhs, d, error);
  };
  if ((!preconditioner_valid_ || cg_slow_ > 0) && !refresh_preconditioner(error)) {
    return no_preconditioner();
  }
  // CG where the matrix is positive definite or truncation is wanted (Newton
  // on a potential); MINRES where a true solve of an indefinite one is.
  const bool minres = !definite_ && !tolerance.truncate;
  // J by its products where it is deferred (not assembled), else the matrix.
  const LinearProduct product = [this](const Vector& p, Vector& q) {
    if (deferred_ && !assembled_) {
      source_->product(definite_, p, q);
    } else {
      q.noalias() = jacobian_ * p;
    }
  };
  auto krylov = [&](int limit) {
    CgResult k = minres ? preconditioned_minres(product, preconditioner_, rhs, tolerance.rtol,
                                                limit, d, minres_)
                        : preconditioned_cg(product, preconditioner_, rhs, tolerance.rtol,
                                            tolerance.atol, limit, d, cg_);
    stats_->linear_iterations += k.iterations;
    return k;
  };
  CgResult cg = krylov(max_iterations);
  if (cg.finite && !cg.converged && !cg.negative_curvature) {
    // The kept factor is too far from this matrix: a fresh one, at once.
    if (!refresh_preconditioner(error)) return no_preconditioner();
    cg = krylov(std::max(max_iterations, kCgHardLimit));
  }
  pay_rent(cg.iterations);
  if (!cg.finite) {
    error = "the linear solve gave a non-finite update";
    return Result{.ok = false};
  }
  if (cg.converged || (tolerance.truncate && cg.negative_curvature)) {
    return Result{.negative_curvature = cg.negative_curvature && cg.iterations == 1,
                  .converged = cg.converged};
  }
  // Indefinite (or still not converged) and a true solve is wanted.
  return solve_factored(definite_ ? MatrixKind::kPositiveDefinite : MatrixKind::kSymmetric, rhs,
                        d, error);
}

void NewtonLinearSolver::pay_rent(int iterations) {
  // What a fresh factor would have needed (header): 1 for the definite
  // matrix, the factor's first exact solve's count for the exact one.
  int fresh = 1;
  if (!definite_) {
    if (exact_iterations_ < 0) exact_iterations_ = iterations;
    fresh = exact_iterations_;
  }
  rent_ += std::max(0, iterations - fresh);
  cg_slow_ = rent_ > kRefreshCost ? 1 : 0;
}

bool NewtonLinearSolver::solve_directly(const Vector& rhs, Vector& d, std::string& error) {
  // The exact stiffness: the matrix may be indefinite (compressed springs),
  // so LDL^T (LU without symmetry); MINRES with the definite factor needs
  // tens of products on cloth 64.
  ++stats_->linear_solves;
  ++stats_->factorizations;
  direct_current_ = false;
  const MatrixKind kind =
      symmetric_ ? MatrixKind::kSymmetric : MatrixKind::kGeneral;
  if (!factorize_on(direct_, direct_version_, assembled_matrix(), kind)) {
    error = direct_.out_of_memory() ? out_of_memory_text(direct_)
                                    : "the step's matrix is singular (" + direct_.error() + ")";
    return false;
  }
  if (!direct_.solve(rhs, d)) {
    error = "the linear solve gave a non-finite update";
    return false;
  }
  return true;
}

}  // namespace springlab
