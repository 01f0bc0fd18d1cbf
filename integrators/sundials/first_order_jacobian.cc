#include "integrators/sundials/first_order_jacobian.h"

#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>

#include "integrators/sundials/sundials_support.h"

namespace springlab::sundials {

FirstOrderJacobian::FirstOrderJacobian(const MechanicalSystem& system)
    : system_(system), n_(static_cast<long>(system.dofs())) {
  const SparseMatrix& p = system.jacobian_pattern();
  column_start_.reserve(static_cast<std::size_t>(2 * n_ + 1));
  column_start_.push_back(0);
  for (int block = 0; block < 2; ++block) {
    for (long c = 0; c < n_; ++c) {
      row_index_.push_back(c);  // x-block: the diagonal; v-block: the identity
      for (int k = p.outerIndexPtr()[c]; k < p.outerIndexPtr()[c + 1]; ++k) {
        row_index_.push_back(n_ + p.innerIndexPtr()[k]);
      }
      column_start_.push_back(static_cast<long>(row_index_.size()));
    }
  }
}

// entry(block, c, k) gives the value for the model-pattern entry k of column
// c (k = -1: the top-block entry at row c).
template <class Entry>
void FirstOrderJacobian::fill(SUNMatrix out, Entry entry) const {
  const SparseMatrix& p = system_.jacobian_pattern();
  if (SUNMatGetID(out) == SUNMATRIX_SPARSE) {
    if (SUNSparseMatrix_NNZ(out) < nonzeros()) {
      check(SUNSparseMatrix_Reallocate(out, nonzeros()), "SUNSparseMatrix_Reallocate");
    }
    sunindextype* colptr = SUNSparseMatrix_IndexPointers(out);
    sunindextype* rowval = SUNSparseMatrix_IndexValues(out);
    realtype* data = SUNSparseMatrix_Data(out);
    std::copy(column_start_.begin(), column_start_.end(), colptr);
    std::copy(row_index_.begin(), row_index_.end(), rowval);
    long slot = 0;
    for (int block = 0; block < 2; ++block) {
      for (long c = 0; c < n_; ++c) {
        data[slot++] = entry(block, c, -1);
        for (int k = p.outerIndexPtr()[c]; k < p.outerIndexPtr()[c + 1]; ++k) {
          data[slot++] = entry(block, c, k);
        }
      }
    }
    return;
  }
  SUNMatZero(out);
  for (int block = 0; block < 2; ++block) {
    for (long c = 0; c < n_; ++c) {
      realtype* column = SUNDenseMatrix_Column(out, block * n_ + c);
      column[c] = entry(block, c, -1);
      for (int k = p.outerIndexPtr()[c]; k < p.outerIndexPtr()[c + 1]; ++k) {
        column[n_ + p.innerIndexPtr()[k]] = entry(block, c, k);
      }
    }
  }
}

void FirstOrderJacobian::fill_ode(const SparseMatrix& dfdx, const SparseMatrix& dfdv,
                                  SUNMatrix out) const {
  const double* K = dfdx.valuePtr();
  const double* D = dfdv.valuePtr();
  const int* row = system_.jacobian_pattern().innerIndexPtr();
  const Vector& m = system_.mass();
  fill(out, [&](int block, long, int k) {
    if (k < 0) return block == 0 ? 0.0 : 1.0;
    return (block == 0 ? K[k] : D[k]) / m[row[k]];
  });
}

void FirstOrderJacobian::fill_dae(const SparseMatrix& dfdx, const SparseMatrix& dfdv, double cj,
                                  SUNMatrix out) const {
  const double* K = dfdx.valuePtr();
  const double* D = dfdv.valuePtr();
  const int* row = system_.jacobian_pattern().innerIndexPtr();
  const Vector& m = system_.mass();
  fill(out, [&](int block, long c, int k) {
    if (k < 0) return block == 0 ? cj : -1.0;
    if (block == 0) return -K[k];
    return (row[k] == c ? cj * m[c] : 0.0) - D[k];
  });
}

void FirstOrderJacobian::ode_times(const SparseMatrix& dfdx, const SparseMatrix& dfdv,
                                   const double* in, double* out) const {
  Eigen::Map<const Vector> in_x(in, n_), in_v(in + n_, n_);
  Eigen::Map<Vector> out_x(out, n_), out_v(out + n_, n_);
  out_x = in_v;
  out_v = (dfdx * in_x + dfdv * in_v).cwiseQuotient(system_.mass());
}

void FirstOrderJacobian::dae_times(const SparseMatrix& dfdx, const SparseMatrix& dfdv, double cj,
                                   const double* in, double* out) const {
  Eigen::Map<const Vector> in_x(in, n_), in_v(in + n_, n_);
  Eigen::Map<Vector> out_x(out, n_), out_v(out + n_, n_);
  out_x = cj * in_x - in_v;
  out_v = cj * system_.mass().cwiseProduct(in_v) - dfdx * in_x - dfdv * in_v;
}

}  // namespace springlab::sundials
