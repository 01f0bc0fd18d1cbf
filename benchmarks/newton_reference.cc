// newton_reference: a plain projected Newton for backward Euler on a
// mass-spring scene, written for comparison only (issue 37). It shares no
// code with springlab's solvers: one file (and the references'
// reference_scene.h: the command line, the scene file, the energies, the time
// loop and the output), a scene file in, a few numbers out, so that `springlab run --integrator implicit-euler` (Newton, the
// defaults) can be timed and checked against it
// (benchmarks/bench_fast_reference.cc).
//
//   newton_reference SCENE.json --dt H --t-end T [--tol TOL] [--positions FILE]
//
// The step. Backward Euler in velocity form: x' = x + h v', with v' the
// minimizer of the incremental potential (Kane et al. 2000; Gast et al.,
// "Optimization integrator for large time steps", 2015)
//   Phi(v) = 1/2 (v - v_n)^T M (v - v_n) + E(x_n + h v) - h M g . v
//            + h gamma/2 |v|^2,
// E = sum over springs (i, j) of k/2 (|x_i - x_j| - L)^2, gravity g, drag
// force -gamma v (its dissipation potential gamma/2 |v|^2, times h). Its
// gradient and Hessian:
//   grad Phi = M (v - v_n) + h grad E(x*) - h M g + h gamma v,
//   H        = M + h gamma I + h^2 K(x*),   x* = x_n + h v.
// A spring's block of K (d = x_i - x_j, l = |d|, n = d / l) is
//   K_s = k n n^T + k (1 - L/l) (I - n n^T),
// added to (i, i) and (j, j) and subtracted from (i, j) and (j, i). A
// compressed spring (l < L) makes the second term negative; projected
// Newton drops it there (Choi and Ko, "Stable but responsive cloth",
// SIGGRAPH 2002), so every block is positive semidefinite and H is
// positive definite (M > 0).
//
// Projected Newton from v = v_n, each iteration:
//   1. assemble H at v with the projected blocks and factor it, LL^T by
//      CHOLMOD (Eigen::CholmodSupernodalLLT, AMD ordering; the pattern is
//      analysed once, on the first step, and kept);
//   2. solve H dv = -grad Phi(v);
//   3. if ||dv||_inf <= tol [m/s] (default 1e-4): v += dv, done;
//   4. else backtracking line search: alpha = 1, 1/2, 1/4, ... until
//      Phi(v + alpha dv) <= Phi(v) + 1e-4 alpha grad Phi . dv (Armijo;
//      Nocedal and Wright, eq. 3.4); v += alpha dv.
// At most 1000 iterations per step (springlab's --max-newton default is
// 200): near a buckling state the projected Hessian leaves out the negative
// curvature the iterates slide along, and projected Newton converges
// linearly and slowly; on cloth 64 at t = 0.1 s one step took 187
// iterations with the supernodal factor and more than 200 with the
// simplicial one (the same matrices, other rounding).
//
// Where springlab's implicit-euler (integrators/newton/newton_loop.cc) differs in
// how, not what: it uses the exact Hessian after a full update and the
// projected one only after a cut step (this program: the projected one
// always, so it converges linearly near a buckling state, not
// quadratically); it solves with conjugate gradients preconditioned by a
// kept factor (this program factors at every iteration); and it stops when
// the update, or, converging linearly at a rate in (0.5, 1), the error that
// rate leaves, update * rate / (1 - rate), is at most tol (this program:
// the update alone, so where it converges slowly its answer lies further
// from the minimizer than tol: about update * rate / (1 - rate)).
// springlab also solves a step whose Newton fails again from its start by
// projected Newton (this program's method), checks that the answer lies
// below the potential of the step's start, and leaves a saddle of Phi
// along negative curvature; this program does none of these.
//
// The scene: gravity, drag, springs, fixed particles (not unknowns: they
// stay where they are). Anything else (wind, spring damping, elements,
// bodies, contact) is refused with one line. It stops when the state turns
// non-finite or the kinetic + spring energy passes 1000 times the scene's
// energy scale (as `springlab run` does by default) and prints one JSON
// line:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., "newton_iterations": .., "factorizations": ..,
//    "x_sum": ..}
// With --positions FILE it also writes the final positions, one line
// "i,x,y[,z]" per particle (scene index, %.17g).
#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "reference_scene.h"

