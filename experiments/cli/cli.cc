#include "experiments/cli/cli.h"

#include "experiments/driver/divergence.h"

#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <type_traits>
#include <variant>

#include "experiments/io/body_output.h"
#include "experiments/kinds/experiment_runner.h"
#include "experiments/cli/check_command.h"
#include "experiments/cli/integrator_table.h"
#include "experiments/cli/parse_errors.h"
#include "experiments/driver/memory_check.h"
#include "experiments/io/output_files.h"
#include "experiments/io/vtk_series.h"
#include "experiments/io/signals.h"
#include "experiments/driver/simulation.h"
#include "experiments/analysis/stability.h"
#include "integrators/registry/plugins.h"
#include "integrators/registry/registry.h"
#include "integrators/linear/sparse_direct_solver.h"
#include "models/core/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/core/element_kind.h"
#include "models/model/model.h"
#include "models/model/modal_analysis.h"
#include "models/model/scene_file.h"
#include "models/model/element_registry.h"

namespace springlab {
namespace {

using Json = nlohmann::ordered_json;

// A bad command-line value: reported like a scene error, exit status 1.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Everything springlab prints on stdout goes through here, so that a write
// error (a full disk, a closed pipe) is an error with exit status 1, not a
// truncated file and exit 0.
void write_stdout(const std::string& text) {
  const char* data = text.data();
  std::size_t size = text.size();
  while (size > 0) {
    const ssize_t n = ::write(1, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error(std::string("stdout: write failed (") + std::strerror(errno) + ")");
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

std::vector<std::pair<std::string, std::string>> split_parameters(
    const std::vector<std::string>& parameters) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const std::string& p : parameters) {
    const auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw UsageError("-p " + printable(p) + ": expected key=value");
    }
    const std::string key = p.substr(0, eq), value = p.substr(eq + 1);
    for (const auto& [other_key, other_value] : pairs) {
      if (other_key == key) {
        throw UsageError("-p " + printable(key) + ": given twice (" + printable(other_value) +
                         " and " + printable(value) + ")");
      }
    }
    pairs.emplace_back(key, value);
  }
  return pairs;
}

std::vector<std::string> builtin_names() {
  std::vector<std::string> names;
  for (const BuiltinScene& s : builtin_scenes()) names.push_back(s.name);
  return names;
}

// The shortest text that reads back as the value: a refusal prints it as
// given (--t-end 1e-7, --dt-min 0.30000000000000004).
std::string number_text(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

// Notes for the user on stderr, one line each.
void print_notes(const std::vector<std::string>& notes) {
  for (const std::string& note : notes) std::cerr << "springlab: note: " << note << std::endl;
}

void require_positive(const std::string& option, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw UsageError(option + ": must be a positive number (got " + number_text(value) + ")");
  }
}

void require_integrator(const std::string& name) {
  if (!is_integrator(name)) {
    throw UsageError("--integrator: " +
                     integrator_registry().unknown("integrator", printable(name)));
  }
}

Json rows(const Eigen::MatrixXd& m) {
  Json out = Json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    Json row = Json::array();
    for (Eigen::Index r = 0; r < m.cols(); ++r) row.push_back(m(i, r));
    out.push_back(std::move(row));
  }
  return out;
}

// Options shared by `run` and `stability`.
struct CommonOptions {
  std::string scene;
  std::vector<std::string> parameters;
  std::vector<std::string> plugins;
  RunSettings run;
  std::map<std::string, std::string> choice_text;  // the choices as given (--stiffness ...)
  bool json = false;
  CLI::App* command = nullptr;

  void add_to(CLI::App& cmd) {
    command = &cmd;
    cmd.add_option("SCENE", scene, "scene file, - for stdin, or a built-in scene's name")->required();
    cmd.add_option("--integrator", run.integrator, "integrator name (springlab list)")->required();
    cmd.add_option("--plugin", plugins, "a plug-in of your own integrators (repeatable)")
        ->allow_extra_args(false)
        ->default_str("");
    cmd.add_option("--t-end", run.t_end, "simulated time [s]")->required()->default_str("");
    cmd.add_option("-p", parameters, "built-in scene parameter key=value (repeatable)")
        ->allow_extra_args(false)
        ->default_str("");
    // The integrators' options, as integrators/core/integrator_options.h declares them.
    for (const OptionSpec& spec : integrator_options()) {
      const std::string name = "--" + std::string(spec.name);
      CLI::Option* option = std::visit(
          [&](auto field) -> CLI::Option* {
            using Field = decltype(field);
            if constexpr (std::is_same_v<Field, std::monostate>) {
              std::string& text = choice_text[std::string(spec.name)];
              text = spec.get(run.options);
              return cmd.add_option(name, text, spec.help);
            } else if constexpr (std::is_same_v<Field, bool IntegratorOptions::*>) {
              return cmd.add_flag(name, run.options.*field, spec.help);
            } else if constexpr (std::is_same_v<Field, double IntegratorOptions::*>) {
              if (std::isnan(spec.bare_value)) return cmd.add_option(name, run.options.*field, spec.help);
              // A value may follow (--chebyshev 0.9) or not (--chebyshev):
              // then the option's bare value.
              double* value = &(run.options.*field);
              const double bare = spec.bare_value;
              return cmd.add_option(
                         name,
                         [value, bare](const CLI::results_t& results) {
                           if (results.empty() || results[0].empty()) {
                             *value = bare;
                             return true;
                           }
                           return CLI::detail::lexical_cast(results[0], *value);
                         },
                         spec.help)
                  ->expected(0, 1);
            } else {
              return cmd.add_option(name, run.options.*field, spec.help);
            }
          },
          spec.field);
      // (An option with a bare value would take its default text as the
      // value: its default is in its text instead.)
      if (*spec.default_text != '\0') {
        if (std::isnan(spec.bare_value)) {
          option->default_str(spec.default_text);
        } else {
          option->option_text(std::string("[VALUE]=") + spec.default_text);
        }
      }
    }
    cmd.add_option("--blowup", run.blowup,
                   "divergence when kinetic + spring energy exceeds this times E_s");
    cmd.add_flag("--json", json, "print one JSON object on stdout");
  }

