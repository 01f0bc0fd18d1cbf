// BM_FluidStep/dam-break/<n>: one explicit step of the 2-D dam break
// (docs/scenes.md "dam-break"): symplectic Euler at the acoustic CFL step
// dt = 0.25 h / c, i.e. one force evaluation -- the neighbours (the list of
// models/fluids/sph_particles.h: filtered by distance at each evaluation,
// searched again within 1.25 x 2h once a particle has moved h / 4 from the
// last search), the summation density, the pressure and the viscosity
// forces -- and the update.
// BM_FluidNeighbours/dam-break/<n>: the neighbour search alone
// (NeighbourGrid::build over every particle, radius 2h), at the initial
// positions.
//
// n is a / spacing (a = 1 m): 16, 64 and 217 give 1,268, 11,108 and 103,982
// particles (water 2 n^2, then three layers of wall particles and the lid).
// Counters: `ns_per_particle` (CPU time per iteration / all particles of the
// fluid, walls included: they are searched like the water, though pairs of
// two wall particles are not kept), `particles`, `water`, `pairs` (within
// 2h at the start). Each run starts from rest at t = 0 (the column starts
// to fall: every step moves every particle, by less than the list's limit,
// so most evaluations filter the last search's list); a run lasts Google
// Benchmark's usual 0.5 s or one step, whichever is longer, well before the
// front reaches the far wall.
//
// BM_FluidImplicit/dam-break: the default dam break (a = 0.1 m, spacing
// 5 mm: 800 water particles, 936 wall particles with the lid, 1,600 unknowns) under
// implicit-euler at dt = 1 ms, issue 50's three figures side by side in one
// iteration (so that they see the same machine load):
//   - step_ms: a run of 0.05 s (50 steps) through simulate(), the driver of
//     `springlab run` (set-up included), CPU time of this thread per step;
//     newton_per_step, factorizations_per_step, cg_per_step; iteration_ms =
//     step_ms / newton_per_step;
//   - eval_ms: at that run's last state, one explicit evaluation of the
//     force and both Jacobians (Model::force, jacobians: the
//     neighbour search, the densities, the pressure's reach-two Hessian
//     and the viscosity's), the pattern already current; the mean of 10;
//   - factor_ms: the numeric Cholesky factorization (CHOLMOD supernodal, as
//     Newton's linear solver) of the Newton matrix M - h^2 dF/dx (definite
//     part) - h dF/dv of that state on the same pattern, its symbolic
//     analysis done once beforehand; the mean of 10 (analyse_ms: that
//     analysis, once);
//   - ratio = iteration_ms / (eval_ms + factor_ms): issue 50's target is
//     at most 3 (and step_ms at most 10).
// Counters also: pattern_nonzeros, factor_nonzeros.
#include <ctime>
#include <map>
#include <memory>

