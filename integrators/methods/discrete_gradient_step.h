// The discrete gradient's step (discrete_gradient.h): the midpoint rule's
// velocity-implicit step (velocity_step.h, (a, b, c) = (1/4, 1/4, 1/2) at
// t* = t_n + h/2) with Gonzalez's correction,
//
//   r(v) = M (v - v_n) - h F(x*, v*) + h c D,   D = y - x_n = h v*,
//   c = (V(y) - V(x_n) + F.D - h F_nc.v*) / |D|^2
//
// (grad V(x*).D = -F.D + the work of the forces that do not derive from V),
// and the Newton policy that solves it. The step itself knows nothing of
// the correction: this problem wraps it, adding its terms to r, Phi and J.
#pragma once

#include <memory>

#include "integrators/newton/newton_policy.h"
#include "integrators/newton/velocity_step.h"

namespace springlab {

class DiscreteGradientStep final : public NewtonProblem, private JacobianTerm {
 public:
  // The step just begun in `step` (VelocityStep::begin with the midpoint's
  // scheme). `own_gradients`: the forces' own exact discrete gradients
  // where they have one (ForceTerm::has_discrete_gradient: the rigidity);
  // false: Gonzalez's for every force.
  void begin(VelocityStep& step, bool own_gradients);

  // r with the correction; where forces have their own discrete gradient
  // g_k (and the coefficient is not frozen), g_k in place of their
  // midpoint force, and the correction that of the others' energy.
  void residual(const Vector& v, Vector& r) override;
  // The midpoint's Phi + c |D|^2 with c frozen (whose gradient r then is).
  double potential(const Vector& v, double& magnitude) override;
  // The midpoint's J, with the own discrete gradients' derivative, plus
  // the correction's: a diagonal shift and a rank-one term.
  void matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) override;
  RankOne rank_one() const override;
  bool follow(const Vector& v) override { return step_->follow(v, *this); }

  // As the step's.
  const Vector& start() const override { return step_->start(); }
  double position_resolution() const override { return step_->position_resolution(); }
  bool fallback_start(Vector& v) const override { return step_->fallback_start(v); }
  bool accepted_start(Vector& v) const override { return step_->accepted_start(v); }
  bool has_potential() const override { return step_->has_potential(); }
  bool has_forbidden_states() const override { return step_->has_forbidden_states(); }
  double admissible_fraction(const Vector& v, const Vector& dv) override {
    return step_->admissible_fraction(v, dv);
  }
  double trusted_fraction(const Vector& v, const Vector& dv) override {
    return step_->trusted_fraction(v, dv);
  }
  bool allowed() override { return step_->allowed(); }

  // The correction's coefficient, frozen (Phi then includes c |D|^2, r its
  // gradient) or not, and its value (the policy below steers them).
  void freeze(bool frozen) { frozen_ = frozen; }
  bool frozen() const { return frozen_; }
  void set_frozen_coefficient(double c) { frozen_c_ = c; }
  // At the start of an iteration on the frozen potential: the coefficient
  // at the last residual()'s v, and r and Phi with it. At the first
  // iteration off it: r of the step at that v (where some forces have
  // their own discrete gradient, which the frozen potential leaves out).
  void update_frozen(Vector& r, double& phi);
  // r at v with the coefficient of v, then frozen at that value.
  void refreeze_at(const Vector& v, Vector& r);

 private:
  // JacobianTerm: the own discrete gradients' derivative with respect to
  // y, in place of those forces' midpoint Hessian (not symmetric).
  void add(double t, const Vector& x, bool definite, double cx,
           SparseMatrix& out) const override;
  bool symmetric(bool definite) const override { return definite; }
  // Gonzalez's coefficient at the last stage, with the force f (F, or F
  // with the own discrete gradients); 0 below round-off.
  double coefficient(double t, const Vector& f) const;

  VelocityStep* step_ = nullptr;
  bool own_gradients_ = true;
  double v_start_potential_ = 0.0;  // V(t*, x_n)
  // D = y - x_n, y = x_n + D, the coefficient c (0: left out), F at y, the
  // rank-one term's vector z.
  Vector delta_, y_, f_end_, z_;
  double correction_ = 0.0;
  // F with the own discrete gradients in place of those forces' midpoint
  // values (MechanicalSystem::add_own_discrete_gradient_difference), when
  // the last residual() used them (own_).
  Vector f_own_;
  bool own_ = false;
  bool rank_one_ = false;  // the last matrix() has the term h c D's derivative
  // On the potential path the coefficient is frozen for each iteration.
  bool frozen_ = false;
  double frozen_c_ = 0.0;
};

// Newton on the discrete gradient's step (newton_policy.h): its residual is
// no gradient, but with the correction's coefficient frozen it is that of
// the midpoint's potential + c |D|^2. Phase 1 minimizes that potential with
// the coefficient frozen at each iteration's start (robust far from the
// solution); once a full exact update is taken, phase 2 is Newton with the
// exact Jacobian (the rank-one term included) and a search on ||r||,
// quadratic near the solution; back to phase 1 when that search fails, and
// to phase 2 when phase 1's update does not descend even with the definite
// matrix.
std::unique_ptr<NewtonPolicy> discrete_gradient_phases(NewtonPolicy::Matrices matrices,
                                                       bool symmetric, DiscreteGradientStep& step);

}  // namespace springlab
