// BM_LinearSolver/<solver>/<scene>/<n>: the linear solvers an implicit
// method could use, side by side on the same matrix
//
//     A = M - h dF/dv - h^2 dF/dx,   h = 1/60 s,
//
// and right-hand side b = h (F + h dF/dx v): linear-implicit (Baraff-Witkin)
// Euler's system for the velocity change dv, of cloth n = 16, 32, 64. The
// state is that of a real animation: kSteps = 30 linear-implicit Euler steps
// of h from the initial state (t = 0.5 s; the cloth is swinging and
// stretching, computed here with an LDL^T, independent of springlab's own
// solvers). The previous step's dv is the warm start of the iterative
// solvers, as it would be in an animation.
//
// One benchmark iteration = what a Newton iteration does with a new matrix
// of the same pattern:
//   ldlt             Eigen SimplicialLDLT, analyzePattern once (outside the
//                    timing); factorize + solve timed
//   ldlt-scratch     Eigen SimplicialLDLT compute() (analysis + factorization)
//                    + solve every time: the "from scratch" baseline
//   sparselu         Eigen SparseLU (the non-symmetric fallback), analysis
//                    reused; factorize + solve
//   cholmod-supernodal  CHOLMOD supernodal LL^T (Eigen/CholmodSupport),
//                    analysis reused; factorize + solve (needs A positive
//                    definite: an error entry when it is not). Its dense
//                    kernels call BLAS; the bench target pins one BLAS thread
//   klu              SUNDIALS' KLU linear solver as cvode-bdf / ida / arkode
//                    use it (SUNDIALS' default COLAMD ordering): the first
//                    setup analyses and factors (outside the timing), later
//                    setups refactor with the same pivot order; setup + solve
//   klu-amd          the same with AMD ordering (SUNLinSol_KLUSetOrdering 0),
//                    the better choice for a matrix of symmetric structure
//   cg-jacobi-warm   Eigen ConjugateGradient, diagonal (Jacobi)
//                    preconditioner, relative residual 1e-8, started from the
//                    previous step's dv; preconditioner setup + solve
//   cg-jacobi-cold   the same started from zero
// Counters: factorize_ms and solve_ms (per iteration; the preconditioner
// setup counts as factorize for CG), cg_iterations, residual (relative, of
// the last solve), initial_residual (CG: relative residual of the guess),
// nonzeros of A, factor_nonzeros (L of LDL^T / LL^T), spd (CHOLMOD only: 1
// when its LL^T succeeded, i.e. A is positive definite).
#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <Eigen/CholmodSupport>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include "benchmarks/bench_support.h"
#include "integrators/linear/preconditioned_cg.h"
#include "integrators/linear/sparse_direct_solver.h"
#include "integrators/sundials/sundials_support.h"

extern "C" void openblas_set_num_threads(int threads);

