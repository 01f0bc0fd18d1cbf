// xpbd — extended position-based dynamics (Macklin, Mueller and Chentanez,
// "XPBD: position-based simulation of compliant constrained dynamics", MIG
// 2016), what games use. Each spring is the constraint
// C = |x_a - x_b| - L with compliance alpha = 1/k. A step of h is S
// substeps of h_s = h/S (--substeps, default 10; "Small Steps", Macklin et
// al. 2019); each substep
//   predicts    v += h_s M^-1 F_ext(t, x, v),  x_prev = x,  x += h_s v
//               (F_ext: gravity, drag, wind, spring damping, explicitly),
//   projects    N times (--iterations, default 1), constraint by constraint
//               (Gauss-Seidel) in the scene's order of its springs (the
//               file's; sorted by particle the pass diverged on cloth 128,
//               issue 37), with lambda_c = 0 at the substep's start:
//               a~ = alpha / h_s^2,
//               dlambda = (-C - a~ lambda_c) / (w_a + w_b + a~),
//               x_a += w_a dlambda n,  x_b -= w_b dlambda n,  lambda_c += dlambda
//               (w = 1/m, n = (x_a - x_b)/|x_a - x_b|),
//   and sets    v = (x - x_prev) / h_s.
// Contact planes (FastSolverViews::plane_constraints) are inequality
// constraints C = n.x_i - offset >= 0 of every free particle, projected
// after the springs in each iteration with compliance 1/k_c (the penalty)
// and lambda kept >= 0 (they push, never pull). The barrier is refused: its
// energy is infinite at d <= 0, where a projection puts a particle (use
// implicit-euler, or the penalty). Coulomb friction as in Mueller et al., "Detailed rigid body
// simulation with extended position based dynamics" (SCA 2020, sec. 3.5-3.6),
// with f_n = lambda / h_s^2 the contact's normal force: static, in each
// projection, the substep's tangential displacement dx_t is undone where
// the force that takes, |dx_t| / (w h_s^2), is at most mu f_n; dynamic,
// after the substep, v_t loses min(h_s mu f_n / m, |v_t|) along -v_t/|v_t|.
// Exact Coulomb friction, without the smoothing: a particle sticks exactly.
// Projective elements (FastSolverViews::projective_form: corotated's
// as-rigid-as-possible energy w/2 |F - R|^2 and, for poisson > 0,
// Bouaziz's volume constraint; docs/integrators.md "Fast solvers") are the constraint
// C = |F - P(F)|, the distance of F to the set it is projected on, with
// compliance 1/w, so that C^2 / (2 alpha) is
// the element's energy (XPBD's energy form, Macklin et al. 2016, eq. 2-4).
// Its gradient at node i is (F - P(F)) g_i / C (the distance's gradient is
// the unit normal to the set; P's own change does not enter), projected
// after the springs as one constraint over all of the element's nodes:
//   dlambda = (-C - a~ lambda_e) / (sum_i w_i |grad_i C|^2 + a~),
//   x_i += w_i dlambda grad_i C.
// Constraints the model projects itself (FastSolverViews::
// position_based_form: a fluid's density constraints, position-based
// fluids, models/fluids/fluid_density_projection.cc) are found at the substep's
// predicted positions (begin) and projected after the elements in each
// iteration (project); their velocity filter runs after v is set.
// On a spring of rest length 0 one iteration is exactly implicit Euler's
// substep (tests/test_fast_solvers.cc), so S substeps of one iteration are S
// implicit Euler steps of h/S; more iterations converge toward it on
// nonlinear springs. Projections count as newton_iterations.
#pragma once

#include "integrators/fast/fast_solver.h"

namespace springlab {

class Xpbd final : public FastSolver {
 public:
  Xpbd();
  std::vector<std::string> options_read() const override { return {"iterations", "substeps"}; }
  static constexpr int kDefaultSubsteps = 10;
  int substeps(const IntegratorOptions& o) const override {
    return o.substeps > 0 ? o.substeps : kDefaultSubsteps;
  }
  static constexpr int kDefaultIterations = 1;

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  // One Gauss-Seidel pass over the distance constraints in projections_'
  // order (D: the dimension), lambda_ accumulating.
  template <int D>
  void project_constraints();
  // The substep's prediction v += h_s M^-1 f_, x_prev = x, x += h_s v.
  void predict(double hs);

  // Projects the plane constraints once (lambda_planes_ accumulates).
  void project_planes(double hs);
  // Coulomb friction on v after the substep.
  void apply_friction(double hs);

  // Projects the projective elements once (lambda_elements_ accumulates).
  void project_elements(double hs);
  // The distance constraints as the projection loop reads them, in the
  // order they are projected (FastSolverViews::projective_form's: the
  // scene's order of its springs): offsets a * dim and b * dim into x (b < 0: anchored),
  // inverse masses, rest length, anchor, and the compliance a~ = 1/(k h_s^2)
  // of the current substep length.
  struct Projection {
    int a, b;
    double wa, wb, length;
    double compliance;
    double anchor[3];
  };
  std::vector<Projection> projections_;
  std::vector<double> stiffness_;  // k per projection (compliance's source)
  double compliance_hs_ = 0.0;     // the h_s the compliances are for
  Vector f_, x_prev_, lambda_, lambda_elements_;
  Vector lambda_planes_;  // per (plane, free particle)
};

}  // namespace springlab
