// The Python module `springlab` (pybind11): scenes, runs and experiments
// from a notebook, results as NumPy arrays (docs/python.md "Python").
//
//   import springlab
//   scene = springlab.load_scene("cloth", n=8)       # a built-in, a file, or a dict
//   run = springlab.run(scene, "implicit-euler", dt=0.01, t_end=1.0, newton_tol=1e-6)
//   run.t, run.x, run.v, run.energies["total"], run.stats["newton_iterations"]
//
// Everything goes through the library the command line uses: the same
// scene checks, the same option checks (keyword `newton_tol` is `--newton-tol`),
// the same messages. A bad input raises springlab.Error whose text is the one
// line `springlab` prints after "springlab: error: ".
#include <dlfcn.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "experiments/io/body_output.h"
#include "experiments/analysis/claims.h"
#include "experiments/cli/cli.h"
#include "experiments/kinds/experiment_runner.h"
#include "experiments/cli/integrator_table.h"
#include "experiments/driver/memory_check.h"
#include "experiments/driver/simulation.h"
#include "models/bodies/bodies.h"
#include "models/model/model.h"
#include "models/core/element_kind.h"
#include "models/core/scene.h"
#include "models/model/scene_file.h"
#include "models/model/element_registry.h"
#include "integrators/registry/plugins.h"
#include "integrators/registry/registry.h"
#include "python_integrator.h"

namespace py = pybind11;
using namespace springlab;

namespace {

// JSON text <-> Python objects, through Python's own json module.
py::object from_json_text(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}
std::string to_json_text(const py::object& value) {
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

// The CPUs this process may run on, at least 1 (as `experiment --jobs`).
int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// A keyword argument's value as typed on the command line.
std::string option_text(const py::handle& value) {
  if (py::isinstance<py::float_>(value)) {
    return py::repr(value).cast<std::string>();  // shortest round trip
  }
  return py::str(value).cast<std::string>();
}

// The state at each output time, and the energies there; for a scene with
// rigid bodies, each body's p and A (bodies.h) too.
class Recorder final : public Observer {
 public:
  explicit Recorder(const Model& model)
      : model_(model), layout_(body_layout(model.scene(), model.particle_order())) {}
  void observe(double t, const Vector& x, const Vector& v) override {
    t_.push_back(t);
    x_.push_back(model_.scene_positions(x));
    v_.push_back(model_.scene_velocities(v));
    e_.push_back(model_.energies(x, v).values());
    if (layout_.bodies.empty()) return;
    Eigen::MatrixXd p(static_cast<Eigen::Index>(layout_.bodies.size()), 3);
    Eigen::MatrixXd A(static_cast<Eigen::Index>(layout_.bodies.size()), 9);
    for (std::size_t b = 0; b < layout_.bodies.size(); ++b) {
      const BodyState s = body_state(layout_.bodies[b], layout_.first[b], x.data(), v.data());
      const auto row = static_cast<Eigen::Index>(b);
      p.row(row) = s.p.transpose();
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) A(row, 3 * i + j) = s.A(i, j);
      }
    }
    body_p_.push_back(std::move(p));
    body_A_.push_back(std::move(A));
  }
  std::size_t bodies() const { return layout_.bodies.size(); }
  std::vector<double> t_;
  std::vector<Eigen::MatrixXd> x_, v_, body_p_, body_A_;
  std::vector<std::vector<double>> e_;

 private:
  const Model& model_;
  BodyLayout layout_;
};

py::array_t<double> stack(const std::vector<Eigen::MatrixXd>& frames, Eigen::Index rows,
                          Eigen::Index cols) {
  py::array_t<double> out({static_cast<py::ssize_t>(frames.size()), static_cast<py::ssize_t>(rows),
                           static_cast<py::ssize_t>(cols)});
  auto a = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < frames.size(); ++k) {
    for (Eigen::Index i = 0; i < rows; ++i) {
      for (Eigen::Index r = 0; r < cols; ++r) a(k, i, r) = frames[k](i, r);
    }
  }
  return out;
}

Scene load_scene(const py::object& source, const py::kwargs& parameters) {
  std::vector<std::string> p;
  for (const auto& [key, value] : parameters) {
    p.push_back(py::str(key).cast<std::string>() + "=" + option_text(value));
  }
  if (py::isinstance<py::dict>(source)) {
    if (!p.empty()) throw SceneError("parameters apply to built-in scenes only, not to a dict");
    return parse_scene(to_json_text(source), "<dict>");
  }
  std::string path = py::str(source).cast<std::string>();
  return resolve_scene(path, p);
}