#include "benchmarks/bench_support.h"
#include "experiments/driver/simulation.h"
#include "experiments/io/output_files.h"
#include "integrators/linear/sparse_direct_solver.h"
#include "integrators/registry/registry.h"
#include "models/fluids/fluids.h"
#include "models/fluids/neighbour_grid.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab::bench {
namespace {

const Model& dam_break_model(int n) {
  static std::map<int, std::unique_ptr<Model>> models;
  auto& slot = models[n];
  if (!slot) {
    const double spacing = 1.0 / n;
    slot = std::make_unique<Model>(make_builtin_scene(
        "dam-break", {{"a", "1"}, {"spacing", format_number(spacing)}, {"dimension", "2"}}));
  }
  return *slot;
}

void fluid_counters(benchmark::State& state, const Model& model, std::size_t pairs) {
  const Fluid& fluid = model.scene().get<Fluids>().front();
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * fluid.count * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["particles"] = fluid.count;
  state.counters["water"] = model.free_particle_count();
  state.counters["pairs"] = static_cast<double>(pairs);
}

std::size_t initial_pairs(const Model& model, NeighbourGrid& grid) {
  const Eigen::MatrixXd x = model.scene_positions(model.initial_positions());
  std::vector<double> flat(static_cast<std::size_t>(x.size()));
  for (Eigen::Index s = 0; s < x.rows(); ++s) {
    for (Eigen::Index r = 0; r < x.cols(); ++r) flat[static_cast<std::size_t>(s * x.cols() + r)] = x(s, r);
  }
  const Fluid& fluid = model.scene().get<Fluids>().front();
  grid.build(flat.data(), static_cast<int>(x.rows()), static_cast<int>(x.cols()),
             2.0 * kSmoothingPerSpacing * fluid.spacing);
  return grid.pairs().size();
}

void fluid_step(benchmark::State& state, int n) {
  const Model& model = dam_break_model(n);
  const Fluid& fluid = model.scene().get<Fluids>().front();
  const double dt = 0.25 * kSmoothingPerSpacing * fluid.spacing / fluid.speed_of_sound;
  std::unique_ptr<Integrator> integrator = make_integrator("symplectic-euler");
  const StepResult r = integrator->initialize(model, 0.0, model.initial_positions(),
                                              model.initial_velocities(), {});
  if (!r.ok) {
    state.SkipWithError(r.message.c_str());
    return;
  }
  for (auto _ : state) {
    const StepResult step = integrator->advance_to(integrator->t() + dt);
    if (!step.ok) {
      state.SkipWithError(step.message.c_str());
      return;
    }
  }
  NeighbourGrid grid;
  fluid_counters(state, model, initial_pairs(model, grid));
  state.counters["dt"] = dt;
}

void fluid_neighbours(benchmark::State& state, int n) {
  const Model& model = dam_break_model(n);
  const Eigen::MatrixXd x = model.scene_positions(model.initial_positions());
  std::vector<double> flat(static_cast<std::size_t>(x.size()));
  for (Eigen::Index s = 0; s < x.rows(); ++s) {
    for (Eigen::Index r = 0; r < x.cols(); ++r) flat[static_cast<std::size_t>(s * x.cols() + r)] = x(s, r);
  }
  const Fluid& fluid = model.scene().get<Fluids>().front();
  NeighbourGrid grid;
  for (auto _ : state) {
    grid.build(flat.data(), static_cast<int>(x.rows()), 2,
               2.0 * kSmoothingPerSpacing * fluid.spacing);
    benchmark::DoNotOptimize(grid.pairs().data());
  }
  fluid_counters(state, model, grid.pairs().size());
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void fluid_implicit(benchmark::State& state) {
  const Model model(make_builtin_scene("dam-break", {}));
  constexpr double kDt = 1e-3, kEnd = 0.05;
  constexpr int kRepeats = 10;
  double step_ms = 0.0, eval_ms = 0.0, factor_ms = 0.0, analyse_ms = 0.0;
  double newton = 0.0, factorizations = 0.0, cg = 0.0, steps = 0.0, factor_nonzeros = 0.0;
  long pattern_nonzeros = 0;
  for (auto _ : state) {
    // 1. The run, through simulate().
    RunSettings run;
    run.integrator = "implicit-euler";
    run.dt = kDt;
    run.t_end = kEnd;
    double start = thread_cpu_seconds();
    const RunResult r = simulate(model, run);
    const double run_seconds = thread_cpu_seconds() - start;
    if (r.status != RunStatus::kCompleted) {
      state.SkipWithError(r.failure.c_str());
      return;
    }
    steps = static_cast<double>(r.stats.steps);
    step_ms = 1e3 * run_seconds / steps;
    newton = static_cast<double>(r.stats.newton_iterations) / steps;
    factorizations = static_cast<double>(r.stats.factorizations) / steps;
    cg = static_cast<double>(r.stats.linear_iterations) / steps;
    // 2. One force and Jacobian evaluation at the last state (the pattern
    // made current by a first one).
    struct {
      double t;
      const Vector &x, &v;
    } last{r.t_final, r.x_final, r.v_final};
    Vector f;
    SparseMatrix dfdx, dfdv;
    model.jacobians(last.t, last.x, last.v, &dfdx, &dfdv);
    start = thread_cpu_seconds();
    for (int k = 0; k < kRepeats; ++k) {
      // A new position each time, as in Newton's iterations (the same
      // positions would reuse the neighbour search).
      Vector x = last.x;
      x[0] += 1e-9 * (k + 1);
      model.force(last.t, x, last.v, f);
      model.jacobians(last.t, x, last.v, &dfdx, &dfdv);
      benchmark::DoNotOptimize(dfdx.valuePtr());
    }
    eval_ms = 1e3 * (thread_cpu_seconds() - start) / kRepeats;
    pattern_nonzeros = static_cast<long>(dfdx.nonZeros());
    // 3. The Newton matrix's factorization on that pattern.
    SparseMatrix definite, velocity;
    model.definite_jacobians(last.t, last.x, last.v, &definite, &velocity);
    SparseMatrix newton_matrix = definite;
    for (Eigen::Index k = 0; k < newton_matrix.nonZeros(); ++k) {
      newton_matrix.valuePtr()[k] =
          -kDt * kDt * definite.valuePtr()[k] - kDt * velocity.valuePtr()[k];
    }
    newton_matrix.diagonal() += model.mass();
    SparseDirectSolver solver;
    start = thread_cpu_seconds();
    if (!solver.factorize(newton_matrix, MatrixKind::kPositiveDefinite)) {
      state.SkipWithError(("factorization: " + solver.error()).c_str());
      return;
    }
    analyse_ms = 1e3 * (thread_cpu_seconds() - start);
    start = thread_cpu_seconds();
    for (int k = 0; k < kRepeats; ++k) solver.factorize(newton_matrix, MatrixKind::kPositiveDefinite);
    factor_ms = 1e3 * (thread_cpu_seconds() - start) / kRepeats;
    factor_nonzeros = solver.factor_nonzeros();
  }
  state.counters["step_ms"] = step_ms;
  state.counters["newton_per_step"] = newton;
  state.counters["factorizations_per_step"] = factorizations;
  state.counters["cg_per_step"] = cg;
  state.counters["iteration_ms"] = step_ms / newton;
  state.counters["eval_ms"] = eval_ms;
  state.counters["factor_ms"] = factor_ms;
  state.counters["analyse_ms"] = analyse_ms;
  state.counters["ratio"] = step_ms / newton / (eval_ms + factor_ms);
  state.counters["pattern_nonzeros"] = static_cast<double>(pattern_nonzeros);
  state.counters["factor_nonzeros"] = factor_nonzeros;
  state.counters["unknowns"] = static_cast<double>(model.dofs());
  state.SetLabel("implicit-euler dt=1ms, 0.05 s");
}

}  // namespace

void register_fluid_benchmarks() {
  benchmark::RegisterBenchmark("BM_FluidImplicit/dam-break", fluid_implicit)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1)
      ->Repetitions(3)
      ->ReportAggregatesOnly(false);
  for (int n : {16, 64, 217}) {
    const std::string size = "dam-break/" + std::to_string(n);
    benchmark::RegisterBenchmark(("BM_FluidStep/" + size).c_str(),
                                 [n](benchmark::State& s) { fluid_step(s, n); })
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_FluidNeighbours/" + size).c_str(),
                                 [n](benchmark::State& s) { fluid_neighbours(s, n); })
        ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace springlab::bench
