// Whether two sparse matrices have the same pattern: dimensions, column
// starts and row indices (compressed). Where a model's pattern varies (a
// fluid's, mechanical_system.h), a matrix kept between evaluations is
// reshaped only when its pattern differs: reading the indices costs less
// than copying them with the values.
#pragma once

#include <algorithm>

#include "models/core/mechanical_system.h"

namespace springlab {

inline bool same_pattern(const SparseMatrix& a, const SparseMatrix& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros() ||
      !a.isCompressed() || !b.isCompressed()) {
    return false;
  }
  const Eigen::Index columns = a.cols() + 1;
  return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + columns, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

}  // namespace springlab
