// BM_ElementForce/<material>/block/<n>: one Model::force evaluation of
// the built-in block (6 n^3 tetrahedra, the ground plane) with each material
// model; BM_ElementForceJacobian/...: force plus dF/dx on the shared
// pattern (what an implicit method assembles per Newton iteration).
//
// Counters: ns_per_tet (time per evaluation / tetrahedra), tetrahedra. The
// state: stretched, turned and perturbed (deformed() below).
#include <Eigen/Geometry>
#include <map>
#include <random>
#include <memory>
#include <string>
#include <utility>

#include "benchmarks/bench_support.h"
#include "models/scenes/builtin_scenes.h"
#include "models/fem/fem.h"
#include "models/materials/material.h"

namespace springlab::bench {
namespace {

const Model& block_model(int model, int n) {
  static std::map<std::pair<int, int>, std::unique_ptr<Model>> cache;
  auto& entry = cache[{model, n}];
  if (!entry) {
    entry = std::make_unique<Model>(make_builtin_scene(
        "block", {{"n", std::to_string(n)}, {"model", std::to_string(model)}}));
  }
  return *entry;
}

// A generic deformed state: a 5 % stretch along x, turned by 0.3 rad about
// (1, 1, 1), each node then moved by up to 1 mm (the cells are 2 cm), so
// that F is a full matrix that differs from element to element (a uniform
// stretch alone gives every element the same diagonal F, which flatters
// the SVD).
Vector deformed(const Model& model, unsigned seed) {
  Vector x = model.initial_positions();
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 1.0, 1.0).normalized()).toRotationMatrix();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-1e-3, 1e-3);
  for (Eigen::Index k = 0; k < x.size(); k += 3) {
    const Eigen::Vector3d X = x.segment<3>(k);
    x.segment<3>(k) = R * Eigen::Vector3d(1.05 * X.x(), X.y(), X.z());
    for (int r = 0; r < 3; ++r) x[k + r] += noise(rng);
  }
  return x;
}

void set_counters(benchmark::State& state, const Model& model) {
  const double tets = static_cast<double>(model.scene().get<Tetrahedra>().size());
  state.counters["ns_per_tet"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * tets * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tetrahedra"] = tets;
}

void element_force(benchmark::State& state, int material, int n, bool jacobian) {
  const Model& model = block_model(material, n);
  // Two states, taken in turn: a model keeps what it derives from an
  // element's F between calls at one state (corotated's R and S, from the
  // force for dF/dx), and each iteration here is one new state, as each
  // Newton iteration is.
  const Vector xs[2] = {deformed(model, 1), deformed(model, 2)};
  const Vector v = model.initial_velocities();
  Vector f;
  SparseMatrix dfdx = model.jacobian_pattern();
  model.force(0.0, xs[0], v, f);
  std::size_t k = 0;
  for (auto _ : state) {
    const Vector& x = xs[k++ % 2];
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
