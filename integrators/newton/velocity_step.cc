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
  if (s_.discrete_gradient) {
    v_start_potential_ = model_->system().position_potential(t_ + s_.t_eval_offset * h_, x);
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
  const double h = h_;
  const VelocityImplicitScheme& s = s_;
  const MechanicalSystem& system = model_->system();
  stage(v);
  const double t = t_ + s.t_eval_offset * h;
  model_->force(t, xs_, vs_, f_);
  const Vector& v_c = s.inertia != nullptr ? *s.inertia : *v_;
  // The forces with their own discrete gradient g_k (ForceTerm::
  // has_discrete_gradient: the rigid bodies' rigidity) use it in place of
  // their midpoint force, except on the frozen potential (whose gradient r
  // then is); Gonzalez's correction below is then that of the others'
  // energy V - sum V_k, since g_k . Delta = V_k(y) - V_k(x_n) exactly.
  own_ = s.discrete_gradient && s.own_discrete_gradients && !frozen_ &&
         system.has_own_discrete_gradients();
  if (s.discrete_gradient) {
    delta_ = h * vs_;  // Delta = y - x_n
    y_ = *x_ + delta_;
  }
  if (own_) {
    f_own_ = f_;
    system.add_own_discrete_gradient_difference(t, *x_, xs_, y_, f_own_);
  }
  const Vector& f = own_ ? f_own_ : f_;
  r = system.mass().cwiseProduct(v - v_c) - (h * s.weight) * f;
  if (!s.discrete_gradient) return;
  // Gonzalez (1996): grad V(x*) becomes
  //   grad V(x*) + (V(y) - V(x_n) - grad V(x*).Delta) / |Delta|^2 Delta,
  // Delta = y - x_n = h v*, x* the midpoint. grad V(x*).Delta is -F.Delta
  // plus the work of the forces that do not derive from V.
  correction_ = coefficient(t, f);
  const double c = frozen_ ? frozen_c_ : correction_;
  if (c != 0.0) r += (h * c) * delta_;
}

double VelocityStep::coefficient(double t, const Vector& f) const {
  const MechanicalSystem& system = model_->system();
  const double v_end = system.position_potential(t, y_);
  const double slope = -f.dot(delta_) + h_ * system.nonconservative_power(t, xs_, vs_);
  const double numerator = v_end - v_start_potential_ - slope;
  double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                 (std::abs(v_end) + std::abs(v_start_potential_) + std::abs(slope));
  // A force with its own discrete gradient may compute its energy through a
  // cancellation (the rigidity's A^T A - I): the round-off of V is then
  // that of its gradient times the state, up to |F| |x| (Cauchy-Schwarz),
  // and a numerator below it is that force's round-off, not the others'.
  if (own_) noise += 1e3 * std::numeric_limits<double>::epsilon() * f_.norm() * xs_.norm();
  const double length2 = delta_.squaredNorm();
  return std::abs(numerator) > noise && length2 > 0.0 ? numerator / length2 : 0.0;
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
  // Where r has forces' own discrete gradients g_k(x_n, y) (own_), their
  // part of J is h w dg_k/dy dy/dv = (h^2 w / 2) dg_k/dy, not their
  // midpoint Hessian's (h^2 w / 4) H_k(x*): the matrix takes it from the
  // model with the step's ends (newton_matrix.h).
  matrix_->set_point({.t = t, .x = &xs_, .v = &vs_, .h = h, .b = s.weight * s.b,
                      .c = s.weight * s.c, .start = own_ ? x_ : nullptr, .end = &y_});
  // That derivative is not symmetric (bodies.cc: its skew part is as large
  // as its difference from the midpoint Hessian), so the exact matrix is
  // then factored by LU; the definite one keeps its symmetric positive part.
  const bool own_exact = own_ && !definite;
  SparseMatrix& jacobian =
      linear.matrix(definite, model_->system().jacobian_symmetric() && !own_exact, *matrix_);
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
  if (own_) {
    // w is that of the others' energy V_g = V - sum V_k: the forces with
    // their own discrete gradient leave out their part, F_k(x*) - F_k(y) +
    // dF_k/dx D / 2 ~ (F_k(y) - F_k(x_n)) / 2 - (F_k(y) - F_k(x*)) (a
    // central difference about x*, O(|D|^3)), from the differences
    // e(m) = -g_k(x_n, y) - F_k(m) (add_own_discrete_gradient_difference)
    // at m = x*, y, x_n.
    const MechanicalSystem& system = model_->system();
    Vector at_end = Vector::Zero(z_.size()), at_start = Vector::Zero(z_.size());
    system.add_own_discrete_gradient_difference(t, *x_, y_, y_, at_end);
    system.add_own_discrete_gradient_difference(t, *x_, *x_, y_, at_start);
    const Vector& at_mid = f_own_;  // f + e(x*)
    // F_k(y) - F_k(x*) = e(x*) - e(y); F_k(y) - F_k(x_n) = e(x_n) - e(y).
    z_ -= 0.5 * (at_start - at_end) - ((at_mid - f_) - at_end);
  }
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

bool VelocityStep::follow(const Vector& v) {
  const MechanicalSystem& system = model_->system();
  stage(v);
  if (!system.follow_lagged_contacts(&xs_, &v, h_)) return false;
  // (residual() and potential() at v with the contacts found there.)
  residual(v, f_part_);
  double magnitude = 0.0;
  if (f_part_.allFinite() && allowed() &&
      (!has_potential() || std::isfinite(potential(v, magnitude)))) {
    ++follows_;
    return true;
  }
  system.follow_lagged_contacts(nullptr, nullptr, 0.0);
  return false;
}

void VelocityStep::update_frozen(Vector& r, double& phi) {
  if (!frozen_) {
    // Leaving the frozen potential (newton_policy.h's phase 2): its r, at
    // the last residual()'s v, had the midpoint force of the forces with
    // their own discrete gradient and the frozen coefficient; r of the
    // step has their discrete gradients and the coefficient of the others.
    if (own_ || !s_.discrete_gradient || !s_.own_discrete_gradients ||
        !model_->system().has_own_discrete_gradients()) {
      return;
    }
    own_ = true;
    const double t = t_ + s_.t_eval_offset * h_;
    f_own_ = f_;
    model_->system().add_own_discrete_gradient_difference(t, *x_, xs_, y_, f_own_);
    r -= (h_ * s_.weight) * (f_own_ - f_);
    correction_ = coefficient(t, f_own_);
    if (correction_ != frozen_c_) r += (h_ * (correction_ - frozen_c_)) * delta_;
    return;
  }
  if (correction_ == frozen_c_) return;
  r += (h_ * (correction_ - frozen_c_)) * delta_;
  phi += (correction_ - frozen_c_) * delta_.squaredNorm();
  frozen_c_ = correction_;
}

void VelocityStep::refreeze_at(const Vector& v, Vector& r) {
  // r of the frozen potential (without the forces' own discrete gradients)
  // with the coefficient at v.
  frozen_ = true;
  frozen_c_ = 0.0;
  residual(v, r);  // sets correction_ at v
  frozen_c_ = correction_;
  if (frozen_c_ != 0.0) r += (h_ * frozen_c_) * delta_;
}

}  // namespace springlab
