// The equations of a velocity-implicit step, the problem the implicit
// one-step and multistep methods give Newton (newton_loop.h).
//
// The step solves for the new velocity v (half the unknowns of the full
// state: positions follow from v)
//
//   r(v) = M (v - v_c) - h w F(t*, x*(v), v*(v)) = 0,
//   x*(v) = x_n + x_o + h (a v_n + b v),   v*(v) = (1 - c) v_n + c v,
//
// with Jacobian J = dr/dv = M - h w c dF/dv - h^2 w b dF/dx (sparse, on the
// model's pattern: newton_matrix.h). Backward Euler is (a, b, c) = (0, 1, 1)
// at t* = t_n + h, w = 1, v_c = v_n, x_o = 0; the implicit midpoint rule is
// (1/4, 1/4, 1/2) at t* = t_n + h/2; the discrete gradient adds Gonzalez's
// correction to the midpoint rule, in a problem of its own around this one
// (methods/discrete_gradient_step.h). The second-order
// and multistep methods (newmark_family.h, bdf2.h, tr_bdf2.h) set a force
// weight w, an inertial centre v_c and a position offset x_o fixed within
// the step (their predictors: a_n, x_{n-1}, a stage's state).
//
// When every force derives from potentials (MechanicalSystem::
// derives_from_potentials: springs, gravity, elements; drag and wind
// through a dissipation potential W of v), r is the gradient of the step's
// incremental potential
//
//   Phi(v) = |v - v_c|^2_M / 2 + (w / b) V(x*(v)) + (h w / c) W(t*, v*(v)),
//
// and J is its Hessian: the step is the variational form of implicit Euler
// (Kane et al. 2000, Gast et al. 2015), and Newton minimizes Phi. Without
// such a potential (spring damping depends on x and v together) r is a
// plain residual and J is not symmetric.
#pragma once

#include "integrators/newton/newton_matrix.h"
#include "integrators/newton/newton_problem.h"

namespace springlab {

struct VelocityImplicitScheme {
  double t_eval_offset;  // t* = t_n + t_eval_offset * h
  double a, b, c;        // see the header comment
  // Whether a step whose Newton fails may be solved by the definite
  // ("projected") Newton (velocity_implicit_method.h). The discrete
  // gradient with forces' own discrete gradients turns it off: its definite
  // Newton never leaves the frozen potential (discrete_gradient_step.h),
  // whose solution is Gonzalez's generic discrete gradient, not the step's.
  bool definite_fallback = true;
  // The step's end is x_{n+1} = x_n + end (x* - x_n): 1 where the forces
  // are evaluated at the end (implicit Euler), 2 at the midpoint.
  double end = 1.0;
  double weight = 1.0;               // w
  const Vector* inertia = nullptr;   // v_c; nullptr: v_n
  const Vector* x_offset = nullptr;  // x_o; nullptr: zero
};

class VelocityStep final : public NewtonProblem {
 public:
  // The model of the run and the matrix the step assembles its J with.
  void bind(const CountedModel& model, NewtonMatrix& matrix);
  // The step of size h from (t_n, x_n, v_n) (kept by reference).
  void begin(double t, const Vector& x, const Vector& v, double h,
             const VelocityImplicitScheme& scheme);
  const VelocityImplicitScheme& scheme() const { return s_; }
  double t() const { return t_; }  // t_n
  double h() const { return h_; }
  const Vector& x() const { return *x_; }  // x_n
  const Vector& v_n() const { return *v_; }  // (start() may differ: below)
  const MechanicalSystem& system() const { return model_->system(); }
  const CountedModel& model() const { return *model_; }
  double t_star() const { return t_ + s_.t_eval_offset * h_; }
  // v_c (v_n where the scheme names none).
  const Vector& inertia() const { return s_.inertia != nullptr ? *s_.inertia : *v_; }
  // The stage x*, v* of the last residual() or stage(), and F there (of
  // the last residual()).
  const Vector& stage_x() const { return xs_; }
  const Vector& stage_v() const { return vs_; }
  const Vector& stage_force() const { return f_; }
  // dF/dx of the last matrix().
  const SparseMatrix& dfdx() const { return matrix_->dfdx(); }

