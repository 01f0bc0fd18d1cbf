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

bool NewtonMatrix::has_products() const {
  return point_.term == nullptr && model_->system().has_jacobian_products();
}

void NewtonMatrix::product(bool definite, const Vector& p, Vector& y) {
  const MechanicalSystem& system = model_->system();
  const Point& q = point_;
  const bool velocity = system.velocity_dependence() != VelocityDependence::kNone;
  system.jacobian_products(definite, q.t, *q.x, *q.v, p, &dfdx_p_, velocity ? &dfdv_p_ : nullptr);
  // J p = M p - h^2 b dF/dx p - h c dF/dv p.
  y = system.mass().cwiseProduct(p) - (q.h * q.h * q.b) * dfdx_p_;
  if (velocity) y -= (q.h * q.c) * dfdv_p_;
}

}  // namespace springlab
