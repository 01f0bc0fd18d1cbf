// The SUNDIALS solvers see the first-order form of M x'' = F(t, x, v):
//
//   y = (x, v),   y' = f(t, y) = (v, M^-1 F(t, x, v))             (CVODE, ARKODE)
//   R(t, y, y') = (x' - v, M v' - F(t, x, v)) = 0                 (IDA)
//
// with the matrices their Newton iterations need, built from the model's
// analytic dF/dx and dF/dv (K, D below):
//
//   J = df/dy              = [ 0        I       ]
//                            [ M^-1 K   M^-1 D  ]
//   G = dR/dy + cj dR/dy'  = [ cj I     -I      ]
//                            [ -K       cj M - D ]
//
// Both have one CSC pattern, derived once from the model's (which holds the
// full diagonal): column c of the x-block holds row c (the diagonal SUNDIALS
// adds gamma to) and rows n + (rows of the model's column c); column n + c of
// the v-block holds row c (the identity) and rows n + (rows of column c).
#pragma once

#include <sundials/sundials_matrix.h>

#include <vector>

#include "models/core/mechanical_system.h"

namespace springlab::sundials {

class FirstOrderJacobian {
 public:
  explicit FirstOrderJacobian(const MechanicalSystem& system);

  long nonzeros() const { return static_cast<long>(row_index_.size()); }

  // Writes J (or G) into a dense or CSC sparse SUNMatrix of size 2n x 2n.
  void fill_ode(const SparseMatrix& dfdx, const SparseMatrix& dfdv, SUNMatrix out) const;
  void fill_dae(const SparseMatrix& dfdx, const SparseMatrix& dfdv, double cj, SUNMatrix out) const;

  // out = J in, and out = G in (matrix-free Krylov solvers).
  void ode_times(const SparseMatrix& dfdx, const SparseMatrix& dfdv, const double* in,
                 double* out) const;
  void dae_times(const SparseMatrix& dfdx, const SparseMatrix& dfdv, double cj, const double* in,
                 double* out) const;

 private:
  // Value of each entry of the 2n pattern, in CSC order, from the blocks.
  template <class Entry>
  void fill(SUNMatrix out, Entry entry) const;

  const MechanicalSystem& system_;
  long n_;
  std::vector<long> column_start_;  // 2n + 1
  std::vector<long> row_index_;
};

}  // namespace springlab::sundials
