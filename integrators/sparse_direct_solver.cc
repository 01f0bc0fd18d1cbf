#include "integrators/sparse_direct_solver.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>
#include <new>
#include <sstream>

// OpenBLAS's own entry point (libopenblas); CHOLMOD reaches OpenBLAS through
// the BLAS interface, which has no thread setting.
extern "C" void openblas_set_num_threads(int threads);

namespace springlab {
namespace {

// One BLAS thread unless SPRINGLAB_BLAS_THREADS says otherwise (header).
void set_blas_threads_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    int threads = 1;
    if (const char* text = std::getenv("SPRINGLAB_BLAS_THREADS")) {
      const int requested = std::atoi(text);
      if (requested >= 1) threads = requested;
    }
    openblas_set_num_threads(threads);
    // Debian's CHOLMOD runs loops of its supernodal factorization in OpenMP
    // parallel regions with a fixed num_threads(4) clause, which neither
    // OMP_NUM_THREADS nor a BLAS setting overrides. On 2 cores their threads
    // wake and wait once per supernode: on cloth 48 at 1/60 the run took
    // 3.6 s wall (0.7 s of it in the kernel, 165,000 context switches) where
    // one thread takes 2.1 s (0.05 s, 150). With one BLAS thread, CHOLMOD's
    // regions are made inactive too (max-active-levels 0: every region runs
    // on the calling thread). libgomp is loaded by CHOLMOD; looked up at run
    // time, so springlab does not link OpenMP itself.
    if (threads == 1) {
      using SetLevels = void (*)(int);
      if (auto set_levels = reinterpret_cast<SetLevels>(
              dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))) {
        set_levels(0);
      }
    }
  });
}

}  // namespace

struct SparseDirectSolver::Cholmod {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  cholmod_dense* x = nullptr;  // solve2's result and workspaces, reused
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;

  explicit Cholmod(FactorUse use) {
    cholmod_start(&common);
    if (use == FactorUse::kSolvedOften) {
      common.supernodal = CHOLMOD_SIMPLICIAL;
      common.final_ll = 1;  // LL^T, not CHOLMOD's default simplicial LDL^T
    } else {
      common.supernodal = CHOLMOD_SUPERNODAL;
    }
    // One ordering, AMD: on these meshes it fills L about as little as
    // METIS's nested dissection (cloth 64: 1.77 M vs 1.91 M nonzeros) and
    // its analysis costs a fraction of METIS's; tried alone, not the
    // default's "AMD, then METIS if AMD fills much".
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_AMD;
    common.postorder = 1;
    // Report through status, not on the terminal.
    common.print = 0;
    common.error_handler = nullptr;
  }
  ~Cholmod() {
    free_factor();
    cholmod_finish(&common);
  }
  void free_factor() {
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    for (cholmod_dense** d : {&x, &y, &e}) {
      if (*d != nullptr) cholmod_free_dense(d, &common);
    }
  }
};

namespace {

// A CHOLMOD view of a compressed column-major Eigen matrix that stores both
// triangles: CHOLMOD reads the lower one (stype = -1) and copies nothing.
cholmod_sparse view_lower(const SparseMatrix& a) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(a.rows());
  view.ncol = static_cast<size_t>(a.cols());
  view.nzmax = static_cast<size_t>(a.nonZeros());
  view.p = const_cast<int*>(a.outerIndexPtr());
  view.i = const_cast<int*>(a.innerIndexPtr());
  view.x = const_cast<double*>(a.valuePtr());
  view.stype = -1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  return view;
}

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

bool cholmod_memory_status(int status) {
  return status == CHOLMOD_OUT_OF_MEMORY || status == CHOLMOD_TOO_LARGE;
}

}  // namespace

FactorEstimate estimate_factor(const SparseMatrix& a) {
  FactorEstimate estimate;
  estimate.nonzeros = estimate.bytes = std::numeric_limits<double>::infinity();
  if (!a.isCompressed()) return estimate;
  // A simplicial symbolic analysis: the ordering and column counts only
  // (O(n) for the factor object), with the solvers' own ordering (AMD).
  cholmod_common c;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SIMPLICIAL;
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  c.print = 0;
  c.error_handler = nullptr;
  cholmod_sparse view = view_lower(a);
  cholmod_factor* symbolic = cholmod_analyze(&view, &c);
  if (symbolic != nullptr) {
    estimate.nonzeros = c.lnz;
    estimate.bytes = kFactorBytesPerNonzero * c.lnz;
    cholmod_free_factor(&symbolic, &c);
  }
  cholmod_finish(&c);
  return estimate;
}

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

