// BM_ElementForce/<material>/block/<n>: one ElasticModel::force evaluation of
// the built-in block (6 n^3 tetrahedra, the ground plane) with each material
// model; BM_ElementForceJacobian/...: force plus dF/dx on the shared
// pattern (what an implicit method assembles per Newton iteration).
//
// Counters: ns_per_tet (time per evaluation / tetrahedra), tetrahedra. The
// state is the initial one under a uniform stretch (F != I everywhere).
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "benchmarks/bench_support.h"
#include "models/builtin_scenes.h"
#include "models/fem.h"
#include "models/materials/material.h"

namespace springlab::bench {
namespace {

const ElasticModel& block_model(int model, int n) {
  static std::map<std::pair<int, int>, std::unique_ptr<ElasticModel>> cache;
  auto& entry = cache[{model, n}];
  if (!entry) {
    entry = std::make_unique<ElasticModel>(make_builtin_scene(
        "block", {{"n", std::to_string(n)}, {"model", std::to_string(model)}}));
  }
  return *entry;
}

Vector stretched(const ElasticModel& model) {
  Vector x = model.initial_positions();
  for (Eigen::Index k = 0; k < x.size(); k += 3) x[k] *= 1.05;  // 5 % along x
  return x;
}

void set_counters(benchmark::State& state, const ElasticModel& model) {
  const double tets = static_cast<double>(model.scene().get<Tetrahedra>().size());
  state.counters["ns_per_tet"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * tets * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tetrahedra"] = tets;
}

void element_force(benchmark::State& state, int material, int n, bool jacobian) {
  const ElasticModel& model = block_model(material, n);
  const Vector x = stretched(model);
  const Vector v = model.initial_velocities();
  Vector f;
  SparseMatrix dfdx = model.jacobian_pattern();
  model.force(0.0, x, v, f);
  for (auto _ : state) {
    model.force(0.0, x, v, f);
    if (jacobian) model.jacobians(0.0, x, v, &dfdx, nullptr);
    benchmark::DoNotOptimize(f.data());
    benchmark::DoNotOptimize(dfdx.valuePtr());
    benchmark::ClobberMemory();
  }
  set_counters(state, model);
}

}  // namespace

void register_element_benchmarks() {
  const int n = 10;  // 6,000 tetrahedra
  for (int m = 0; m < static_cast<int>(material_models().size()); ++m) {
    const std::string path =
        std::string(material_models()[static_cast<std::size_t>(m)]->name) + "/block/" +
        std::to_string(n);
    benchmark::RegisterBenchmark(("BM_ElementForce/" + path).c_str(),
                                 [m](benchmark::State& s) { element_force(s, m, n, false); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.2);
    benchmark::RegisterBenchmark(("BM_ElementForceJacobian/" + path).c_str(),
                                 [m](benchmark::State& s) { element_force(s, m, n, true); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.2);
  }
}

}  // namespace springlab::bench