  void validate() {
    for (const std::string& plugin : plugins) load_plugin(plugin);
    require_integrator(run.integrator);
    require_positive("--t-end", run.t_end);
    require_positive("--blowup", run.blowup);
    for (const OptionSpec& spec : integrator_options()) {
      // Each refusal names the option as the user wrote it: "--name: ".
      const std::string option = "--" + std::string(spec.name) + ": ";
      if (spec.set != nullptr) {
        const std::string& text = choice_text.at(std::string(spec.name));
        if (!spec.set(run.options, text)) {
          throw UsageError(option + choice_refusal(spec, printable(text)));
        }
      }
      const std::string why = check_option_range(spec, run.options, given(std::string(spec.name)));
      if (!why.empty()) throw UsageError(option + why);
    }
  }

  bool given(const std::string& option) const { return command->count("--" + option) > 0; }

  // Option values the method cannot take are refused (exit 1, before any
  // file is touched); the options it does not read are returned, one note
  // each (`run` prints them on stderr, Python warns).
  std::vector<std::string> check_against_method(const Model& model,
                                                const Integrator& integrator) const {
    if (std::string why = integrator.check_options(run.options, model.dofs()); !why.empty()) {
      throw UsageError(why);
    }
    const std::vector<std::string> read = integrator.options_read();
    std::string ignored;
    for (const OptionSpec& spec : integrator_options()) {
      const std::string option(spec.name);
      if (given(option) && std::find(read.begin(), read.end(), option) == read.end()) {
        ignored += std::string(ignored.empty() ? "" : ", ") + "--" + option;
      }
    }
    if (ignored.empty()) return {};
    return {run.integrator + " does not use " + ignored + " (ignored)"};
  }
};

// A scene whose energy does not fit in a double has nothing to simulate.
void check_initial_energy(const Model& model, const std::string& scene_arg) {
  const double e0 = model.energies(model.initial_positions(), model.initial_velocities()).total();
  if (!std::isfinite(e0) || !std::isfinite(model.energy_scale())) {
    throw SceneError(printable(scene_arg) +
                     ": the initial energy is not finite (positions, velocities or stiffnesses "
                     "too large for double precision)");
  }
}

// A pairing the method refuses before its first step (xpbd and a
// neo-Hookean block, projective dynamics and the barrier) is a usage error:
// one line naming the fix, before any output is opened (issue 38.6).
std::unique_ptr<Integrator> prepare_or_refuse_pairing(const Model& model,
                                                      const RunSettings& run,
                                                      const std::string& scene_arg,
                                                      std::unique_ptr<Integrator> integrator);

// A Newton method whose matrix's factor will not fit in memory is refused
// before any output, with the estimate and the limit (issue 38.1; the rule
// is sparse_direct_solver.h's). Quasi-Newton factors a smaller matrix and
// meets the check at run time only if it falls back to Newton.
// `integrator`: the one make_integrator(run.integrator) the caller asked
// about (check_against_method); it is the one that runs.
std::unique_ptr<Integrator> prepare_or_refuse(const Model& model, const RunSettings& run,
                                              const std::string& scene_arg,
                                              std::unique_ptr<Integrator> integrator) {
  // The Jacobian pattern, before the method builds it (memory_check.h).
  check_jacobian_memory(model, *integrator,
                        scene_arg.empty() ? "the scene" : printable(scene_arg));
  integrator = prepare_or_refuse_pairing(model, run, scene_arg, std::move(integrator));
  if (integrator->factors_jacobian(run.options)) {
    const std::string why = factor_fit_error(model.jacobian_pattern());
    if (!why.empty()) {
      // The method's own way out: the option with which it factors none.
      IntegratorOptions without = run.options;
      const std::string option = integrator->factor_free_option(without);
      throw UsageError("--integrator " + run.integrator + ": " + why + ": use a coarser mesh, " +
                       (option.empty() ? "" : option + ", ") +
                       "or a method that factors none (rk4, xpbd, projective-dynamics)");
    }
  }
  return integrator;
}

std::unique_ptr<Integrator> prepare_or_refuse_pairing(const Model& model,
                                                      const RunSettings& run,
                                                      const std::string& scene_arg,
                                                      std::unique_ptr<Integrator> integrator) {
  try {
    return prepare_integrator(model, run, std::move(integrator));
  } catch (const RunRefused& e) {
    std::string why = e.reason();
    // A built-in scene: the parameter that makes the pairing work.
    const BuiltinScene* builtin = nullptr;
    struct stat st {};
    if (scene_arg != "-" && ::stat(scene_arg.c_str(), &st) != 0) {
      for (const BuiltinScene& s : builtin_scenes()) {
        if (!scene_arg.empty() && s.name == scene_arg) builtin = &s;
      }
    }
    // The remedy is data (models/core/refusal.h): told as the built-in
    // scene's parameter of the same name, where it has one.
    const SceneRemedy& remedy = e.remedy();
    std::string fix;
    if (builtin != nullptr && !remedy.empty()) {
      for (const SceneParameter& p : builtin->parameters) {
        if (p.name != remedy.field) continue;
        fix = "-p " + remedy.field + "=" + remedy.value;
        if (!remedy.meaning.empty()) fix += " (" + remedy.meaning + ")";
      }
    }
    if (!fix.empty()) why += " (for this scene: " + fix + ")";
    throw UsageError("--integrator " + run.integrator + ": " + why);
  }
}

// Output times of a run: t = 0, every K-th step and the last.
double output_times(const TimeGrid& grid, int every) {
  const double steps = static_cast<double>(grid.steps);
  return 1.0 + std::floor(steps / every) + (grid.steps % every != 0 ? 1.0 : 0.0);
}

// One line on stderr, overwritten in place, while a long run goes on (a
// terminal only; nothing in the first second).
class ProgressLine final : public Observer {
 public:
  ProgressLine(std::string label, double t_end)
      : label_(std::move(label)), t_end_(t_end), start_(Clock::now()), last_(start_) {}
  ~ProgressLine() override {
    if (shown_) std::fprintf(stderr, "\r\033[K");
  }
  void observe(double t, const Vector&, const Vector&) override {
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(200)) {
      return;
    }
    last_ = now;
    shown_ = true;
    // The time left at the pace so far (issue 38.10: an adaptive method
    // that creeps, arkode-dirk on a stiff block, says how long it will take).
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    std::fprintf(stderr, "\r\033[K[%s] t = %.6g of %.6g s (%d%%), %.0f s", label_.c_str(), t,
                 t_end_, static_cast<int>(100.0 * t / t_end_), elapsed);
    if (t > 0.0) std::fprintf(stderr, ", about %.0f s left", elapsed * (t_end_ - t) / t);
    std::fflush(stderr);
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  double t_end_;
  Clock::time_point start_, last_;
  bool shown_ = false;
};

// The paths `run` writes to ("" where not asked for).
struct RunPaths {
  std::string energy, trajectory, vtk;
  bool any() const { return !energy.empty() || !trajectory.empty() || !vtk.empty(); }
};

// Two outputs at one path: refused before the run (issue 46.11: --energy
// and --vtk at one new path ran the whole run, then failed).
void check_distinct_outputs(const RunPaths& paths) {
  const std::pair<const char*, const std::string*> outputs[] = {
      {"--energy", &paths.energy}, {"--trajectory", &paths.trajectory}, {"--vtk", &paths.vtk}};
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t b = a + 1; b < 3; ++b) {
      const std::string &pa = *outputs[a].second, &pb = *outputs[b].second;
      if (!pa.empty() && !pb.empty() && same_file(pa, pb)) {
        throw UsageError(std::string(outputs[a].first) + " " + printable(pa) + " and " +
                         outputs[b].first + " " + printable(pb) + " name the same " +
                         (b == 2 ? "path" : "file"));
      }
    }
  }
}

