#include "integrators/methods/symplectic_euler.h"

#include "integrators/core/integrator_entry.h"

namespace springlab {

SymplecticEuler::SymplecticEuler()
    : Integrator({.name = "symplectic-euler",
                  .scheme = "v' = v + h M^-1 F(t, x, v),  x' = x + h v'",
                  .order = 1,
                  .symplectic = true,
                  .stability = StabilityKind::kConditional,
                  .stability_limit = 2.0,
                  // It conserves (v^2 + w^2 x^2 - w^2 h x v)/2, whose level
                  // set holds E between 1 -+ w h/2 times it.
                  .energy_excursion = [](double wh) { return (1.0 + wh / 2.0) / (1.0 - wh / 2.0); }}) {}

namespace {

// v += h M^-1 f, then x += h v: a = M^-1 F, the kick and the drift in one
// pass (three as separate vector operations), each entry rounded exactly as
// v += h a, x += h v. The arrays never overlap (__restrict lets the compiler
// vectorize without run-time alias checks).
void kick_drift(Eigen::Index n, double h, const double* __restrict f,
                const double* __restrict inv_m, double* __restrict x, double* __restrict v) {
  for (Eigen::Index i = 0; i < n; ++i) {
    v[i] += h * (f[i] * inv_m[i]);
    x[i] += h * v[i];
  }
}

}  // namespace

StepResult SymplecticEuler::do_step(double h) {
  eval_force(t_, x_, v_, f_);
  kick_drift(x_.size(), h, f_.data(), inv_mass().data(), x_.data(), v_.data());
  return StepResult::success();
}

SPRINGLAB_INTEGRATOR(SymplecticEuler, symplectic_euler_integrator)

}  // namespace springlab