namespace {

using reference::Spring;

constexpr int D = 3;               // the cloth is 3-D; a 2-D scene is refused
constexpr int kMaxIterations = 1000;  // see the header
constexpr double kArmijo = 1e-4;   // the sufficient decrease's constant
constexpr int kMaxHalvings = 50;

int refuse(const char* scene, const std::string& where, const std::string& what) {
  std::fprintf(stderr, "newton_reference: error: %s: %s: %s\n", scene, where.c_str(), what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  reference::CommandLine args;
  double tol = 1e-4;
  std::string positions_file;
  if (!reference::read_command_line("newton_reference", argc, argv,
                                    {{"--tol", "TOL", &tol}, {"--positions", "FILE", &positions_file}}, args)) {
    return 2;
  }
  // One thread, as springlab runs: one BLAS thread (CHOLMOD's supernodal
  // factorization calls BLAS), and CHOLMOD's OpenMP regions, of a fixed
  // thread count, made inactive (max-active-levels 0). OpenBLAS and libgomp
  // come with CHOLMOD: looked up, not linked.
  using SetInt = void (*)(int);
  if (auto set = reinterpret_cast<SetInt>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
  if (auto set = reinterpret_cast<SetInt>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))) set(0);

  // The scene.
  reference::Scene scene;
  const reference::Refusal refusal = reference::read_scene(args.scene, {.dimension = D}, scene);
  switch (refusal.what) {
    case reference::Unmodelled::kKey:
      return refuse(args.scene, refusal.key, "not modelled (only gravity, drag, springs, fixed particles)");
    case reference::Unmodelled::kDimension: return refuse(args.scene, "dimension", "only 3 is modelled");
    case reference::Unmodelled::kSpringDamping: return refuse(args.scene, "springs", "spring damping is not modelled");
    default: break;
  }
  const int n = scene.n, unknowns = D * scene.free;
  std::vector<int> row(n, -1);  // the particle's first row in the matrix; -1: fixed
  for (int i = 0; i < n; ++i) if (!scene.fixed(i)) row[i] = D * scene.row[i];
  const std::vector<double>& m = scene.m;
  const std::vector<Spring>& springs = scene.springs;
  const double* g = scene.g;
  const double drag = scene.drag;
  std::vector<double> x = scene.x, v = scene.v;

  // Energies, and the scale the divergence test compares with.
  auto kinetic_plus_spring = [&] { return reference::kinetic_energy(scene, v, reference::spring_energy(scene, x)); };
  reference::TimeLoop loop(args.dt, args.t_end, reference::energy_scale(scene, kinetic_plus_spring()));

  // H's pattern (lower triangle: CHOLMOD reads only that), built once; for
  // every entry a spring or a particle adds to, its place in H's value
  // array, so each iteration writes the values in place.
  using SparseMatrix = Eigen::SparseMatrix<double>;
  SparseMatrix H(unknowns, unknowns);
  {
    std::vector<Eigen::Triplet<double>> pattern;
    auto block = [&](int a, int b) {  // a >= b: rows a.., columns b..
      for (int p = 0; p < D; ++p) {
        for (int q = 0; q < D; ++q) {
          if (a + p >= b + q) pattern.emplace_back(a + p, b + q, 0.0);
        }
      }
    };
    for (int i = 0; i < n; ++i) if (row[i] >= 0) block(row[i], row[i]);
    for (const Spring& s : springs) {
      if (row[s.i] >= 0 && row[s.j] >= 0) block(std::max(row[s.i], row[s.j]), std::min(row[s.i], row[s.j]));
    }
    H.setFromTriplets(pattern.begin(), pattern.end());
  }
  auto place = [&](int r, int c) {  // the index of (r, c), r >= c, in H.valuePtr()
    const int* begin = H.innerIndexPtr() + H.outerIndexPtr()[c];
    const int* end = H.innerIndexPtr() + H.outerIndexPtr()[c + 1];
    return static_cast<int>(std::lower_bound(begin, end, r) - H.innerIndexPtr());
  };
  // A 3 x 3 block's places, row-major; -1 above the diagonal of a diagonal block.
  auto places = [&](int a, int b, int* out) {
    for (int p = 0; p < D; ++p) {
      for (int q = 0; q < D; ++q) out[p * D + q] = a + p >= b + q ? place(a + p, b + q) : -1;
    }
  };
  struct SpringPlaces { int ii[9], jj[9], ij[9]; };  // ij: the block (max, min)
  std::vector<SpringPlaces> spring_places(springs.size());
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const int a = row[springs[s].i], b = row[springs[s].j];
    if (a >= 0) places(a, a, spring_places[s].ii);
    if (b >= 0) places(b, b, spring_places[s].jj);
    if (a >= 0 && b >= 0) places(std::max(a, b), std::min(a, b), spring_places[s].ij);
  }
  std::vector<int> diagonal_places(unknowns);
  for (int u = 0; u < unknowns; ++u) diagonal_places[u] = place(u, u);

  Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> factor;
  factor.cholmod().nmethods = 1;
  factor.cholmod().method[0].ordering = CHOLMOD_AMD;
  factor.analyzePattern(H);

