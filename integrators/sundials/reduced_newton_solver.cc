#include "integrators/sundials/reduced_newton_solver.h"

#include <nvector/nvector_serial.h>

#include <memory>

#include "integrators/linear/sparse_direct_solver.h"

namespace springlab::sundials {
namespace {

struct MatrixContent {
  ReducedForm form;
  ReducedSystem system;
};

MatrixContent& content_of(SUNMatrix m) { return *static_cast<MatrixContent*>(m->content); }

// The n x n matrix of the header, factored, and the two halves' solve.
class ReducedSolver {
 public:
  explicit ReducedSolver(const ReducedSystem& system) : system_(system) {}

  int setup(const ReducedForm& f) {
    const SparseMatrix& K = *system_.dfdx;
    const SparseMatrix& D = *system_.dfdv;
    const Vector& M = system_.system->mass();
    if (f.dae) {
      // cj^2 M - cj D - K
      S_ = -K;
      if (D.size() > 0) S_ -= f.cj * D;
      S_.diagonal() += f.cj * f.cj * M;
    } else {
      if (f.beta == 0.0) return SUNLS_PACKAGE_FAIL_REC;  // alpha J alone: never asked
      // beta^2 M + alpha beta D - alpha^2 K
      S_ = -(f.alpha * f.alpha) * K;
      if (D.size() > 0) S_ += (f.alpha * f.beta) * D;
      S_.diagonal() += f.beta * f.beta * M;
    }
    const MatrixKind kind = system_.system->jacobian_symmetric() ? MatrixKind::kPositiveDefinite
                                                                 : MatrixKind::kGeneral;
    last_flag_ = direct_.factorize(S_, kind) ? SUNLS_SUCCESS : SUNLS_LUFACT_FAIL;
    return last_flag_;
  }

  int solve(const ReducedForm& f, const double* in, double* out) {
    const Eigen::Index n = S_.rows();
    const Eigen::Map<const Vector> r(in, n), s(in + n, n);
    Eigen::Map<Vector> a(out, n), b(out + n, n);
    const SparseMatrix& K = *system_.dfdx;
    const SparseMatrix& D = *system_.dfdv;
    const Vector& M = system_.system->mass();
    if (f.dae) {
      // (cj^2 M - cj D - K) a = s + (cj M - D) r,  b = cj a - r
      rhs_ = s + f.cj * M.cwiseProduct(r);
      if (D.size() > 0) rhs_ -= D * r;
      if (!direct_.solve(rhs_, half_)) return last_flag_ = SUNLS_PACKAGE_FAIL_REC;
      a = half_;
      b = f.cj * half_ - r;
    } else {
      // (beta^2 M + alpha beta D - alpha^2 K) b = beta M s - alpha K r,
      // a = (r - alpha b) / beta
      rhs_ = f.beta * M.cwiseProduct(s) - f.alpha * (K * r);
      if (!direct_.solve(rhs_, half_)) return last_flag_ = SUNLS_PACKAGE_FAIL_REC;
      b = half_;
      a = (r - f.alpha * half_) / f.beta;
    }
    return last_flag_ = SUNLS_SUCCESS;
  }

  int last_flag() const { return last_flag_; }