// More rows than a file may hold: refused from the scene alone, before its
// model takes any memory.
void check_output_rows(const RunPaths& paths, const Scene& scene, double times) {
  auto check_rows = [&](const char* option, double rows, const std::string& what) {
    if (rows > kMaxOutputRows) {
      std::ostringstream m;
      m << option << ": would hold " << static_cast<long long>(rows) << " rows (" << what
        << "), over the cap of " << static_cast<long long>(kMaxOutputRows)
        << " per file: write every K-th step with --every";
      throw UsageError(m.str());
    }
  };
  const std::string count = std::to_string(static_cast<long long>(times));
  const double particles = static_cast<double>(scene.particles.size());
  if (!paths.energy.empty()) check_rows("--energy", times, count + " output times");
  if (!paths.trajectory.empty()) {
    check_rows("--trajectory", times * particles,
               std::to_string(scene.particles.size()) + " particles x " + count + " output times");
  }
  if (!paths.vtk.empty()) {
    if (times > kMaxVtkFrames) {
      throw UsageError("--vtk: would write " + count + " frames, over the cap of " +
                       std::to_string(kMaxVtkFrames) + ": write every K-th step with --every");
    }
    check_rows("--vtk", times * particles,
               std::to_string(scene.particles.size()) + " points x " + count + " frames");
  }
}

// The files of a run, opened (regular files as temporaries) before any
// step runs and published after the last, with the progress line.
struct RunOutputs {
  std::unique_ptr<OutputFile> energy_file, trajectory_file;
  std::unique_ptr<Observer> energy_csv, trajectory_csv, progress;
  std::unique_ptr<VtkSeries> vtk;
  std::vector<Observer*> observers;

  RunOutputs(const RunPaths& paths, const Model& model, const Scene& scene,
             const RunSettings& run) {
    if (!paths.energy.empty()) {
      energy_file = std::make_unique<OutputFile>(paths.energy);
      energy_csv = std::make_unique<EnergyCsv>(model, *energy_file);
      observers.push_back(energy_csv.get());
    }
    if (!paths.trajectory.empty()) {
      trajectory_file = std::make_unique<OutputFile>(paths.trajectory);
      trajectory_csv = std::make_unique<TrajectoryCsv>(model, *trajectory_file);
      observers.push_back(trajectory_csv.get());
    }
    if (!paths.vtk.empty()) {
      vtk = std::make_unique<VtkSeries>(model, scene, paths.vtk);
      observers.push_back(vtk.get());
    }
    if (::isatty(2)) {
      progress = std::make_unique<ProgressLine>(run.integrator, run.t_end);
      observers.push_back(progress.get());
    }
  }

