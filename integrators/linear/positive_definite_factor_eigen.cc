// PositiveDefiniteFactor by Eigen's SimplicialLLT: the WebAssembly build's
// (positive_definite_factor.h), which has no CHOLMOD and no BLAS. The same
// factor LL^T of P A P^T, P from the same minimum-degree ordering (AMD),
// computed column by column (left-looking, no supernodes): the same
// solution up to rounding, the order of the operations being another.
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <limits>

#include "integrators/linear/positive_definite_factor.h"

namespace springlab {
namespace {

// SimplicialLLT, which knows nnz(L) after its symbolic analysis (the
// column counts of the elimination tree) but does not say it.
class Llt : public Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>> {
 public:
  double nonzeros() const { return static_cast<double>(this->m_matrix.nonZeros()); }
};

}  // namespace

struct PositiveDefiniteFactor::Impl {
  Llt llt;
  bool analyzed = false;
  Eigen::MatrixXd solution;
};

FactorEstimate estimate_factor(const SparseMatrix& a) {
  FactorEstimate estimate;
  estimate.nonzeros = estimate.bytes = std::numeric_limits<double>::infinity();
  if (!a.isCompressed()) return estimate;
  Llt symbolic;
  symbolic.analyzePattern(a);
  estimate.nonzeros = symbolic.nonzeros();
  estimate.bytes = kFactorBytesPerNonzero * estimate.nonzeros;
  return estimate;
}

PositiveDefiniteFactor::PositiveDefiniteFactor(FactorUse /*use: one layout here*/)
    : impl_(std::make_unique<Impl>()) {}

PositiveDefiniteFactor::~PositiveDefiniteFactor() = default;

void PositiveDefiniteFactor::reset() { impl_->analyzed = false; }

bool PositiveDefiniteFactor::uses_blas() const { return false; }

double PositiveDefiniteFactor::nonzeros() const { return impl_->llt.nonzeros(); }
double PositiveDefiniteFactor::flops() const { return 0.0; }

PositiveDefiniteFactor::Status PositiveDefiniteFactor::factorize(const SparseMatrix& a) {
  if (!impl_->analyzed) {
    impl_->llt.analyzePattern(a);
    impl_->analyzed = true;
  }
  impl_->llt.factorize(a);
  // NumericalIssue: a pivot that is not positive.
  return impl_->llt.info() == Eigen::Success ? Status::kOk : Status::kNotPositiveDefinite;
}

const double* PositiveDefiniteFactor::solve(const double* b, Eigen::Index rows,
                                            Eigen::Index cols) {
  impl_->solution = impl_->llt.solve(Eigen::Map<const Eigen::MatrixXd>(b, rows, cols));
  if (impl_->llt.info() != Eigen::Success) return nullptr;
  return impl_->solution.data();
}

}  // namespace springlab
