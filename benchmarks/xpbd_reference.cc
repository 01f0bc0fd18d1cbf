// xpbd_reference: a plain XPBD, written for comparison only (issue 37). It
// shares no code with springlab's solvers: one file, a scene file in, a few
// numbers out, so that `springlab run --integrator xpbd` can be timed and
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
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

struct Spring {
  int i, j;
  double k, rest, damping;
};

double vec(const nlohmann::json& j, int r) { return r < static_cast<int>(j.size()) ? j[r].get<double>() : 0.0; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: xpbd_reference SCENE.json --dt H --t-end T [--substeps S] [--iterations N]\n");
    return 2;
  }
  double dt = 1.0 / 60.0, t_end = 1.0;
  int substeps = 10, iterations = 1;
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    const double value = std::atof(argv[a + 1]);
    if (key == "--dt") dt = value;
    else if (key == "--t-end") t_end = value;
    else if (key == "--substeps") substeps = static_cast<int>(value);
    else if (key == "--iterations") iterations = static_cast<int>(value);
    else { std::fprintf(stderr, "unknown option %s\n", key.c_str()); return 2; }
  }
  const auto start = std::chrono::steady_clock::now();

  std::ifstream file(argv[1]);
  const nlohmann::json scene = nlohmann::json::parse(file);
  const int D = scene.at("dimension").get<int>();
  const int n = static_cast<int>(scene.at("particles").size());
  std::vector<double> x(n * D), v(n * D, 0.0), p(n * D), w(n), m(n);
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& q = scene["particles"][i];
    m[i] = q.value("mass", 1.0);
    w[i] = q.value("fixed", false) ? 0.0 : 1.0 / m[i];
    for (int r = 0; r < D; ++r) {
      x[i * D + r] = vec(q["x"], r);
      if (q.contains("v") && w[i] > 0.0) v[i * D + r] = vec(q["v"], r);
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
    springs.push_back({i, j, s.at("k").get<double>(), rest, s.value("damping", 0.0)});
  }
  double g[3] = {0, 0, 0}, wind[3] = {0, 0, 0};
  double drag = scene.value("drag", 0.0), wind_c = 0.0, gust = 0.0, frequency = 0.0;
  if (scene.contains("gravity")) for (int r = 0; r < D; ++r) g[r] = vec(scene["gravity"], r);
  if (scene.contains("wind")) {
    const nlohmann::json& wj = scene["wind"];
    for (int r = 0; r < D; ++r) wind[r] = vec(wj.at("velocity"), r);
    wind_c = wj.value("coefficient", 0.0);
    gust = wj.value("gust", 0.0);
    frequency = wj.value("frequency", 0.0);
  }
  bool damped = false;
  for (const Spring& s : springs) damped = damped || s.damping > 0.0;

  // Energies, and the scale the divergence test compares with.
  auto kinetic_plus_spring = [&]() {
    double e = 0.0;
    for (int i = 0; i < n; ++i) {
      if (w[i] == 0.0) continue;
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
      if (w[i] == 0.0) continue;
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
  double diameter = 0.0, g_norm = 0.0, w_max = 0.0;
  for (int r = 0; r < D; ++r) {
    diameter += (hi[r] - lo[r]) * (hi[r] - lo[r]);
    g_norm += g[r] * g[r];
    w_max += wind[r] * wind[r];
  }
  diameter = std::sqrt(diameter);
  g_norm = std::sqrt(g_norm);
  w_max = std::sqrt(w_max) * (1.0 + std::abs(gust));
  double scale = kinetic_plus_spring();
  for (int i = 0; i < n; ++i) {
    if (w[i] > 0.0) scale += m[i] * (g_norm * diameter + 0.5 * w_max * w_max);
  }

  const double exact = t_end / dt;
  const long steps = std::abs(exact - std::round(exact)) <= 1e-9 ? std::lround(exact)
                                                                 : static_cast<long>(std::ceil(exact));
  const double pi = std::acos(-1.0);
  std::vector<double> lambda(springs.size());
  double t = 0.0;
  long taken = 0;
  bool diverged = false;
  for (long step = 0; step < steps && !diverged; ++step) {
    const double H = step + 1 == steps ? t_end - t : dt;
    const double h = H / substeps;
    for (int s = 0; s < substeps; ++s) {
      const double ts = t + s * h;
      // Explicit forces.
      const double gust_factor = 1.0 + gust * std::sin(2.0 * pi * frequency * ts);
      for (int i = 0; i < n; ++i) {
        if (w[i] == 0.0) continue;
        for (int r = 0; r < D; ++r) {
          const double f = m[i] * g[r] - drag * v[i * D + r] +
                           wind_c * (wind[r] * gust_factor - v[i * D + r]);
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
    t += H;
    ++taken;
    const double e = kinetic_plus_spring();
    diverged = !std::isfinite(e) || (scale > 0.0 && e > 1000.0 * scale);
  }
  double x_sum = 0.0;
  for (double c : x) x_sum += c;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("{\"steps\": %ld, \"diverged\": %s, \"diverged_at\": %s, \"energy_final\": %.17g, "
              "\"seconds\": %.9g, \"x_sum\": %.17g}\n",
              taken, diverged ? "true" : "false", diverged ? std::to_string(t).c_str() : "null",
              kinetic_plus_spring() + gravity_energy(), seconds, x_sum);
  return 0;
}
