// The implicit methods on the cloth at an animation step, h = 1/60 s, for
// 2 s of motion from rest: what a whole run costs and how accurately Newton
// solves each step. Long (cloth 128: about 10 minutes per family), so
// registered only when SPRINGLAB_BENCH_LONG=1 (or SPRINGLAB_BENCH_ALL=1) is
// set; one iteration each.
//
// BM_Run/<integrator>/cloth/<n>: simulate() (the driver `springlab run`
// uses: no output files) from t = 0 to 2 s at dt = 1/60 s with the default
// options (linear-implicit-euler:definite: with --stiffness definite;
// implicit-euler:quasi-newton-1e-3: --solver quasi-newton --newton-tol
// 1e-3). Counters: status (1 completed, 0 diverged or failed), t_final,
// cpu_ms_per_step and wall_ms_per_step (process CPU time and wall time over
// the steps taken), newton_per_step, factorizations_per_step,
// cg_per_step (linear_iterations), energy_final - energy_initial.
//
// BM_NewtonBuckling/implicit-euler/cloth/32-128: issue 51's Newton target
// in one benchmark, so the exponent comes from one run: the first 0.3 s
// (18 steps of 1/60 s, the cloth falls and starts to buckle) of cloth 32, 64
// and 128 in turn with the default options, each as a whole `springlab run
// cloth -p n=N --integrator implicit-euler --dt 1/60 --t-end 0.3 --json`
// process (timed: its user + system CPU time), then stepped here untimed to
// see each step's Newton iterations (the same code and options: the total
// must equal the process's, or the benchmark fails). Counters per size N:
// cpu_ms_N (the process's CPU time per step), newton_N (per step),
// newton_max_N (the most in one step: the buckling steps'), over_12_N
// (steps of more than 12 iterations), cg_N and factorizations_N (per
// step); exponent = log(cpu_ms_128 / cpu_ms_32) / log(unknowns_128 /
// unknowns_32).
//
// BM_NewtonAccuracy/<integrator>/cloth/<n>[/tol:T]: the same run (at the
// default tolerance, or at T) stepped here, with
// every step's Newton iterations recorded (newton_mean, newton_p95,
// newton_max: what the iteration cap is set from), and at every tenth step,
// from the same start state (t_n, x_n, v_n), three fresh solves:
//   a. one step at the tolerance,
//   b. one step at the tolerance / 1000,
//   c. two steps of h/2 at the tolerance;
// solver_mm = max over samples of ||x_a - x_b||_inf (the solver error of a
// step), run_solver_mm = the same for the run's own step (its kept
// preconditioner takes another path to the root, sometimes to another root
// of a buckling cloth), disc_mm_min / disc_mm_median = ||x_a - x_c||_inf
// (h against h/2: the size of the step's discretization error), and
// ratio_max = max of solver_mm / disc_mm over the samples.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <unistd.h>

#include "benchmarks/bench_support.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"

