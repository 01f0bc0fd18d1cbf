// BM_Force/<scene>/<n>: one Model::force evaluation (all forces).
// BM_ForceJacobian/<scene>/<n>: force plus both Jacobians (dF/dx, dF/dv) on
// the model's fixed pattern: what an implicit method assembles per Newton
// iteration.
//
// Scenes: all_cases() and the finite-element solid_cases() (bench_support.h).
// Counters: ns_per_spring (time per evaluation / springs), ns_per_element
// (per triangle or tetrahedron, on the solids), unknowns_per_second
// (free degrees of freedom processed per second), and the size counters.
// The state is the initial one, perturbed so no spring sits at rest length.
#include "benchmarks/bench_support.h"

namespace springlab::bench {
namespace {

void set_rate_counters(benchmark::State& state, const Model& model) {
  const double iterations = static_cast<double>(state.iterations());
  if (element_count(model) > 0) {
    state.counters["ns_per_element"] = benchmark::Counter(
        iterations * static_cast<double>(element_count(model)) * 1e-9,
        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
  // kIsRate | kInvert: CPU seconds per (iteration x springs); scaled to ns.
  state.counters["ns_per_spring"] = benchmark::Counter(
      iterations * static_cast<double>(spring_count(model)) * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["unknowns_per_second"] = benchmark::Counter(
      iterations * static_cast<double>(model.dofs()), benchmark::Counter::kIsRate);
  add_size_counters(state, model);
}

void force_benchmark(benchmark::State& state, const SceneCase& c) {
  const Model& model = model_for(c);
  Vector x, v, f;
  perturbed_state(model, x, v);
  model.force(0.0, x, v, f);  // sizes f, warms the caches
  for (auto _ : state) {
    model.force(0.0, x, v, f);
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, model);
}

void force_jacobian_benchmark(benchmark::State& state, const SceneCase& c) {
  const Model& model = model_for(c);
  Vector x, v, f;
  perturbed_state(model, x, v);
  SparseMatrix dfdx = model.jacobian_pattern();
  SparseMatrix dfdv = model.jacobian_pattern();
  model.force(0.0, x, v, f);
  model.jacobians(0.0, x, v, &dfdx, &dfdv);
  for (auto _ : state) {
    model.force(0.0, x, v, f);
    model.jacobians(0.0, x, v, &dfdx, &dfdv);
    benchmark::DoNotOptimize(f.data());
    benchmark::DoNotOptimize(dfdx.valuePtr());
    benchmark::DoNotOptimize(dfdv.valuePtr());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, model);
  state.counters["jacobian_nonzeros"] = static_cast<double>(dfdx.nonZeros());
}

}  // namespace

void register_force_benchmarks() {
  const std::vector<SceneCase> cases = spring_and_solid_cases();
  for (const SceneCase& c : cases) {
    benchmark::RegisterBenchmark(("BM_Force/" + c.path()).c_str(),
                                 [c](benchmark::State& s) { force_benchmark(s, c); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.3);
  }
  for (const SceneCase& c : all_cases()) {
    benchmark::RegisterBenchmark(("BM_ForceJacobian/" + c.path()).c_str(),
                                 [c](benchmark::State& s) { force_jacobian_benchmark(s, c); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.3);
  }
}

}  // namespace springlab::bench
