#include "integrators/newton/velocity_step.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springlab {

void VelocityStep::bind(const CountedModel& model, NewtonMatrix& matrix) {
  model_ = &model;
  matrix_ = &matrix;
}

void VelocityStep::begin(double t, const Vector& x, const Vector& v, double h,
                         const VelocityImplicitScheme& scheme) {
  t_ = t;
  x_ = &x;
  v_ = &v;
  h_ = h;
  s_ = scheme;
  term_ = nullptr;
  // With a trust region, the start is the inertial prediction v_n cut back
  // into it from the stage at x_n (start_): v_n itself where it moves no
  // particle further than the region's length.
  rest_start_ = false;
  if (model_->system().has_trust_region() && (accepted_start(start_) || fallback_start(start_))) {
    const Vector towards = *v_ - start_;
    const double alpha = trusted_fraction(start_, towards);
    rest_start_ = alpha < 1.0;
    if (rest_start_) start_ += alpha * towards;
  }
}

double VelocityStep::position_resolution() const {
  const double moved = h_ * s_.weight * std::abs(s_.b);
  if (!(moved > 0.0)) return 0.0;
  double x = x_->lpNorm<Eigen::Infinity>();
  if (s_.x_offset != nullptr) x += s_.x_offset->lpNorm<Eigen::Infinity>();
  return x / moved;
}

double VelocityStep::stored_magnitude() {
  const MechanicalSystem& system = model_->system();
  if (!(s_.b != 0.0)) return 0.0;
  const double t = t_ + s_.t_eval_offset * h_;
  double sum = 0.0;
  for (ForcePart part : {ForcePart::kStiff, ForcePart::kNonstiff}) {
    system.force(part, t, xs_, vs_, f_part_);
    sum += f_part_.cwiseAbs().dot(xs_.cwiseAbs());
  }
  return std::abs(s_.weight / s_.b) * sum;
}

bool VelocityStep::fallback_start(Vector& v) const {
  if (!(s_.b > 0.0)) return false;
  v = (-s_.a / s_.b) * *v_;
  return true;
}

bool VelocityStep::accepted_start(Vector& v) const {
  if (!(s_.b > 0.0) || s_.x_offset == nullptr) return false;
  v = (-s_.a / s_.b) * *v_ - (1.0 / (h_ * s_.b)) * *s_.x_offset;
  return true;
}

bool VelocityStep::has_potential() const {
  return model_->system().derives_from_potentials() && s_.b > 0.0 && s_.c > 0.0;
}

bool VelocityStep::has_forbidden_states() const { return model_->system().has_forbidden_states(); }

void VelocityStep::stage(const Vector& v) {
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  xs_ = *x_ + h * (s.a * *v_ + s.b * v);
  if (s.x_offset != nullptr) xs_ += *s.x_offset;
  vs_ = (1.0 - s.c) * *v_ + s.c * v;
}

void VelocityStep::residual(const Vector& v, Vector& r) {
  stage_and_force(v);
  residual_with(v, f_, r);
}

void VelocityStep::stage_and_force(const Vector& v) {
  stage(v);
  model_->force(t_star(), xs_, vs_, f_);
}

void VelocityStep::residual_with(const Vector& v, const Vector& f, Vector& r) const {
  r = system().mass().cwiseProduct(v - inertia()) - (h_ * s_.weight) * f;
}

double VelocityStep::potential(const Vector& v, double& magnitude) {
  // xs_ and vs_ are those of the last residual() (or stage()), at this v.
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  const MechanicalSystem& system = model_->system();
  const double t = t_ + s.t_eval_offset * h;
  const Vector& v_c = s.inertia != nullptr ? *s.inertia : *v_;
  const double inertia = 0.5 * (v - v_c).cwiseAbs2().dot(system.mass());
  const double stored = s.weight * system.position_potential(t, xs_) / s.b;
  const double dissipated = (h * s.weight) / s.c * system.velocity_potential(t, vs_);
  magnitude = inertia + std::abs(stored) + std::abs(dissipated);
  return inertia + stored + dissipated;
}

