#include "benchmarks/bench_support.h"

#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <utility>

#include "models/scenes/builtin_scenes.h"
#include "models/fem/fem.h"
#include "models/model/modal_analysis.h"
#include "models/springs/springs.h"

namespace springlab::bench {

const std::vector<SceneCase>& all_cases() {
  static const std::vector<SceneCase> cases = {
      {"cloth", 16}, {"cloth", 32}, {"cloth", 64}, {"cloth", 128}, {"chain", 1000}};
  return cases;
}

const std::vector<SceneCase>& solid_cases() {
  static const std::vector<SceneCase> cases = [] {
    std::vector<SceneCase> out;
    for (int nx : {40, 80, 160}) {
      out.push_back({"beam", nx, "nx", {{"dimension", "2"}, {"ny", std::to_string(nx / 10)}}});
    }
    for (int n : {4, 8, 12}) out.push_back({"block", n});
    return out;
  }();
  return cases;
}

std::vector<SceneCase> spring_and_solid_cases() {
  std::vector<SceneCase> cases = all_cases();
  cases.insert(cases.end(), solid_cases().begin(), solid_cases().end());
  return cases;
}

namespace {

struct Cached {
  std::unique_ptr<Model> model;
  double w_max = -1.0;
};

Cached& cached(const SceneCase& c) {
  static std::map<std::pair<std::string, int>, Cached> cache;
  Cached& entry = cache[{c.scene, c.n}];
  if (!entry.model) {
    auto parameters = c.parameters;
    parameters.emplace_back(c.size_key, std::to_string(c.n));
    entry.model = std::make_unique<Model>(make_builtin_scene(c.scene, parameters));
  }
  return entry;
}

}  // namespace

const Model& model_for(const SceneCase& c) { return *cached(c).model; }

double max_frequency_for(const SceneCase& c) {
  Cached& entry = cached(c);
  if (entry.w_max < 0.0) entry.w_max = max_angular_frequency(*entry.model);
  return entry.w_max;
}

long spring_count(const Model& model) {
  return static_cast<long>(model.scene().get<Springs>().size());
}

long element_count(const Model& model) {
  return static_cast<long>(model.scene().get<Triangles>().size() +
                           model.scene().get<Tetrahedra>().size());
}

void add_size_counters(benchmark::State& state, const Model& model) {
  state.counters["unknowns"] = static_cast<double>(model.dofs());
  state.counters["particles"] = static_cast<double>(model.free_particle_count());
  state.counters["springs"] = static_cast<double>(spring_count(model));
  if (element_count(model) > 0) state.counters["elements"] = static_cast<double>(element_count(model));
}

double shortest_rest_length(const Model& model) {
  double shortest = std::numeric_limits<double>::infinity();
  for (const Spring& s : model.scene().get<Springs>()) {
    if (s.rest > 0.0) shortest = std::min(shortest, s.rest);
  }
  return std::isfinite(shortest) ? shortest : 1.0;
}

void perturbed_state(const Model& model, Vector& x, Vector& v) {
  x = model.initial_positions();
  v = model.initial_velocities();
  const double amplitude = 1e-3 * shortest_rest_length(model);
  // A fixed linear congruential sequence: the same state on every run.
  unsigned long long seed = 0x5eed5eedULL;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = static_cast<double>(seed >> 11) * 0x1.0p-53;  // [0, 1)
    x[i] += amplitude * (2.0 * u - 1.0);
  }
}

std::string short_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

double run_process(std::vector<std::string> args, const std::filesystem::path& out,
                   double* cpu, double* max_rss_mb) {
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
  struct rusage usage {};
  if (pid < 0 || ::wait4(pid, &status, 0, &usage) != pid) return -1.0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (cpu != nullptr) {
    *cpu = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  }
  if (max_rss_mb != nullptr) *max_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? seconds : -1.0;
}

double json_number(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\"" + key + "\":");
  if (at == std::string::npos) return -1.0;
  return std::strtod(text.c_str() + at + key.size() + 3, nullptr);
}

}  // namespace springlab::bench