namespace springlab::bench {
namespace {

constexpr double kFrame = 1.0 / 60.0;
constexpr double kDuration = 2.0;
constexpr long kSampleEvery = 10;

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

const Model& cloth(int n) {
  // Sizes beyond bench_support's cases (48, 96) are built here once.
  return model_for({"cloth", n});
}

void run_benchmark(benchmark::State& state, const std::string& integrator, int n,
                   const IntegratorOptions& options, double duration = kDuration) {
  const Model& model = cloth(n);
  RunSettings settings;
  settings.integrator = integrator;
  settings.options = options;
  settings.dt = kFrame;
  settings.t_end = duration;
  RunResult r;
  double cpu = 0.0;
  for (auto _ : state) {
    const double start = cpu_seconds();
    r = simulate(model, settings);
    cpu = cpu_seconds() - start;
  }
  const double steps = std::max(1.0, static_cast<double>(r.stats.steps));
  state.counters["status"] = r.status == RunStatus::kCompleted ? 1.0 : 0.0;
  state.counters["t_final"] = r.t_final;
  state.counters["cpu_ms_per_step"] = 1e3 * cpu / steps;
  state.counters["wall_ms_per_step"] = 1e3 * r.wall_seconds / steps;
  state.counters["newton_per_step"] = static_cast<double>(r.stats.newton_iterations) / steps;
  state.counters["factorizations_per_step"] = static_cast<double>(r.stats.factorizations) / steps;
  state.counters["cg_per_step"] = static_cast<double>(r.stats.linear_iterations) / steps;
  state.counters["energy_change"] = r.energy_final - r.energy_initial;
  state.counters["energy_scale"] = model.energy_scale();
  add_size_counters(state, model);
  state.SetLabel(r.status == RunStatus::kCompleted
                     ? "dt=1/60 s, " + short_number(duration) + " s, default options"
                     : "did not complete: " + r.failure);
}

// One step of a fresh integrator from (t, x, v), in `steps` equal parts.
bool fresh_step(const std::string& name, const Model& model, double t, const Vector& x,
                const Vector& v, double tol, int steps, Vector& x_out) {
  auto integrator = make_integrator(name);
  IntegratorOptions options;
  options.newton_tol = tol;
  if (!integrator->initialize(model, t, x, v, options).ok) return false;
  for (int k = 1; k <= steps; ++k) {
    if (!integrator->advance_to(t + kFrame * k / steps).ok) return false;
  }
  x_out = integrator->x();
  return true;
}

void accuracy_benchmark(benchmark::State& state, const std::string& name, int n, double tol) {
  const Model& model = cloth(n);
  std::vector<double> newton, disc;
  double solver_max = 0.0, run_solver_max = 0.0, ratio_max = 0.0;
  long failures = 0;
  double t_final = 0.0;
  for (auto _ : state) {
    auto integrator = make_integrator(name);
    IntegratorOptions options;
    options.newton_tol = tol;
    integrator->initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                           options);
    const long steps = std::lround(kDuration / kFrame);
    for (long k = 1; k <= steps; ++k) {
      const double t = integrator->t();
      const Vector x = integrator->x(), v = integrator->v();
      const long before = integrator->stats().newton_iterations;
      if (!integrator->advance_to(k * kFrame).ok) break;
      t_final = integrator->t();
      newton.push_back(static_cast<double>(integrator->stats().newton_iterations - before));
      if (k % kSampleEvery != 0) continue;
      Vector xa, xb, xc;
      if (!fresh_step(name, model, t, x, v, tol, 1, xa) ||
          !fresh_step(name, model, t, x, v, tol / 1000.0, 1, xb) ||
          !fresh_step(name, model, t, x, v, tol, 2, xc)) {
        ++failures;
        continue;
      }
      const double solver = (xa - xb).lpNorm<Eigen::Infinity>();
      const double d = (xa - xc).lpNorm<Eigen::Infinity>();
      solver_max = std::max(solver_max, solver);
      run_solver_max = std::max(run_solver_max, (integrator->x() - xb).lpNorm<Eigen::Infinity>());
      disc.push_back(d);
      if (d > 0.0) ratio_max = std::max(ratio_max, solver / d);
    }
  }
  auto percentile = [](std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
  };
  double sum = 0.0;
  for (double k : newton) sum += k;
  state.counters["t_final"] = t_final;
  state.counters["newton_mean"] = newton.empty() ? 0.0 : sum / static_cast<double>(newton.size());
  state.counters["newton_p95"] = percentile(newton, 0.95);
  state.counters["newton_max"] = percentile(newton, 1.0);
  state.counters["solver_mm"] = 1e3 * solver_max;
  state.counters["run_solver_mm"] = 1e3 * run_solver_max;
  state.counters["disc_mm_min"] = 1e3 * percentile(disc, 0.0);
  state.counters["disc_mm_median"] = 1e3 * percentile(disc, 0.5);
  state.counters["ratio_max"] = ratio_max;
  state.counters["sample_failures"] = static_cast<double>(failures);
  state.counters["newton_tol"] = tol;
  add_size_counters(state, model);
  state.SetLabel("dt=1/60 s, 2 s; samples every " + std::to_string(kSampleEvery) + " steps");
}

// The Newton iterations of each step of the first `duration` seconds of
// the cloth, from an integrator stepped here with the default options (the
// same code and options as `springlab run`'s: the same counts).
std::vector<long> newton_per_step(const Model& model, double duration) {
  auto integrator = make_integrator("implicit-euler");
  integrator->initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                         IntegratorOptions{});
  std::vector<long> counts;
  const long steps = std::lround(duration / kFrame);
  for (long k = 1; k <= steps; ++k) {
    const long before = integrator->stats().newton_iterations;
    if (!integrator->advance_to(static_cast<double>(k) * kFrame).ok) break;
    counts.push_back(integrator->stats().newton_iterations - before);
  }
  return counts;
}

