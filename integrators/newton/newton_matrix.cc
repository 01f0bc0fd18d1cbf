#include "integrators/newton/newton_matrix.h"

#include "models/core/sparse_pattern.h"

namespace springlab {

void NewtonMatrix::assemble(bool definite, SparseMatrix& out) {
  const CountedModel& model = *model_;
  const Point& p = point_;
  // No force depends on v: dF/dv = 0 is neither assembled nor stored (on
  // cloth n = 128, 23 MB of values and indices).
  SparseMatrix* dfdv =
      model.system().velocity_dependence() == VelocityDependence::kNone ? nullptr : &dfdv_;
  if (definite) {
    model.definite_jacobians(p.t, *p.x, *p.v, &dfdx_, dfdv);
  } else {
    model.jacobians(p.t, *p.x, *p.v, &dfdx_, dfdv);
  }
  // All three share the model's pattern: combine value by value. (Where the
  // pattern varies, as a fluid's does, an equal count does not mean an
  // equal pattern: the indices are compared, cheaper than a copy.)
  if (model.system().pattern_varies() ? !same_pattern(out, dfdx_)
                                      : out.nonZeros() != dfdx_.nonZeros()) {
    out = dfdx_;
  }
  const Eigen::Index nnz = dfdx_.nonZeros();
  const double* px = dfdx_.valuePtr();
  double* pj = out.valuePtr();
  const double cx = -p.h * p.h * p.b, cv = -p.h * p.c;
  if (dfdv != nullptr) {
    const double* pv = dfdv_.valuePtr();
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k] + cv * pv[k];
  } else {
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k];
  }
  if (p.term != nullptr) p.term->add(p.t, *p.x, definite, cx, out);
  out.diagonal() += model.system().mass();
}

}  // namespace springlab
