// pd_reference: a plain projective dynamics on a mass-spring scene, written
// for comparison only (issue 37). It shares no code with springlab's solvers:
// one file (and the references' reference_scene.h: the command line, the
// scene file, the energies, the time loop, the matrix below and the output),
// a scene file in, a few numbers out, so that `springlab run
// --integrator projective-dynamics` can be timed and checked against it
// (benchmarks/bench_fast_reference.cc).
//
//   pd_reference SCENE.json --dt H --t-end T [--iterations N] [--positions FILE]
//
// The method (Liu, Bargteil, O'Brien and Kavan, "Fast simulation of
// mass-spring systems", SIGGRAPH Asia 2013). Implicit Euler's step with
// gravity g, drag -gamma v and springs (i, j) of stiffness k, rest length L:
//   M (x' - x - h v) / h^2 = M g - gamma (x' - x) / h - grad E(x'),
// E(x) = sum k/2 (|x_i - x_j| - L)^2 = min over |d| = L of
// sum k/2 |x_i - x_j - d|^2. With y = x + h v + h^2 (g - gamma v / m) (the
// forces at the step's start) this is, times h^2,
//   (M + h gamma I + h^2 Lap) x' = M y + h gamma (x + h v) + h^2 J d
// (Lap = sum k (e_i - e_j)(e_i - e_j)^T over the free particles; a spring to
// a fixed particle j puts k on i's diagonal and k x_j into J d). Starting
// from x' = y, N times (default 10):
//   local:  d = L (x'_i - x'_j) / |x'_i - x'_j| for every spring;
//   global: solve the system above for x' (x, y and z as three columns of
//           one right-hand side).
// Then v = (x' - x) / h, x = x'. The matrix depends only on h: it is
// factored once, by CHOLMOD's simplicial LL^T through Eigen
// (Eigen::CholmodSimplicialLLT, CHOLMOD's default ordering), and kept.
// Wind and spring damping are not modelled: such a scene is refused.
// It stops when the state turns non-finite or the kinetic + spring energy
// passes 1000 times the scene's energy scale (as `springlab run` does by
// default) and prints one JSON line:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., "x_sum": ..}
// With --positions FILE it also writes the final positions, one line
// "i,x,y[,z]" per particle (scene index, %.17g).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "reference_scene.h"

using reference::Spring;

int main(int argc, char** argv) {
  reference::CommandLine args;
  int iterations = 10;
  std::string positions_file;
  if (!reference::read_command_line("pd_reference", argc, argv,
                                    {{"--iterations", "N", &iterations}, {"--positions", "FILE", &positions_file}},
                                    args)) {
    return 2;
  }

  // The scene: spring damping and wind are refused, other keys (planes, elements, ...) ignored.
  reference::Scene scene;
  const reference::Refusal refusal = reference::read_scene(args.scene, {.ignore_other_keys = true}, scene);
  if (refusal.what == reference::Unmodelled::kSpringDamping) {
    std::fprintf(stderr, "pd_reference: spring damping is not modelled\n");
    return 2;
  }
  if (refusal.what == reference::Unmodelled::kWind) {
    std::fprintf(stderr, "pd_reference: wind is not modelled\n");
    return 2;
  }
  const int D = scene.D, n = scene.n, free = scene.free;
  const std::vector<int>& row = scene.row;  // the particle's row in the matrix; -1: fixed
  const std::vector<double>& m = scene.m;
  const double drag = scene.drag;
  std::vector<double> x = scene.x, v = scene.v;

  auto kinetic_plus_spring = [&] { return reference::spring_energy(scene, x, reference::kinetic_energy(scene, v)); };
  reference::TimeLoop loop(args.dt, args.t_end, reference::energy_scale(scene, kinetic_plus_spring()));

  // The global matrix M + h gamma I + h^2 Lap for one h, factored once and kept.
  Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
  double factored_h = 0.0;
  auto factorize = [&](double h) {
    factor.compute(reference::mass_spring_matrix(scene, h, drag));
    factored_h = h;
    return factor.info() == Eigen::Success;
  };

  Eigen::MatrixXd y(free, D), rhs0(free, D), rhs(free, D), xn(free, D);
  while (loop.running()) {
    const double h = loop.h();
    if (std::abs(h - factored_h) > 1e-12 * h && !factorize(h)) {
      std::fprintf(stderr, "pd_reference: the global matrix is not positive definite\n");
      return 1;
    }
    // y, and the part of the right-hand side that stays: M y + h gamma (x + h v).
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        const double xi = x[i * D + r], vi = v[i * D + r];
        y(row[i], r) = xi + h * vi + h * h * (scene.g[r] - drag * vi / m[i]);
        rhs0(row[i], r) = m[i] * y(row[i], r) + h * drag * (xi + h * vi);
      }
    }
    xn = y;
    auto position = [&](int p, int r) { return row[p] >= 0 ? xn(row[p], r) : x[p * D + r]; };
    for (int it = 0; it < iterations; ++it) {
      rhs = rhs0;
      for (const Spring& s : scene.springs) {  // local steps, into the right-hand side
        double d[3] = {0, 0, 0}, l = 0.0;
        for (int r = 0; r < D; ++r) {
          d[r] = position(s.i, r) - position(s.j, r);
          l += d[r] * d[r];
        }
        l = std::sqrt(l);
        const double w = h * h * s.k, c = l > 0.0 ? s.rest / l : 0.0;
        const int a = row[s.i], b = row[s.j];
        for (int r = 0; r < D; ++r) {
          if (a >= 0) rhs(a, r) += w * (c * d[r] + (b < 0 ? x[s.j * D + r] : 0.0));
          if (b >= 0) rhs(b, r) -= w * (c * d[r] - (a < 0 ? x[s.i * D + r] : 0.0));
        }
      }
      xn = factor.solve(rhs);  // the global step
    }
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        v[i * D + r] = (xn(row[i], r) - x[i * D + r]) / h;
        x[i * D + r] = xn(row[i], r);
      }
    }
    loop.step_done(h, kinetic_plus_spring());
  }
  if (!reference::write_positions(args.program, positions_file, scene, x)) return 1;
  reference::print_summary(loop, kinetic_plus_spring() + reference::gravity_energy(scene, x), args.start,
                           {{"x_sum", reference::number(reference::coordinate_sum(x))}});
  return 0;
}
