#include "integrators/symplectic_euler.h"

namespace springlab {

SymplecticEuler::SymplecticEuler()
    : Integrator({.name = "symplectic-euler",
                  .scheme = "v' = v + h M^-1 F(t, x, v),  x' = x + h v'",
                  .order = 1,
                  .symplectic = true,
                  .stability = StabilityKind::kConditional,
                  .stability_limit = 2.0}) {}

namespace {

// v' = v + h M^-1 f, then x' = x + h v': a = M^-1 F, the kick and the
// drift in one pass (three as separate vector operations), each entry
// rounded exactly as v += h a, x += h v; the new state goes to (x', v'),
// the start stays in (x, v). The arrays never overlap (__restrict lets the
// compiler vectorize without run-time alias checks).
void kick_drift(Eigen::Index n, double h, const double* __restrict f,
                const double* __restrict inv_m, const double* __restrict x,
                const double* __restrict v, double* __restrict x_new, double* __restrict v_new) {
  for (Eigen::Index i = 0; i < n; ++i) {
    v_new[i] = v[i] + h * (f[i] * inv_m[i]);
    x_new[i] = x[i] + h * v_new[i];
  }
}

}  // namespace

StepResult SymplecticEuler::do_step(double h) {
  eval_force(t_, x_, v_, f_);
  // The start becomes the previous state; the step writes into the
  // buffers of the one before (swaps of pointers, no copy).
  start_.t = t_;
  start_.x.swap(x_);
  start_.v.swap(v_);
  const Eigen::Index n = start_.x.size();
  x_.resize(n);  // (allocates at the first step only)
  v_.resize(n);
  kick_drift(n, h, f_.data(), inv_mass().data(), start_.x.data(), start_.v.data(), x_.data(),
             v_.data());
  return StepResult::success();
}

}  // namespace springlab
