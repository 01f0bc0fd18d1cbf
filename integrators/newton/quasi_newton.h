// implicit-euler --solver quasi-newton (docs/integrators.md "Fast
// solvers"): the step's incremental potential Phi(v) (velocity_step.h)
// minimized by L-BFGS instead of Newton (Liu, Bouaziz and Kavan,
// "Quasi-Newton methods for real-time simulation of hyperelastic
// materials", ACM TOG 2017); quasi_newton.cc has the method.
#pragma once

#include <vector>

#include "integrators/linear/sparse_direct_solver.h"
#include "integrators/newton/velocity_step.h"

namespace springlab {

class Lbfgs {
 public:
  // Builds the initial Hessian's Laplacian; false when the system's stiff
  // forces are not distance constraints or elements (another force), or it
  // has no fast solvers' views (models/core/fast_solver_views.h).
  bool prepare(const MechanicalSystem& system);
  // Minimizes the step's Phi from projective dynamics' inertial prediction
  // to the tolerance (m/s) in at most max_iterations; true with v the
  // minimizer, false where L-BFGS stalls (then Newton solves the step).
  // inv_mass: M^-1 as a vector.
  bool solve(VelocityStep& step, const CountedModel& model, const Vector& inv_mass, double tol,
             int max_iterations, Vector& v);

 private:
  // Factors H0 for the step size h (once per h).
  bool factor_h0(double h, double b, IntegratorStats& stats);
  // z = H0^-1 q, the coordinates as the columns of an n x dim matrix.
  bool apply_h0_inverse(IntegratorStats& stats);
  // d = -H r by the two-loop recursion (H0 alone where the history gives
  // no descent direction), and the slope r.d.
  bool direction(IntegratorStats& stats, double& slope);
  // Armijo on Phi from the full step d, then the extrapolation: the trial
  // in v_try_, r_try_ at step_length, with its Phi, and a*.
  bool search(VelocityStep& step, const Vector& v, double phi, double magnitude, double slope,
              double& step_length, double& phi_try, double& a_star);
  // Keeps the pair (step_length d, r_try - r) where it has positive
  // curvature, the last kHistory of them.
  void remember(double step_length);

  // The particles' stiffness Laplacian L of the distance constraints, the
  // factor of M_p + h^2 L (one per step size), and the L-BFGS history.
  const FastSolverViews* views_ = nullptr;  // the system's (prepare)
  int dim_ = 0;
  SparseMatrix laplacian_;
  Vector particle_mass_;
  SparseDirectSolver factor_{FactorUse::kSolvedOften};
  double factored_h_ = 0.0;
  std::vector<Vector> s_, y_;  // the last updates and gradient changes
  std::vector<double> rho_;    // 1 / (y . s)
  Vector r_, q_, z_, v_try_, r_try_, v_long_, r_long_, d_;
  double magnitude_try_ = 0.0;
  Eigen::MatrixXd columns_, solved_;  // n x dim: one coordinate per column
};

}  // namespace springlab