py::dict run_result(const Model& model, const RunResult& r, const Recorder& rec) {
  py::dict out;
  const Eigen::Index n = model.particle_count(), d = model.dimension();
  py::array_t<double> t(static_cast<py::ssize_t>(rec.t_.size()));
  std::copy(rec.t_.begin(), rec.t_.end(), t.mutable_data());
  out["t"] = t;
  out["x"] = stack(rec.x_, n, d);
  out["v"] = stack(rec.v_, n, d);
  py::dict energies;
  const std::vector<std::string> columns = model.energy_columns();
  for (std::size_t c = 0; c < columns.size(); ++c) {
    py::array_t<double> column(static_cast<py::ssize_t>(rec.e_.size()));
    for (std::size_t k = 0; k < rec.e_.size(); ++k) column.mutable_data()[k] = rec.e_[k][c];
    energies[py::str(columns[c])] = column;
  }
  out["energies"] = energies;
  out["stats"] = from_json_text(stats_json(r.stats).dump());
  out["integrator"] = r.integrator;
  out["dt"] = r.dt;
  out["t_end"] = r.t_end;
  out["status"] = std::string(to_string(r.status));
  out["diverged"] = r.diverged();
  out["diverged_at"] = r.diverged_at ? py::object(py::float_(*r.diverged_at)) : py::object(py::none());
  out["failure"] = r.failure.empty() ? py::object(py::none()) : py::object(py::str(r.failure));
  out["verdict"] = r.verdict ? from_json_text(verdict_json(*r.verdict).dump()) : py::object(py::none());
  py::list warnings;
  for (const std::string& w : warning_texts(r.warnings, r.integrator)) warnings.append(w);
  out["warnings"] = warnings;
  out["t_final"] = r.t_final;
  out["energy_scale"] = model.energy_scale();
  out["wall_seconds"] = r.wall_seconds;
  if (rec.bodies() > 0) {
    // As `run --json`'s "bodies" (the last good state), and p and A at each
    // output time: body_p (frames, bodies, 3), body_A (frames, bodies, 3, 3).
    out["bodies"] = from_json_text(bodies_json(model, r.x_final, r.v_final).dump());
    const auto b = static_cast<Eigen::Index>(rec.bodies());
    out["body_p"] = stack(rec.body_p_, b, 3);
    out["body_A"] = stack(rec.body_A_, b, 9).attr("reshape")(
        py::make_tuple(rec.body_A_.size(), rec.bodies(), 3, 3));
  }
  return out;
}

// A plug-in calls the springlab it is loaded into: Python loads this module
// with RTLD_LOCAL, so before the first plug-in its symbols are made global.
void make_symbols_global() {
  static const bool done = [] {
    Dl_info self{};
    if (::dladdr(reinterpret_cast<void*>(&make_symbols_global), &self) != 0 && self.dli_fname) {
      ::dlopen(self.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
    }
    return true;
  }();
  (void)done;
}

// Runs `work` on a thread of its own while this one, the GIL released,
// wakes every kSignalCheck to ask Python for signals (PyErr_CheckSignals,
// with the GIL): Ctrl-C (a notebook's "interrupt kernel") sets `stop`,
// which every simulate() on that thread honours (StopScope), and raises
// the handler's KeyboardInterrupt once the work has stopped. Python only
// notes a signal and runs its handler when the main thread asks.
template <class Result>
Result interruptible(const std::function<Result()>& work, std::atomic<bool>& stop) {
  constexpr auto kSignalCheck = std::chrono::milliseconds(20);
  bool interrupted = false;
  Result result{};
  {
    py::gil_scoped_release release;
    std::future<Result> running = std::async(std::launch::async, [&] {
      const StopScope scope(&stop);
      return work();
    });
    while (running.wait_for(kSignalCheck) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        interrupted = true;
        stop = true;
        break;
      }
    }
    try {
      result = running.get();  // rethrows the work's exception
    } catch (const StopRequested&) {
      if (!interrupted) throw;
    }
  }
  if (interrupted) throw py::error_already_set();  // the handler's exception, still set
  return result;
}

}  // namespace

