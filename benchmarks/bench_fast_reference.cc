// BM_XpbdVsReference/cloth/<n> (issue 37): `springlab run --integrator xpbd`
// against benchmarks/xpbd_reference.cc (a plain single-file Gauss-Seidel
// XPBD over the springs in file order, no springlab code), each a whole
// process on the same scene file (`springlab scene cloth -p n=N`, written
// once to a temporary folder), dt = 1/60 s, 10 substeps x 1 iteration,
// t_end = 2 s (120 steps). One benchmark iteration runs both, which goes
// first alternating. Counters: springlab_ms and reference_ms per step (the
// process's wall time / 120, start-up and scene reading included), each the
// minimum over the iterations, and ratio = springlab_ms / reference_ms; the
// runs' status is checked (both complete, no divergence).
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "benchmarks/bench_support.h"

#ifndef SPRINGLAB_EXE
#error "SPRINGLAB_EXE must name the springlab executable"
#endif
#ifndef XPBD_REFERENCE_EXE
#error "XPBD_REFERENCE_EXE must name the xpbd_reference executable"
#endif

namespace springlab::bench {
namespace {

namespace fs = std::filesystem;

constexpr long kSteps = 120;

// Runs argv with stdout to `out`; the wall time in seconds, < 0 on failure.
double run_process(std::vector<std::string> args, const fs::path& out) {
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (std::freopen(out.c_str(), "w", stdout) == nullptr) ::_exit(127);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  if (pid < 0 || ::waitpid(pid, &status, 0) != pid) return -1.0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? seconds : -1.0;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void xpbd_vs_reference(benchmark::State& state, int n) {
  const fs::path dir = fs::temp_directory_path() /
                       ("springlab-bench-xpbd-" + std::to_string(::getpid()) + "-" + std::to_string(n));
  fs::create_directories(dir);
  const std::string scene = (dir / "cloth.json").string();
  if (run_process({SPRINGLAB_EXE, "scene", "cloth", "-p", "n=" + std::to_string(n)}, scene) < 0) {
    state.SkipWithError("springlab scene failed");
    return;
  }
  const std::string dt = "0.016666666666666666";
  const std::vector<std::string> springlab = {SPRINGLAB_EXE, "run", scene, "--integrator", "xpbd",
                                              "--substeps", "10", "--iterations", "1", "--dt", dt,
                                              "--t-end", "2", "--json"};
  const std::vector<std::string> reference = {XPBD_REFERENCE_EXE, scene, "--dt", dt, "--t-end",
                                              "2", "--substeps", "10", "--iterations", "1"};
  double best_springlab = 1e300, best_reference = 1e300;
  bool springlab_first = true;
  for (auto _ : state) {
    for (int side = 0; side < 2; ++side) {
      const bool is_springlab = (side == 0) == springlab_first;
      const fs::path out = dir / (is_springlab ? "springlab.json" : "reference.json");
      const double s = run_process(is_springlab ? springlab : reference, out);
      const std::string text = read_text(out);
      const bool bounded = text.find("\"diverged\": false") != std::string::npos ||
                           text.find("\"diverged\":false") != std::string::npos;
      if (s < 0 || !bounded) {
        state.SkipWithError((std::string(is_springlab ? "springlab" : "the reference") +
                             " failed or diverged: " + text.substr(0, 200)).c_str());
        fs::remove_all(dir);
        return;
      }
      (is_springlab ? best_springlab : best_reference) =
          std::min(is_springlab ? best_springlab : best_reference, s);
    }
    springlab_first = !springlab_first;
  }
  fs::remove_all(dir);
  state.counters["springlab_ms"] = 1e3 * best_springlab / kSteps;
  state.counters["reference_ms"] = 1e3 * best_reference / kSteps;
  state.counters["ratio"] = best_springlab / best_reference;
  state.SetLabel("whole processes, min of each; dt=1/60, 10 substeps x 1 iteration, " +
                 std::to_string(kSteps) + " steps");
}

}  // namespace

void register_fast_reference_benchmarks() {
  for (int n : {32, 64, 128}) {
    benchmark::RegisterBenchmark(("BM_XpbdVsReference/cloth/" + std::to_string(n)).c_str(),
                                 [n](benchmark::State& s) { xpbd_vs_reference(s, n); })
        ->Unit(benchmark::kMillisecond)
        ->Iterations(n >= 128 ? 3 : 5)
        ->UseRealTime();
  }
}

}  // namespace springlab::bench
