// xpbd_reference: a plain XPBD, written for comparison only (issue 37). It
// shares no code with springlab's solvers: one file (and the references'
// reference_scene.h: the command line, the scene file, the energies, the time
// loop and the output), a scene file in, a few numbers out, so that `springlab run --integrator xpbd` can be timed and
// checked against it (benchmarks/bench_fast_reference.cc).
//
//   xpbd_reference SCENE.json --dt H --t-end T [--substeps S] [--iterations N]
//
// The method (Macklin, Mueller and Chentanez, "XPBD", MIG 2016; Macklin et
// al., "Small Steps in Physics Simulation", SCA 2019). Each step of H is S
// substeps of h = H/S; each substep:
//   v += h F_ext(t, x, v) / m            (gravity, drag, wind, spring damping)
//   p = x + h v
//   lambda = 0 for every spring
//   N times, for every spring (i, j) in the file's order (Gauss-Seidel):
//     C = |p_i - p_j| - L,  n = (p_i - p_j) / |p_i - p_j|,  a = 1 / (k h^2)
//     dl = (-C - a lambda) / (w_i + w_j + a)       (w = 1/m, 0 when fixed)
//     p_i += w_i dl n,  p_j -= w_j dl n,  lambda += dl
//   v = (p - x) / h,  x = p
// Fixed particles never move (w = 0). It stops when the state turns
// non-finite or the kinetic + spring energy passes 1000 times the scene's
// energy scale (as `springlab run` does by default) and prints one JSON line:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., "x_sum": ..}
// (x_sum: the sum of all coordinates at the end, a fingerprint of the run).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "reference_scene.h"

using reference::Spring;

int main(int argc, char** argv) {
  reference::CommandLine args;
  int substeps = 10, iterations = 1;
  if (!reference::read_command_line("xpbd_reference", argc, argv,
                                    {{"--substeps", "S", &substeps}, {"--iterations", "N", &iterations}}, args)) {
    return 2;
  }

  // The scene, with spring damping and wind; other keys (planes, elements, ...) are ignored.
  reference::Scene scene;
  reference::read_scene(args.scene, {.ignore_other_keys = true, .spring_damping = true, .wind = true}, scene);
  const int D = scene.D, n = scene.n;
  const std::vector<double>& m = scene.m;
  const std::vector<Spring>& springs = scene.springs;
  const reference::Wind& wind = scene.wind;
  std::vector<double> x = scene.x, v = scene.v, p(n * D), w(n);
  for (int i = 0; i < n; ++i) w[i] = scene.fixed(i) ? 0.0 : 1.0 / m[i];
  bool damped = false;
  for (const Spring& s : springs) damped = damped || s.damping > 0.0;

  auto kinetic_plus_spring = [&] { return reference::spring_energy(scene, x, reference::kinetic_energy(scene, v)); };
  reference::TimeLoop loop(args.dt, args.t_end, reference::energy_scale(scene, kinetic_plus_spring()));
  const double pi = std::acos(-1.0);
  std::vector<double> lambda(springs.size());
  while (loop.running()) {
    const double H = loop.h(), t = loop.t;
    const double h = H / substeps;
    for (int s = 0; s < substeps; ++s) {
      const double ts = t + s * h;
      // Explicit forces.
      const double gust_factor = 1.0 + wind.gust * std::sin(2.0 * pi * wind.frequency * ts);
      for (int i = 0; i < n; ++i) {
        if (w[i] == 0.0) continue;
        for (int r = 0; r < D; ++r) {
          const double f = m[i] * scene.g[r] - scene.drag * v[i * D + r] +
                           wind.coefficient * (wind.velocity[r] * gust_factor - v[i * D + r]);
          v[i * D + r] += h * w[i] * f;
        }
      }
      if (damped) {
        // Spring damping from the velocities at the substep's start.
        std::vector<double> dv(n * D, 0.0);
        for (const Spring& sp : springs) {
          if (sp.damping == 0.0) continue;
          double d[3] = {0, 0, 0}, l = 0.0, rel = 0.0;
          for (int r = 0; r < D; ++r) {
            d[r] = x[sp.i * D + r] - x[sp.j * D + r];
            l += d[r] * d[r];
          }
          l = std::sqrt(l);
          if (l == 0.0) continue;
          for (int r = 0; r < D; ++r) rel += (v[sp.i * D + r] - v[sp.j * D + r]) * d[r] / l;
          for (int r = 0; r < D; ++r) {
            const double f = -sp.damping * rel * d[r] / l;
            dv[sp.i * D + r] += h * w[sp.i] * f;
            dv[sp.j * D + r] -= h * w[sp.j] * f;
          }
        }
        for (int k = 0; k < n * D; ++k) v[k] += dv[k];
      }
      for (int k = 0; k < n * D; ++k) p[k] = x[k] + h * v[k];
      std::fill(lambda.begin(), lambda.end(), 0.0);
      for (int it = 0; it < iterations; ++it) {
        for (std::size_t c = 0; c < springs.size(); ++c) {
          const Spring& sp = springs[c];
          const double wsum = w[sp.i] + w[sp.j];
          if (wsum == 0.0 || sp.k == 0.0) continue;
          double d[3] = {0, 0, 0}, l = 0.0;
          for (int r = 0; r < D; ++r) {
            d[r] = p[sp.i * D + r] - p[sp.j * D + r];
            l += d[r] * d[r];
          }
          l = std::sqrt(l);
          if (l == 0.0) continue;
          const double alpha = 1.0 / (sp.k * h * h);
          const double dl = (-(l - sp.rest) - alpha * lambda[c]) / (wsum + alpha);
          for (int r = 0; r < D; ++r) {
            p[sp.i * D + r] += w[sp.i] * dl * d[r] / l;
            p[sp.j * D + r] -= w[sp.j] * dl * d[r] / l;
          }
          lambda[c] += dl;
        }
      }
      for (int k = 0; k < n * D; ++k) {
        v[k] = (p[k] - x[k]) / h;
        x[k] = p[k];
      }
    }
    loop.step_done(H, kinetic_plus_spring());
  }
  reference::print_summary(loop, kinetic_plus_spring() + reference::gravity_energy(scene, x), args.start,
                           {{"x_sum", reference::number(reference::coordinate_sum(x))}});
  return 0;
}
