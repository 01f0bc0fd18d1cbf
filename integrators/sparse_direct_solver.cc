#include "integrators/sparse_direct_solver.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <cstdlib>
#include <mutex>

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

}  // namespace

SparseDirectSolver::SparseDirectSolver(FactorUse use) : cholmod_(std::make_unique<Cholmod>(use)) {
  set_blas_threads_once();
}

SparseDirectSolver::~SparseDirectSolver() = default;

void SparseDirectSolver::reset() {
  cholmod_->free_factor();
  ldlt_analyzed_ = lu_analyzed_ = false;
  method_ = Method::kNone;
  factor_nonzeros_ = factor_flops_ = 0.0;
}

bool SparseDirectSolver::factorize(const SparseMatrix& a, MatrixKind kind) {
  error_.clear();
  factor_flops_ = 0.0;
  if (kind == MatrixKind::kPositiveDefinite && factorize_cholesky(a)) return true;
  if (kind != MatrixKind::kGeneral && factorize_ldlt(a)) return true;
  return factorize_lu(a);
}

bool SparseDirectSolver::factorize_cholesky(const SparseMatrix& a) {
  method_ = Method::kNone;
  if (!a.isCompressed()) return false;
  cholmod_sparse view = view_lower(a);
  cholmod_common& c = cholmod_->common;
  if (cholmod_->factor == nullptr) {
    cholmod_->factor = cholmod_analyze(&view, &c);
    if (cholmod_->factor == nullptr) return false;  // out of memory or too large: LDL^T
  }
  // LL^T: ok only when every pivot is positive (status CHOLMOD_OK);
  // CHOLMOD_NOT_POSDEF leaves the factor incomplete.
  if (!cholmod_factorize(&view, cholmod_->factor, &c) || c.status != CHOLMOD_OK) return false;
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
