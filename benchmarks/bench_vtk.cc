// BM_VtkSeries/<frames>: what `springlab run --vtk DIR` costs per frame
// (experiments/io/vtk_series.h): VtkSeries::observe writing each frame into its
// temporary folder, then publish() putting the series in a new DIR, on the
// oscillator (2 particles, 1 spring: the frame's text is small, so the
// figure is the per-frame overhead, not the formatting of points).
// One benchmark iteration: a whole series of <frames> frames into a fresh
// folder under $TMPDIR (removed after). Issue 38.4: the temporary folder
// was listed at every frame (1,001 frames 0.57 s, 20,001 63 s): the time
// per frame must not grow with the frames; 1e3, 1e4 and 1e5 frames side by
// side show it. Counters: us_per_frame.
#include <stdlib.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "benchmarks/bench_support.h"
#include "experiments/io/vtk_series.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab::bench {
namespace {

void vtk_series(benchmark::State& state) {
  const int frames = static_cast<int>(state.range(0));
  const Scene scene = make_builtin_scene("oscillator", {});
  const Model model(scene);
  namespace fs = std::filesystem;
  std::string root = (fs::temp_directory_path() / "springlab-bench-vtk-XXXXXX").string();
  if (::mkdtemp(root.data()) == nullptr) {
    state.SkipWithError("cannot make a temporary folder");
    return;
  }
  const Vector& x = model.initial_positions();
  const Vector& v = model.initial_velocities();
  double seconds = 0.0;
  long written = 0;
  for (auto _ : state) {
    const std::string dir = root + "/series";
    const auto start = std::chrono::steady_clock::now();
    {
      VtkSeries series(model, scene, dir);
      for (int k = 0; k < frames; ++k) series.observe(1e-3 * k, x, v);
      series.publish();
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    written += frames;
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
  }
  fs::remove_all(root);
  if (written > 0) state.counters["us_per_frame"] = 1e6 * seconds / static_cast<double>(written);
  state.SetLabel("oscillator, a new DIR per iteration");
}

}  // namespace

void register_vtk_benchmarks() {
  benchmark::RegisterBenchmark("BM_VtkSeries", vtk_series)
      ->Arg(1000)
      ->Arg(10000)
      ->Arg(100000)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
}

}  // namespace springlab::bench