namespace springlab::bench {
namespace {

constexpr double kH = 1.0 / 60.0;
constexpr int kSteps = 30;  // t = 0.5 s: mid-swing
constexpr double kCgTolerance = 1e-8;
constexpr Eigen::Index kCgMaxIterations = 5000;  // reported as an error beyond

struct LinearSystem {
  SparseMatrix a;
  Vector b;       // at t1
  Vector x_prev;  // solution of the t0 system (warm start)
  // The same matrix from the definite Jacobians (positive definite), at this
  // state and at the state one step before: what springlab factors.
  SparseMatrix a_definite, a_definite_prev;
};

SparseMatrix definite_matrix(const Model& model, double t, const Vector& x,
                             const Vector& v) {
  SparseMatrix dfdx = model.jacobian_pattern();
  model.definite_jacobians(t, x, v, &dfdx, nullptr);
  SparseMatrix a = -kH * kH * dfdx;
  a.diagonal() += model.mass();
  a.makeCompressed();
  return a;
}

// A and b at a state (see the header comment).
void assemble(const Model& model, double t, const Vector& x, const Vector& v,
              SparseMatrix& a, Vector& b) {
  SparseMatrix dfdx = model.jacobian_pattern(), dfdv = model.jacobian_pattern();
  model.jacobians(t, x, v, &dfdx, &dfdv);
  Vector f;
  model.force(t, x, v, f);
  a = -kH * kH * dfdx - kH * dfdv;
  a.diagonal() += model.mass();
  a.makeCompressed();
  b = kH * (f + kH * (dfdx * v));
}

const LinearSystem& system_for(const SceneCase& c) {
  static std::map<std::string, LinearSystem> cache;
  auto found = cache.find(c.path());
  if (found != cache.end()) return found->second;
  const Model& model = model_for(c);
  Vector x = model.initial_positions(), v = model.initial_velocities(), dv;
  LinearSystem sys;
  Eigen::SimplicialLDLT<SparseMatrix> ldlt;
  for (int k = 0; k <= kSteps; ++k) {
    assemble(model, k * kH, x, v, sys.a, sys.b);
    if (k == kSteps - 1) sys.a_definite_prev = definite_matrix(model, k * kH, x, v);
    if (k == kSteps) {
      sys.a_definite = definite_matrix(model, k * kH, x, v);
      break;
    }
    if (k == 0) ldlt.analyzePattern(sys.a);
    ldlt.factorize(sys.a);
    dv = ldlt.solve(sys.b);
    v += dv;
    x += kH * v;
  }
  sys.x_prev = dv;
  return cache.emplace(c.path(), std::move(sys)).first->second;
}

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Timings {
  double factorize_ms = 0.0, solve_ms = 0.0;
  long cg_iterations = 0;
};

void finish(benchmark::State& state, const SceneCase& c, const LinearSystem& sys,
            const Timings& t, const Vector& x, double factor_nonzeros) {
  using benchmark::Counter;
  state.counters["factorize_ms"] = Counter(t.factorize_ms, Counter::kAvgIterations);
  state.counters["solve_ms"] = Counter(t.solve_ms, Counter::kAvgIterations);
  if (t.cg_iterations > 0) {
    state.counters["cg_iterations"] =
        Counter(static_cast<double>(t.cg_iterations), Counter::kAvgIterations);
  }
  state.counters["residual"] = (sys.a * x - sys.b).norm() / sys.b.norm();
  state.counters["nonzeros"] = static_cast<double>(sys.a.nonZeros());
  if (factor_nonzeros > 0) state.counters["factor_nonzeros"] = factor_nonzeros;
  add_size_counters(state, model_for(c));
  state.SetLabel("h=1/60 s, state after 30 linear-implicit Euler steps (t=0.5 s)");
}

// Direct solvers with Eigen's analyzePattern / factorize / solve interface.
template <class Solver>
void direct_benchmark(benchmark::State& state, const SceneCase& c, bool reuse_analysis) {
  const LinearSystem& sys = system_for(c);
  Solver solver;
  solver.analyzePattern(sys.a);
  Vector x = sys.x_prev;
  Timings t;
  for (auto _ : state) {
    auto start = Clock::now();
    if (reuse_analysis) {
      solver.factorize(sys.a);
    } else {
      solver.compute(sys.a);
    }
    t.factorize_ms += ms_since(start);
    if (solver.info() != Eigen::Success) {
      state.SkipWithError("factorization failed (matrix singular or, for LL^T, indefinite)");
      break;
    }
    start = Clock::now();
    x = solver.solve(sys.b);
    t.solve_ms += ms_since(start);
    benchmark::DoNotOptimize(x.data());
  }
  double factor_nonzeros = 0.0;
  if constexpr (requires { solver.matrixL().nestedExpression().nonZeros(); }) {
    if (solver.info() == Eigen::Success)
      factor_nonzeros = static_cast<double>(solver.matrixL().nestedExpression().nonZeros());
  }
  finish(state, c, sys, t, x, factor_nonzeros);
}

void cg_benchmark(benchmark::State& state, const SceneCase& c, bool warm) {
  const LinearSystem& sys = system_for(c);
  Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper,
                           Eigen::DiagonalPreconditioner<double>>
      cg;
  cg.setTolerance(kCgTolerance);
  cg.setMaxIterations(kCgMaxIterations);
  const Vector guess = warm ? sys.x_prev : Vector::Zero(sys.b.size());
  Vector x;
  Timings t;
  for (auto _ : state) {
    auto start = Clock::now();
    cg.compute(sys.a);
    t.factorize_ms += ms_since(start);
    start = Clock::now();
    x = cg.solveWithGuess(sys.b, guess);
    t.solve_ms += ms_since(start);
    t.cg_iterations += cg.iterations();
    benchmark::DoNotOptimize(x.data());
  }
  if (cg.info() != Eigen::Success) {
    state.SkipWithError("CG did not reach the tolerance within kCgMaxIterations iterations");
  }
  state.counters["initial_residual"] = (sys.a * guess - sys.b).norm() / sys.b.norm();
  finish(state, c, sys, t, x, 0.0);
}

void cholmod_benchmark(benchmark::State& state, const SceneCase& c) {
  const LinearSystem& sys = system_for(c);
  Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> solver;
  solver.analyzePattern(sys.a);
  Vector x = sys.x_prev;
  Timings t;
  for (auto _ : state) {
    auto start = Clock::now();
    solver.factorize(sys.a);
    t.factorize_ms += ms_since(start);
    if (solver.info() != Eigen::Success) {
      state.counters["spd"] = 0.0;
      state.SkipWithError("CHOLMOD LL^T failed: A is not positive definite at this state");
      break;
    }
    start = Clock::now();
    x = solver.solve(sys.b);
    t.solve_ms += ms_since(start);
    benchmark::DoNotOptimize(x.data());
  }
  if (solver.info() == Eigen::Success) {
    state.counters["spd"] = 1.0;
    const auto& factor = solver.cholmod();  // the Common: lnz counted by the analysis
    state.counters["factor_nonzeros"] = factor.lnz;
  }
  finish(state, c, sys, t, x, 0.0);
}

// springlab's own solver (integrators/linear/sparse_direct_solver.h: CHOLMOD
// supernodal LL^T, one BLAS thread) on the definite matrix.
void springlab_cholesky_benchmark(benchmark::State& state, const SceneCase& c) {
  const LinearSystem& sys = system_for(c);
  SparseDirectSolver solver;
  Vector x;
  Timings t;
  for (auto _ : state) {
    auto start = Clock::now();
    const bool ok = solver.factorize(sys.a_definite, MatrixKind::kPositiveDefinite) &&
                    solver.positive_definite();
    t.factorize_ms += ms_since(start);
    if (!ok) {
      state.SkipWithError("LL^T of the definite matrix failed");
      return;
    }
    start = Clock::now();
    solver.solve(sys.b, x);
    t.solve_ms += ms_since(start);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["factor_flops"] = solver.factor_flops();
  finish(state, c, sys, t, x, solver.factor_nonzeros());
  state.counters["residual"] = (sys.a_definite * x - sys.b).norm() / sys.b.norm();
}

// CG on the definite matrix preconditioned by the factor of the one a step
// earlier (what a kept factor does across steps), to a relative error
// estimate of 1e-6 (the linearized step's) and 1e-2.
void kept_factor_benchmark(benchmark::State& state, const SceneCase& c, double rtol) {
  const LinearSystem& sys = system_for(c);
  SparseDirectSolver kept;
  if (!kept.factorize(sys.a_definite_prev, MatrixKind::kPositiveDefinite)) {
    state.SkipWithError("LL^T of the definite matrix failed");
    return;
  }
  Vector x;
  CgScratch scratch;
  Timings t;
  for (auto _ : state) {
    const auto start = Clock::now();
    const CgResult r = preconditioned_cg(sys.a_definite, kept, sys.b, rtol, 0.0, 1000, x, scratch);
    t.solve_ms += ms_since(start);
    t.cg_iterations += r.iterations;
    if (!r.converged) {
      state.SkipWithError("CG did not converge in 1000 iterations");
      return;
    }
  }
  finish(state, c, sys, t, x, kept.factor_nonzeros());
  state.counters["residual"] = (sys.a_definite * x - sys.b).norm() / sys.b.norm();
}

// The definite matrix factored with one and with two OpenBLAS threads in
// alternation (the thread count is process-wide), each timed by the wall
// clock: on a busy 2-core machine the pair sees the same load.
void threads_benchmark(benchmark::State& state, const SceneCase& c) {
  const LinearSystem& sys = system_for(c);
  SparseDirectSolver solver;
  double ms[2] = {0.0, 0.0};
  bool one_first = true;
  for (auto _ : state) {
    for (int k = 0; k < 2; ++k) {
      const int threads = (k == 0) == one_first ? 1 : 2;
      openblas_set_num_threads(threads);
      const auto start = Clock::now();
      solver.factorize(sys.a_definite, MatrixKind::kPositiveDefinite);
      ms[threads - 1] += ms_since(start);
    }
    one_first = !one_first;
  }
  openblas_set_num_threads(1);
  const double n = static_cast<double>(state.iterations());
  state.counters["one_thread_ms"] = ms[0] / n;
  state.counters["two_threads_ms"] = ms[1] / n;
  state.counters["ratio"] = ms[1] / ms[0];
  add_size_counters(state, model_for(c));
  state.SetLabel("definite matrix, h=1/60 s, state after 30 linear-implicit Euler steps");
}

// SUNDIALS' KLU on a copy of A in a SUNDIALS sparse (CSC) matrix.
void klu_benchmark(benchmark::State& state, const SceneCase& c, int ordering) {
  namespace sd = springlab::sundials;
  const LinearSystem& sys = system_for(c);
  const auto n = static_cast<sunindextype>(sys.a.rows());
  const auto nnz = static_cast<sunindextype>(sys.a.nonZeros());
  SUNContext raw_ctx = nullptr;
  if (SUNContext_Create(nullptr, &raw_ctx) != 0) {
    state.SkipWithError("SUNContext_Create failed");
    return;
  }
  sd::ContextPtr ctx(raw_ctx);
  sd::MatrixPtr a(SUNSparseMatrix(n, n, nnz, CSC_MAT, ctx.get()));
  sd::VectorPtr xv(N_VNew_Serial(n, ctx.get())), bv(N_VNew_Serial(n, ctx.get()));
  if (!a || !xv || !bv) {
    state.SkipWithError("SUNDIALS allocation failed");
    return;
  }
  sunindextype* colptr = SUNSparseMatrix_IndexPointers(a.get());
  sunindextype* rowind = SUNSparseMatrix_IndexValues(a.get());
  double* data = SUNSparseMatrix_Data(a.get());
  for (sunindextype j = 0; j <= n; ++j) colptr[j] = sys.a.outerIndexPtr()[j];
  for (sunindextype k = 0; k < nnz; ++k) {
    rowind[k] = sys.a.innerIndexPtr()[k];
    data[k] = sys.a.valuePtr()[k];
  }
  Eigen::Map<Vector>(N_VGetArrayPointer(bv.get()), n) = sys.b;
  sd::LinearSolverPtr ls(SUNLinSol_KLU(xv.get(), a.get(), ctx.get()));
  if (!ls || (ordering >= 0 && SUNLinSol_KLUSetOrdering(ls.get(), ordering) != 0) ||
      SUNLinSolInitialize(ls.get()) != 0 || SUNLinSolSetup(ls.get(), a.get()) != 0) {
    state.SkipWithError("KLU: initial analysis/factorization failed");
    return;
  }
  Timings t;
  for (auto _ : state) {
    auto start = Clock::now();
    const int setup = SUNLinSolSetup(ls.get(), a.get());  // klu_refactor
    t.factorize_ms += ms_since(start);
    if (setup != 0) {
      state.SkipWithError("KLU: refactorization failed");
      break;
    }
    start = Clock::now();
    const int solve = SUNLinSolSolve(ls.get(), a.get(), xv.get(), bv.get(), 0.0);
    t.solve_ms += ms_since(start);
    if (solve != 0) {
      state.SkipWithError("KLU: solve failed");
      break;
    }
  }
  const Vector x = Eigen::Map<const Vector>(N_VGetArrayPointer(xv.get()), n);
  finish(state, c, sys, t, x, 0.0);
}

}  // namespace

void register_linear_solver_benchmarks() {
  using Ldlt = Eigen::SimplicialLDLT<SparseMatrix>;
  using Lu = Eigen::SparseLU<SparseMatrix>;
  for (const SceneCase& c : all_cases()) {
    if (c.scene != "cloth") continue;
    const std::string path = "/" + c.path();
    auto reg = [&](const std::string& solver, auto fn) {
      benchmark::RegisterBenchmark(("BM_LinearSolver/" + solver + path).c_str(), fn)
          ->Unit(benchmark::kMillisecond)
          ->MinTime(0.3);
    };
    reg("springlab-cholesky", [c](benchmark::State& s) { springlab_cholesky_benchmark(s, c); });
    reg("kept-factor-cg-1e-6", [c](benchmark::State& s) { kept_factor_benchmark(s, c, 1e-6); });
    reg("kept-factor-cg-1e-2", [c](benchmark::State& s) { kept_factor_benchmark(s, c, 1e-2); });
    benchmark::RegisterBenchmark(("BM_CholeskyThreads" + path).c_str(),
                                 [c](benchmark::State& s) { threads_benchmark(s, c); })
        ->Unit(benchmark::kMillisecond)
        ->MinTime(1.0);
    if (c.n > 64) continue;  // the simplicial and KLU solvers take seconds on cloth 128
    reg("ldlt", [c](benchmark::State& s) { direct_benchmark<Ldlt>(s, c, true); });
    reg("ldlt-scratch", [c](benchmark::State& s) { direct_benchmark<Ldlt>(s, c, false); });
    reg("sparselu", [c](benchmark::State& s) { direct_benchmark<Lu>(s, c, true); });
    reg("cholmod-supernodal", [c](benchmark::State& s) { cholmod_benchmark(s, c); });
    reg("klu", [c](benchmark::State& s) { klu_benchmark(s, c, -1); });
    reg("klu-amd", [c](benchmark::State& s) { klu_benchmark(s, c, 0); });
    reg("cg-jacobi-warm", [c](benchmark::State& s) { cg_benchmark(s, c, true); });
    reg("cg-jacobi-cold", [c](benchmark::State& s) { cg_benchmark(s, c, false); });
  }
}

}  // namespace springlab::bench