  // A run that diverged or failed still publishes its files: they hold the
  // rows up to its last good state (t_final), and the summary says so.
  void publish() {
    progress.reset();  // clears its line
    for (OutputFile* f : {energy_file.get(), trajectory_file.get()}) {
      if (f != nullptr) f->finish();
    }
    for (OutputFile* f : {energy_file.get(), trajectory_file.get()}) {
      if (f != nullptr) f->publish();
    }
    if (vtk) vtk->publish();
  }
};

// `run --json`'s one object (docs/command-line.md).
std::string run_summary_json(const Scene& scene, const Model& model, const RunResult& r,
                             int substeps, bool any_output) {
  Json j;
  j["scene"] = scene.name;
  j["integrator"] = r.integrator;
  j["dt"] = r.dt;
  j["t_end"] = r.t_end;
  j["status"] = to_string(r.status);
  const Json stats = stats_json(r.stats);  // named: a temporary would die before the loop
  for (const auto& [key, value] : stats.items()) j[key] = value;
  if (substeps > 0) j["substeps"] = substeps;
  j["wall_seconds"] = r.wall_seconds;
  j["diverged"] = r.diverged();
  j["diverged_at"] = r.diverged_at ? Json(*r.diverged_at) : Json(nullptr);
  j["failure"] = r.failure.empty() ? Json(nullptr) : Json(r.failure);
  if (r.verdict) j["verdict"] = verdict_json(*r.verdict);
  j["warnings"] = warning_texts(r.warnings, r.integrator);
  j["t_final"] = r.t_final;
  j["outputs_complete"] = r.status == RunStatus::kCompleted;
  j["last_output_t"] = any_output ? Json(r.t_final) : Json(nullptr);
  j["energy_initial"] = r.energy_initial;
  j["energy_final"] = r.energy_final;
  j["energy_scale"] = model.energy_scale();
  j["energy_columns"] = model.energy_columns();  // of --energy, after t
  j["final_state"] = Json{{"x", rows(model.scene_positions(r.x_final))},
                          {"v", rows(model.scene_velocities(r.v_final))}};
  if (Json bodies = bodies_json(model, r.x_final, r.v_final); !bodies.empty()) {
    j["bodies"] = std::move(bodies);
  }
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + '\n';
}

// `run`'s summary for a reader.
std::string run_summary_text(const Scene& scene, const Model& model, const RunResult& r,
                             bool any_output) {
  std::ostringstream out;
  out << "scene " << scene.name << ", " << model.free_particle_count() << " free particles";
  for (const ElementCount& c : element_counts(scene)) out << ", " << c.count << ' ' << c.key;
  out << '\n'
      << "integrator " << r.integrator << ", dt " << r.dt << ", t_end " << r.t_end << '\n'
      << "status " << to_string(r.status);
  if (r.diverged_at) out << " at t = " << *r.diverged_at;
  if (!r.failure.empty()) out << ": " << r.failure;
  out << '\n';
  const IntegratorStats& s = r.stats;
  out << "steps " << s.steps << ", rejected " << s.rejected_steps << ", force evals "
      << s.force_evals << ", jacobian evals " << s.jacobian_evals << ", linear solves "
      << s.linear_solves << ", newton iterations " << s.newton_iterations << '\n'
      << "energy " << r.energy_initial << " -> " << r.energy_final << " (t = " << r.t_final
      << "), wall " << r.wall_seconds << " s\n";
  for (const std::string& w : warning_texts(r.warnings, r.integrator)) out << "warning: " << w << '\n';
  if (any_output && r.status != RunStatus::kCompleted) {
    out << "output files incomplete: rows up to t = " << r.t_final << ", the last good state\n";
  }
  return out.str();
}

int command_run(CommonOptions& common, const RunPaths& paths) {
  common.validate();
  require_positive("--dt", common.run.dt);
  if (common.run.every < 1) throw UsageError("--every: must be >= 1");
  check_distinct_outputs(paths);
  const Scene scene = resolve_scene(common.scene, common.parameters);
  TimeGrid grid;
  try {
    grid = make_time_grid(common.run.dt, common.run.t_end);  // refused before any output exists
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--dt, --t-end: ") + e.what());
  }
  check_output_rows(paths, scene, output_times(grid, common.run.every));
  check_scene_memory(scene, printable(common.scene));  // before the model (memory_check.h)
  const Model model(scene);
  check_initial_energy(model, common.scene);
  std::unique_ptr<Integrator> integrator = make_integrator(common.run.integrator);
  print_notes(common.check_against_method(model, *integrator));
  integrator = prepare_or_refuse(model, common.run, common.scene, std::move(integrator));
  // docs/command-line.md: a method with substeps (xpbd) reports them per step.
  const std::vector<std::string> read = integrator->options_read();
  const int substeps = std::find(read.begin(), read.end(), "substeps") != read.end()
                           ? integrator->substeps(common.run.options)
                           : 0;
  RunOutputs outputs(paths, model, scene, common.run);
  const RunResult r = simulate(model, common.run, outputs.observers, std::move(integrator));
  outputs.publish();
  write_stdout(common.json ? run_summary_json(scene, model, r, substeps, paths.any())
                           : run_summary_text(scene, model, r, paths.any()));
  return 0;
}