void buckling_benchmark(benchmark::State& state) {
  constexpr double kBucklingDuration = 0.3;
  constexpr long kMostPerStep = 12;
  const std::vector<int> sizes = {32, 64, 128};
  std::vector<double> cpu_ms(sizes.size()), unknowns(sizes.size());
  const std::filesystem::path out = std::filesystem::temp_directory_path() /
                                    ("springlab_bench_buckling_" + std::to_string(::getpid()) +
                                     ".json");
  for (auto _ : state) {
    for (std::size_t s = 0; s < sizes.size(); ++s) {
      const int n = sizes[s];
      const std::string N = std::to_string(n);
      double cpu = 0.0;
      if (run_process({SPRINGLAB_EXE, "run", "cloth", "-p", "n=" + N, "--integrator",
                       "implicit-euler", "--dt", "0.016666666666666666", "--t-end", "0.3",
                       "--json"},
                      out, &cpu) < 0) {
        state.SkipWithError(("springlab run on cloth " + N + " failed").c_str());
        return;
      }
      std::ifstream in(out);
      const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
      const double steps = std::max(1.0, json_number(text, "steps"));
      const double newton = json_number(text, "newton_iterations");
      // Each step's count, from the same code stepped here (untimed).
      const std::vector<long> counts = newton_per_step(cloth(n), kBucklingDuration);
      long most = 0, over = 0, sum = 0;
      for (long k : counts) {
        most = std::max(most, k);
        over += k > kMostPerStep ? 1 : 0;
        sum += k;
      }
      if (static_cast<double>(sum) != newton) {
        state.SkipWithError(("cloth " + N + ": the stepped run's Newton iterations differ from "
                             "springlab run's").c_str());
        return;
      }
      cpu_ms[s] = 1e3 * cpu / steps;
      unknowns[s] = static_cast<double>(cloth(n).dofs());
      state.counters["cpu_ms_" + N] = cpu_ms[s];
      state.counters["newton_" + N] = newton / steps;
      state.counters["newton_max_" + N] = static_cast<double>(most);
      state.counters["over_12_" + N] = static_cast<double>(over);
      state.counters["cg_" + N] = json_number(text, "linear_iterations") / steps;
      state.counters["factorizations_" + N] = json_number(text, "factorizations") / steps;
      state.counters["unknowns_" + N] = unknowns[s];
    }
  }
  std::filesystem::remove(out);
  state.counters["exponent"] =
      std::log(cpu_ms.back() / cpu_ms.front()) / std::log(unknowns.back() / unknowns.front());
  state.SetLabel("springlab run, dt=1/60 s, 0.3 s, default options, cloth 32, 64, 128 in turn");
}

}  // namespace

