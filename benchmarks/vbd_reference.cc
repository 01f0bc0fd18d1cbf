// vbd_reference: a plain vertex block descent on a mass-spring scene,
// written for comparison only (issue 51). It shares no code with
// springlab's solvers: one file (and the references' reference_scene.h: the
// command line, the scene file, the energies, the time loop and the output),
// a scene file in, a few numbers out, so that
// `springlab run --integrator vbd` can be timed and checked against it
// (benchmarks/bench_fast_reference.cc).
//
//   vbd_reference SCENE.json --dt H --t-end T [--substeps S] [--iterations N]
//                 [--rho RHO] [--positions FILE]
//
// The method (Chen, Macklin et al., "Vertex Block Descent", SIGGRAPH 2024).
// Implicit Euler's positions minimize
//   G(x) = sum_i m_i / (2 h^2) |x_i - y_i|^2 + sum k/2 (|x_i - x_j| - L)^2
//          - sum_i m_i g.x_i + gamma |x - x_n|^2 / (2 h),   y = x_n + h v_n,
// (gravity g, drag -gamma v, springs (i, j) of stiffness k, rest length L).
// Per particle i, holding the others: the gradient and Hessian of G,
//   g_i = m_i / h^2 (x_i - y_i) - m_i g + gamma (x_i - x_n,i) / h
//         + sum_j t_ij d_ij,                d = x_i - x_j, t = k (1 - L/|d|),
//   H_i = (m_i / h^2 + gamma / h) I + sum_j [(k - t) d d^T / |d|^2 + t I],
// and the step x_i -= H_i^-1 g_i (Cholesky; where H_i is not positive
// definite, or the step is longer than |g_i| h^2 / m_i, the inertia's
// alone, again with every t clamped at 0; failing that, H_i's
// eigenvalues raised to at least m_i / h^2). The free particles are
// coloured greedily in scene order (each the smallest colour none of its
// spring neighbours has); an iteration sweeps the colours in order, each
// colour's particles in scene order. Initial guess: x = y + h^2 a g,
// a = clamp(a_n . g / |g|^2, 0, 1) with a_n = (v_n - v_n-1) / h (a = 1 at
// the first step). Chebyshev acceleration across iterations (Wang 2015):
// x^(k+1) = w (x^ - x^(k-1)) + x^(k-1), w_2 = 2 / (2 - rho^2),
// w_(k+1) = 4 / (4 - rho^2 w_k), no extrapolation after the first sweep;
// --rho 0: off (the default). Then v = (x - x_n) / h. A step of H is S
// substeps of h = H / S (default 1), each as above.
// Wind and spring damping are not modelled: such a scene is refused.
// It stops when the state turns non-finite or the kinetic + spring energy
// passes 1000 times the scene's energy scale (as `springlab run` does by
// default) and prints one JSON line:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., "x_sum": .., "colours": ..}
// With --positions FILE it also writes the final positions, one line
// "i,x,y[,z]" per particle (scene index, %.17g).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "reference_scene.h"

