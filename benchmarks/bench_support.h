// Shared pieces of springlab_bench: the scenes every family runs on, one
// cached model per (scene, size), and the counters that make figures
// comparable across sizes.
//
// Sizes: the benchmark's size argument is the scene's own `n` (cloth: n x n
// grid, chain: n particles); every entry also carries `unknowns` (free
// degrees of freedom), `particles` (free particles) and `springs` as counters
// so a reader (and report/make_report.py) can plot against the real size.
#pragma once

#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <vector>

#include "models/model/model.h"

namespace springlab::bench {

struct SceneCase {
  std::string scene;  // a built-in scene with its default parameters
  int n;              // its size parameter (`size_key`)
  std::string size_key = "n";
  // Further built-in parameters, as `-p` pairs (the solids' refinements).
  std::vector<std::pair<std::string, std::string>> parameters = {};
  std::string path() const { return scene + "/" + std::to_string(n); }
};

// cloth n = 16, 32, 64, 128 and chain n = 1000.
const std::vector<SceneCase>& all_cases();
// The finite-element scenes at three sizes each: the 2-D beam with
// nx = 40, 80, 160 cells along and nx / 10 across (320, 1280, 5120
// triangles), the block with n = 4, 8, 12 cubes per side (384, 3072,
// 10368 tetrahedra); default materials (neo-Hookean).
const std::vector<SceneCase>& solid_cases();
// all_cases() then solid_cases(): the scenes of BM_Force and BM_Step.
std::vector<SceneCase> spring_and_solid_cases();

// Built once, then shared (benchmarks run one at a time, so the model's
// scratch arrays are never used concurrently).
const Model& model_for(const SceneCase& c);
// w_max at the initial state (models/model/modal_analysis.h), cached.
double max_frequency_for(const SceneCase& c);

long spring_count(const Model& model);
long element_count(const Model& model);  // triangles + tetrahedra

// unknowns, particles, springs, elements (triangles and tetrahedra)
// (plain values, not divided by anything).
void add_size_counters(benchmark::State& state, const Model& model);

// The initial state moved off equilibrium by a small deterministic amount
// (1e-3 of the rest spacing scale) so that no spring sits exactly at its rest
// length: a generic state for force / Jacobian / matrix benchmarks.
void perturbed_state(const Model& model, Vector& x, Vector& v);

// Rest spacing of a grid/chain: the length of the shortest spring.
double shortest_rest_length(const Model& model);

// "7.07e-05"-style short number for labels.
std::string short_number(double value);

// Family registration (each file registers its own family).
void register_force_benchmarks();
void register_step_benchmarks();
void register_linear_solver_benchmarks();
void register_odeint_benchmarks();
void register_run_benchmarks();
void register_newton_benchmarks();
void register_element_benchmarks();
void register_vtk_benchmarks();
void register_fast_reference_benchmarks();
void register_fluid_benchmarks();

// Runs argv (argv[0] a path) with stdout to `out`; the wall time in
// seconds, < 0 on failure, in *cpu (when given) the child's user + system
// CPU time and in *max_rss_mb (when given) its peak resident memory [MiB]:
// a whole process, as the user runs it.
double run_process(std::vector<std::string> args, const std::filesystem::path& out,
                   double* cpu = nullptr, double* max_rss_mb = nullptr);

// The number after "key": in a run's JSON line (either spacing); -1 if absent.
double json_number(const std::string& text, const std::string& key);

}  // namespace springlab::bench