// The stability search's progress on a terminal: one line on stderr,
// overwritten in place (nothing in the first second), naming the trial, its
// step, the bracket so far, how far the trial has run and, once it has run
// a while, how long it will take. A thread redraws it every second too: an
// adaptive method's output interval can take many seconds (issue 46.14:
// arkode-dirk on box-chain n=2, 7 s for each of a trial's 100 intervals, and
// minutes without a line).
class StabilityProgress final : public Observer {
 public:
  explicit StabilityProgress(std::string integrator)
      : integrator_(std::move(integrator)), start_(Clock::now()), last_(start_),
        ticker_([this] { tick(); }) {}
  ~StabilityProgress() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    ticker_.join();
    if (shown_) std::fprintf(stderr, "\r\033[K");
  }
  void trial(const StabilityTrial& t) {
    std::lock_guard<std::mutex> lock(mutex_);
    trial_ = t;
    t_ = 0.0;
    trial_start_ = Clock::now();
    show(true);
  }
  void observe(double t, const Vector&, const Vector&) override {
    std::lock_guard<std::mutex> lock(mutex_);
    t_ = t;
    show(false);
  }

 private:
  using Clock = std::chrono::steady_clock;
  void tick() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::seconds(1), [this] { return done_; })) show(true);
  }
  // (mutex_ held)
  void show(bool force) {
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1)) return;
    if (!force && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    shown_ = true;
    char bracket[64] = "";
    if (trial_.lo > 0.0 || trial_.hi > 0.0) {
      std::snprintf(bracket, sizeof bracket, ", bracket [%.4g, %.4g]", trial_.lo, trial_.hi);
    }
    std::fprintf(stderr, "\r\033[K[stability %s] run %d: dt %.4g%s, t = %.4g of %.4g s, %.0f s",
                 integrator_.c_str(), trial_.run, trial_.dt, bracket, t_, trial_.t_end,
                 std::chrono::duration<double>(now - start_).count());
    // The trial's time left at its pace so far (as run's progress line).
    const double spent = std::chrono::duration<double>(now - trial_start_).count();
    if (t_ > 0.0 && spent >= 1.0) {
      std::fprintf(stderr, ", this run about %.0f s more", spent * (trial_.t_end - t_) / t_);
    }
    std::fflush(stderr);
  }
  std::string integrator_;
  StabilityTrial trial_;
  double t_ = 0.0;
  Clock::time_point start_, last_, trial_start_ = start_;
  bool shown_ = false, done_ = false;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread ticker_;  // last: started once the rest is set
};

// `stability --json`'s one object (docs/command-line.md).
std::string stability_summary_json(const Scene& scene, const StabilitySettings& s,
                                   const StabilityResult& r) {
  const TheoryLimit& theory = r.theory;
  static const char* outcomes[] = {"bracketed", "stable up to dt_max", "unstable at dt_min"};
  Json j;
  j["scene"] = scene.name;
  j["integrator"] = r.integrator;
  j["t_end"] = s.run.t_end;
  j["max_stable_dt"] = r.max_stable_dt;
  j["bracket"] = Json::array({r.lo, r.hi});
  j["outcome"] = outcomes[static_cast<int>(r.outcome)];
  j["runs"] = r.runs;
  j["min_steps"] = s.min_steps;
  j["min_periods"] = s.min_periods;
  j["trial_t_end"] = r.lo_run_time > 0.0 ? Json(r.lo_run_time) : Json(nullptr);
  j["w_max"] = r.mode.w;
  j["damping"] = r.mode.damping;
  j["theory_dt"] = theory.dt ? Json(*theory.dt) : Json(nullptr);
  j["theory"] = theory.rule;
  if (theory.dt) j["ratio"] = r.max_stable_dt / *theory.dt;
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + '\n';
}

// `stability`'s answer for a reader: the limit, what it means, and theory's.
std::string stability_summary_text(const Scene& scene, const StabilitySettings& s,
                                   const StabilityResult& r) {
  const double w = r.mode.w;
  const TheoryLimit& theory = r.theory;
  std::ostringstream out;
  const char* runs = r.runs == 1 ? " run" : " runs";
  out << r.integrator << " on " << scene.name << " for t_end " << s.run.t_end << ": ";
  switch (r.outcome) {
    case StabilityOutcome::kBracketed:
      if (r.no_stable_step) {
        // Issue 52: not "largest stable dt" beside "unstable at every step".
        out << "no step is stable without damping (every undamped mode grows at every step); "
               "the largest step whose trial stayed within the blow-up bound is "
            << r.max_stable_dt << " (bracket [" << r.lo << ", " << r.hi << "], " << r.runs
            << runs << "): it shrinks as the trial grows, a property of --t-end and --blowup, "
               "not a stability limit\n";
        break;
      }
      out << "largest stable dt " << r.max_stable_dt << " (bracket [" << r.lo << ", " << r.hi
          << "], " << r.runs << runs << ")\n";
      if (r.growth_at_lo > 1.0 + 1e-9) {
        out << "at " << r.lo << " the fastest mode's energy still grows x" << r.growth_at_lo
            << " per step: unstable, but too slowly to pass the blow-up bound within the trial "
               "(a longer --t-end or a smaller --blowup reads nearer the limit)\n";
      }
      break;
    case StabilityOutcome::kStableUpToDtMax:
      out << "no step diverged up to --dt-max " << s.dt_max << " (" << r.runs << runs << ")\n";
      break;
    case StabilityOutcome::kUnstableAtDtMin:
      out << "diverged even at --dt-min " << s.dt_min << " (" << r.runs << runs << ")\n";
      break;
  }
  if (r.lo_run_time > s.run.t_end) {
    out << "the trial at " << r.lo << " ran " << r.lo_run_time
        << " s, past --t-end: every trial runs at least " << s.min_steps << " steps and "
        << s.min_periods << " periods of the fastest mode\n";
  }
  out << "w_max " << w << " rad/s";
  if (r.mode.damping > 0.0) out << ", damping " << r.mode.damping << " 1/s";
  out << "; theory: ";
  if (theory.dt) {
    out << "dt* = " << *theory.dt << " (" << theory.rule << ")";
    if (r.outcome == StabilityOutcome::kBracketed) {
      out << ", measured / theory " << r.max_stable_dt / *theory.dt;
    }
    out << '\n';
  } else {
    out << theory.rule << '\n';
  }
  return out.str();
}

