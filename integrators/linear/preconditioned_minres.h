// Preconditioned MINRES (Paige and Saunders 1975) for a symmetric, possibly
// indefinite system A d = b -- linear-implicit Euler's step matrix with the
// exact stiffness, M - h^2 dF/dx, is indefinite where springs are compressed,
// and conjugate gradients may then break down -- preconditioned by a
// positive definite P given by its factorization (the kept Cholesky factor
// of the definite matrix, as for CG). Each iteration: one product with A,
// one solve with P. MINRES minimizes the residual in the P^-1 norm over the
// Krylov space, so it never breaks down on an indefinite A.
//
// Stops (converged) when that residual norm, ||b - A d||_{P^-1}, is below
// rtol times its initial value, or after max_iterations (not converged).
// The recurrences follow SciPy's scipy.sparse.linalg.minres, a port of
// Paige and Saunders' own MINRES.
#pragma once

#include "integrators/linear/preconditioned_cg.h"

namespace springlab {

struct MinresScratch {
  Vector r1, r2, y, v, w, w1, w2;
};
CgResult preconditioned_minres(const SparseMatrix& a, SparseDirectSolver& p, const Vector& b,
                               double rtol, int max_iterations, Vector& d,
                               MinresScratch& scratch);
CgResult preconditioned_minres(const LinearProduct& a, SparseDirectSolver& p, const Vector& b,
                               double rtol, int max_iterations, Vector& d,
                               MinresScratch& scratch);

}  // namespace springlab
