#include "integrators/integrator.h"

#include <cmath>

namespace springlab {

StepResult Integrator::initialize(const MechanicalSystem& system, double t0, const Vector& x0,
                                  const Vector& v0, const IntegratorOptions& options) {
  system_ = &system;
  options_ = options;
  stats_ = {};
  t_ = t0;
  x_ = x0;
  v_ = v0;
  inv_mass_ = system.mass().cwiseInverse();
  return do_initialize();
}

StepResult Integrator::advance_to(double t_out) {
  const double h = t_out - t_;
  if (!(h > 0.0)) return StepResult::failure(name() + ": step size must be positive");
  StepResult result = do_step(h);
  if (!result.ok) return result;
  t_ = t_out;  // exactly, so fixed-step times do not drift
  ++stats_.steps;
  return result;
}

void Integrator::eval_force(double t, const Vector& x, const Vector& v, Vector& f) {
  ++stats_.force_evals;
  system_->force(t, x, v, f);
}

void Integrator::eval_acceleration(double t, const Vector& x, const Vector& v, Vector& a) {
  eval_force(t, x, v, a);
  a.array() *= inv_mass_.array();
}

void Integrator::eval_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                                SparseMatrix* dfdv) {
  ++stats_.jacobian_evals;
  system_->jacobians(t, x, v, dfdx, dfdv);
}

void Integrator::eval_definite_jacobians(double t, const Vector& x, const Vector& v,
                                         SparseMatrix* dfdx, SparseMatrix* dfdv) {
  ++stats_.jacobian_evals;
  system_->definite_jacobians(t, x, v, dfdx, dfdv);
}

}  // namespace springlab
