// Preconditioned conjugate gradients for the Newton system A d = b of an
// implicit step, A symmetric (the Jacobian, maybe indefinite), started from
// d = 0 and preconditioned by a positive definite matrix P given by its
// factorization (SparseDirectSolver), typically one kept from an earlier
// Newton iteration or step: with P close to A, a few iterations of a sparse
// product and two triangular solves replace a new factorization.
//
// Truncated at negative curvature (Nocedal and Wright, "Numerical
// Optimization", Algorithm 7.1, line-search Newton-CG): when a search
// direction p has p^T A p <= 0, A is not positive definite along it; CG
// stops and returns the iterate it has, or P^-1 b if it has none yet. When b
// is minus the gradient of a function and A its Hessian, every iterate of CG
// from 0 is a descent direction (each minimizes the quadratic model over a
// growing Krylov space on which A is positive definite), and so is P^-1 b:
// the result always descends, whatever A's inertia.
//
// Stops (converged) when the error of d, estimated by the preconditioned
// residual z = P^-1 (b - A d) (exact were P = A), is small in the max norm:
// ||z||_inf <= max(rtol ||d||_inf, atol); or after max_iterations (not
// converged: P is too far from A). The max norm of an update is what the
// Newton stop measures, in the update's own units (m/s).
#pragma once

#include <functional>

#include "integrators/linear/sparse_direct_solver.h"
#include "models/core/mechanical_system.h"

namespace springlab {

struct CgResult {
  int iterations = 0;       // products with A (= preconditioner solves)
  bool converged = false;
  bool negative_curvature = false;
  bool finite = true;       // false when a solve with P or A p was not finite
};

// The product q = A p where A is not assembled (MechanicalSystem::
// jacobian_products): Krylov methods need nothing else of A.
using LinearProduct = std::function<void(const Vector& p, Vector& q)>;

// Scratch vectors are the caller's, so repeated solves do not allocate.
struct CgScratch {
  Vector r, z, p, q;
};
CgResult preconditioned_cg(const SparseMatrix& a, SparseDirectSolver& p,
                           const Vector& b, double rtol, double atol, int max_iterations,
                           Vector& d, CgScratch& scratch);
CgResult preconditioned_cg(const LinearProduct& a, SparseDirectSolver& p, const Vector& b,
                           double rtol, double atol, int max_iterations, Vector& d,
                           CgScratch& scratch);

}  // namespace springlab