PYBIND11_MODULE(springlab, m) {
  m.doc() = "springlab: time integrators on mass-spring systems and finite elements";
  static py::exception<std::runtime_error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::runtime_error& e) {
      std::string what = e.what();
      std::replace(what.begin(), what.end(), '\n', ' ');
      error(what.c_str());
    } catch (const std::invalid_argument& e) {
      error(e.what());
    }
  });

  py::class_<Scene>(m, "Scene", "a scene: particles and the elements between them")
      .def_readonly("name", &Scene::name)
      .def_readonly("dimension", &Scene::dimension)
      .def_property_readonly("particle_count", [](const Scene& s) { return s.particles.size(); })
      .def("to_dict", [](const Scene& s) { return from_json_text(scene_to_json(s)); },
           "the scene as a scene file's JSON object")
      .def("cells", [](const Scene& s) {
            py::list out;
            for (const Cell& c : scene_cells(s)) {
              py::tuple nodes(c.size);
              for (int a = 0; a < c.size; ++a) nodes[a] = c.nodes[a];
              out.append(nodes);
            }
            return out;
          }, "each element as a tuple of the particles it joins: springs (i, j), triangles, tetrahedra")
      .def("__repr__", [](const Scene& s) {
        std::string text = "<springlab.Scene " + s.name + ": " + std::to_string(s.particles.size()) + " particles";
        for (const ElementCount& c : element_counts(s)) {
          if (c.count > 0) text += ", " + std::to_string(c.count) + " " + std::string(c.key);
        }
        return text + ">";
      });

  m.def("load_scene", &load_scene, py::arg("source"),
        "A scene from a built-in's name (its parameters as keywords: load_scene('cloth', n=8)),\n"
        "a scene file's path, or a dict in the scene file format.");

  m.def(
      "run",
      [](const Scene& scene, const py::object& method, double dt, double t_end, int every,
         const py::kwargs& options) {
        validate_scene(scene, scene.name);
        if (options.contains("plugin")) make_symbols_global();
        // A springlab.Integrator instance is registered under its name.
        const std::string integrator = springlab::python::method_name(method);
        if (springlab::python::restore_step_error()) PyErr_Clear();
        std::vector<std::pair<std::string, std::string>> typed;
        for (const auto& [key, value] : options) {
          std::string option = "--" + py::str(key).cast<std::string>();
          std::replace(option.begin(), option.end(), '_', '-');
          if (py::isinstance<py::bool_>(value)) {
            if (value.cast<bool>()) typed.emplace_back(option, "");
          } else {
            typed.emplace_back(option, option_text(value));
          }
        }
        check_scene_memory(scene, "scene '" + scene.name + "'");  // before the model
        const Model model(scene);
        std::vector<std::string> notes;
        CheckedRun checked = run_settings_for(model, integrator, dt, t_end, every, typed, &notes);
        const RunSettings& settings = checked.settings;
        for (const std::string& note : notes) {  // `run`'s "springlab: note: ..." as warnings
          PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1);
        }
        const TimeGrid grid = make_time_grid(dt, t_end);
        const double frames = 1.0 + std::floor(static_cast<double>(grid.steps) / every) + 1.0;
        // A row per particle and per body at each kept time, and at least
        // one (its time and energies): a bodies-only scene is capped too
        // (issue 46.10: MemoryError at dt 1e-6, t_end 30).
        const std::size_t bodies = scene.get<Bodies>().size();
        const double rows_per_frame =
            std::max(1.0, static_cast<double>(scene.particles.size() + bodies));
        if (frames * rows_per_frame > kMaxOutputRows) {
          std::string what = std::to_string(scene.particles.size()) + " particles";
          if (bodies > 0) what += " and " + std::to_string(bodies) + (bodies == 1 ? " body" : " bodies");
          throw std::runtime_error("every: the run would keep " +
                                   std::to_string(static_cast<long long>(frames)) + " states of " +
                                   what + ", over the cap of 10000000 rows: keep every K-th step with every=K");
        }
        Recorder recorder(model);
        std::atomic<bool> stop{false};
        RunSettings interruptible_settings = settings;
        interruptible_settings.options.stop = &stop;
        // A pairing the method refuses (xpbd and a neo-Hookean material, the
        // barrier with a projection method) raises springlab.Error, as the
        // command line refuses it; a failure during the run is a result.
        std::unique_ptr<Integrator> prepared =
            prepare_run(model, interruptible_settings, "", std::move(checked.integrator));
        const RunResult r = interruptible<RunResult>(
            [&] { return simulate(model, interruptible_settings, {&recorder}, std::move(prepared)); },
            stop);
        // A Python method's step that raised: its exception, with its traceback.
        if (springlab::python::restore_step_error()) throw py::error_already_set();
        return run_result(model, r, recorder);
      },
      py::arg("scene"), py::arg("integrator"), py::arg("dt"), py::arg("t_end"), py::arg("every") = 1,
      "Runs a scene with one integrator, as `springlab run` does: a registered name, or an\n"
      "instance of a springlab.Integrator subclass (your own method, registered under its name).\n"
      "Keywords are run's options\n"
      "(newton_tol=1e-6 is --newton-tol 1e-6, stald=True is --stald). Returns a dict: t (frames,),\n"
      "x and v (frames, particles, dimension), energies (column -> (frames,)), stats (the\n"
      "statistics every integrator reports), status, diverged, diverged_at, failure, verdict\n"
      "(the rule that ended a diverged run: rule, value, bound, where), warnings (one line\n"
      "each, as `run --json`), t_final,\n"
      "energy_scale, wall_seconds; with rigid bodies also bodies (as run --json's, at the last\n"
      "good state), body_p (frames, bodies, 3) and body_A (frames, bodies, 3, 3). A divergence\n"
      "or a solver failure is a result, not an error;\n"
      "a pairing the method refuses before its first step raises springlab.Error.");

  m.def("integrators", [] { return from_json_text(integrator_table_json()["integrators"].dump()); },
        "every registered integrator as `springlab list --json` lists it: name, order, family,\n"
        "stability, colour, marker, ...");
  m.def("scenes", [] { return from_json_text(integrator_table_json()["scenes"].dump()); },
        "the built-in scenes as `springlab list --json` lists them: name, description and\n"
        "parameters (each name, default, meaning)");

  m.def(
      "experiment",
      [](const py::object& source, const std::string& out, int jobs, const py::object& integrators) {
        make_symbols_global();  // its "plugins" are loaded into this process
        // A dict, or a definition whose integrators are replaced, is written
        // to a temporary file first (removed after the run): beside the
        // definition, so that its scene paths still resolve.
        py::object temporary = py::none();
        std::string definition;
        if (py::isinstance<py::dict>(source) || !integrators.is_none()) {
          py::object json = source;
          std::string folder;
          if (!py::isinstance<py::dict>(source)) {
            definition = py::str(source).cast<std::string>();
            const py::object path = py::module_::import("pathlib").attr("Path")(definition);
            json = py::module_::import("json").attr("loads")(path.attr("read_text")());
            folder = py::str(path.attr("parent")).cast<std::string>();
          } else {
            json = py::module_::import("copy").attr("deepcopy")(source);
          }
          if (!integrators.is_none()) {
            py::list names;
            for (const py::handle& method : integrators) {
              names.append(springlab::python::method_name(py::reinterpret_borrow<py::object>(method)));
            }
            json["integrators"] = names;
          }
          py::dict file_options;
          file_options["mode"] = "w";
          file_options["suffix"] = ".json";
          if (!folder.empty()) {
            file_options["dir"] = folder;
            file_options["prefix"] = ".springlab-";
          }
          temporary = py::module_::import("tempfile").attr("NamedTemporaryFile")(**file_options);
          temporary.attr("write")(to_json_text(json));
          temporary.attr("flush")();
          definition = temporary.attr("name").cast<std::string>();
        } else {
          definition = py::str(source).cast<std::string>();
        }
        if (jobs < 1) {
          throw std::runtime_error("jobs: must be at least 1 (got " + std::to_string(jobs) + ")");
        }
        // More threads than CPUs gain nothing (as `experiment --jobs`).
        const int cpus = usable_cpus();
        if (jobs > cpus) {
          const std::string note = "jobs=" + std::to_string(jobs) + " capped at " +
                                   std::to_string(cpus) + ", the CPUs this process may use";
          PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1);
          jobs = cpus;
        }
        ExperimentRunOptions options;
        options.out_dir = out;
        options.jobs = jobs;
        options.progress = false;
        // Ctrl-C, as for run(): the experiment goes on a thread of its own
        // while this one asks Python for signals every kSignalCheck; a
        // signal stops it as the command line's first SIGINT does (no task
        // starts, running ones stop at their next step, the finished ones
        // are written whole and marked incomplete) and raises the handler's
        // KeyboardInterrupt (issue 46.9: it ran on to the end, 22 s).
        constexpr auto kSignalCheck = std::chrono::milliseconds(20);
        std::atomic<bool> stop{false};
        options.cancel = &stop;
        ExperimentRunSummary summary;
        bool interrupted = false;
        {
          py::gil_scoped_release release;
          std::future<ExperimentRunSummary> running = std::async(
              std::launch::async, [&] { return run_experiment(definition, options); });
          while (running.wait_for(kSignalCheck) != std::future_status::ready) {
            py::gil_scoped_acquire acquire;
            if (PyErr_CheckSignals() != 0) {
              interrupted = true;
              stop = true;
              break;
            }
          }
          summary = running.get();  // rethrows the experiment's exception
        }
        if (interrupted) throw py::error_already_set();  // the handler's exception, still set
        if (springlab::python::restore_step_error()) PyErr_Clear();  // failures are in the tables
        py::dict result;
        result["tasks_total"] = summary.tasks_total;
        result["tasks_done"] = summary.tasks_done;
        result["out"] = out;
        return result;
      },
      py::arg("definition"), py::arg("out"), py::arg("jobs") = 1, py::arg("integrators") = py::none(),
      "Runs an experiment definition (a path to one of experiments/*.json, or a dict in that\n"
      "format) into the folder `out`, as `springlab experiment` does; its tables are CSV files\n"
      "there. integrators=[...] replaces the definition's list: names and your own methods\n"
      "(springlab.Integrator instances) side by side. A definition's \"python\": [files] registers\n"
      "the springlab.Integrator classes those files define. jobs: tasks run at once (at least 1;\n"
      "capped at the CPUs, with a warning). Ctrl-C stops it as the command line's does (the\n"
      "finished tasks written, marked incomplete) and raises KeyboardInterrupt. Returns\n"
      "{tasks_total, tasks_done, out}.");

  springlab::python::bind_python_methods(m);

  m.def(
      "load_plugin",
      [](const std::string& path) {
        make_symbols_global();
        return load_plugin(path);
      },
      py::arg("path"),
      "Loads a plug-in of C++ integrators (springlab_add_plugin, docs/your-own-integrator.md)\n"
      "and returns the names it registered.");

  m.def(
      "check",
      [](const py::object& method, const py::object& order, const py::object& stable_limit,
         bool a_stable, bool symplectic, bool dissipative, bool momentum, bool deterministic,
         const py::object& plugin) {
        std::string plugin_arguments;
        if (!plugin.is_none()) {
          make_symbols_global();
          const std::string path = py::str(plugin).cast<std::string>();
          load_plugin(path);
          plugin_arguments = " --plugin " + path;
        }
        const bool python = !py::isinstance<py::str>(method);
        const std::string name = springlab::python::method_name(method);
        if (!is_integrator(name)) make_integrator(name);  // the registry's message
        Claims claims;
        if (!order.is_none()) claims.order = order.cast<int>();
        if (!stable_limit.is_none()) claims.stable_limit = stable_limit.cast<double>();
        claims.a_stable = a_stable;
        claims.symplectic = symplectic;
        claims.dissipative = dissipative;
        claims.momentum = momentum;
        claims.deterministic = deterministic;
        if (claims.stable_limit && claims.a_stable) {
          throw std::invalid_argument("stable_limit and a_stable: a method has a limit or none, not both");
        }
        if (!claims.any()) claims = stated_claims(make_integrator(name)->info());
        CheckSubject subject{name, "--integrator " + name + plugin_arguments,
                             "springlab check " + name + plugin_arguments};
        if (python) {
          const std::string cls = py::str(py::type::of(method).attr("__name__")).cast<std::string>();
          subject.python_call = cls + "()";
        }
        std::atomic<bool> stop{false};
        const CheckReport report = interruptible<CheckReport>(
            [&] { return check_claims(subject, claims); }, stop);
        if (springlab::python::restore_step_error()) PyErr_Clear();  // failures are results
        py::dict out = from_json_text(check_report_json(report).dump());
        out["text"] = check_report_text(report);
        return out;
      },
      py::arg("method"), py::arg("order") = py::none(), py::arg("stable_limit") = py::none(),
      py::arg("a_stable") = false, py::arg("symplectic") = false, py::arg("dissipative") = false,
      py::arg("momentum") = false, py::arg("deterministic") = false, py::arg("plugin") = py::none(),
      "Runs a method against its claims, as `springlab check` does: a registered name or your\n"
      "own springlab.Integrator instance; claims as keywords (order=2, stable_limit=2.0,\n"
      "a_stable=True, symplectic=True, dissipative=True, momentum=True, deterministic=True);\n"
      "none given: the ones it states (its class attributes). Returns a dict: passed, claims\n"
      "(each claim, passed, measured, figures, run), sanity, and text (the report as printed).");
}
