// discrete-gradient — the energy-conserving implicit method of Gonzalez
// ("Time integration and discrete Hamiltonian systems", J. Nonlinear Sci. 6,
// 1996), on M x'' = -grad V(x) + F_nc(t, x, v):
//
//   x_{n+1} = x_n + h (v_n + v_{n+1}) / 2
//   M (v_{n+1} - v_n) = -h grad_d V(x_n, x_{n+1}) + h F_nc(t_n + h/2, x_m, v_m)
//
// with x_m, v_m the midpoints and Gonzalez's discrete gradient
//
//   grad_d V(x, y) = grad V(x_m) + (V(y) - V(x) - grad V(x_m).D) / |D|^2 D,
//   D = y - x,
//
// the midpoint gradient corrected along D so that grad_d V . D = V(y) - V(x)
// exactly. Then the kinetic energy changes by
//   (v_{n+1} - v_n)^T M (v_{n+1} + v_n) / 2 = -(V(x_{n+1}) - V(x_n)) + h F_nc . v_m,
// so without non-conservative forces the mechanical energy T + V is
// conserved exactly, whatever h -- up to how well Newton solves the step
// (the energy error of a step is r . v_m, r the residual left). The
// implicit midpoint rule, which lacks the correction, does not conserve it
// for nonlinear springs and can gain energy at large steps.
//
// Forces that do not derive from V (drag, wind, spring damping) and the time
// dependence (wind gusts) are evaluated at the midpoint, t_n + h/2: their
// energy balance is exactly h F_nc(t_m, x_m, v_m) . v_m per step, which for
// drag is -h gamma |v_m|^2 <= 0, dissipative as the true motion is. V is
// evaluated at t_n + h/2 at both ends (the models' V does not depend on t).
//
// Needs only V, its gradient (-F) and F_nc . v (MechanicalSystem::
// position_potential, force, nonconservative_power): it runs every model.
//
// A force may give its own discrete gradient g_k(x_n, x_{n+1}) of its
// potential V_k (ForceTerm::has_discrete_gradient), exact as Gonzalez's
// (g_k . D = V_k(x_{n+1}) - V_k(x_n)); the step then uses it in place of
// that force's midpoint gradient, and the correction above is that of the
// other forces' energy V - sum V_k (their midpoint slope, g_k . D, is
// V_k's change already). The generic correction along D is not equivariant
// under rotations: its torque h sum x_m x c D moves the angular momentum of
// a rotation-invariant energy (7.2e-6 relative over 10^3 steps of the
// tumbling box). A discrete gradient built from the energy's invariants
// (the rigid bodies' rigidity, a function of A^T A: bodies.cc; Gonzalez
// 1996, sec. 4) exerts none, and keeps L to round-off (3.0e-15 relative
// over the same steps). Newton's matrix then has, for those forces, the
// derivative of their discrete gradient with respect to the step's end
// (ForceTerm::add_discrete_gradient_jacobian), not their midpoint Hessian,
// which is off from it by O(|D|) times kappa V (bodies.cc: 40.5 Newton
// iterations per step on box-chain at 10 ms with it, 4.18 with the exact
// block); that derivative is not symmetric, so the exact matrix is
// factored by LU. On the frozen potential (below) they take their midpoint
// force and Hessian, whose potential it is.
// The correction is left out when its numerator is below the round-off of
// V(y) - V(x) (tiny steps, equilibrium): there it is noise, and the midpoint
// rule's own energy error is smaller still.
//
// The step's equations with the correction, and the Newton policy that
// solves them, are discrete_gradient_step.h. The residual is not the
// gradient of a potential, but with the correction's coefficient frozen it
// is that of the midpoint's potential plus c |D|^2: where the forces derive
// from potentials Newton first minimizes that (robust far from the
// solution), then, once a full update is taken, iterates on r with the
// exact matrix -- the midpoint rule's M - h/2 dF/dv - h^2/4 dF/dx plus the
// correction's derivative, a diagonal shift and a rank-one term solved by
// Sherman and Morrison -- and a line search on ||r|| (quadratic near the
// solution). Order 2 (as the midpoint rule: the correction is O(h^3) per
// step); A-stable, and on the linear oscillator (V quadratic: the
// correction vanishes) it is the midpoint rule, R(z) = (1 + z/2) / (1 - z/2).
#pragma once

#include "integrators/methods/discrete_gradient_step.h"
#include "integrators/newton/velocity_implicit_method.h"

namespace springlab {

// A step whose Newton fails is solved again as 2, then 4, then 8 substeps
// of h / n (VelocityImplicitMethod::retry_in_substeps; with the forces' own
// discrete gradients each substep keeps the energy and the angular
// momentum, so their composition does); where forces have their own
// discrete gradients and those fail too, it falls back to Gonzalez's
// generic discrete gradient for every force in the whole step: energy
// still exact, the angular momentum not (its torque above). The run
// reports the steps that did either (Fallback::kSubsteps,
// kGenericDiscreteGradient: run warnings).
// tumbling-box at dt 0.05: |L| 0.3142 -> 0.0044 over 5 s when two steps
// fell back to the generic gradient at once; with substeps first, kept.
class DiscreteGradient final : public VelocityImplicitMethod {
 public:
  DiscreteGradient();
  std::vector<FallbackCount> fallbacks() const override;

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;
  // The midpoint step with Gonzalez's correction (discrete_gradient_step.h),
  // solved in two phases (the frozen potential, then Newton on r).
  NewtonProblem& newton_problem(VelocityStep& step) override;
  std::unique_ptr<NewtonPolicy> newton_policy(NewtonPolicy::Matrices matrices,
                                              bool symmetric) override;

 private:
  // One step of h with the scheme from (t_, x_, v_); on failure x_ and v_
  // are as before.
  StepResult gradient_step(double h, const VelocityImplicitScheme& scheme);

  DiscreteGradientStep gonzalez_;
  bool own_gradients_ = true;  // the forces' own discrete gradients in this step
  Vector v_new_;
  long generic_steps_ = 0;
};

}  // namespace springlab