  // v_n; where the system has a trust region (MechanicalSystem::
  // has_trust_region: a fluid) and v_n's stage moves a particle beyond it
  // from x_n, v_n cut back towards the v whose stage is x_n
  // (accepted_start, else fallback_start) until it no longer does: the
  // inertial prediction x_n + h v_n may carry a particle through a wall
  // thinner than h |v_n| (a fluid's wall of particles), and Newton, moving
  // each particle a little at a time from there, finds the solution beyond
  // it.
  const Vector& start() const override { return rest_start_ ? start_ : *v_; }
  // (||x_n||_inf + ||x_o||_inf) / (h w |b|): the stage moves by h w b per
  // unit of v (its positions' round-off, newton_problem.h).
  double position_resolution() const override;
  // The v that keeps the stage at x_n, a v_n + b v = 0: a state the last
  // step accepted (where v_n leaves the states with an energy).
  bool fallback_start(Vector& v) const override;
  // With an offset x_o (BDF2's extrapolation) the fallback's stage is
  // x_n + x_o; this one's is x_n itself: h (a v_n + b v) + x_o = 0.
  bool accepted_start(Vector& v) const override;
  void residual(const Vector& v, Vector& r) override;
  bool has_potential() const override;
  double potential(const Vector& v, double& magnitude) override;
  // J at v for the solver: by its products where the model gives them
  // (NewtonLinearSolver::defer), else assembled.
  void matrix(const Vector& v, bool definite, NewtonLinearSolver& linear) override;
  // J assembled at v, whatever the model gives (a method's problem around
  // this one adds its own terms to it: discrete_gradient_step.h).
  SparseMatrix& assemble(const Vector& v, bool definite, NewtonLinearSolver& linear);
  // A term of the method's in J's dF/dx part (newton_matrix.h) for the
  // next matrix() of this step; nullptr: none.
  void set_jacobian_term(const JacobianTerm* term) { term_ = term; }
  bool has_forbidden_states() const override;
  // The fraction of dv at which the first gap of the stage -- or, for the
  // midpoint methods, of the step's end -- would close
  // (MechanicalSystem::admissible_fraction).
  double admissible_fraction(const Vector& v, const Vector& dv) override;
  // The fraction of dv within the system's trust region at the stage --
  // and, for the midpoint methods, at the step's end
  // (MechanicalSystem::trusted_fraction).
  double trusted_fraction(const Vector& v, const Vector& dv) override;
  // Where some states have no energy, a trial whose step would end in one
  // is refused even when the forces' state (the midpoint) is allowed.
  bool allowed() override;
  // The contacts between bodies found again at the stage x*(v)
  // (MechanicalSystem::follow_lagged_contacts), unless r or Phi at v would
  // then not be finite or the step's end not allowed.
  bool follow(const Vector& v) override { return follow(v, *this); }
  // The same, with the r and Phi of `problem` (this step, or a method's
  // problem around it) checked at v.
  bool follow(const Vector& v, NewtonProblem& problem);
  // How many times follow() has set the step up again (over all steps).
  long follows() const { return follows_; }

  // Sets the stage x*(v), v*(v) (potential() then refers to it).
  void stage(const Vector& v);
  // The stage at v and the Newton matrix's point there (its coefficients).
  void set_matrix_point(const Vector& v);
  // J assembled at the point set last.
  SparseMatrix& assemble_at_point(bool definite, NewtonLinearSolver& linear);
  // The stage and F there (stage_force()): residual() without r.
  void stage_and_force(const Vector& v);
  // r = M (v - v_c) - h w f at v, for a force f at the stage: F, or a
  // method's own in place of some forces' (discrete_gradient_step.h).
  void residual_with(const Vector& v, const Vector& f, Vector& r) const;
  // The scale of the round-off of Phi's stored term at the stage (after
  // stage() or residual()): (w / |b|) sum_parts |F_part(x*)| . |x*|, the
  // stiff and the non-stiff forces apart (MechanicalSystem's ForcePart).
  // For a force that is linear in x (gravity) it is the sum of its
  // potential's terms' magnitudes, which cancel in the sum where the
  // positions straddle the origin (a beam centred on y = 0: terms of
  // +-25 J summing to -0.5 J); for any other, V's sensitivity to the
  // rounding of x* (|dV| <= |F| . |dx|). Two force evaluations.
  double stored_magnitude();

 private:
  const CountedModel* model_ = nullptr;
  NewtonMatrix* matrix_ = nullptr;
  double t_ = 0.0, h_ = 0.0;
  const Vector* x_ = nullptr;  // x_n
  const Vector* v_ = nullptr;  // v_n
  VelocityImplicitScheme s_{};
  Vector xs_, vs_, f_, f_part_;
  Vector x_end_;           // a trial's step end (allowed)
  Vector x_cap_, dx_cap_;  // the step cap's state and step (admissible_fraction)
  bool rest_start_ = false;  // start() is start_, not v_n
  Vector start_;
  const JacobianTerm* term_ = nullptr;
  long follows_ = 0;
};

}  // namespace springlab
