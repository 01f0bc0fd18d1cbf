// springlab_python_bench: what a method written in Python costs per step
// beyond the force call (issue 48; docs/your-own-integrator.md).
//
// BM_PythonStepOverhead/cloth/<n>: the Python symplectic Euler of the
// tutorial (examples/my_methods.py's MyEuler: one model.force call, the
// kick and drift in NumPy) and the built-in symplectic-euler, each run by
// springlab.run over the same 200 steps of the built-in cloth (n x n, dt 2e-4,
// output only at the start and the end), alternating within one iteration.
// The built-in's step is the force call plus a fused kick-drift loop, so
// the difference per step is what the Python method adds beyond the force
// call: the call into Python with the GIL, the state handed over as fresh
// arrays, the force's array, NumPy's kick and drift and the copy back.
// Counters (microseconds per step): python_us, builtin_us, overhead_us =
// python_us - builtin_us (target <= 30 on cloth 32), and the fastest
// batch of each (python_min_us, builtin_min_us, overhead_min_us); the same
// in the process's CPU time (python_cpu_us, builtin_cpu_us, overhead_cpu_us,
// overhead_cpu_min_us: user + system of every thread, getrusage), which a
// busy machine's time slicing does not inflate (resolution ~1 ms per
// 200-step run: read the means).
//
// The interpreter is embedded here (pybind11::embed) and imports the
// module built beside it (SPRINGLAB_PYTHON_DIR), as a notebook would.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <pybind11/embed.h>

#include <algorithm>
#include <chrono>
#include <limits>

namespace py = pybind11;

namespace {

constexpr const char* kSetup = R"(
import sys
sys.path.insert(0, SPRINGLAB_PYTHON_DIR)
import springlab

class MyEuler(springlab.Integrator):
    order = 1
    symplectic = True
    stability_limit = 2.0

    def step(self, model, t, x, v, h):
        v = v + h * model.force(t, x, v) / model.mass()
        return x + h * v, v
)";

py::object& globals() {
  static py::scoped_interpreter* interpreter = new py::scoped_interpreter();  // for the process
  static py::object* g = [] {
    auto* d = new py::object(py::module_::import("__main__").attr("__dict__"));
    (*d)["SPRINGLAB_PYTHON_DIR"] = SPRINGLAB_PYTHON_DIR;
    py::exec(kSetup, *d);
    return d;
  }();
  (void)interpreter;
  return *g;
}

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

void BM_PythonStepOverhead(benchmark::State& state) {
  py::object& g = globals();
  const long n = state.range(0);
  const int steps = 200;
  const double dt = 2e-4, t_end = steps * dt;  // stable on cloth 64 too (1e-3 is not past n = 16)
  const py::object springlab = g["springlab"];
  const py::object scene = springlab.attr("load_scene")("cloth", py::arg("n") = n);
  const py::object run = springlab.attr("run");
  const py::object mine = g["MyEuler"]();
  // Wall seconds of one run, and the process's CPU seconds (user + system,
  // every thread: the run steps in a worker thread), which a busy machine's
  // time slicing does not inflate.
  double cpu = 0;
  auto seconds = [&](const py::object& method) {
    const double cpu_start = process_cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    const py::dict r = run(scene, method, py::arg("dt") = dt, py::arg("t_end") = t_end,
                           py::arg("every") = steps);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    cpu = process_cpu_seconds() - cpu_start;
    if (r["status"].cast<std::string>() != "completed") state.SkipWithError("the run did not complete");
    return s;
  };
  seconds(mine);  // the first run registers the class and warms the caches
  double python = 0, builtin = 0, python_min = std::numeric_limits<double>::infinity(),
         builtin_min = std::numeric_limits<double>::infinity();
  double python_cpu = 0, builtin_cpu = 0, python_cpu_min = std::numeric_limits<double>::infinity(),
         builtin_cpu_min = std::numeric_limits<double>::infinity();
  long batches = 0;
  for (auto _ : state) {
    const double p = seconds(mine);
    const double pc = cpu;
    const double b = seconds(py::str("symplectic-euler"));
    const double bc = cpu;
    python += p, builtin += b, ++batches;
    python_min = std::min(python_min, p), builtin_min = std::min(builtin_min, b);
    python_cpu += pc, builtin_cpu += bc;
    python_cpu_min = std::min(python_cpu_min, pc), builtin_cpu_min = std::min(builtin_cpu_min, bc);
  }
  const double per = 1e6 / steps;
  state.counters["python_cpu_us"] = python_cpu / batches * per;
  state.counters["builtin_cpu_us"] = builtin_cpu / batches * per;
  state.counters["overhead_cpu_us"] = (python_cpu - builtin_cpu) / batches * per;
  state.counters["overhead_cpu_min_us"] = (python_cpu_min - builtin_cpu_min) * per;
  state.counters["python_us"] = python / batches * per;
  state.counters["builtin_us"] = builtin / batches * per;
  state.counters["overhead_us"] = (python - builtin) / batches * per;
  state.counters["python_min_us"] = python_min * per;
  state.counters["builtin_min_us"] = builtin_min * per;
  state.counters["overhead_min_us"] = (python_min - builtin_min) * per;
  state.counters["unknowns"] = 3.0 * static_cast<double>(n * n - 2);
}
BENCHMARK(BM_PythonStepOverhead)->Name("BM_PythonStepOverhead/cloth")->Arg(16)->Arg(32)->Arg(64)
    ->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