 private:
  ReducedSystem system_;
  SparseDirectSolver direct_;
  SparseMatrix S_;
  Vector rhs_, half_;
  int last_flag_ = SUNLS_SUCCESS;
};

ReducedSolver& solver_of(SUNLinearSolver s) { return *static_cast<ReducedSolver*>(s->content); }

// The matrix's operations: it holds a form, which SUNDIALS copies, zeroes,
// and scales (A <- c A + I: alpha, beta <- c alpha, c beta + 1).
SUNMatrix_ID matrix_id(SUNMatrix) { return SUNMATRIX_CUSTOM; }
SUNMatrix matrix_clone(SUNMatrix m) {
  return make_reduced_matrix(content_of(m).system, m->sunctx);
}
void matrix_destroy(SUNMatrix m) {
  if (m == nullptr) return;
  delete static_cast<MatrixContent*>(m->content);
  m->content = nullptr;
  SUNMatFreeEmpty(m);
}
int matrix_zero(SUNMatrix m) {
  content_of(m).form = {};
  return 0;
}
int matrix_copy(SUNMatrix from, SUNMatrix to) {
  content_of(to).form = content_of(from).form;
  return 0;
}
int matrix_scale_add_identity(realtype c, SUNMatrix m) {
  ReducedForm& f = content_of(m).form;
  if (f.dae) return -1;  // IDA forms G itself
  f.alpha *= c;
  f.beta = c * f.beta + 1.0;
  return 0;
}
// y = A x, from the first-order products (for checks; the solvers never ask).
int matrix_times(SUNMatrix m, N_Vector x, N_Vector y) {
  const MatrixContent& c = content_of(m);
  const double* in = N_VGetArrayPointer(x);
  double* out = N_VGetArrayPointer(y);
  if (c.form.dae) {
    c.system.jacobian->dae_times(*c.system.dfdx, *c.system.dfdv, c.form.cj, in, out);
    return 0;
  }
  c.system.jacobian->ode_times(*c.system.dfdx, *c.system.dfdv, in, out);
  const Eigen::Index size = N_VGetLength(x);
  Eigen::Map<Vector>(out, size) =
      c.form.alpha * Eigen::Map<Vector>(out, size) + c.form.beta * Eigen::Map<const Vector>(in, size);
  return 0;
}
int matrix_space(SUNMatrix, long* real_words, long* integer_words) {
  *real_words = 3;
  *integer_words = 1;
  return 0;
}

SUNLinearSolver_Type solver_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID solver_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int solver_initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }
int solver_setup(SUNLinearSolver s, SUNMatrix m) { return solver_of(s).setup(content_of(m).form); }
int solver_solve(SUNLinearSolver s, SUNMatrix m, N_Vector x, N_Vector b, realtype) {
  return solver_of(s).solve(content_of(m).form, N_VGetArrayPointer(b), N_VGetArrayPointer(x));
}
sunindextype solver_last_flag(SUNLinearSolver s) { return solver_of(s).last_flag(); }
int solver_free(SUNLinearSolver s) {
  if (s == nullptr) return SUNLS_SUCCESS;
  delete static_cast<ReducedSolver*>(s->content);
  s->content = nullptr;
  SUNLinSolFreeEmpty(s);
  return SUNLS_SUCCESS;
}

}  // namespace

SUNMatrix make_reduced_matrix(const ReducedSystem& system, SUNContext context) {
  SUNMatrix m = SUNMatNewEmpty(context);
  if (m == nullptr) return nullptr;
  m->ops->getid = matrix_id;
  m->ops->clone = matrix_clone;
  m->ops->destroy = matrix_destroy;
  m->ops->zero = matrix_zero;
  m->ops->copy = matrix_copy;
  m->ops->scaleaddi = matrix_scale_add_identity;
  m->ops->matvec = matrix_times;
  m->ops->space = matrix_space;
  m->content = new MatrixContent{{}, system};
  return m;
}

SUNLinearSolver make_reduced_solver(const ReducedSystem& system, SUNContext context) {
  SUNLinearSolver s = SUNLinSolNewEmpty(context);
  if (s == nullptr) return nullptr;
  s->ops->gettype = solver_type;
  s->ops->getid = solver_id;
  s->ops->initialize = solver_initialize;
  s->ops->setup = solver_setup;
  s->ops->solve = solver_solve;
  s->ops->lastflag = solver_last_flag;
  s->ops->free = solver_free;
  s->content = new ReducedSolver(system);
  return s;
}

bool is_reduced(SUNMatrix m) {
  return m != nullptr && m->ops->getid == matrix_id;
}

void set_ode_jacobian(SUNMatrix J) { content_of(J).form = {.dae = false, .alpha = 1.0, .beta = 0.0}; }

void set_dae_jacobian(SUNMatrix G, double cj) { content_of(G).form = {.dae = true, .cj = cj}; }

const ReducedForm& reduced_form(SUNMatrix m) { return content_of(m).form; }

}  // namespace springlab::sundials