int command_stability(CommonOptions& common, StabilitySettings& s) {
  common.validate();
  require_positive("--dt-min", s.dt_min);
  require_positive("--dt-max", s.dt_max);
  if (!(s.dt_max > s.dt_min)) throw UsageError("--dt-max: must be greater than --dt-min");
  require_positive("--rel-tol", s.rel_tol);
  // An impossible range is refused now, not after the first runs.
  for (const auto& [option, dt] : {std::pair{"--dt-min", s.dt_min}, std::pair{"--dt-max", s.dt_max}}) {
    try {
      make_time_grid(dt, common.run.t_end);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string(option) + " " + number_text(dt) + " with --t-end " +
                       number_text(common.run.t_end) + ": " + e.what());
    }
  }
  const Scene scene = resolve_scene(common.scene, common.parameters);
  check_scene_memory(scene, printable(common.scene));  // before the model (memory_check.h)
  const Model model(scene);
  check_initial_energy(model, common.scene);
  std::unique_ptr<Integrator> integrator = make_integrator(common.run.integrator);
  print_notes(common.check_against_method(model, *integrator));
  // A refusal is not "diverged even at --dt-min"; each trial of the search
  // then makes its own.
  prepare_or_refuse(model, common.run, common.scene, std::move(integrator));
  s.run = common.run;
  std::unique_ptr<StabilityProgress> progress;
  if (::isatty(2)) {
    progress = std::make_unique<StabilityProgress>(s.run.integrator);
    s.on_trial = [p = progress.get()](const StabilityTrial& t) { p->trial(t); };
    s.observer = progress.get();
  }
  StabilityResult r;
  try {
    r = find_max_stable_dt(model, s);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());  // a trial longer than t_end with no valid grid
  }
  progress.reset();  // clears its line
  write_stdout(common.json ? stability_summary_json(scene, s, r)
                           : stability_summary_text(scene, s, r));
  return 0;
}

int command_list(bool json) {
  if (json) {
    write_stdout(integrator_table_json().dump(2) + "\n");
    return 0;
  }
  std::ostringstream out;
  out << "integrators:\n";
  for (const std::string& name : integrator_names()) {
    const auto integrator = make_integrator(name);
    const IntegratorInfo& i = integrator->info();
    out << "  " << name << "  order " << i.order
        << (i.position_order > i.order
                ? " (positions " + std::to_string(i.position_order) + " where F depends on x alone)"
                : std::string())
        << (i.adaptive ? ", adaptive" : ", fixed step")
        << (i.implicit ? ", implicit" : ", explicit") << (i.symplectic ? ", symplectic" : "")
        << ", " << stability_text(i) << "\n      " << i.scheme << '\n';
  }
  out << "divergence: a run stops at the first step that breaks a rule (docs/command-line.md "
         "\"Divergence\"):\n";
  for (const std::string& rule : divergence_sentences()) out << "  " << rule << '\n';
  out << "built-in scenes:\n";
  for (const BuiltinScene& s : builtin_scenes()) {
    out << "  " << s.name << "  " << s.description << '\n';
    for (const SceneParameter& p : s.parameters) {
      out << "      -p " << p.name << '=';
      if (p.choices.empty()) {
        out << p.default_value;
      } else {
        out << p.choices[static_cast<std::size_t>(p.default_value)];
      }
      out << "  " << p.meaning << '\n';
    }
  }
  write_stdout(out.str());
  return 0;
}

void parse_shard(const std::string& text, ExperimentRunOptions& o) {
  const auto slash = text.find('/');
  try {
    std::size_t end_i = 0, end_n = 0;
    if (slash == std::string::npos) throw std::invalid_argument(text);
    o.shard_index = std::stoi(text.substr(0, slash), &end_i);
    o.shard_count = std::stoi(text.substr(slash + 1), &end_n);
    if (end_i != slash || end_n != text.size() - slash - 1) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw UsageError("--shard " + printable(text) + ": expected i/N, e.g. 2/8");
  }
  if (o.shard_count < 1 || o.shard_index < 1 || o.shard_index > o.shard_count) {
    throw UsageError("--shard " + printable(text) + ": need 1 <= i <= N");
  }
}