void VelocityStep::matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) {
  set_matrix_point(v);
  // Where the model multiplies by its Jacobians without them (a fluid's),
  // J is handed to the solver by its products: assembled only where a
  // solve needs the matrix.
  if (matrix_->has_products()) {
    linear.defer(definite, model_->system().jacobian_symmetric(), *matrix_);
  } else {
    assemble_at_point(definite, linear);
  }
}

void VelocityStep::set_matrix_point(const Vector& v) {
  const VelocityImplicitScheme& s = s_;
  stage(v);
  // The Newton matrix's coefficients of dF/dx (h^2 w b) and dF/dv (h w c),
  // and the method's own term of dF/dx (term_).
  matrix_->set_point({.t = t_star(), .x = &xs_, .v = &vs_, .h = h_, .b = s.weight * s.b,
                      .c = s.weight * s.c, .term = term_});
}

SparseMatrix& VelocityStep::assemble(const Vector& v, bool definite,
                                     NewtonLinearSolver& linear) {
  set_matrix_point(v);
  return assemble_at_point(definite, linear);
}

SparseMatrix& VelocityStep::assemble_at_point(bool definite, NewtonLinearSolver& linear) {
  const bool symmetric =
      model_->system().jacobian_symmetric() && (term_ == nullptr || term_->symmetric(definite));
  SparseMatrix& jacobian = linear.matrix(definite, symmetric, *matrix_);
  matrix_->assemble(definite, jacobian);
  return jacobian;
}

double VelocityStep::admissible_fraction(const Vector& v, const Vector& dv) {
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  const MechanicalSystem& system = model_->system();
  x_cap_ = *x_ + h * (s.a * *v_ + s.b * v);
  if (s.x_offset != nullptr) x_cap_ += *s.x_offset;
  dx_cap_ = (h * s.b) * dv;
  double fraction = system.admissible_fraction(x_cap_, dx_cap_);
  if (s.end != 1.0) {
    x_cap_ = *x_ + s.end * (x_cap_ - *x_);
    dx_cap_ *= s.end;
    fraction = std::min(fraction, system.admissible_fraction(x_cap_, dx_cap_));
  }
  return fraction;
}

double VelocityStep::trusted_fraction(const Vector& v, const Vector& dv) {
  const VelocityImplicitScheme& s = s_;
  const MechanicalSystem& system = model_->system();
  if (!system.has_trust_region()) return std::numeric_limits<double>::infinity();
  x_cap_ = *x_ + h_ * (s.a * *v_ + s.b * v);
  if (s.x_offset != nullptr) x_cap_ += *s.x_offset;
  dx_cap_ = (h_ * s.b) * dv;
  double fraction = system.trusted_fraction(x_cap_, dx_cap_);
  if (s.end != 1.0) {
    x_cap_ = *x_ + s.end * (x_cap_ - *x_);
    dx_cap_ *= s.end;
    fraction = std::min(fraction, system.trusted_fraction(x_cap_, dx_cap_));
  }
  return fraction;
}

bool VelocityStep::allowed() {
  if (s_.end == 1.0 || !has_forbidden_states()) return true;
  x_end_ = *x_ + s_.end * (xs_ - *x_);
  return std::isfinite(model_->system().position_potential(t_ + h_, x_end_));
}

bool VelocityStep::follow(const Vector& v, NewtonProblem& problem) {
  const MechanicalSystem& system = model_->system();
  stage(v);
  if (!system.follow_lagged_contacts(&xs_, &v, h_)) return false;
  // (residual() and potential() at v with the contacts found there.)
  problem.residual(v, f_part_);
  double magnitude = 0.0;
  if (f_part_.allFinite() && allowed() &&
      (!problem.has_potential() || std::isfinite(problem.potential(v, magnitude)))) {
    ++follows_;
    return true;
  }
  system.follow_lagged_contacts(nullptr, nullptr, 0.0);
  return false;
}

}  // namespace springlab
