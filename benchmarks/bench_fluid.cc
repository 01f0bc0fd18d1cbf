// BM_FluidStep/dam-break/<n>: one explicit step of the 2-D dam break
// (docs/scenes.md "dam-break"): symplectic Euler at the acoustic CFL step
// dt = 0.25 h / c, i.e. one force evaluation -- the neighbour search
// (models/fluids/neighbour_grid.cc, rebuilt at every evaluation), the summation
// density, the pressure and the viscosity forces -- and the update.
// BM_FluidNeighbours/dam-break/<n>: the neighbour search alone
// (NeighbourGrid::build over every particle, radius 2h), at the initial
// positions.
//
// n is a / spacing (a = 1 m): 16, 64 and 217 give 1,010, 10,130 and 100,709
// particles (water 2 n^2, then three layers of wall particles). Counters:
// `ns_per_particle` (CPU time per iteration / all particles of the fluid,
// walls included: they are searched and summed like the water), `particles`,
// `water`, `pairs` (within 2h at the start). Each run starts from rest at
// t = 0 (the column starts to fall: every step moves every particle, so
// no evaluation reuses the last search); a run lasts Google Benchmark's
// usual 0.5 s or one step, whichever is longer, well before the front
// reaches the far wall.
#include <map>
#include <memory>

#include "benchmarks/bench_support.h"
#include "experiments/io/output_files.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/fluids/fluids.h"
#include "models/fluids/neighbour_grid.h"

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

}  // namespace

void register_fluid_benchmarks() {
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
