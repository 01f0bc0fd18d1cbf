#include "integrators/velocity_step.h"

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
  if (s_.discrete_gradient) {
    v_start_potential_ = model_->system().position_potential(t_ + s_.t_eval_offset * h_, x);
  }
}

bool VelocityStep::fallback_start(Vector& v) const {
  if (!(s_.b > 0.0)) return false;
  v = (-s_.a / s_.b) * *v_;
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
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  const MechanicalSystem& system = model_->system();
  stage(v);
  const double t = t_ + s.t_eval_offset * h;
  model_->force(t, xs_, vs_, f_);
  const Vector& v_c = s.inertia != nullptr ? *s.inertia : *v_;
  r = system.mass().cwiseProduct(v - v_c) - (h * s.weight) * f_;
  if (!s.discrete_gradient) return;
  // Gonzalez (1996): grad V(x*) becomes
  //   grad V(x*) + (V(y) - V(x_n) - grad V(x*).Delta) / |Delta|^2 Delta,
  // Delta = y - x_n = h v*, x* the midpoint. grad V(x*).Delta is -F.Delta
  // plus the work of the forces that do not derive from V.
  delta_ = h * vs_;
  y_ = *x_ + delta_;
  const double v_end = system.position_potential(t, y_);
  const double slope = -f_.dot(delta_) + h * system.nonconservative_power(t, xs_, vs_);
  const double numerator = v_end - v_start_potential_ - slope;
  const double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                       (std::abs(v_end) + std::abs(v_start_potential_) + std::abs(slope));
  const double length2 = delta_.squaredNorm();
  correction_ = std::abs(numerator) > noise && length2 > 0.0 ? numerator / length2 : 0.0;
  const double c = frozen_ ? frozen_c_ : correction_;
  if (c != 0.0) r += (h * c) * delta_;
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
  // The discrete gradient's correction with its coefficient frozen,
  // h c D = d/dv (c |D|^2).
  const double corrected = s.discrete_gradient ? frozen_c_ * delta_.squaredNorm() : 0.0;
  magnitude = inertia + std::abs(stored) + std::abs(dissipated) + std::abs(corrected);
  return inertia + stored + dissipated + corrected;
}

void VelocityStep::matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) {
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  const double t = t_ + s.t_eval_offset * h;
  stage(v);
  // The Newton matrix's coefficients of dF/dx (h^2 w b) and dF/dv (h w c).
  matrix_->set_point({.t = t, .x = &xs_, .v = &vs_, .h = h, .b = s.weight * s.b,
                      .c = s.weight * s.c});
  SparseMatrix& jacobian =
      linear.matrix(definite, model_->system().jacobian_symmetric(), *matrix_);
  matrix_->assemble(definite, jacobian);
  // The discrete gradient's correction c D (c = correction_) has the
  // derivative (h^2/2) (c I + D (w - 2 c D)^T / |D|^2) with respect to v,
  // w = grad V(y) - grad V(x*) - H(x*) D / 2 (H = -dF/dx): a shift of the
  // diagonal and a rank-one term D z^T (Sherman and Morrison in the loop).
  rank_one_ = s.discrete_gradient && correction_ != 0.0;
  if (!rank_one_) return;
  model_->force(t, y_, vs_, f_end_);
  z_.noalias() = matrix_->dfdx() * delta_;
  z_ = 0.5 * z_ - (f_end_ - f_) - 2.0 * correction_ * delta_;
  z_ *= 0.5 * h * h / delta_.squaredNorm();
  // (The definite matrix keeps only a positive shift.)
  jacobian.diagonal().array() +=
      0.5 * h * h * (definite ? std::max(0.0, correction_) : correction_);
}

NewtonProblem::RankOne VelocityStep::rank_one() const {
  if (!rank_one_) return {};
  return {.u = &delta_, .z = &z_};
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

bool VelocityStep::allowed() {
  if (s_.end == 1.0 || !has_forbidden_states()) return true;
  x_end_ = *x_ + s_.end * (xs_ - *x_);
  return std::isfinite(model_->system().position_potential(t_ + h_, x_end_));
}

void VelocityStep::update_frozen(Vector& r, double& phi) {
  if (!frozen_ || correction_ == frozen_c_) return;
  r += (h_ * (correction_ - frozen_c_)) * delta_;
  phi += (correction_ - frozen_c_) * delta_.squaredNorm();
  frozen_c_ = correction_;
}

void VelocityStep::refreeze_at(const Vector& v, Vector& r) {
  frozen_ = false;
  residual(v, r);  // sets correction_ at v, and r with it
  frozen_ = true;
  frozen_c_ = correction_;
}

}  // namespace springlab
