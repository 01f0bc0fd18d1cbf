#include "experiments/cli.h"

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "experiments/experiment_runner.h"
#include "experiments/integrator_table.h"
#include "experiments/output_files.h"
#include "experiments/simulation.h"
#include "experiments/stability.h"
#include "integrators/registry.h"
#include "models/builtin_scenes.h"
#include "models/mass_spring_model.h"

namespace springlab {
namespace {

using Json = nlohmann::ordered_json;

// A bad command-line value: reported like a scene error, exit status 1.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::vector<std::pair<std::string, std::string>> split_parameters(
    const std::vector<std::string>& parameters) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const std::string& p : parameters) {
    const auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw UsageError("-p " + p + ": expected key=value");
    }
    pairs.emplace_back(p.substr(0, eq), p.substr(eq + 1));
  }
  return pairs;
}

std::string builtin_list() {
  std::string names;
  for (const BuiltinScene& s : builtin_scenes()) names += (names.empty() ? "" : ", ") + s.name;
  return names;
}

void require_positive(const std::string& option, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    std::ostringstream m;
    m << option << ": must be a positive number (got " << value << ")";
    throw UsageError(m.str());
  }
}

void require_integrator(const std::string& name) {
  if (!is_integrator(name)) {
    std::string valid;
    for (const std::string& n : integrator_names()) valid += (valid.empty() ? "" : ", ") + n;
    throw UsageError("--integrator: unknown integrator '" + name + "' (integrators: " + valid + ")");
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

Json stats_json(const IntegratorStats& s) {
  return Json{{"steps", s.steps},
              {"rejected_steps", s.rejected_steps},
              {"force_evals", s.force_evals},
              {"jacobian_evals", s.jacobian_evals},
              {"linear_solves", s.linear_solves},
              {"newton_iterations", s.newton_iterations},
              {"factorizations", s.factorizations},
              {"nonlinear_failures", s.nonlinear_failures}};
}

// Options shared by `run` and `stability`.
struct CommonOptions {
  std::string scene;
  std::vector<std::string> parameters;
  RunSettings run;
  bool json = false;

  void add_to(CLI::App& cmd) {
    cmd.add_option("SCENE", scene, "scene file or built-in scene name")->required();
    cmd.add_option("--integrator", run.integrator, "integrator name (springlab list)")->required();
    cmd.add_option("--t-end", run.t_end, "simulated time [s]")->required();
    cmd.add_option("-p", parameters, "built-in scene parameter key=value (repeatable)");
    cmd.add_option("--rtol", run.options.rtol, "adaptive methods: relative tolerance");
    cmd.add_option("--atol", run.options.atol, "adaptive methods: absolute tolerance");
    cmd.add_option("--newton-tol", run.options.newton_tol,
                   "implicit methods: Newton stops when ||M^-1 r||_inf <= tol max(1, ||v||_inf)");
    cmd.add_option("--max-newton", run.options.max_newton,
                   "implicit methods: Newton iterations per step before the run fails");
    cmd.add_option("--max-steps", run.options.max_steps,
                   "adaptive methods: internal steps per output interval before failing");
    cmd.add_option("--max-order", run.options.max_order,
                   "adaptive methods: highest order (ARKODE: the method's order); 0 = default");
    cmd.add_option("--linear-solver", run.options.linear_solver,
                   "implicit adaptive methods: dense, klu, gmres or auto (dense up to 100 "
                   "unknowns, klu above)");
    cmd.add_flag("--dq-jacobian", run.options.dq_jacobian,
                 "implicit adaptive methods: SUNDIALS difference quotients instead of the "
                 "analytic Jacobian");
    cmd.add_flag("--stald", run.options.stald, "cvode-bdf: stability limit detection");
    cmd.add_option("--blowup", run.blowup,
                   "divergence when kinetic + spring energy exceeds this times E_s");
    cmd.add_flag("--json", json, "print one JSON object on stdout");
  }

  void validate() const {
    require_integrator(run.integrator);
    require_positive("--t-end", run.t_end);
    require_positive("--rtol", run.options.rtol);
    require_positive("--atol", run.options.atol);
    require_positive("--newton-tol", run.options.newton_tol);
    require_positive("--blowup", run.blowup);
    if (run.options.max_newton < 1) throw UsageError("--max-newton: must be >= 1");
    if (run.options.max_steps < 1) throw UsageError("--max-steps: must be >= 1");
    if (run.options.max_order < 0) throw UsageError("--max-order: must be >= 0");
    static const char* solvers[] = {"auto", "dense", "klu", "gmres"};
    if (std::find(std::begin(solvers), std::end(solvers), run.options.linear_solver) ==
        std::end(solvers)) {
      throw UsageError("--linear-solver: unknown '" + run.options.linear_solver +
                       "' (auto, dense, klu, gmres)");
    }
  }
};

int command_run(CommonOptions& common, const std::string& energy_path,
                const std::string& trajectory_path) {
  common.validate();
  require_positive("--dt", common.run.dt);
  if (common.run.every < 1) throw UsageError("--every: must be >= 1");
  if (!energy_path.empty() && !trajectory_path.empty() && same_file(energy_path, trajectory_path)) {
    throw UsageError("--energy " + energy_path + " and --trajectory " + trajectory_path +
                     " name the same file");
  }
  const Scene scene = resolve_scene(common.scene, common.parameters);
  make_time_grid(common.run.dt, common.run.t_end);  // refuse a bad grid before any output exists
  const MassSpringModel model(scene);

  // Files are opened (as temporaries) before any step runs.
  std::unique_ptr<AtomicFile> energy_file, trajectory_file;
  std::unique_ptr<Observer> energy_csv, trajectory_csv;
  std::vector<Observer*> observers;
  if (!energy_path.empty()) {
    energy_file = std::make_unique<AtomicFile>(energy_path);
    energy_csv = std::make_unique<EnergyCsv>(model, *energy_file);
    observers.push_back(energy_csv.get());
  }
  if (!trajectory_path.empty()) {
    trajectory_file = std::make_unique<AtomicFile>(trajectory_path);
    trajectory_csv = std::make_unique<TrajectoryCsv>(model, *trajectory_file);
    observers.push_back(trajectory_csv.get());
  }

  const RunResult r = simulate(model, common.run, observers);
  for (AtomicFile* f : {energy_file.get(), trajectory_file.get()}) {
    if (f != nullptr) f->finish();
  }
  for (AtomicFile* f : {energy_file.get(), trajectory_file.get()}) {
    if (f != nullptr) f->publish();
  }

  // A run that diverged or failed still publishes its files: they hold the
  // rows up to its last good state (t_final), and the summary says so.
  const bool any_output = energy_file != nullptr || trajectory_file != nullptr;
  const bool outputs_complete = r.status == RunStatus::kCompleted;
  if (common.json) {
    Json out;
    out["scene"] = scene.name;
    out["integrator"] = r.integrator;
    out["dt"] = r.dt;
    out["t_end"] = r.t_end;
    out["status"] = to_string(r.status);
    const Json stats = stats_json(r.stats);  // named: a temporary would die before the loop
    for (const auto& [key, value] : stats.items()) out[key] = value;
    out["wall_seconds"] = r.wall_seconds;
    out["diverged"] = r.diverged();
    out["diverged_at"] = r.diverged_at ? Json(*r.diverged_at) : Json(nullptr);
    out["failure"] = r.failure.empty() ? Json(nullptr) : Json(r.failure);
    out["t_final"] = r.t_final;
    out["outputs_complete"] = outputs_complete;
    out["last_output_t"] = any_output ? Json(r.t_final) : Json(nullptr);
    out["energy_initial"] = r.energy_initial;
    out["energy_final"] = r.energy_final;
    out["energy_scale"] = model.energy_scale();
    out["final_state"] = Json{{"x", rows(model.scene_positions(r.x_final))},
                              {"v", rows(model.scene_velocities(r.v_final))}};
    std::cout << out.dump() << '\n';
  } else {
    std::cout << "scene " << scene.name << ", " << model.free_particle_count()
              << " free particles, " << scene.springs.size() << " springs\n"
              << "integrator " << r.integrator << ", dt " << r.dt << ", t_end " << r.t_end << '\n'
              << "status " << to_string(r.status);
    if (r.diverged_at) std::cout << " at t = " << *r.diverged_at;
    if (!r.failure.empty()) std::cout << ": " << r.failure;
    std::cout << '\n';
    const IntegratorStats& s = r.stats;
    std::cout << "steps " << s.steps << ", rejected " << s.rejected_steps << ", force evals "
              << s.force_evals << ", jacobian evals " << s.jacobian_evals << ", linear solves "
              << s.linear_solves << ", newton iterations " << s.newton_iterations << '\n'
              << "energy " << r.energy_initial << " -> " << r.energy_final << " (t = " << r.t_final
              << "), wall " << r.wall_seconds << " s\n";
    if (any_output && !outputs_complete) {
      std::cout << "output files incomplete: rows up to t = " << r.t_final
                << ", the last good state\n";
    }
  }
  return 0;
}

int command_stability(CommonOptions& common, StabilitySettings& s) {
  common.validate();
  require_positive("--dt-min", s.dt_min);
  require_positive("--dt-max", s.dt_max);
  if (!(s.dt_max > s.dt_min)) throw UsageError("--dt-max: must be greater than --dt-min");
  require_positive("--rel-tol", s.rel_tol);
  const Scene scene = resolve_scene(common.scene, common.parameters);
  const MassSpringModel model(scene);
  s.run = common.run;
  const StabilityResult r = find_max_stable_dt(model, s);
  if (common.json) {
    Json out;
    out["scene"] = scene.name;
    out["integrator"] = r.integrator;
    out["t_end"] = s.run.t_end;
    out["max_stable_dt"] = r.max_stable_dt;
    out["bracket"] = Json::array({r.lo, r.hi});
    out["runs"] = r.runs;
    std::cout << out.dump() << '\n';
  } else {
    std::cout << r.integrator << " on " << scene.name << " for t_end " << s.run.t_end
              << ": largest stable dt " << r.max_stable_dt << " (bracket [" << r.lo << ", "
              << r.hi << "], " << r.runs << " runs)\n";
  }
  return 0;
}

int command_list(bool json) {
  if (json) {
    std::cout << integrator_table_json().dump(2) << '\n';
    return 0;
  }
  std::cout << "integrators:\n";
  for (const std::string& name : integrator_names()) {
    const auto integrator = make_integrator(name);
    const IntegratorInfo& i = integrator->info();
    std::cout << "  " << name << "  order " << i.order
              << (i.adaptive ? ", adaptive" : ", fixed step")
              << (i.implicit ? ", implicit" : ", explicit") << (i.symplectic ? ", symplectic" : "")
              << ", " << stability_text(i) << "\n      " << i.scheme << '\n';
  }
  std::cout << "built-in scenes:\n";
  for (const BuiltinScene& s : builtin_scenes()) {
    std::cout << "  " << s.name << "  " << s.description << '\n';
    for (const SceneParameter& p : s.parameters) {
      std::cout << "      -p " << p.name << '=' << p.default_value << "  " << p.meaning << '\n';
    }
  }
  return 0;
}

std::atomic<bool> interrupted{false};

extern "C" void on_interrupt(int) { interrupted.store(true); }

// Installs on_interrupt for SIGINT and SIGTERM while alive.
class InterruptGuard {
 public:
  InterruptGuard() {
    interrupted.store(false);
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~InterruptGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

void parse_shard(const std::string& text, ExperimentRunOptions& o) {
  const auto slash = text.find('/');
  try {
    std::size_t end_i = 0, end_n = 0;
    if (slash == std::string::npos) throw std::invalid_argument(text);
    o.shard_index = std::stoi(text.substr(0, slash), &end_i);
    o.shard_count = std::stoi(text.substr(slash + 1), &end_n);
    if (end_i != slash || end_n != text.size() - slash - 1) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw UsageError("--shard " + text + ": expected i/N, e.g. 2/8");
  }
  if (o.shard_count < 1 || o.shard_index < 1 || o.shard_index > o.shard_count) {
    throw UsageError("--shard " + text + ": need 1 <= i <= N");
  }
}

}  // namespace

Scene resolve_scene(const std::string& scene_arg, const std::vector<std::string>& parameters) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(scene_arg, ec)) {
    if (!parameters.empty()) {
      throw SceneError(scene_arg + ": -p applies to built-in scenes only, edit the file instead");
    }
    return load_scene_file(scene_arg);
  }
  if (is_builtin_scene(scene_arg)) return make_builtin_scene(scene_arg, split_parameters(parameters));
  throw SceneError(scene_arg + ": no such scene file or built-in scene (built-in scenes: " +
                   builtin_list() + ")");
}

int run_cli(int argc, char** argv) {
  CLI::App app{"springlab: time integrators on mass-spring systems"};
  app.require_subcommand(1);

  CommonOptions run_options;
  std::string energy_path, trajectory_path;
  CLI::App* run = app.add_subcommand("run", "simulate a scene with one integrator");
  run_options.add_to(*run);
  run->add_option("--dt", run_options.run.dt,
                  "step [s] (adaptive methods: output interval)")->required();
  run->add_option("--energy", energy_path, "CSV t,kinetic,spring,gravity,total");
  run->add_option("--trajectory", trajectory_path, "CSV t,i,x,y[,z],vx,vy[,vz]");
  run->add_option("--every", run_options.run.every, "write every K-th output time (and the last)");

  CommonOptions stability_options;
  StabilitySettings stability_settings;
  CLI::App* stability = app.add_subcommand("stability", "largest stable step, by bisection on log dt");
  stability_options.add_to(*stability);
  stability->add_option("--dt-min", stability_settings.dt_min, "smallest step tried");
  stability->add_option("--dt-max", stability_settings.dt_max, "largest step tried");
  stability->add_option("--rel-tol", stability_settings.rel_tol, "bisection stops at hi/lo <= 1 + tol");

  std::string scene_name;
  std::vector<std::string> scene_parameters;
  CLI::App* scene = app.add_subcommand("scene", "print a built-in scene as a scene file");
  scene->add_option("NAME", scene_name, "built-in scene")->required();
  scene->add_option("-p", scene_parameters, "parameter key=value (repeatable)");

  bool list_json = false;
  CLI::App* list = app.add_subcommand("list", "integrators and built-in scenes");
  list->add_flag("--json", list_json,
                 "as JSON, with each integrator's family, stability, colour and marker");

  std::string experiment_file, shard;
  ExperimentRunOptions experiment_options;
  CLI::App* experiment = app.add_subcommand("experiment", "run one experiment definition");
  experiment->add_option("FILE", experiment_file, "experiment definition (experiments/*.json)")
      ->required();
  experiment->add_option("--out", experiment_options.out_dir, "output directory")->required();
  experiment->add_option("--jobs", experiment_options.jobs, "tasks run at once (default: all cores)");
  experiment->add_option("--shard", shard, "run only shard i of N (i/N), for job arrays");
  experiment->add_option("--merge", experiment_options.merge,
                         "merge N shards into the full tables instead of running");
  experiment->add_flag("!--no-progress", experiment_options.progress, "no progress line on stderr");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  try {
    if (*run) return command_run(run_options, energy_path, trajectory_path);
    if (*stability) return command_stability(stability_options, stability_settings);
    if (*scene) {
      if (!is_builtin_scene(scene_name)) {
        throw SceneError("unknown built-in scene '" + scene_name + "' (built-in scenes: " +
                         builtin_list() + ")");
      }
      std::cout << scene_to_json(make_builtin_scene(scene_name, split_parameters(scene_parameters)))
                << '\n';
      return 0;
    }
    if (*list) return command_list(list_json);
    if (*experiment) {
      if (!shard.empty()) parse_shard(shard, experiment_options);
      if (experiment_options.jobs < 0) throw UsageError("--jobs: must be >= 0");
      if (experiment_options.merge < 0) throw UsageError("--merge: must be >= 1");
      // Ctrl-C (or a job scheduler's SIGTERM) stops the sweep between tasks:
      // the finished ones are written, whole, and marked incomplete.
      InterruptGuard guard;
      experiment_options.cancel = &interrupted;
      const ExperimentRunSummary summary = run_experiment(experiment_file, experiment_options);
      if (!summary.complete()) {
        std::cerr << "springlab: interrupted: " << summary.tasks_done << " of "
                  << summary.tasks_total << " tasks written, marked incomplete in "
                  << experiment_options.out_dir << "\n";
        return 130;
      }
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "springlab: error: " << e.what() << '\n';
    return 1;
  }
  return 1;
}

}  // namespace springlab
