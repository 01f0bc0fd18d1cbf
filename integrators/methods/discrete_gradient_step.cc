#include "integrators/methods/discrete_gradient_step.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springlab {

void DiscreteGradientStep::begin(VelocityStep& step, bool own_gradients) {
  step_ = &step;
  own_gradients_ = own_gradients;
  v_start_potential_ = step.system().position_potential(step.t_star(), step.x());
}

void DiscreteGradientStep::residual(const Vector& v, Vector& r) {
  const VelocityStep& step = *step_;
  const MechanicalSystem& system = step.system();
  const double h = step.h(), t = step.t_star();
  step_->stage_and_force(v);
  const Vector& f_mid = step.stage_force();  // F(x*, v*)
  // The forces with their own discrete gradient g_k (ForceTerm::
  // has_discrete_gradient: the rigid bodies' rigidity) use it in place of
  // their midpoint force, except on the frozen potential (whose gradient r
  // then is); Gonzalez's correction below is then that of the others'
  // energy V - sum V_k, since g_k . Delta = V_k(y) - V_k(x_n) exactly.
  own_ = own_gradients_ && !frozen_ && system.has_own_discrete_gradients();
  delta_ = h * step.stage_v();  // Delta = y - x_n
  y_ = step.x() + delta_;
  if (own_) {
    f_own_ = f_mid;
    system.add_own_discrete_gradient_difference(t, step.x(), step.stage_x(), y_, f_own_);
  }
  step.residual_with(v, own_ ? f_own_ : f_mid, r);  // M (v - v_c) - h w f
  // Gonzalez (1996): grad V(x*) becomes
  //   grad V(x*) + (V(y) - V(x_n) - grad V(x*).Delta) / |Delta|^2 Delta,
  // Delta = y - x_n = h v*, x* the midpoint. grad V(x*).Delta is -F.Delta
  // plus the work of the forces that do not derive from V.
  correction_ = coefficient(t, own_ ? f_own_ : f_mid);
  const double c = frozen_ ? frozen_c_ : correction_;
  if (c != 0.0) r += (h * c) * delta_;
}

double DiscreteGradientStep::coefficient(double t, const Vector& f) const {
  const VelocityStep& step = *step_;
  const MechanicalSystem& system = step.system();
  const double v_end = system.position_potential(t, y_);
  const double slope =
      -f.dot(delta_) + step.h() * system.nonconservative_power(t, step.stage_x(), step.stage_v());
  const double numerator = v_end - v_start_potential_ - slope;
  double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                 (std::abs(v_end) + std::abs(v_start_potential_) + std::abs(slope));
  // A force with its own discrete gradient may compute its energy through a
  // cancellation (the rigidity's A^T A - I): the round-off of V is then
  // that of its gradient times the state, up to |F| |x| (Cauchy-Schwarz),
  // and a numerator below it is that force's round-off, not the others'.
  if (own_) {
    noise += 1e3 * std::numeric_limits<double>::epsilon() * step.stage_force().norm() *
             step.stage_x().norm();
  }
  const double length2 = delta_.squaredNorm();
  return std::abs(numerator) > noise && length2 > 0.0 ? numerator / length2 : 0.0;
}

double DiscreteGradientStep::potential(const Vector& v, double& magnitude) {
  const double phi = step_->potential(v, magnitude);
  // The correction with its coefficient frozen, h c D = d/dv (c |D|^2).
  const double corrected = frozen_c_ * delta_.squaredNorm();
  magnitude += std::abs(corrected);
  return phi + corrected;
}

void DiscreteGradientStep::add(double t, const Vector& x, bool definite, double cx,
                               SparseMatrix& out) const {
  step_->system().add_own_discrete_gradient_jacobian_difference(t, step_->x(), x, y_, definite,
                                                                cx, out);
}

void DiscreteGradientStep::matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) {
  VelocityStep& step = *step_;
  const double h = step.h();
  // Where r has forces' own discrete gradients g_k(x_n, y) (own_), their
  // part of J is h w dg_k/dy dy/dv = (h^2 w / 2) dg_k/dy, not their
  // midpoint Hessian's (h^2 w / 4) H_k(x*): the step's matrix takes it as
  // this problem's term (add() above). That derivative is not symmetric
  // (bodies.cc: its skew part is as large as its difference from the
  // midpoint Hessian), so the exact matrix is then factored by LU; the
  // definite one keeps its symmetric positive part.
  step.set_jacobian_term(own_ ? this : nullptr);
  SparseMatrix& jacobian = step.assemble(v, definite, linear);
  // The correction c D (c = correction_) has the derivative
  // (h^2/2) (c I + D (w - 2 c D)^T / |D|^2) with respect to v,
  // w = grad V(y) - grad V(x*) - H(x*) D / 2 (H = -dF/dx): a shift of the
  // diagonal and a rank-one term D z^T (Sherman and Morrison in the loop).
  rank_one_ = correction_ != 0.0;
  if (!rank_one_) return;
  const double t = step.t_star();
  const Vector& f = step.stage_force();
  step.model().force(t, y_, step.stage_v(), f_end_);
  z_.noalias() = step.dfdx() * delta_;
  z_ = 0.5 * z_ - (f_end_ - f) - 2.0 * correction_ * delta_;
  if (own_) {
    // w is that of the others' energy V_g = V - sum V_k: the forces with
    // their own discrete gradient leave out their part, F_k(x*) - F_k(y) +
    // dF_k/dx D / 2 ~ (F_k(y) - F_k(x_n)) / 2 - (F_k(y) - F_k(x*)) (a
    // central difference about x*, O(|D|^3)), from the differences
    // e(m) = -g_k(x_n, y) - F_k(m) (add_own_discrete_gradient_difference)
    // at m = x*, y, x_n.
    const MechanicalSystem& system = step.system();
    Vector at_end = Vector::Zero(z_.size()), at_start = Vector::Zero(z_.size());
    system.add_own_discrete_gradient_difference(t, step.x(), y_, y_, at_end);
    system.add_own_discrete_gradient_difference(t, step.x(), step.x(), y_, at_start);
    const Vector& at_mid = f_own_;  // f + e(x*)
    // F_k(y) - F_k(x*) = e(x*) - e(y); F_k(y) - F_k(x_n) = e(x_n) - e(y).
    z_ -= 0.5 * (at_start - at_end) - ((at_mid - f) - at_end);
  }
  z_ *= 0.5 * h * h / delta_.squaredNorm();
  // (The definite matrix keeps only a positive shift.)
  jacobian.diagonal().array() +=
      0.5 * h * h * (definite ? std::max(0.0, correction_) : correction_);
}

