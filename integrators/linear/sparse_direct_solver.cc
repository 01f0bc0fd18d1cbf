#include "integrators/linear/sparse_direct_solver.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>

#include "integrators/linear/positive_definite_factor.h"

namespace springlab {
namespace {

std::string dimensions(const SparseMatrix& a) {
  return std::to_string(a.rows()) + " x " + std::to_string(a.cols());
}

std::string short_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", value);
  std::string out = text;  // "1.1e+08" -> "1.1e8"
  if (const auto e = out.find("e+"); e != std::string::npos) {
    out.erase(e + 1, 1);
    while (out.size() > e + 2 && out[e + 1] == '0') out.erase(e + 1, 1);
  }
  return out;
}

}  // namespace

double memory_limit_bytes() {
  double limit = std::numeric_limits<double>::infinity();
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_size > 0) limit = static_cast<double>(pages) * static_cast<double>(page_size);
  rlimit address_space{};
  if (getrlimit(RLIMIT_AS, &address_space) == 0 && address_space.rlim_cur != RLIM_INFINITY) {
    // The address space already mapped (VmSize, statm's first field, in pages).
    double mapped = 0.0;
    std::ifstream statm("/proc/self/statm");
    double mapped_pages = 0.0;
    if (statm >> mapped_pages && page_size > 0) mapped = mapped_pages * static_cast<double>(page_size);
    limit = std::min(limit, std::max(0.0, static_cast<double>(address_space.rlim_cur) - mapped));
  }
  return limit;
}

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) return "an unknown amount of memory";
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB"};
  int unit = 0;
  while (bytes >= 999.5 && unit < 4) {
    bytes /= 1000.0;
    ++unit;
  }
  // Three significant digits: "273 MB", "1.71 GB".
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", bytes);
  return std::string(text) + " " + units[unit];
}

std::string factor_fit_error(const SparseMatrix& a, double limit, double extra) {
  const FactorEstimate estimate = estimate_factor(a);
  const std::string matrix = "the " + dimensions(a) + " matrix";
  if (!std::isfinite(estimate.nonzeros)) {
    return "the symbolic analysis of " + matrix + " ran out of memory (limit " +
           format_bytes(limit) + ")";
  }
  // Eigen's LDL^T and CHOLMOD's supernodal factor index L with ints.
  if (estimate.nonzeros >= static_cast<double>(INT_MAX)) {
    return "the factor of " + matrix + " would have " + short_number(estimate.nonzeros) +
           " nonzeros (about " + format_bytes(estimate.bytes) +
           "), more than 32-bit indices address (2.1e9)";
  }
  if (estimate.bytes + extra > limit) {
    return "the factor of " + matrix + " needs about " + format_bytes(estimate.bytes + extra) +
           " (" + short_number(estimate.nonzeros) + " nonzeros x " +
           short_number(kFactorBytesPerNonzero) + " bytes" +
           (extra > 0.0 ? " + " + format_bytes(extra) + " for BLAS" : std::string()) +
           "), over the " + format_bytes(limit) + " this process may allocate";
  }
  return {};
}

SparseDirectSolver::SparseDirectSolver(FactorUse use)
    : cholesky_(std::make_unique<PositiveDefiniteFactor>(use)) {}

SparseDirectSolver::~SparseDirectSolver() = default;

void SparseDirectSolver::reset() {
  cholesky_->reset();
  ldlt_analyzed_ = lu_analyzed_ = fit_checked_ = false;
  out_of_memory_ = false;
  method_ = Method::kNone;
  factor_nonzeros_ = factor_flops_ = 0.0;
}

bool SparseDirectSolver::fits(const SparseMatrix& a) {
  if (fit_checked_) return true;
  const double limit = memory_limit_ < 0.0 ? memory_limit_bytes() : memory_limit_;
  // A dense factor, the most any ordering can fill, fits: no estimate
  // needed (it is a symbolic analysis of its own, as costly as the
  // factorization's: a fluid's pattern, rebuilt as it flows, paid it at
  // every new pattern).
  const double n = static_cast<double>(a.rows());
  if (0.5 * n * (n + 1.0) * kFactorBytesPerNonzero +
          (cholesky_->uses_blas() ? kBlasBufferBytes : 0.0) <= limit) {
    fit_checked_ = true;
    return true;
  }
  std::string why = factor_fit_error(a, limit, cholesky_->uses_blas() ? kBlasBufferBytes : 0.0);
  if (!why.empty()) {
    out_of_memory_ = true;
    error_ = "out of memory: " + why;
    return false;
  }
  fit_checked_ = true;  // once per pattern (reset() forgets it)
  return true;
}