  // The step's pieces. V: the velocities of the unknowns; position(V, i, r)
  // the stage x* = x_n + h v.
  using Vector = Eigen::VectorXd;
  double h = args.dt;
  Vector vn(unknowns), V(unknowns), grad(unknowns), dv(unknowns), trial(unknowns);
  std::vector<double> xs(n * D);
  auto stage = [&](const Vector& at) {
    for (int i = 0; i < n; ++i) {
      for (int r = 0; r < D; ++r) xs[i * D + r] = row[i] >= 0 ? x[i * D + r] + h * at[row[i] + r] : x[i * D + r];
    }
  };
  // Phi (less its constant terms) at `at`; leaves x* staged.
  auto potential = [&](const Vector& at) {
    stage(at);
    double phi = reference::spring_energy(scene, xs);
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        const double u = at[row[i] + r], du = u - vn[row[i] + r];
        phi += 0.5 * m[i] * du * du - h * m[i] * g[r] * u + 0.5 * h * drag * u * u;
      }
    }
    return phi;
  };
  // grad Phi at `at` into grad, and H's values (projected blocks).
  auto gradient_and_hessian = [&](const Vector& at) {
    stage(at);
    double* value = H.valuePtr();
    std::fill(value, value + H.nonZeros(), 0.0);
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        const int u = row[i] + r;
        grad[u] = m[i] * (at[u] - vn[u]) - h * m[i] * g[r] + h * drag * at[u];
        value[diagonal_places[u]] += m[i] + h * drag;
      }
    }
    for (std::size_t s = 0; s < springs.size(); ++s) {
      const Spring& sp = springs[s];
      double d[3], l = 0.0;
      for (int r = 0; r < D; ++r) {
        d[r] = xs[sp.i * D + r] - xs[sp.j * D + r];
        l += d[r] * d[r];
      }
      l = std::sqrt(l);
      const int a = row[sp.i], b = row[sp.j];
      // grad E: k (l - L) n at i, minus that at j; times h (d x*/dv = h).
      for (int r = 0; r < D; ++r) {
        const double f = h * sp.k * (l - sp.rest) * d[r] / l;
        if (a >= 0) grad[a + r] += f;
        if (b >= 0) grad[b + r] -= f;
      }
      // h^2 K_s, with the transverse term only when stretched (Choi and Ko).
      const double transverse = l > sp.rest ? sp.k * (1.0 - sp.rest / l) : 0.0;
      double K[9];
      for (int p = 0; p < D; ++p) {
        for (int q = 0; q < D; ++q) {
          const double nn = d[p] * d[q] / (l * l);
          K[p * D + q] = h * h * (sp.k * nn + transverse * ((p == q ? 1.0 : 0.0) - nn));
        }
      }
      const SpringPlaces& at_s = spring_places[s];
      for (int e = 0; e < 9; ++e) {
        if (a >= 0 && at_s.ii[e] >= 0) value[at_s.ii[e]] += K[e];
        if (b >= 0 && at_s.jj[e] >= 0) value[at_s.jj[e]] += K[e];
        if (a >= 0 && b >= 0) value[at_s.ij[e]] -= K[e];  // symmetric: (i, j) = (j, i)^T
      }
    }
  };

  long newton_iterations = 0, factorizations = 0;
  while (loop.running()) {
    h = loop.h();
    for (int i = 0; i < n; ++i) {
      if (row[i] >= 0) for (int r = 0; r < D; ++r) vn[row[i] + r] = v[i * D + r];
    }
    V = vn;
    double phi = potential(V);
    for (int iteration = 0;; ++iteration) {
      if (iteration == kMaxIterations) {
        std::fprintf(stderr, "newton_reference: no convergence in %d Newton iterations at t = %g; try a smaller --dt\n",
                     kMaxIterations, loop.t);
        return 1;
      }
      gradient_and_hessian(V);
      factor.factorize(H);
      ++factorizations;
      if (factor.info() != Eigen::Success) {
        std::fprintf(stderr, "newton_reference: the projected Hessian is not positive definite at t = %g\n", loop.t);
        return 1;
      }
      dv = factor.solve(-grad);
      ++newton_iterations;
      if (!dv.allFinite()) {
        std::fprintf(stderr, "newton_reference: the Newton update is not finite at t = %g; try a smaller --dt\n", loop.t);
        return 1;
      }
      if (dv.lpNorm<Eigen::Infinity>() <= tol) {
        V += dv;
        break;
      }
      const double slope = grad.dot(dv);  // < 0: H is positive definite
      double alpha = 1.0, phi_trial = 0.0;
      int halvings = 0;
      for (;; alpha *= 0.5, ++halvings) {
        if (halvings == kMaxHalvings) {
          std::fprintf(stderr, "newton_reference: the line search could not decrease Phi at t = %g; try a smaller --dt\n", loop.t);
          return 1;
        }
        trial = V + alpha * dv;
        phi_trial = potential(trial);
        if (phi_trial <= phi + kArmijo * alpha * slope) break;
      }
      V.swap(trial);
      phi = phi_trial;
    }
    for (int i = 0; i < n; ++i) {
      if (row[i] < 0) continue;
      for (int r = 0; r < D; ++r) {
        v[i * D + r] = V[row[i] + r];
        x[i * D + r] += h * V[row[i] + r];
      }
    }
    loop.step_done(h, kinetic_plus_spring());
  }
  if (!reference::write_positions(args.program, positions_file, scene, x)) return 1;
  reference::print_summary(loop, kinetic_plus_spring() + reference::gravity_energy(scene, x), args.start,
                           {{"newton_iterations", std::to_string(newton_iterations)},
                            {"factorizations", std::to_string(factorizations)},
                            {"x_sum", reference::number(reference::coordinate_sum(x))}});
  return 0;
}
