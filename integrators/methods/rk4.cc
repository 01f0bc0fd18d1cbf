#include "integrators/methods/rk4.h"

#include <cmath>

#include "integrators/core/integrator_entry.h"

namespace springlab {

RungeKutta4::RungeKutta4()
    : Integrator({.name = "rk4",
                  .scheme = "y' = y + h/6 (k1 + 2 k2 + 2 k3 + k4)",
                  .order = 4,
                  .stability = StabilityKind::kConditional,
                  .stability_limit = 2.0 * std::sqrt(2.0),
                  .stability_function = [](std::complex<double> z) {
                    return 1.0 + z * (1.0 + z / 2.0 * (1.0 + z / 3.0 * (1.0 + z / 4.0)));
                  }}) {}

// The stages are combined as they are produced: after each force
// evaluation one loop computes the stage's acceleration a_s = M^-1 F, adds
// its weighted k_s = (v_s, a_s) to the running sums and forms the next
// stage's state, instead of separate vector operations (each another pass
// over the state). The sums build v1 + 2 v2 + 2 v3 + v4 in that order, so
// every entry rounds exactly as the textbook expression does. The arrays
// never overlap; __restrict tells the compiler so, which lets it vectorize
// these loops (with eight pointers it will not version them for aliasing).
namespace {

// k1 = (v, M^-1 f); stage 2 state (xs, vs) = y + c k1.
void first_stage(Eigen::Index n, double c, const double* __restrict x,
                 const double* __restrict v, const double* __restrict f,
                 const double* __restrict inv_m, double* __restrict xs, double* __restrict vs,
                 double* __restrict sum_v, double* __restrict sum_a) {
  for (Eigen::Index i = 0; i < n; ++i) {
    const double a = f[i] * inv_m[i];
    sum_v[i] = v[i];
    sum_a[i] = a;
    xs[i] = x[i] + c * v[i];
    vs[i] = v[i] + c * a;
  }
}

// k = (vs, M^-1 f) of stage 2 or 3: sums += 2 k; next state (xs, vs) = y + c k.
void middle_stage(Eigen::Index n, double c, const double* __restrict x,
                  const double* __restrict v, const double* __restrict f,
                  const double* __restrict inv_m, double* __restrict xs, double* __restrict vs,
                  double* __restrict sum_v, double* __restrict sum_a) {
  for (Eigen::Index i = 0; i < n; ++i) {
    const double a = f[i] * inv_m[i];
    sum_v[i] += 2.0 * vs[i];
    sum_a[i] += 2.0 * a;
    xs[i] = x[i] + c * vs[i];
    vs[i] = v[i] + c * a;
  }
}

// k4 = (vs, M^-1 f); y += c (sums + k4) with c = h/6.
void last_stage(Eigen::Index n, double c, const double* __restrict vs,
                const double* __restrict f, const double* __restrict inv_m,
                const double* __restrict sum_v, const double* __restrict sum_a,
                double* __restrict x, double* __restrict v) {
  for (Eigen::Index i = 0; i < n; ++i) {
    x[i] += c * (sum_v[i] + vs[i]);
    v[i] += c * (sum_a[i] + f[i] * inv_m[i]);
  }
}

}  // namespace

StepResult RungeKutta4::do_step(double h) {
  const Eigen::Index n = x_.size();
  const double* inv_m = inv_mass().data();
  xs_.resize(n);
  vs_.resize(n);
  sum_v_.resize(n);
  sum_a_.resize(n);

  eval_force(t_, x_, v_, f_);
  first_stage(n, 0.5 * h, x_.data(), v_.data(), f_.data(), inv_m, xs_.data(), vs_.data(),
              sum_v_.data(), sum_a_.data());
  eval_force(t_ + 0.5 * h, xs_, vs_, f_);
  middle_stage(n, 0.5 * h, x_.data(), v_.data(), f_.data(), inv_m, xs_.data(), vs_.data(),
               sum_v_.data(), sum_a_.data());
  eval_force(t_ + 0.5 * h, xs_, vs_, f_);
  middle_stage(n, h, x_.data(), v_.data(), f_.data(), inv_m, xs_.data(), vs_.data(),
               sum_v_.data(), sum_a_.data());
  eval_force(t_ + h, xs_, vs_, f_);
  last_stage(n, h / 6.0, vs_.data(), f_.data(), inv_m, sum_v_.data(), sum_a_.data(), x_.data(),
             v_.data());
  return StepResult::success();
}

SPRINGLAB_INTEGRATOR(RungeKutta4, rk4_integrator)

}  // namespace springlab
