// BM_Bodies/<scene>/<integrator>/<n> (issue 49, and issue 46 item 5): what
// bodies meeting bodies cost, as the user meets it: one whole `springlab
// run <scene> -p n=N --integrator I --dt DT --t-end T --json` process per
// benchmark iteration (start-up, scene building and the run's own output
// included; nothing written but the JSON summary). The cases:
//   - box-pile n = 8 under implicit Euler at 1/60 s for 5 s (300 steps):
//     issue 49's target, at most 20 ms per step;
//   - box-pile n = 8 under generalized-alpha and the implicit midpoint at
//     1 ms for 5 s (5000 steps): methods that damp little, standing with
//     the boxes' contact damping;
//   - box-tower n = 10 under implicit Euler at 1/60 s for 5 s;
//   - box-drop n = 100 (100 boxes into a bin) under implicit Euler at
//     1/60 s for 3 s (180 steps): the cost per step of many bodies in
//     contact at once;
//   - box-chain n = 400 under symplectic Euler at 1e-5 s for 1e-4 s (10
//     steps): 400 bodies whose contact is looked for by the broad phase at
//     every force evaluation (issue 46 item 5: 21 s and 2.9 GB when every
//     pair was stored), and n = 1000, the parameter's maximum.
// Counters: wall_ms_per_step and cpu_ms_per_step (the process's wall and
// user + system time over the run's steps, minimum over the iterations),
// max_rss_mb (the process's peak resident memory, from wait4), steps,
// newton_per_step, and completed (1 when the run's status is "completed";
// the benchmark fails otherwise).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "benchmarks/bench_support.h"

#ifndef SPRINGLAB_EXE
#error "SPRINGLAB_EXE must name the springlab executable"
#endif

namespace springlab::bench {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string scene, integrator;
  int n;
  std::string dt, t_end;
};

void BM_Bodies(benchmark::State& state, const Case& c) {
  const fs::path dir = fs::temp_directory_path() / ("springlab-bench-bodies-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path out = dir / "run.json";
  double wall = INFINITY, cpu = INFINITY, rss = 0.0, steps = 0.0, newton = 0.0;
  for (auto _ : state) {
    double p_cpu = 0.0, p_rss = 0.0;
    const double p_wall =
        run_process({SPRINGLAB_EXE, "run", c.scene, "-p", "n=" + std::to_string(c.n),
                     "--integrator", c.integrator, "--dt", c.dt, "--t-end", c.t_end, "--json"},
                    out, &p_cpu, &p_rss);
    std::ifstream in(out);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const nlohmann::json summary = nlohmann::json::parse(text, nullptr, false);
    if (p_wall < 0.0 || summary.is_discarded() || summary.value("status", "") != "completed") {
      state.SkipWithError(("the run did not complete: " + text.substr(0, 300)).c_str());
      break;
    }
    steps = summary.at("steps").get<double>();
    newton = summary.at("newton_iterations").get<double>();
    wall = std::min(wall, p_wall);
    cpu = std::min(cpu, p_cpu);
    rss = std::max(rss, p_rss);
  }
  fs::remove_all(dir);
  if (steps > 0.0) {
    state.counters["wall_ms_per_step"] = 1e3 * wall / steps;
    state.counters["cpu_ms_per_step"] = 1e3 * cpu / steps;
    state.counters["max_rss_mb"] = rss;
    state.counters["steps"] = steps;
    state.counters["newton_per_step"] = newton / steps;
    state.counters["completed"] = 1.0;
  }
}

const bool registered = [] {
  const std::vector<Case> cases = {
      {"box-pile", "implicit-euler", 8, "0.0166666666666667", "5"},
      {"box-pile", "generalized-alpha", 8, "0.001", "5"},
      {"box-pile", "implicit-midpoint", 8, "0.001", "5"},
      {"box-tower", "implicit-euler", 10, "0.0166666666666667", "5"},
      {"box-drop", "implicit-euler", 100, "0.0166666666666667", "3"},
      {"box-chain", "symplectic-euler", 400, "1e-5", "1e-4"},
      {"box-chain", "symplectic-euler", 1000, "1e-5", "1e-4"},
  };
  for (const Case& c : cases) {
    benchmark::RegisterBenchmark(
        ("BM_Bodies/" + c.scene + "/" + c.integrator + "/" + std::to_string(c.n)).c_str(),
        [c](benchmark::State& state) { BM_Bodies(state, c); })
        ->Iterations(3)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  return true;
}();

}  // namespace
}  // namespace springlab::bench