SparseDirectSolver::SparseDirectSolver(FactorUse use) : cholmod_(std::make_unique<Cholmod>(use)) {
  set_blas_threads_once();
}

SparseDirectSolver::~SparseDirectSolver() = default;

void SparseDirectSolver::reset() {
  cholmod_->free_factor();
  ldlt_analyzed_ = lu_analyzed_ = fit_checked_ = false;
  out_of_memory_ = false;
  method_ = Method::kNone;
  factor_nonzeros_ = factor_flops_ = 0.0;
}

bool SparseDirectSolver::fits(const SparseMatrix& a) {
  if (fit_checked_) return true;
  const double limit = memory_limit_ < 0.0 ? memory_limit_bytes() : memory_limit_;
  const bool blas = cholmod_->common.supernodal == CHOLMOD_SUPERNODAL;
  std::string why = factor_fit_error(a, limit, blas ? kBlasBufferBytes : 0.0);
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
    cholmod_->free_factor();
    ldlt_analyzed_ = lu_analyzed_ = false;
    return fail_out_of_memory(a, "the factorization");
  }
}

bool SparseDirectSolver::factorize_cholesky(const SparseMatrix& a) {
  method_ = Method::kNone;
  if (!a.isCompressed()) return false;
  cholmod_sparse view = view_lower(a);
  cholmod_common& c = cholmod_->common;
  if (cholmod_->factor == nullptr) {
    cholmod_->factor = cholmod_analyze(&view, &c);
    if (cholmod_->factor == nullptr) {
      if (cholmod_memory_status(c.status)) return fail_out_of_memory(a, "CHOLMOD's analysis");
      return false;  // LDL^T
    }
  }
  // LL^T: ok only when every pivot is positive (status CHOLMOD_OK);
  // CHOLMOD_NOT_POSDEF leaves the factor incomplete.
  if (!cholmod_factorize(&view, cholmod_->factor, &c) || c.status != CHOLMOD_OK) {
    if (cholmod_memory_status(c.status)) {
      // Its partial factor is of no use; free it for what comes next.
      cholmod_->free_factor();
      return fail_out_of_memory(a, "CHOLMOD's factorization");
    }
    return false;
  }
  method_ = Method::kCholesky;
  factor_nonzeros_ = c.lnz;
  factor_flops_ = c.fl;
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
      cholmod_common& c = cholmod_->common;
      cholmod_dense rhs{};
      rhs.nrow = static_cast<size_t>(b.size());
      rhs.ncol = 1;
      rhs.nzmax = rhs.nrow;
      rhs.d = rhs.nrow;
      rhs.x = const_cast<double*>(b.data());
      rhs.xtype = CHOLMOD_REAL;
      rhs.dtype = CHOLMOD_DOUBLE;
      if (!cholmod_solve2(CHOLMOD_A, cholmod_->factor, &rhs, nullptr, &cholmod_->x, nullptr,
                          &cholmod_->y, &cholmod_->e, &c)) {
        return false;
      }
      x = Eigen::Map<const Vector>(static_cast<const double*>(cholmod_->x->x), b.size());
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
      cholmod_common& c = cholmod_->common;
      cholmod_dense rhs{};
      rhs.nrow = static_cast<size_t>(B.rows());
      rhs.ncol = static_cast<size_t>(B.cols());
      rhs.nzmax = rhs.nrow * rhs.ncol;
      rhs.d = rhs.nrow;
      rhs.x = const_cast<double*>(B.data());
      rhs.xtype = CHOLMOD_REAL;
      rhs.dtype = CHOLMOD_DOUBLE;
      if (!cholmod_solve2(CHOLMOD_A, cholmod_->factor, &rhs, nullptr, &cholmod_->x, nullptr,
                          &cholmod_->y, &cholmod_->e, &c)) {
        return false;
      }
      X = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(cholmod_->x->x), B.rows(),
                                            B.cols());
      break;
    }
    case Method::kLdlt: X = ldlt_.solve(B); break;
    case Method::kLu: X = lu_.solve(B); break;
    case Method::kNone: return false;
  }
  return X.allFinite();
}

}  // namespace springlab
