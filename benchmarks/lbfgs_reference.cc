// lbfgs_reference: a plain quasi-Newton (L-BFGS) implicit Euler on a
// mass-spring scene, written for comparison only (issue 37). It shares no
// code with springlab's solvers: one file (and the references'
// reference_scene.h: the command line, the scene file, the energy scale, the
// time loop, the matrix H0 below and the output), a scene file in, a few
// numbers out, so that `springlab run --integrator implicit-euler --solver
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
#include <deque>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "reference_scene.h"

namespace {

using reference::Spring;

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
  reference::CommandLine args;
  double tol = 1e-3;
  int max_iterations = 200;
  std::string positions_file;
  if (!reference::read_command_line("lbfgs_reference", argc, argv,
                                    {{"--tol", "TOL", &tol}, {"--max-iterations", "N", &max_iterations},
                                     {"--positions", "FILE", &positions_file}},
                                    args)) {
    return 2;
  }

  // The scene: particles (the free ones numbered in scene order), springs.
  reference::Scene scene;
  const reference::Refusal refusal = reference::read_scene(args.scene, {}, scene);
  if (refusal.what == reference::Unmodelled::kKey) {
    std::fprintf(stderr, "lbfgs_reference: error: %s: \"%s\" is not modelled\n", args.scene, refusal.key.c_str());
    return 2;
  }
  if (refusal.what == reference::Unmodelled::kSpringDamping) {
    std::fprintf(stderr, "lbfgs_reference: error: %s: spring damping is not modelled\n", args.scene);
    return 2;
  }
  const int D = scene.D, n = scene.n, free = scene.free;
  const std::vector<double>& x0 = scene.x;
  const std::vector<double>& m = scene.m;
  const std::vector<int>& row = scene.row;  // the particle's row among the free ones; -1: fixed
  const std::vector<Spring>& springs = scene.springs;
  const double* g = scene.g;
  const double drag = scene.drag;

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
      v[row[i] * D + r] = scene.v[i * D + r];
      mass[row[i] * D + r] = m[i];
    }
  }

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
  // The kinetic + spring energy, which the divergence test watches.
  auto kinetic_plus_spring = [&]() {
    all.head(N) = x;
    return 0.5 * v.cwiseAbs2().dot(mass) + spring_energy();
  };
  reference::TimeLoop loop(args.dt, args.t_end, reference::energy_scale(scene, kinetic_plus_spring()));

  // H0 = M + h^2 Lap (free particles only), factored once per h.
  Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
  double factored_h = 0.0;
  auto factorize = [&](double h) {
    factor.compute(reference::mass_spring_matrix(scene, h, 0.0));
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
  double h = args.dt;
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

  while (loop.running()) {
    h = loop.h();
    if (std::abs(h - factored_h) > 1e-12 * h && !factorize(h)) {
      std::fprintf(stderr, "lbfgs_reference: M + h^2 L is not positive definite\n");
      return 1;
    }
    if (!lbfgs_step()) ++stalls;  // the last iterate is kept
    x += h * u;
    v = u;
    loop.step_done(h, kinetic_plus_spring());
  }
  // Every particle's final position, scene order (the fixed ones where they were).
  std::vector<double> positions = x0;
  for (int i = 0; i < n; ++i) {
    if (row[i] >= 0) for (int r = 0; r < D; ++r) positions[i * D + r] = x[row[i] * D + r];
  }
  if (!reference::write_positions(args.program, positions_file, scene, positions)) return 1;
  reference::print_summary(loop, kinetic_plus_spring() + gravity_energy(x), args.start,
                           {{"x_sum", reference::number(reference::coordinate_sum(positions))},
                            {"lbfgs_iterations", std::to_string(iterations)}, {"stalls", std::to_string(stalls)}});
  return 0;
}

}  // namespace