bool SparseDirectSolver::fail_out_of_memory(const SparseMatrix& a, const std::string& where) {
  method_ = Method::kNone;
  out_of_memory_ = true;
  error_ = "out of memory in " + where + " of the " + dimensions(a) + " matrix (limit " +
           format_bytes(memory_limit_ < 0.0 ? memory_limit_bytes() : memory_limit_) + ")";
  return false;
}

bool SparseDirectSolver::factorize(const SparseMatrix& a, MatrixKind kind) {
  error_.clear();
  out_of_memory_ = false;
  factor_flops_ = 0.0;
  if (!fits(a)) return false;
  // An allocation that fails ends the attempt: no other method, which
  // would need as much memory again.
  try {
    if (kind == MatrixKind::kPositiveDefinite && factorize_cholesky(a)) return true;
    if (out_of_memory_) return false;
    if (kind != MatrixKind::kGeneral && factorize_ldlt(a)) return true;
    if (out_of_memory_) return false;
    return factorize_lu(a);
  } catch (const std::bad_alloc&) {
    // CHOLMOD's factor goes; the next attempt analyzes the pattern again
    // (Eigen's solvers resize their storage in their analysis).
    cholesky_->reset();
    ldlt_analyzed_ = lu_analyzed_ = false;
    return fail_out_of_memory(a, "the factorization");
  }
}

bool SparseDirectSolver::factorize_cholesky(const SparseMatrix& a) {
  method_ = Method::kNone;
  if (!a.isCompressed()) return false;
  switch (cholesky_->factorize(a)) {
    case PositiveDefiniteFactor::Status::kOk: break;
    case PositiveDefiniteFactor::Status::kNotPositiveDefinite: return false;  // LDL^T
    case PositiveDefiniteFactor::Status::kOutOfMemory:
      return fail_out_of_memory(a, cholesky_->failed_step());
  }
  method_ = Method::kCholesky;
  factor_nonzeros_ = cholesky_->nonzeros();
  factor_flops_ = cholesky_->flops();
  return true;
}

bool SparseDirectSolver::factorize_ldlt(const SparseMatrix& a) {
  method_ = Method::kNone;
  if (!ldlt_analyzed_) {
    ldlt_.analyzePattern(a);
    ldlt_analyzed_ = true;
  }
  ldlt_.factorize(a);
  if (ldlt_.info() != Eigen::Success) return false;
  method_ = Method::kLdlt;
  factor_nonzeros_ = static_cast<double>(ldlt_.matrixL().nestedExpression().nonZeros());
  return true;
}

bool SparseDirectSolver::factorize_lu(const SparseMatrix& a) {
  method_ = Method::kNone;
  if (!lu_analyzed_) {
    lu_.analyzePattern(a);
    lu_analyzed_ = true;
  }
  lu_.factorize(a);
  if (lu_.info() != Eigen::Success &&
      lu_.lastErrorMessage().find("MEMORY") != std::string::npos) {
    return fail_out_of_memory(a, "the sparse LU factorization");
  }
  if (lu_.info() != Eigen::Success) {
    error_ = "sparse LU factorization failed: " + lu_.lastErrorMessage();
    return false;
  }
  method_ = Method::kLu;
  factor_nonzeros_ = 0.0;
  return true;
}

bool SparseDirectSolver::solve(const Vector& b, Vector& x) {
  switch (method_) {
    case Method::kCholesky: {
      const double* solution = cholesky_->solve(b.data(), b.size(), 1);
      if (solution == nullptr) return false;
      x = Eigen::Map<const Vector>(solution, b.size());
      break;
    }
    case Method::kLdlt: x = ldlt_.solve(b); break;
    case Method::kLu: x = lu_.solve(b); break;
    case Method::kNone: return false;
  }
  return x.allFinite();
}

bool SparseDirectSolver::solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) {
  switch (method_) {
    case Method::kCholesky: {
      const double* solution = cholesky_->solve(B.data(), B.rows(), B.cols());
      if (solution == nullptr) return false;
      X = Eigen::Map<const Eigen::MatrixXd>(solution, B.rows(), B.cols());
      break;
    }
    case Method::kLdlt: X = ldlt_.solve(B); break;
    case Method::kLu: X = lu_.solve(B); break;
    case Method::kNone: return false;
  }
  return X.allFinite();
}

}  // namespace springlab