NewtonProblem::RankOne DiscreteGradientStep::rank_one() const {
  if (!rank_one_) return {};
  return {.u = &delta_, .z = &z_};
}

void DiscreteGradientStep::update_frozen(Vector& r, double& phi) {
  const VelocityStep& step = *step_;
  if (!frozen_) {
    // Leaving the frozen potential (the policy's phase 2): its r, at the
    // last residual()'s v, had the midpoint force of the forces with their
    // own discrete gradient and the frozen coefficient; r of the step has
    // their discrete gradients and the coefficient of the others.
    if (own_ || !own_gradients_ || !step.system().has_own_discrete_gradients()) return;
    own_ = true;
    const double h = step.h(), t = step.t_star();
    const Vector& f_mid = step.stage_force();
    f_own_ = f_mid;
    step.system().add_own_discrete_gradient_difference(t, step.x(), step.stage_x(), y_, f_own_);
    r -= (h * step.scheme().weight) * (f_own_ - f_mid);
    correction_ = coefficient(t, f_own_);
    if (correction_ != frozen_c_) r += (h * (correction_ - frozen_c_)) * delta_;
    return;
  }
  if (correction_ == frozen_c_) return;
  r += (step.h() * (correction_ - frozen_c_)) * delta_;
  phi += (correction_ - frozen_c_) * delta_.squaredNorm();
  frozen_c_ = correction_;
}

void DiscreteGradientStep::refreeze_at(const Vector& v, Vector& r) {
  // r of the frozen potential (without the forces' own discrete gradients)
  // with the coefficient at v.
  frozen_ = true;
  frozen_c_ = 0.0;
  residual(v, r);  // sets correction_ at v
  frozen_c_ = correction_;
  if (frozen_c_ != 0.0) r += (step_->h() * frozen_c_) * delta_;
}

namespace {

class DiscreteGradientPhases final : public NewtonPolicy {
 public:
  DiscreteGradientPhases(Matrices matrices, bool symmetric, DiscreteGradientStep& step)
      : NewtonPolicy(matrices, symmetric), step_(step) {}

  void start(bool has_potential, NewtonMode& mode) override {
    NewtonPolicy::start(has_potential, mode);
    has_potential_ = has_potential;
    newton_phase_ = false;
    step_.freeze(mode.minimize);
    step_.set_frozen_coefficient(0.0);
  }

  void begin_iteration(NewtonMode& mode, NewtonIterate& it) override {
    if (has_potential_) {
      mode.minimize = !newton_phase_;
      step_.freeze(mode.minimize);
      mode.careful = mode.careful || newton_phase_;
    }
    // The coefficient at this v: the potential and r of the next
    // iterations use it.
    step_.update_frozen(it.r, it.phi);
  }

  bool retry_not_descending(NewtonMode& mode) override {
    if (NewtonPolicy::retry_not_descending(mode)) return true;
    if (!step_.frozen()) return false;
    newton_phase_ = true;  // the frozen potential is only a guide: Newton on r
    return true;
  }

  bool retry_search_failed(NewtonMode& mode, NewtonProblem& problem, NewtonIterate& it) override {
    if (!newton_phase_) return NewtonPolicy::retry_search_failed(mode, problem, it);
    // Back to the frozen potential, from v.
    newton_phase_ = false;
    mode.careful = false;
    step_.refreeze_at(it.v, it.r);
    it.phi = step_.potential(it.v, it.magnitude);
    return true;
  }

  void step_taken(NewtonMode& mode, double alpha) override {
    if (has_potential_ && !newton_phase_ && alpha == 1.0 && !mode.definite) newton_phase_ = true;
    NewtonPolicy::step_taken(mode, alpha);
  }

 private:
  DiscreteGradientStep& step_;
  bool has_potential_ = false;
  bool newton_phase_ = false;  // phase 2
};

}  // namespace

std::unique_ptr<NewtonPolicy> discrete_gradient_phases(NewtonPolicy::Matrices matrices,
                                                       bool symmetric,
                                                       DiscreteGradientStep& step) {
  return std::make_unique<DiscreteGradientPhases>(matrices, symmetric, step);
}

}  // namespace springlab
