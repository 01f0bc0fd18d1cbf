#include "web/cursor_spring.h"


namespace springlab {

CursorSpring::CursorSpring(const Model& model, double w_max)
    : model_(model), dim_(model.dimension()) {
  // The lightest free particle's mass: the stiffest the spring gets.
  double m = model.mass().size() > 0 ? model.mass().minCoeff() : 1.0;
  k_ = w_max > 0.0 ? m * w_max * w_max / 4.0 : 100.0 * m;
}

bool CursorSpring::grab(int particle, const Eigen::Vector3d& cursor) {
  const ParticleOrder& order = model_.particle_order();
  if (particle < 0 || particle >= static_cast<int>(order.internal_of_scene.size())) return false;
  const int p = order.internal_of_scene[static_cast<std::size_t>(particle)];
  if (p < 0 || p >= order.free_particles) return false;
  unknown_ = p * dim_;
  cursor_ = cursor;
  return true;
}

void CursorSpring::add_force(const Vector& x, Vector& f) const {
  if (unknown_ < 0) return;
  for (int r = 0; r < dim_; ++r) f[unknown_ + r] -= k_ * (x[unknown_ + r] - cursor_[r]);
}

void CursorSpring::add_stiffness(SparseMatrix* dfdx) const {
  if (unknown_ < 0 || dfdx == nullptr) return;
  for (int r = 0; r < dim_; ++r) dfdx->coeffRef(unknown_ + r, unknown_ + r) -= k_;
}

void CursorSpring::force(ForcePart part, double t, const Vector& x, const Vector& v,
                         Vector& f) const {
  model_.force(part, t, x, v, f);
  if (part != ForcePart::kNonstiff) add_force(x, f);  // a stiff spring
}

void CursorSpring::jacobians(ForcePart part, double t, const Vector& x, const Vector& v,
                             SparseMatrix* dfdx, SparseMatrix* dfdv) const {
  model_.jacobians(part, t, x, v, dfdx, dfdv);
  if (part != ForcePart::kNonstiff) add_stiffness(dfdx);
}

void CursorSpring::definite_jacobians(double t, const Vector& x, const Vector& v,
                                      SparseMatrix* dfdx, SparseMatrix* dfdv) const {
  model_.definite_jacobians(t, x, v, dfdx, dfdv);
  add_stiffness(dfdx);  // -k_c I: negative definite already
}

double CursorSpring::position_potential(double t, const Vector& x) const {
  double v = model_.position_potential(t, x);
  if (unknown_ >= 0) {
    double d2 = 0.0;
    for (int r = 0; r < dim_; ++r) {
      const double d = x[unknown_ + r] - cursor_[r];
      d2 += d * d;
    }
    v += 0.5 * k_ * d2;
  }
  return v;
}

void CursorSpring::external_force(double t, const Vector& x, const Vector& v, Vector& f) const {
  model_.external_force(t, x, v, f);
  add_force(x, f);
}

}  // namespace springlab
