// The SUNDIALS Newton matrix solved at half its size (--linear-solver
// reduced, the default above 100 unknowns). CVODE and ARKODE solve
// (I - gamma J) dy = r and IDA solves G dy = r with the first-order
// matrices of first_order_jacobian.h (K = dF/dx, D = dF/dv, M the mass):
//
//   alpha J + beta I = [ beta I       alpha I            ]   (SUNDIALS scales
//                      [ alpha M^-1 K beta I + alpha M^-1 D ]    J to -gamma J + I)
//   G(cj)            = [ cj I   -I       ]
//                      [ -K     cj M - D ]
//
// Eliminating one half of dy = (a, b) leaves a system of n unknowns whose
// matrix is the one implicit Euler's Newton factors (M - h D - h^2 K):
//
//   ODE: (beta^2 M + alpha beta D - alpha^2 K) b = beta M s - alpha K r,
//        a = (r - alpha b) / beta                  (alpha = -gamma, beta = 1)
//   DAE: (cj^2 M - cj D - K) a = s + (cj M - D) r,   b = cj a - r
//
// (the Schur complement of the first block, the usual reduction of a
// second-order system's Newton matrix). SparseDirectSolver factors it:
// CHOLMOD's supernodal LL^T where it is definite, LDL^T or LU otherwise.
// KLU on the 2n x 2n matrix fills in badly on a 2-D mesh
// (docs/integrators.md "SUNDIALS" has the measured cost of both).
//
// SUNDIALS sees a matrix object of its own kind (SUNMATRIX_CUSTOM) that
// holds no entries, only what it stands for (ReducedForm): the Jacobian
// callbacks set it to J or G(cj), SUNDIALS scales it and adds I as it does
// a dense or sparse one, and the solver reads the form in its setup. dF/dx
// and dF/dv stay in the integrator's matrices (ReducedSystem).
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include "integrators/sundials/first_order_jacobian.h"
#include "models/core/mechanical_system.h"

namespace springlab::sundials {

// Where the reduced matrices read the model's Jacobians (the integrator's,
// alive as long as the matrix and the solver).
struct ReducedSystem {
  const MechanicalSystem* system = nullptr;
  const SparseMatrix* dfdx = nullptr;  // K
  const SparseMatrix* dfdv = nullptr;  // D
  const FirstOrderJacobian* jacobian = nullptr;  // the products, for matvec
};

// What the matrix stands for.
struct ReducedForm {
  bool dae = false;
  double alpha = 0.0, beta = 0.0;  // ODE: alpha J + beta I
  double cj = 0.0;                 // DAE: G(cj)
};

// The placeholder matrix and the solver (both freed by SUNDIALS' destroy
// and free calls, as any SUNMatrix and SUNLinearSolver).
SUNMatrix make_reduced_matrix(const ReducedSystem& system, SUNContext context);
SUNLinearSolver make_reduced_solver(const ReducedSystem& system, SUNContext context);
bool is_reduced(SUNMatrix m);
// The Jacobian callbacks: the matrix now stands for J, or for G(cj).
void set_ode_jacobian(SUNMatrix J);
void set_dae_jacobian(SUNMatrix G, double cj);
const ReducedForm& reduced_form(SUNMatrix m);

}  // namespace springlab::sundials
