// Backward Euler by textbook Newton, with nothing else: the reference the
// tests compare implicit-euler's step with (as models/fem/fem_force.cc is for
// tet_force.cc). One step from (t_n, x_n, v_n) of size h solves
//
//   r(v) = M (v - v_n) - h F(t_n + h, x_n + h v, v) = 0
//
// for v = v_{n+1} by full Newton updates from v = v_n,
//
//   J dv = -r,   J = dr/dv = M - h dF/dv - h^2 dF/dx,   v <- v + dv,
//
// J factored by Eigen's dense LU with partial pivoting (or its
// simplicial LDL^T above kDenseLimit unknowns), until ||dv||_inf <= tol;
// x_{n+1} = x_n + h v_{n+1}. No line search, no definite matrix, no kept
// factor, no inexact solve: where those matter (large steps on a buckling
// cloth) the reference may not converge, and says so. As implicit-euler,
// friction's normal forces are those of x_n during the step
// (MechanicalSystem::lag_normal_forces): that is part of the step's
// equations, not of how they are solved.
#pragma once

#include <string>

#include "models/core/mechanical_system.h"

namespace springlab {

struct ReferenceStepResult {
  bool ok = false;
  int iterations = 0;
  std::string message;  // why it failed
};

// Advances (x, v) from t by one backward Euler step of h, to ||dv||_inf <=
// tol in at most max_iterations Newton iterations.
ReferenceStepResult reference_backward_euler_step(const MechanicalSystem& system, double t,
                                                  double h, double tol, int max_iterations,
                                                  Vector& x, Vector& v);

}  // namespace springlab
