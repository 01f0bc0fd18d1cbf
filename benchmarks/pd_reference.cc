// pd_reference: a plain projective dynamics on a mass-spring scene, written
// for comparison only (issue 37). It shares no code with springlab's solvers:
// one file, a scene file in, a few numbers out, so that `springlab run
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
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <nlohmann/json.hpp>

namespace {

struct Spring {
  int i, j;
  double k, rest;
};

double vec(const nlohmann::json& j, int r) { return r < static_cast<int>(j.size()) ? j[r].get<double>() : 0.0; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: pd_reference SCENE.json --dt H --t-end T [--iterations N] [--positions FILE]\n");
    return 2;
  }
  double dt = 1.0 / 60.0, t_end = 1.0;
  int iterations = 10;
  std::string positions_file;
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    const double value = std::atof(argv[a + 1]);
    if (key == "--dt") dt = value;
    else if (key == "--t-end") t_end = value;
    else if (key == "--iterations") iterations = static_cast<int>(value);
    else if (key == "--positions") positions_file = argv[a + 1];
    else { std::fprintf(stderr, "unknown option %s\n", key.c_str()); return 2; }
  }
  const auto start = std::chrono::steady_clock::now();

  std::ifstream file(argv[1]);
  const nlohmann::json scene = nlohmann::json::parse(file);
  const int D = scene.at("dimension").get<int>();
  const int n = static_cast<int>(scene.at("particles").size());
  std::vector<double> x(n * D), v(n * D, 0.0), m(n);
  std::vector<int> row(n, -1);  // the particle's row in the matrix; -1: fixed
  int free = 0;
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& q = scene["particles"][i];
    m[i] = q.value("mass", 1.0);
    if (!q.value("fixed", false)) row[i] = free++;
    for (int r = 0; r < D; ++r) {
      x[i * D + r] = vec(q["x"], r);
      if (q.contains("v") && row[i] >= 0) v[i * D + r] = vec(q["v"], r);
    }
  }
  std::vector<Spring> springs;
  for (const nlohmann::json& s : scene.at("springs")) {
    const int i = s.at("i").get<int>(), j = s.at("j").get<int>();
    double rest = 0.0;
    if (s.contains("rest")) {
      rest = s["rest"].get<double>();
    } else {
      for (int r = 0; r < D; ++r) rest += (x[i * D + r] - x[j * D + r]) * (x[i * D + r] - x[j * D + r]);
      rest = std::sqrt(rest);
    }
    if (s.value("damping", 0.0) != 0.0) {
      std::fprintf(stderr, "pd_reference: spring damping is not modelled\n");
      return 2;
    }
    springs.push_back({i, j, s.at("k").get<double>(), rest});
  }
  if (scene.contains("wind")) {
    std::fprintf(stderr, "pd_reference: wind is not modelled\n");
    return 2;
  }
  double g[3] = {0, 0, 0};
  const double drag = scene.value("drag", 0.0);
  if (scene.contains("gravity")) for (int r = 0; r < D; ++r) g[r] = vec(scene["gravity"], r);

  // Energies, and the scale the divergence test compares with.
  auto kinetic_plus_spring = [&]() {
    double e = 0.0;
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) e += 0.5 * m[i] * v[i * D + r] * v[i * D + r];
    }
    for (const Spring& s : springs) {
      double l = 0.0;
      for (int r = 0; r < D; ++r) l += (x[s.i * D + r] - x[s.j * D + r]) * (x[s.i * D + r] - x[s.j * D + r]);
      const double stretch = std::sqrt(l) - s.rest;
      e += 0.5 * s.k * stretch * stretch;
    }
    return e;
  };
  auto gravity_energy = [&]() {
    double e = 0.0;
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) e -= m[i] * g[r] * x[i * D + r];
    }
    return e;
  };
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < D; ++r) {
      lo[r] = std::min(lo[r], x[i * D + r]);
      hi[r] = std::max(hi[r], x[i * D + r]);
    }
  }
  double diameter = 0.0, g_norm = 0.0;
  for (int r = 0; r < D; ++r) {
    diameter += (hi[r] - lo[r]) * (hi[r] - lo[r]);
    g_norm += g[r] * g[r];
  }
  diameter = std::sqrt(diameter);
  g_norm = std::sqrt(g_norm);
  double scale = kinetic_plus_spring();
  for (int i = 0; i < n; ++i) {
    if (row[i] >= 0) scale += m[i] * g_norm * diameter;
  }

  // The global matrix for one h, factored once and kept.
  using SparseMatrix = Eigen::SparseMatrix<double>;
  Eigen::CholmodSimplicialLLT<SparseMatrix, Eigen::Lower> factor;
  double factored_h = 0.0;
  auto factorize = [&](double h) {
    std::vector<Eigen::Triplet<double>> entries;
    for (int i = 0; i < n; ++i) {
      if (row[i] >= 0) entries.emplace_back(row[i], row[i], m[i] + h * drag);
    }
    for (const Spring& s : springs) {
      const double w = h * h * s.k;
      const int a = row[s.i], b = row[s.j];
      if (a >= 0) entries.emplace_back(a, a, w);
      if (b >= 0) entries.emplace_back(b, b, w);
      if (a >= 0 && b >= 0) {
        entries.emplace_back(std::max(a, b), std::min(a, b), -w);  // the lower triangle
      }
    }
    SparseMatrix A(free, free);
    A.setFromTriplets(entries.begin(), entries.end());
    factor.compute(A);
    factored_h = h;
    return factor.info() == Eigen::Success;
  };

  const double exact = t_end / dt;
  const long steps = std::abs(exact - std::round(exact)) <= 1e-9 ? std::lround(exact)
                                                                 : static_cast<long>(std::ceil(exact));
  Eigen::MatrixXd y(free, D), rhs0(free, D), rhs(free, D), xn(free, D);
  double t = 0.0;
  long taken = 0;
  bool diverged = false;
  for (long step = 0; step < steps && !diverged; ++step) {
    const double h = step + 1 == steps ? t_end - t : dt;
    if (std::abs(h - factored_h) > 1e-12 * h && !factorize(h)) {
      std::fprintf(stderr, "pd_reference: the global matrix is not positive definite\n");
      return 1;
    }
    // y, and the part of the right-hand side that stays: M y + h gamma (x + h v).
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        const double xi = x[i * D + r], vi = v[i * D + r];
        y(row[i], r) = xi + h * vi + h * h * (g[r] - drag * vi / m[i]);
        rhs0(row[i], r) = m[i] * y(row[i], r) + h * drag * (xi + h * vi);
      }
    }
    xn = y;
    auto position = [&](int p, int r) { return row[p] >= 0 ? xn(row[p], r) : x[p * D + r]; };
    for (int it = 0; it < iterations; ++it) {
      rhs = rhs0;
      for (const Spring& s : springs) {  // local steps, into the right-hand side
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
    t += h;
    ++taken;
    const double e = kinetic_plus_spring();
    diverged = !std::isfinite(e) || (scale > 0.0 && e > 1000.0 * scale);
  }
  double x_sum = 0.0;
  for (double c : x) x_sum += c;
  if (!positions_file.empty()) {
    std::FILE* out = std::fopen(positions_file.c_str(), "w");
    if (out == nullptr) { std::fprintf(stderr, "pd_reference: cannot write %s\n", positions_file.c_str()); return 1; }
    for (int i = 0; i < n; ++i) {
      std::fprintf(out, "%d", i);
      for (int r = 0; r < D; ++r) std::fprintf(out, ",%.17g", x[i * D + r]);
      std::fprintf(out, "\n");
    }
    std::fclose(out);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("{\"steps\": %ld, \"diverged\": %s, \"diverged_at\": %s, \"energy_final\": %.17g, "
              "\"seconds\": %.9g, \"x_sum\": %.17g}\n",
              taken, diverged ? "true" : "false", diverged ? std::to_string(t).c_str() : "null",
              kinetic_plus_spring() + gravity_energy(), seconds, x_sum);
  return 0;
}