// The CPUs this process may run on (a job scheduler's allocation, a
// container's limit), at least 1.
int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace

Scene resolve_scene(const std::string& scene_arg, const std::vector<std::string>& parameters) {
  const bool from_stdin = scene_arg == "-";
  struct stat st {};
  const bool exists = !from_stdin && ::stat(scene_arg.c_str(), &st) == 0;
  const int error = exists ? 0 : errno;
  if (from_stdin || exists) {
    const std::string label = from_stdin ? "stdin" : printable(scene_arg);
    if (exists && S_ISDIR(st.st_mode)) throw SceneError(label + ": is a directory, not a scene file");
    if (!parameters.empty()) {
      throw SceneError(label + ": -p applies to built-in scenes only, edit the file instead");
    }
    // A pipe or a FIFO (`<(springlab scene cloth)`) is read like a file.
    return load_scene_file(from_stdin ? "/dev/stdin" : scene_arg, label);
  }
  if (is_builtin_scene(scene_arg)) return make_builtin_scene(scene_arg, split_parameters(parameters));
  const std::string why = from_stdin || error == ENOENT ? "no such scene file or built-in scene"
                                                        : std::string("cannot open (") + std::strerror(error) + ")";
  const std::vector<std::string> names = builtin_names();
  // A name like a built-in's, not a path: say which one it may be.
  const std::string like = scene_arg.find('/') == std::string::npos && !from_stdin
                               ? did_you_mean(scene_arg, names)
                               : std::string();
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  throw SceneError(printable(scene_arg) + ": " + why + like + " (built-in scenes: " + list + ")");
}

CheckedRun run_settings_for(const Model& model, const std::string& integrator, double dt,
                            double t_end, int every,
                            const std::vector<std::pair<std::string, std::string>>& options,
                            std::vector<std::string>* notes) {
  CLI::App app{"springlab run"};
  app.option_defaults()->always_capture_default();
  CommonOptions common;
  common.add_to(app);
  app.add_option("--dt", common.run.dt)->required();
  app.add_option("--every", common.run.every);
  std::vector<std::string> args = {"springlab", "(scene)", "--integrator", integrator,
                                   "--dt", format_number(dt), "--t-end", format_number(t_end),
                                   "--every", std::to_string(every)};
  for (const auto& [option, value] : options) {
    if (option == "--json" || option == "-p") {
      throw UsageError(option + ": not an option of a run from Python");
    }
    args.push_back(option);
    if (!value.empty()) args.push_back(value);
  }
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    throw UsageError(parse_error_line(e, app, static_cast<int>(argv.size()), argv.data(), "run"));
  }
  common.validate();
  require_positive("--dt", common.run.dt);
  if (common.run.every < 1) throw UsageError("--every: must be >= 1");
  CheckedRun checked{common.run, make_integrator(common.run.integrator)};
  std::vector<std::string> method_notes = common.check_against_method(model, *checked.integrator);
  if (notes != nullptr) {
    *notes = std::move(method_notes);
  } else {
    print_notes(method_notes);
  }
  return checked;
}

std::unique_ptr<Integrator> prepare_run(const Model& model, const RunSettings& settings,
                                        const std::string& scene_arg,
                                        std::unique_ptr<Integrator> integrator) {
  return prepare_or_refuse(model, settings, scene_arg, std::move(integrator));
}

Json verdict_json(const Verdict& v) {
  Json j{{"rule", std::string(to_string(v.rule))}, {"value", v.value}, {"bound", v.bound}};
  if (v.where >= 0) j["where"] = v.where;
  if (v.plane >= 0) j["plane"] = v.plane;
  return j;
}

Json stats_json(const IntegratorStats& s) {
  return Json{{"steps", s.steps},
              {"rejected_steps", s.rejected_steps},
              {"force_evals", s.force_evals},
              {"jacobian_evals", s.jacobian_evals},
              {"linear_solves", s.linear_solves},
              {"linear_iterations", s.linear_iterations},
              {"newton_iterations", s.newton_iterations},
              {"factorizations", s.factorizations},
              {"nonlinear_failures", s.nonlinear_failures}};
}