int main(int argc, char** argv) {
  reference::CommandLine args;
  double rho = 0.0;
  int iterations = 10, substeps = 1;
  std::string positions_file;
  if (!reference::read_command_line("vbd_reference", argc, argv,
                                    {{"--substeps", "S", &substeps},
                                     {"--iterations", "N", &iterations},
                                     {"--rho", "RHO", &rho},
                                     {"--positions", "FILE", &positions_file}},
                                    args)) {
    return 2;
  }
  reference::Scene scene;
  const reference::Refusal refusal =
      reference::read_scene(args.scene, {.ignore_other_keys = true, .dimension = 3}, scene);
  if (refusal.refused()) {
    const char* what = refusal.what == reference::Unmodelled::kDimension ? "3-D scenes only"
                       : refusal.what == reference::Unmodelled::kWind   ? "wind is not modelled"
                                                                        : "spring damping is not modelled";
    std::fprintf(stderr, "vbd_reference: %s\n", what);
    return 2;
  }
  const int n = scene.n;
  const std::vector<double>& m = scene.m;
  const std::vector<reference::Spring>& springs = scene.springs;
  const double* g = scene.g;
  const double drag = scene.drag;
  const double dt = args.dt, t_end = args.t_end;
  std::vector<double> x = scene.x, v = scene.v;
  auto fixed = [&](int i) { return scene.fixed(i); };

  // Each free particle's springs, in the file's order.
  std::vector<std::vector<int>> around(n);
  for (int c = 0; c < static_cast<int>(springs.size()); ++c) {
    if (springs[c].k == 0.0) continue;
    if (!fixed(springs[c].i)) around[springs[c].i].push_back(c);
    if (!fixed(springs[c].j)) around[springs[c].j].push_back(c);
  }
  // Greedy colouring in scene order.
  std::vector<int> colour(n, -1);
  std::vector<std::vector<int>> colours;
  for (int i = 0; i < n; ++i) {
    if (fixed(i)) continue;
    std::vector<bool> taken(colours.size() + 1, false);
    for (int c : around[i]) {
      const int j = springs[c].i == i ? springs[c].j : springs[c].i;
      if (colour[j] >= 0) taken[colour[j]] = true;
    }
    int c = 0;
    while (taken[c]) ++c;
    colour[i] = c;
    if (c == static_cast<int>(colours.size())) colours.emplace_back();
    colours[c].push_back(i);
  }

  // Energies, and the scale the divergence test compares with.
  auto kinetic_plus_spring = [&] {
    return reference::spring_energy(scene, x, reference::kinetic_energy(scene, v));
  };
  reference::TimeLoop loop(dt, t_end, reference::energy_scale(scene, kinetic_plus_spring()));

  // particle i's gradient and Hessian of G at x (definite: t clamped at 0)
  auto local = [&](int i, double h, const std::vector<double>& xn, const std::vector<double>& y,
                   bool definite, Eigen::Vector3d& grad, Eigen::Matrix<double, 3, 3, Eigen::RowMajor>& H) {
    const double w = m[i] / (h * h);
    double f[3] = {}, A[3][3] = {}, T = 0.0;  // f: the springs' force on i
    for (int c : around[i]) {
      const reference::Spring& s = springs[c];
      const int j = s.i == i ? s.j : s.i;
      double d[3], l2 = 0.0;
      for (int r = 0; r < 3; ++r) {
        d[r] = x[i * 3 + r] - x[j * 3 + r];
        l2 += d[r] * d[r];
      }
      if (!(l2 > 0.0)) {
        if (s.rest == 0.0) T += s.k;
        continue;
      }
      const double t = s.k * (1.0 - s.rest / std::sqrt(l2));
      for (int r = 0; r < 3; ++r) f[r] -= t * d[r];
      const double tt = definite && t < 0.0 ? 0.0 : t;
      const double a = (s.k - tt) / l2;
      T += tt;
      for (int r = 0; r < 3; ++r)
        for (int q = r; q < 3; ++q) A[r][q] += a * d[r] * d[q];
    }
    for (int r = 0; r < 3; ++r) {
      // gravity, the springs, drag
      const double force = (m[i] * g[r] + f[r]) - drag * ((x[i * 3 + r] - xn[i * 3 + r]) / h);
      grad[r] = w * (x[i * 3 + r] - y[i * 3 + r]) - force;
      H(r, r) = A[r][r] + T + drag / h + w;
      for (int q = r + 1; q < 3; ++q) H(r, q) = H(q, r) = A[r][q];
    }
  };

  std::vector<double> xn(n * 3), vn(n * 3), v_before(n * 3), y(n * 3), x_before(n * 3), x_last(n * 3);
  bool has_before = false;
  while (loop.running()) {
    const double H = loop.h();
    const double h = H / substeps;
    for (int sub = 0; sub < substeps; ++sub) {
      xn = x;
      vn = v;
      for (int i = 0; i < n; ++i) {
        if (fixed(i)) continue;
        // The initial guess: y plus the part of gravity the last step's
        // acceleration had.
        // (gravity's acceleration as the force over the mass: m g (1/m))
        double ag[3], aa = 0.0, an = 0.0;
        for (int r = 0; r < 3; ++r) {
          ag[r] = m[i] * g[r] * (1.0 / m[i]);
          aa += ag[r] * ag[r];
          if (has_before) an += (vn[i * 3 + r] - v_before[i * 3 + r]) / h * ag[r];
        }
        const double a = has_before ? std::clamp(an / aa, 0.0, 1.0) : 1.0;
        for (int r = 0; r < 3; ++r) {
          y[i * 3 + r] = xn[i * 3 + r] + h * vn[i * 3 + r];
          x[i * 3 + r] = y[i * 3 + r] + (aa > 0.0 ? h * h * a * ag[r] : 0.0);
        }
      }
      double omega = 1.0;
      for (int it = 0; it < iterations; ++it) {
        if (rho > 0.0) {
          x_before.swap(x_last);
          x_last = x;
        }
        for (const std::vector<int>& members : colours) {
          for (int i : members) {
            Eigen::Vector3d grad;
            Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H;
            local(i, h, xn, y, false, grad, H);
            Eigen::LLT<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> llt(H);
            const double w = m[i] / (h * h);
            if (llt.info() != Eigen::Success || llt.solve(grad).norm() * w > grad.norm()) {
              local(i, h, xn, y, true, grad, H);
              llt.compute(H);
              if (llt.info() != Eigen::Success) {
                Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> eig(H);
                H = eig.eigenvectors() * eig.eigenvalues().cwiseMax(m[i] / (h * h)).asDiagonal() *
                    eig.eigenvectors().transpose();
                llt.compute(H);
              }
            }
            const Eigen::Vector3d dx = -llt.solve(grad);
            for (int r = 0; r < 3; ++r) x[i * 3 + r] += dx[r];
          }
        }
        if (rho > 0.0 && it > 0) {
          omega = it == 1 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
          for (int k = 0; k < n * 3; ++k) x[k] = omega * (x[k] - x_before[k]) + x_before[k];
        }
      }
      for (int i = 0; i < n; ++i) {
        if (fixed(i)) continue;
        for (int r = 0; r < 3; ++r) v[i * 3 + r] = (x[i * 3 + r] - xn[i * 3 + r]) / h;
      }
      v_before = vn;
      has_before = true;
    }
    loop.step_done(H, kinetic_plus_spring());
  }
  if (!reference::write_positions(args.program, positions_file, scene, x)) return 1;
  reference::print_summary(loop, kinetic_plus_spring() + reference::gravity_energy(scene, x), args.start,
                           {{"x_sum", reference::number(reference::coordinate_sum(x))},
                            {"colours", std::to_string(colours.size())}});
  return 0;
}
