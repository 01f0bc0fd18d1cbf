// springlab_bench: every benchmark family in one executable.
//
//   springlab_bench [--benchmark_filter=REGEX] [--benchmark_out=FILE.json
//                    --benchmark_out_format=json] [other Google Benchmark flags]
//
// Families (each file's header says what one iteration is and which counters
// it reports):
//   BM_Force/<scene>/<n>, BM_ForceJacobian/<scene>/<n>         bench_force.cc
//   BM_Step/<integrator>/<scene>/<n>                            bench_step.cc
//   BM_OdeintStep/<rk4|symplectic-euler>/<scene>/<n>            bench_odeint.cc
//   BM_OdeintPair/<rk4|symplectic-euler>/<scene>/<n>            bench_odeint.cc
//   BM_LinearSolver/<solver>/<scene>/<n>                        bench_linear_solver.cc
//   BM_RunPair/<symplectic-euler|rk4>/<scene>/<n>               bench_run.cc
//   BM_Run/<integrator>/cloth/<n>, BM_NewtonAccuracy/...         bench_newton.cc
//   BM_NewtonBuckling/implicit-euler/cloth/32-128               bench_newton.cc
//   BM_ElementForce[Jacobian]/<material>/block/<n>              bench_elements.cc
//   BM_XpbdVsReference/cloth/<n>                                bench_fast_reference.cc
//     (long: only with SPRINGLAB_BENCH_LONG=1)
//   BM_VtkSeries/<frames>                                        bench_vtk.cc
// `cmake --build --preset bench` runs it all and writes
// build/release/report-data/benchmarks.json, which report/make_report.py reads.
#include <benchmark/benchmark.h>

#include "benchmarks/bench_support.h"

int main(int argc, char** argv) {
  namespace sb = springlab::bench;
  sb::register_force_benchmarks();
  sb::register_step_benchmarks();
  sb::register_odeint_benchmarks();
  sb::register_linear_solver_benchmarks();
  sb::register_run_benchmarks();
  sb::register_newton_benchmarks();
  sb::register_element_benchmarks();
  sb::register_vtk_benchmarks();
  sb::register_fast_reference_benchmarks();
  sb::register_fluid_benchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
