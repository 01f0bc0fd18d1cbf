// lbfgs_reference: a plain quasi-Newton (L-BFGS) implicit Euler on a
// mass-spring scene, written for comparison only (issue 37). It shares no
// code with springlab's solvers: one file, a scene file in, a few numbers
// out, so that `springlab run --integrator implicit-euler --solver
// quasi-newton` can be timed and checked against it
// (benchmarks/bench_fast_reference.cc).
//
//   lbfgs_reference SCENE.json --dt H --t-end T [--tol TOL] [--max-iterations N]
//                   [--positions FILE]
//
// The step (Liu, Bouaziz and Kavan, "Quasi-Newton methods for real-time
// simulation of hyperelastic materials", ACM TOG 2017). Implicit Euler's
// step from (x, v) with gravity g, drag -gamma v and springs (i, j) of
// stiffness k, rest length L, written for the new velocity u:
//   x' = x + h u,   M (u - v) = h F(x', u),
// is the minimum of the incremental potential
//   Phi(u) = |u - v|_M^2 / 2 + E(x + h u) - sum m_i g.(x_i + h u_i) + h gamma |u|^2 / 2,
// E(x) = sum k/2 (|x_i - x_j| - L)^2, whose gradient is the residual
//   r(u) = M (u - v) - h F(x + h u, u).
// L-BFGS minimizes it (Nocedal and Wright, "Numerical Optimization", 2006,
// Algorithm 7.4: the last 5 pairs s = u' - u, y = r(u') - r(u), applied by
// the two-loop recursion) with the initial Hessian
//   H0 = M + h^2 Lap,  Lap = sum k (e_i - e_j)(e_i - e_j)^T
// over the free particles (a spring to a fixed particle puts k on the
// free one's diagonal): Phi's Hessian with every spring as stiff across as
// along it, the same for x, y and z, so one n x n factor (CHOLMOD's
// simplicial LL^T through Eigen, made once per h) solves the three
// coordinates as three columns. Each iteration, from u = v + h M^-1 (m g -
// gamma v) (the forces other than the springs, at the step's start):
//   d = -H r (two-loop; where r.d >= 0 the history is dropped and H0 alone
//            is used);
//   Armijo on Phi from the full step, halving (at most 30 times):
//            Phi(u + a d) - Phi(u) <= 1e-4 a r.d, or, where a |r.d| is
//            below Phi's round-off (1e3 eps of its terms' magnitudes), a
//            smaller |r|;
//   where the full step is taken and the slope at its end, r(u + d).d, is
//            still negative, the secant minimum on the line
//            a* = r.d / (r.d - r(u + d).d); if a* >= 1.2 the step
//            min(a*, 4) d is tried and kept if Phi is lower there;
//   the pair (a d, r(u + a d) - r(u)) is kept if y.s > 1e-12 |y| |s|.
// Stopping (as springlab's, on the update it proposes, in m/s): the
// update e = max(1, a*) |d|_inf, or while e shrinks by a rate q in (1/2, 1)
// from the iteration before, q / (1 - q) e, at most TOL (default 1e-3); or
// e below 1e3 eps (|u|_inf + |v|_inf). After --max-iterations (default
// 200), or a failed search, or no descent even from H0, the step has
// stalled: this program then keeps the last iterate and counts the stall
// (springlab solves such a step again by Newton; on the benchmark's cloths
// neither stalls). springlab also refuses an answer whose potential lies
// above the step's start (then Newton solves the step); this program does
// not check it. Then v = u, x = x + h u. Only gravity, drag, springs and
// fixed particles are modelled: a scene with any other key (wind, planes,
// elements, ...) or with spring damping is refused with one line.
// It stops when the state turns non-finite or the kinetic + spring energy
// passes 1000 times the scene's energy scale (as `springlab run` does by
// default) and prints one JSON line:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., "x_sum": .., "lbfgs_iterations": .., "stalls": ..}
// With --positions FILE it also writes the final positions, one line
// "i,x,y[,z]" per particle (scene index, %.17g).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <exception>
#include <fstream>
#include <limits>
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

