// PositiveDefiniteFactor by CHOLMOD (SuiteSparse): the native build's
// (positive_definite_factor.h). BLAS threads and CHOLMOD's layout by
// FactorUse: sparse_direct_solver.h.
#include <cholmod.h>
#include <dlfcn.h>

#include <cstdlib>
#include <limits>
#include <mutex>

#include "integrators/linear/positive_definite_factor.h"

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

bool cholmod_memory_status(int status) {
  return status == CHOLMOD_OUT_OF_MEMORY || status == CHOLMOD_TOO_LARGE;
}

}  // namespace

struct PositiveDefiniteFactor::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  cholmod_dense* x = nullptr;  // solve2's result and workspaces, reused
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;

  explicit Impl(FactorUse use) {
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
  ~Impl() {
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

PositiveDefiniteFactor::PositiveDefiniteFactor(FactorUse use) : impl_(std::make_unique<Impl>(use)) {
  set_blas_threads_once();
}

PositiveDefiniteFactor::~PositiveDefiniteFactor() = default;

void PositiveDefiniteFactor::reset() { impl_->free_factor(); }

bool PositiveDefiniteFactor::uses_blas() const {
  return impl_->common.supernodal == CHOLMOD_SUPERNODAL;
}

double PositiveDefiniteFactor::nonzeros() const { return impl_->common.lnz; }
double PositiveDefiniteFactor::flops() const { return impl_->common.fl; }

PositiveDefiniteFactor::Status PositiveDefiniteFactor::factorize(const SparseMatrix& a) {
  cholmod_sparse view = view_lower(a);
  cholmod_common& c = impl_->common;
  if (impl_->factor == nullptr) {
    impl_->factor = cholmod_analyze(&view, &c);
    if (impl_->factor == nullptr) {
      if (cholmod_memory_status(c.status)) {
        failed_step_ = "CHOLMOD's analysis";
        return Status::kOutOfMemory;
      }
      return Status::kNotPositiveDefinite;  // the caller tries LDL^T
    }
  }
  // LL^T: ok only when every pivot is positive (status CHOLMOD_OK);
  // CHOLMOD_NOT_POSDEF leaves the factor incomplete.
  if (!cholmod_factorize(&view, impl_->factor, &c) || c.status != CHOLMOD_OK) {
    if (cholmod_memory_status(c.status)) {
      // Its partial factor is of no use; free it for what comes next.
      impl_->free_factor();
      failed_step_ = "CHOLMOD's factorization";
      return Status::kOutOfMemory;
    }
    return Status::kNotPositiveDefinite;
  }
  return Status::kOk;
}

const double* PositiveDefiniteFactor::solve(const double* b, Eigen::Index rows,
                                            Eigen::Index cols) {
  cholmod_dense rhs{};
  rhs.nrow = static_cast<size_t>(rows);
  rhs.ncol = static_cast<size_t>(cols);
  rhs.nzmax = rhs.nrow * rhs.ncol;
  rhs.d = rhs.nrow;
  rhs.x = const_cast<double*>(b);
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr, &impl_->y,
                      &impl_->e, &impl_->common)) {
    return nullptr;
  }
  return static_cast<const double*>(impl_->x->x);
}

}  // namespace springlab