int run_cli(int argc, char** argv) {
  install_signal_handlers();
  CLI::App app{"springlab: time integrators on mass-spring systems"};
  app.require_subcommand(1);
  app.option_defaults()->always_capture_default();

  CommonOptions run_options;
  std::string energy_path, trajectory_path, vtk_dir;
  CLI::App* run = app.add_subcommand("run", "simulate a scene with one integrator");
  run_options.add_to(*run);
  run->add_option("--dt", run_options.run.dt,
                  "step [s] (adaptive methods: output interval)")
      ->required()
      ->default_str("");
  run->add_option("--energy", energy_path, "CSV t,kinetic,spring,gravity,total");
  run->add_option("--trajectory", trajectory_path, "CSV t,i,x,y[,z],vx,vy[,vz]");
  run->add_option("--vtk", vtk_dir, "folder for ParaView frames: <scene>_NNNNNN.vtu and <scene>.pvd");
  run->add_option("--every", run_options.run.every, "write every K-th output time (and the last)");

  CommonOptions stability_options;
  stability_options.run.blowup = kStabilityBlowup;
  StabilitySettings stability_settings;
  CLI::App* stability = app.add_subcommand("stability", "largest stable step, by bisection on log dt");
  stability_options.add_to(*stability);
  stability->get_option("--blowup")
      ->description("a trial diverges when kinetic + spring energy exceeds this times E_s, times "
                    "the swing a stable orbit of the method allows at w_max dt (1 for most methods, "
                    "more for symplectic ones: docs/command-line.md)");
  stability->add_option("--dt-min", stability_settings.dt_min, "smallest step tried");
  stability->add_option("--dt-max", stability_settings.dt_max, "largest step tried");
  stability->add_option("--rel-tol", stability_settings.rel_tol, "bisection stops at hi/lo <= 1 + tol");

  std::string scene_name;
  std::vector<std::string> scene_parameters;
  CLI::App* scene = app.add_subcommand("scene", "print a built-in scene as a scene file");
  scene->add_option("NAME", scene_name, "built-in scene")->required();
  scene->add_option("-p", scene_parameters, "parameter key=value (repeatable)")
      ->allow_extra_args(false)
      ->default_str("");

  bool list_json = false;
  CLI::App* list = app.add_subcommand("list", "integrators and built-in scenes");
  list->add_flag("--json", list_json,
                 "as JSON, with each integrator's family, stability, colour and marker");

  std::string experiment_file, shard;
  bool no_progress = false;
  ExperimentRunOptions experiment_options;
  CLI::App* experiment = app.add_subcommand("experiment", "run one experiment definition");
  experiment->add_option("FILE", experiment_file, "experiment definition (experiments/*.json)")
      ->required();
  experiment->add_option("--out", experiment_options.out_dir, "output directory")->required();
  experiment->add_option("--jobs", experiment_options.jobs, "tasks run at once, at most the CPUs")
      ->default_str("all CPUs");
  experiment->add_option("--shard", shard, "run only shard i of N (i/N), for job arrays");
  experiment->add_option("--merge", experiment_options.merge,
                         "merge N shards into the full tables instead of running")
      ->default_str("");
  experiment->add_flag("--no-progress", no_progress, "no progress line on stderr")->default_str("");
  CheckCommand check_options;
  CLI::App* check = add_check_command(app, check_options);
  for (CLI::App* cmd : {run, stability}) {
    for (const char* flag : {"--dq-jacobian", "--stald", "--json"}) cmd->get_option(flag)->default_str("");
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "springlab: error: " << parse_error_line(e, app, argc, argv) << '\n';
    return 1;
  }

  try {
    if (*run) {
      // An empty name is a mistake (an unset shell variable), not "no file".
      for (const auto& [option, value, what] :
           {std::tuple{"--energy", &energy_path, "file"}, std::tuple{"--trajectory", &trajectory_path, "file"},
            std::tuple{"--vtk", &vtk_dir, "folder"}}) {
        if (run->count(option) > 0 && value->empty()) {
          throw UsageError(std::string(option) + ": the " + what + " name is empty");
        }
      }
      return command_run(run_options, {energy_path, trajectory_path, vtk_dir});
    }
    if (*stability) return command_stability(stability_options, stability_settings);
    if (*scene) {
      // An unknown name: make_builtin_scene's message, with "did you mean".
      write_stdout(
          scene_to_json(make_builtin_scene(scene_name, split_parameters(scene_parameters))));
      return 0;
    }
    if (*list) return command_list(list_json);
    if (*check) return run_check_command(check_options);
    if (*experiment) {
      const bool merging = experiment->count("--merge") > 0;
      if (merging && experiment_options.merge < 1) throw UsageError("--merge: must be >= 1");
      if (merging && !shard.empty()) {
        throw UsageError("--merge and --shard: merge the shards in a run of its own, without --shard");
      }
      if (!shard.empty()) parse_shard(shard, experiment_options);
      if (experiment_options.jobs < 0) throw UsageError("--jobs: must be >= 0");
      experiment_options.progress = !no_progress;
      // More threads than CPUs gain nothing on these compute-bound tasks and
      // hold one more model each: --jobs is capped at the usable CPUs.
      const int cpus = usable_cpus();
      if (experiment_options.jobs > cpus) {
        std::cerr << "springlab: note: --jobs " << experiment_options.jobs << " capped at " << cpus
                  << ", the CPUs this process may use" << std::endl;
      }
      experiment_options.jobs =
          experiment_options.jobs == 0 ? cpus : std::min(experiment_options.jobs, cpus);
      // Ctrl-C (or a job scheduler's SIGTERM) stops the sweep: the finished
      // tasks are written, whole, and marked incomplete.
      StopOnSignals stop;
      experiment_options.cancel = &stop.flag();
      const ExperimentRunSummary summary = run_experiment(experiment_file, experiment_options);
      if (!summary.complete()) {
        std::cerr << "springlab: interrupted: " << summary.tasks_done << " of "
                  << summary.tasks_total << " tasks written, marked incomplete in "
                  << printable(experiment_options.out_dir) << "\n";
        return 130;
      }
      return 0;
    }
  } catch (const std::bad_alloc&) {
    // An allocation outside the factor checks (the scene itself, its
    // matrices) failed: one line, not "std::bad_alloc" alone (issue 38.1).
    std::cerr << "springlab: error: out of memory (the scene or its matrices): use a coarser "
                 "mesh, or raise ulimit -v if it is set\n";
    return 1;
  } catch (const std::exception& e) {
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    std::cerr << "springlab: error: " << what << '\n';
    return 1;
  }
  return 1;
}

}  // namespace springlab