void register_newton_benchmarks() {
  if (std::getenv("SPRINGLAB_BENCH_LONG") == nullptr &&
      std::getenv("SPRINGLAB_BENCH_ALL") == nullptr) {
    return;
  }
  struct Case {
    const char* integrator;
    std::vector<int> sizes;
  };
  const std::vector<Case> runs = {{"implicit-euler", {16, 32, 48, 64, 96, 128}},
                                  {"linear-implicit-euler", {16, 32, 64, 128}},
                                  {"implicit-midpoint", {16}},
                                  {"discrete-gradient", {16, 32}}};
  for (const Case& c : runs) {
    for (int n : c.sizes) {
      const std::string name = c.integrator;
      benchmark::RegisterBenchmark(
          ("BM_Run/" + name + "/cloth/" + std::to_string(n)).c_str(),
          [name, n](benchmark::State& s) { run_benchmark(s, name, n, IntegratorOptions{}); })
          ->Unit(benchmark::kSecond)
          ->Iterations(1);
    }
  }
  // Issue 37's Newton target on its first 0.3 s (18 steps: the cloth falls
  // and starts to buckle), where a whole run of cloth 128 takes about ten
  // minutes of CPU: the step cost and its exponent over 32-128.
  for (int n : {32, 64, 128}) {
    benchmark::RegisterBenchmark(
        ("BM_Run/implicit-euler/cloth/" + std::to_string(n) + "/t:0.3").c_str(),
        [n](benchmark::State& s) { run_benchmark(s, "implicit-euler", n, IntegratorOptions{}, 0.3); })
        ->Unit(benchmark::kSecond)
        ->Iterations(1);
  }
  benchmark::RegisterBenchmark("BM_NewtonBuckling/implicit-euler/cloth/32-128", buckling_benchmark)
      ->Unit(benchmark::kSecond)
      ->Iterations(1);
  for (int n : {16, 32, 64, 128}) {
    benchmark::RegisterBenchmark(
        ("BM_Run/linear-implicit-euler:definite/cloth/" + std::to_string(n)).c_str(),
        [n](benchmark::State& s) {
          IntegratorOptions definite;
          definite.stiffness = Stiffness::kDefinite;
          run_benchmark(s, "linear-implicit-euler", n, definite);
        })
        ->Unit(benchmark::kSecond)
        ->Iterations(1);
  }
  // The fast solvers of issue 13 at their defaults (projective dynamics: 10
  // iterations; xpbd: 10 substeps x 1 iteration), and quasi-Newton at
  // 1e-3 m/s, the targets on cloth 64 and its exponent over 32-128.
  IntegratorOptions quasi_newton;
  quasi_newton.solver = Solver::kQuasiNewton;
  quasi_newton.newton_tol = 1e-3;
  for (const auto& [label, name, options] :
       std::vector<std::tuple<std::string, std::string, IntegratorOptions>>{
           {"projective-dynamics", "projective-dynamics", IntegratorOptions{}},
           {"xpbd", "xpbd", IntegratorOptions{}},
           {"implicit-euler:quasi-newton-1e-3", "implicit-euler", quasi_newton}}) {
    for (int n : {32, 64, 128}) {
      benchmark::RegisterBenchmark(
          ("BM_Run/" + label + "/cloth/" + std::to_string(n)).c_str(),
          [name, n, options](benchmark::State& s) { run_benchmark(s, name, n, options); })
          ->Unit(benchmark::kSecond)
          ->Iterations(1);
    }
  }
  // The default tolerance on every size; 10 and 100 times it on two, to show
  // how the solver error scales with it.
  const double tol = IntegratorOptions{}.newton_tol;
  for (const auto& [n, factor] : std::vector<std::pair<int, double>>{
           {16, 1}, {32, 1}, {64, 1}, {128, 1}, {32, 10}, {64, 10}, {32, 100}, {64, 100}}) {
    const std::string name = "BM_NewtonAccuracy/implicit-euler/cloth/" + std::to_string(n) +
                             (factor == 1 ? "" : "/tol:" + short_number(factor * tol));
    benchmark::RegisterBenchmark(name.c_str(),
                                 [n, t = factor * tol](benchmark::State& s) {
                                   accuracy_benchmark(s, "implicit-euler", n, t);
                                 })
        ->Unit(benchmark::kSecond)
        ->Iterations(1);
  }
}

}  // namespace springlab::bench