constexpr int kHistory = 5;
constexpr double kArmijo = 1e-4;
constexpr int kHalvings = 30;
constexpr double kEps = std::numeric_limits<double>::epsilon();

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // a scene file that is no JSON, or lacks a key
    std::fprintf(stderr, "lbfgs_reference: error: %s: %s\n", argc > 1 ? argv[1] : "", e.what());
    return 1;
  }
}

namespace {

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: lbfgs_reference SCENE.json --dt H --t-end T [--tol TOL] "
                 "[--max-iterations N] [--positions FILE]\n");
    return 2;
  }
  double dt = 1.0 / 60.0, t_end = 1.0, tol = 1e-3;
  int max_iterations = 200;
  std::string positions_file;
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    const double value = std::atof(argv[a + 1]);
    if (key == "--dt") dt = value;
    else if (key == "--t-end") t_end = value;
    else if (key == "--tol") tol = value;
    else if (key == "--max-iterations") max_iterations = static_cast<int>(value);
    else if (key == "--positions") positions_file = argv[a + 1];
    else { std::fprintf(stderr, "unknown option %s\n", key.c_str()); return 2; }
  }
  const auto start = std::chrono::steady_clock::now();

  // The scene: particles (the free ones numbered in scene order), springs.
  std::ifstream file(argv[1]);
  const nlohmann::json scene = nlohmann::json::parse(file);
  for (const auto& [key, value] : scene.items()) {
    if (key != "name" && key != "dimension" && key != "gravity" && key != "drag" &&
        key != "particles" && key != "springs") {
      std::fprintf(stderr, "lbfgs_reference: error: %s: \"%s\" is not modelled\n", argv[1], key.c_str());
      return 2;
    }
  }
  const int D = scene.at("dimension").get<int>();
  const int n = static_cast<int>(scene.at("particles").size());
  std::vector<double> x0(n * D), v0(n * D, 0.0), m(n);
  std::vector<int> row(n, -1);  // the particle's row among the free ones; -1: fixed
  int free = 0;
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& p = scene["particles"][i];
    m[i] = p.value("mass", 1.0);
    if (!p.value("fixed", false)) row[i] = free++;
    for (int r = 0; r < D; ++r) {
      x0[i * D + r] = vec(p["x"], r);
      if (p.contains("v") && row[i] >= 0) v0[i * D + r] = vec(p["v"], r);
    }
  }
  std::vector<Spring> springs;
  for (const nlohmann::json& s : scene.at("springs")) {
    const int i = s.at("i").get<int>(), j = s.at("j").get<int>();
    double rest = 0.0;
    if (s.contains("rest")) {
      rest = s["rest"].get<double>();
    } else {
      for (int r = 0; r < D; ++r) rest += (x0[i * D + r] - x0[j * D + r]) * (x0[i * D + r] - x0[j * D + r]);
      rest = std::sqrt(rest);
    }
    if (s.value("damping", 0.0) != 0.0) {
      std::fprintf(stderr, "lbfgs_reference: error: %s: spring damping is not modelled\n", argv[1]);
      return 2;
    }
    springs.push_back({i, j, s.at("k").get<double>(), rest});
  }
  double g[3] = {0, 0, 0};
  const double drag = scene.value("drag", 0.0);
  if (scene.contains("gravity")) for (int r = 0; r < D; ++r) g[r] = vec(scene["gravity"], r);

  // The unknowns: the free particles' coordinates, particle by particle.
  // The springs see all particles, the free ones first (in the unknowns'
  // order), then the fixed ones: a spring's ends are slots in that order.
  const int N = free * D;
  Eigen::VectorXd x(N), v(N), mass(N);  // mass: m per coordinate
  Eigen::VectorXd all(n * D);           // every particle's position (the fixed ones stay)
  std::vector<int> slot(n);
  for (int i = 0, fixed = free; i < n; ++i) {
    slot[i] = row[i] >= 0 ? row[i] : fixed++;
    for (int r = 0; r < D; ++r) all[slot[i] * D + r] = x0[i * D + r];
    if (row[i] < 0) continue;
    for (int r = 0; r < D; ++r) {
      x[row[i] * D + r] = x0[i * D + r];
      v[row[i] * D + r] = v0[i * D + r];
      mass[row[i] * D + r] = m[i];
    }
  }
  // A particle's position in a state y of the free ones.
  auto at = [&](const Eigen::VectorXd& y, int p, int r) {
    return row[p] >= 0 ? y[row[p] * D + r] : x0[p * D + r];
  };

  // The springs' energy and force (on every particle: f_all) at the
  // positions in `all`.
  auto spring_energy = [&]() {
    double e = 0.0;
    for (const Spring& s : springs) {
      double l = 0.0;
      for (int r = 0; r < D; ++r) {
        const double d = all[slot[s.i] * D + r] - all[slot[s.j] * D + r];
        l += d * d;
      }
      const double stretch = std::sqrt(l) - s.rest;
      e += 0.5 * s.k * stretch * stretch;
    }
    return e;
  };
  Eigen::VectorXd f_all(n * D);
  auto spring_force = [&]() {
    f_all.setZero();
    for (const Spring& s : springs) {
      const int a = slot[s.i] * D, b = slot[s.j] * D;
      double d[3] = {0, 0, 0}, l = 0.0;
      for (int r = 0; r < D; ++r) {
        d[r] = all[a + r] - all[b + r];
        l += d[r] * d[r];
      }
      if (l == 0.0) continue;
      const double c = s.k * (1.0 - s.rest / std::sqrt(l));  // k (l - L) / l
      for (int r = 0; r < D; ++r) {
        f_all[a + r] -= c * d[r];
        f_all[b + r] += c * d[r];
      }
    }
  };
  auto gravity_energy = [&](const Eigen::Ref<const Eigen::VectorXd>& y) {
    double e = 0.0;
    for (int c = 0; c < N; ++c) e -= mass[c] * g[c % D] * y[c];
    return e;
  };

  // The scale the divergence test compares with (as pd_reference).
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < D; ++r) {
      lo[r] = std::min(lo[r], x0[i * D + r]);
      hi[r] = std::max(hi[r], x0[i * D + r]);
    }
  }
  double diameter = 0.0, g_norm = 0.0;
  for (int r = 0; r < D; ++r) {
    diameter += (hi[r] - lo[r]) * (hi[r] - lo[r]);
    g_norm += g[r] * g[r];
  }
  diameter = std::sqrt(diameter);
  g_norm = std::sqrt(g_norm);
  auto kinetic_plus_spring = [&]() {
    all.head(N) = x;
    return 0.5 * v.cwiseAbs2().dot(mass) + spring_energy();
  };
  double scale = kinetic_plus_spring();
  for (int i = 0; i < n; ++i) {
    if (row[i] >= 0) scale += m[i] * g_norm * diameter;
  }

  // H0 = M + h^2 Lap (free particles only), factored once per h.
  using SparseMatrix = Eigen::SparseMatrix<double>;
  Eigen::CholmodSimplicialLLT<SparseMatrix, Eigen::Lower> factor;
  double factored_h = 0.0;
  auto factorize = [&](double h) {
    std::vector<Eigen::Triplet<double>> entries;
    for (int i = 0; i < n; ++i) {
      if (row[i] >= 0) entries.emplace_back(row[i], row[i], m[i]);
    }
    for (const Spring& s : springs) {
      const double w = h * h * s.k;
      const int a = row[s.i], b = row[s.j];
      if (a >= 0) entries.emplace_back(a, a, w);
      if (b >= 0) entries.emplace_back(b, b, w);
      if (a >= 0 && b >= 0) entries.emplace_back(std::max(a, b), std::min(a, b), -w);  // lower triangle
    }
    SparseMatrix A(free, free);
    A.setFromTriplets(entries.begin(), entries.end());
    factor.compute(A);
    factored_h = h;
    return factor.info() == Eigen::Success;
  };
  // z = H0^-1 q, the coordinates as the columns of a free x D matrix.
  Eigen::MatrixXd columns(free, D);
  auto apply_h0_inverse = [&](const Eigen::VectorXd& q, Eigen::VectorXd& z) {
    columns = Eigen::Map<const Eigen::MatrixXd>(q.data(), D, free).transpose();
    const Eigen::MatrixXd solved = factor.solve(columns);
    z.resize(N);
    Eigen::Map<Eigen::MatrixXd>(z.data(), D, free) = solved.transpose();
  };

  // One step's problem: x, v the step's start, h its size.
  double h = dt;
  Eigen::VectorXd f(N);
  auto residual = [&](const Eigen::VectorXd& u, Eigen::VectorXd& r) {  // r = M (u - v) - h F
    all.head(N) = x + h * u;
    spring_force();
    for (int c = 0; c < N; ++c) f[c] = f_all[c] + mass[c] * g[c % D] - drag * u[c];
    r = mass.cwiseProduct(u - v) - h * f;
  };
  auto potential = [&](const Eigen::VectorXd& u, double& magnitude) {  // Phi(u)
    all.head(N) = x + h * u;
    const double inertia = 0.5 * (u - v).cwiseAbs2().dot(mass);
    const double stored = spring_energy() + gravity_energy(all.head(N));
    const double dissipated = h * 0.5 * drag * u.squaredNorm();
    magnitude = inertia + std::abs(stored) + std::abs(dissipated);
    return inertia + stored + dissipated;
  };

  std::deque<Eigen::VectorXd> hist_s, hist_y;  // the last kHistory pairs
  std::deque<double> hist_rho;                 // 1 / (y.s)
  Eigen::VectorXd u(N), r(N), d(N), q(N), z(N), u_try(N), r_try(N), u_long(N), r_long(N);
  long iterations = 0, stalls = 0;

  // Minimizes Phi for the step from (x, v): u the answer; false: stalled.
  auto lbfgs_step = [&]() {
    hist_s.clear();
    hist_y.clear();
    hist_rho.clear();
    for (int c = 0; c < N; ++c) u[c] = v[c] + h * (g[c % D] - drag * v[c] / mass[c]);
    residual(u, r);
    double magnitude = 0.0;
    double phi = potential(u, magnitude);
    if (!std::isfinite(phi) || !r.allFinite()) return false;
    double previous_update = 0.0;
    for (int it = 0; it < max_iterations; ++it) {
      ++iterations;
      // The direction d = -H r, by the two-loop recursion.
      const std::size_t k_max = hist_s.size();
      std::vector<double> alpha(k_max);
      q = r;
      for (std::size_t k = k_max; k-- > 0;) {
        alpha[k] = hist_rho[k] * hist_s[k].dot(q);
        q -= alpha[k] * hist_y[k];
      }
      apply_h0_inverse(q, z);
      for (std::size_t k = 0; k < k_max; ++k) {
        const double beta = hist_rho[k] * hist_y[k].dot(z);
        z += (alpha[k] - beta) * hist_s[k];
      }
      d = -z;
      double slope = r.dot(d);
      if (!(slope < 0.0) && k_max > 0) {  // the history does not descend: H0 alone
        hist_s.clear();
        hist_y.clear();
        hist_rho.clear();
        apply_h0_inverse(r, z);
        d = -z;
        slope = r.dot(d);
      }
      if (!(slope < 0.0)) return r.lpNorm<Eigen::Infinity>() == 0.0;
      // Armijo on Phi, halving from the full step.
      double a = 1.0, phi_try = 0.0, magnitude_try = 0.0;
      bool accepted = false;
      for (int k = 0; k <= kHalvings && !accepted; ++k) {
        if (k > 0) a *= 0.5;
        u_try = u + a * d;
        residual(u_try, r_try);
        if (!r_try.allFinite()) continue;
        phi_try = potential(u_try, magnitude_try);
        if (!std::isfinite(phi_try)) continue;
        const double noise = 1e3 * kEps * std::max(magnitude, magnitude_try);
        accepted = phi_try - phi <= kArmijo * a * slope ||
                   (a * -slope <= noise && r_try.norm() < r.norm());
      }
      if (!accepted) return false;
      // The minimum on the line beyond the full step: the slope's secant.
      double a_star = 1.0;
      if (a == 1.0) {
        const double slope_end = r_try.dot(d);
        if (slope_end < 0.0) a_star = slope / (slope - slope_end);
        if (a_star >= 1.2) {
          const double longer = std::min(a_star, 4.0);
          u_long = u + longer * d;
          residual(u_long, r_long);
          double magnitude_long = 0.0;
          const double phi_long = r_long.allFinite() ? potential(u_long, magnitude_long) : phi_try;
          if (phi_long < phi_try) {
            a = longer;
            u_try.swap(u_long);
            r_try.swap(r_long);
            phi_try = phi_long;
            magnitude_try = magnitude_long;
          }
        }
      }
      const double update = a_star * d.lpNorm<Eigen::Infinity>();
      // Remember the pair where its curvature y.s is positive.
      Eigen::VectorXd s_new = a * d, y_new = r_try - r;
      const double ys = y_new.dot(s_new);
      if (ys > 1e-12 * y_new.norm() * s_new.norm()) {
        if (static_cast<int>(hist_s.size()) == kHistory) {
          hist_s.pop_front();
          hist_y.pop_front();
          hist_rho.pop_front();
        }
        hist_s.push_back(std::move(s_new));
        hist_y.push_back(std::move(y_new));
        hist_rho.push_back(1.0 / ys);
      }
      u.swap(u_try);
      r.swap(r_try);
      phi = phi_try;
      magnitude = magnitude_try;
      // Converged: the update, or what remains of a linear convergence.
      const double rate = previous_update > 0.0 ? update / previous_update : 0.0;
      const double remaining = rate > 0.5 && rate < 1.0 ? update * rate / (1.0 - rate) : update;
      const double floor = 1e3 * kEps * (u.lpNorm<Eigen::Infinity>() + v.lpNorm<Eigen::Infinity>());
      if (remaining <= tol || update <= floor) return true;
      previous_update = update;
    }
    return false;
  };

  const double exact = t_end / dt;
  const long steps = std::abs(exact - std::round(exact)) <= 1e-9 ? std::lround(exact)
                                                                 : static_cast<long>(std::ceil(exact));
  double t = 0.0;
  long taken = 0;
  bool diverged = false;
  for (long step = 0; step < steps && !diverged; ++step) {
    h = step + 1 == steps ? t_end - t : dt;
    if (std::abs(h - factored_h) > 1e-12 * h && !factorize(h)) {
      std::fprintf(stderr, "lbfgs_reference: M + h^2 L is not positive definite\n");
      return 1;
    }
    if (!lbfgs_step()) ++stalls;  // the last iterate is kept
    x += h * u;
    v = u;
    t += h;
    ++taken;
    const double e = kinetic_plus_spring();
    diverged = !std::isfinite(e) || (scale > 0.0 && e > 1000.0 * scale);
  }
  double x_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < D; ++r) x_sum += at(x, i, r);
  }
  if (!positions_file.empty()) {
    std::FILE* out = std::fopen(positions_file.c_str(), "w");
    if (out == nullptr) { std::fprintf(stderr, "lbfgs_reference: cannot write %s\n", positions_file.c_str()); return 1; }
    for (int i = 0; i < n; ++i) {
      std::fprintf(out, "%d", i);
      for (int r = 0; r < D; ++r) std::fprintf(out, ",%.17g", at(x, i, r));
      std::fprintf(out, "\n");
    }
    std::fclose(out);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("{\"steps\": %ld, \"diverged\": %s, \"diverged_at\": %s, \"energy_final\": %.17g, "
              "\"seconds\": %.9g, \"x_sum\": %.17g, \"lbfgs_iterations\": %ld, \"stalls\": %ld}\n",
              taken, diverged ? "true" : "false", diverged ? std::to_string(t).c_str() : "null",
              kinetic_plus_spring() + gravity_energy(x), seconds, x_sum, iterations, stalls);
  return 0;
}

}  // namespace
