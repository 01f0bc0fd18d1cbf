// verlet — velocity Verlet (kick-drift-kick leapfrog).
//
//   v_{n+1/2} = v_n + h/2 M^-1 F(t_n, x_n, v_n)
//   x_{n+1}   = x_n + h v_{n+1/2}
//   v_{n+1}   = v_{n+1/2} + h/2 M^-1 F(t_{n+1}, x_{n+1}, v_{n+1})
//
// The closing half-kick is implicit in v_{n+1} when F depends on v (drag,
// spring damping, wind, friction). Where the forces are affine in v,
// F(t, x, v) = F(t, x, 0) + dF/dv(x) v, it is solved exactly:
//   (M - h/2 dF/dv) v_{n+1} = M v_{n+1/2} + h/2 F(t_{n+1}, x_{n+1}, 0)
// (an element-wise division when dF/dv is diagonal, a sparse SPD solve with
// spring damping). Coulomb friction is not affine in v: there Newton solves
//   r(v) = M (v - v_{n+1/2}) - h/2 F(t_{n+1}, x_{n+1}, v) = 0
// with the matrix M - h/2 dF/dv(v) (SPD: friction's dF/dv is symmetric
// negative semidefinite) and a backtracking search on ||r||, to
// ||dv||_inf <= --newton-tol. The end-of-step
// acceleration is reused by the next step, so a step costs one force
// evaluation (affine) or one per Newton iteration.
//
// Order 2. Symplectic and time-reversible when F depends on x only: energy
// stays bounded. On the undamped oscillator it is stable for w h <= 2.
#pragma once

#include "integrators/core/integrator.h"
#include "integrators/linear/sparse_direct_solver.h"

namespace springlab {

class VelocityVerlet : public Integrator {
 public:
  VelocityVerlet();
  // Its closing half-kick's matrix, where the forces depend on v.
  bool assembles_jacobians(const MechanicalSystem& system) const override {
    return system.velocity_dependence() != VelocityDependence::kNone;
  }

 protected:
  // For the compositions of Verlet steps (yoshida.h).
  explicit VelocityVerlet(IntegratorInfo info) : Integrator(std::move(info)) {}

  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  // Sets v_ from the closing half-kick and a_ to the acceleration at the new state.
  StepResult closing_kick(double t, double h, const Vector& v_half);
  // The same by Newton, for forces that are not affine in v.
  StepResult nonlinear_closing_kick(double t, double h, const Vector& v_half);

  bool have_acceleration_ = false;
  Vector a_, f0_, rhs_, v_half_, dv_, v_try_, f_try_, r_try_;
  SparseMatrix dfdv_, lhs_;
  SparseDirectSolver solver_;
  long solver_version_ = -1;  // the pattern solver_ analysed (a fluid's varies)
};

}  // namespace springlab
