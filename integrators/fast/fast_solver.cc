#include "integrators/fast/fast_solver.h"

#include <algorithm>

namespace springlab {

StepResult FastSolver::do_initialize() {
  views_ = system().fast_solver_views();
  dim_ = views_ != nullptr ? views_->dimension_of_state() : 0;
  Refusal why{"this system has no projective form; use implicit-euler", {}};
  position_projections_.clear();
  const bool has_form =
      dim_ >= 1 &&
      (takes_projections_
           ? views_->position_based_form(constraints_, elements_, position_projections_, why)
           : views_->projective_form(constraints_, elements_, why));
  if (!has_form) {
    return StepResult::refusal(name(), std::move(why));
  }
  views_->plane_constraints(planes_);
  for (const PlaneConstraint& plane : planes_) {
    if (!(plane.stiffness > 0.0)) {
      // A projection puts a particle on the plane, where the barrier's
      // energy is infinite.
      return StepResult::refusal(
          name(), {"this scene's contact is the barrier, whose energy is infinite on the plane, "
                   "where a projection puts a particle; use the penalty contact with " + name() +
                       ", or implicit-euler with the barrier",
                   SceneRemedy{"contact", "0", "penalty"}});
    }
  }
  const Eigen::Index n = system().dofs() / dim_;
  inv_particle_mass_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) inv_particle_mass_[i] = inv_mass()[i * dim_];
  return StepResult::success();
}

void FastSolver::eval_external_force(double t, const Vector& x, const Vector& v, Vector& f) {
  ++mutable_stats().force_evals;
  views_->external_force(t, x, v, f);
}

Eigen::Vector3d FastSolver::difference(const DistanceConstraint& c, const Vector& x) const {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (int r = 0; r < dim_; ++r) {
    d[r] = x[c.a * dim_ + r] - (c.b >= 0 ? x[c.b * dim_ + r] : c.anchor[r]);
  }
  return d;
}

double FastSolver::gap(const PlaneConstraint& plane, const Vector& x, Eigen::Index i) const {
  double d = -plane.offset;
  for (int r = 0; r < dim_; ++r) d += plane.normal[r] * x[i * dim_ + r];
  return d;
}

void FastSolver::slow_tangential_velocity(const PlaneConstraint& plane, Eigen::Index i,
                                          double max_dv) {
  double vn = 0.0;
  for (int r = 0; r < dim_; ++r) vn += plane.normal[r] * v_[i * dim_ + r];
  Eigen::Vector3d vt = Eigen::Vector3d::Zero();
  for (int r = 0; r < dim_; ++r) vt[r] = v_[i * dim_ + r] - vn * plane.normal[r];
  const double speed = vt.norm();
  if (!(speed > 0.0)) return;
  const double dv = std::min(max_dv, speed);
  for (int r = 0; r < dim_; ++r) v_[i * dim_ + r] -= dv * vt[r] / speed;
}

}  // namespace springlab
