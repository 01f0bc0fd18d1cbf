// solver-error: how far each way of solving implicit Euler's step is from
// the step it approximates (its solver error), next to how far that step is
// from the true motion (implicit Euler's own discretization error), against
// what the step costs -- the frame-rate comparison of docs/integrators.md "Fast solvers".
//
// Steps are compared from the same state, never by where runs end after
// seconds of folding (two correct solvers of the same step can pick
// different solutions once springs buckle, and those drift apart): the
// reference is implicit Euler solved tightly (`reference_tol`, m/s) for
// `steps` steps of `dt` from the scene's initial state; at every `every`-th
// step k, each run -- an integrator with its options -- takes one step of dt
// from the reference's state (x_k, v_k), and its end x is compared with
//   - x_{k+1}, the tightly solved implicit Euler step: the solver error;
//   - the true motion over dt from the same state, RK4 at a step of
//     0.1 / w_max (w_max at the initial state; the fastest mode's error
//     (0.1)^4 / 120 per step): the total error of the run's step.
// The reference's own distance to the true motion is implicit Euler's
// discretization error, the floor below which solving the step more
// tightly buys nothing. Errors are max norms over the positions, in m.
//
// Whole runs: each fixed-step run also runs the `steps` steps from the
// scene's initial state as a user would (`springlab run`), which gives what
// the one-step errors do not -- the energy the run lost, E(0) - E(T), and the
// largest spring strain |l - L| / L at any step (the "Small Steps" grid of
// XPBD's substeps x iterations at equal cost, Macklin et al. 2019, is read
// off these) -- and its wall time per step. Adaptive methods are left out
// of it (a CVODE run of the cloth costs seconds per step).
//
// Costs: the wall time of the one step (the integrator is set up outside
// it; its first factorization, where it has one, counts, as it would on a
// run's first step) and its Newton/local-global iterations. One task per
// (case, run); the reference and the true motion of a case are computed
// once, by whichever of its tasks comes first.
#include <algorithm>
#include <chrono>
#include <limits>
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/output_files.h"
#include "integrators/registry/registry.h"
#include "models/model/modal_analysis.h"
#include "models/springs/springs.h"

namespace springlab {
namespace {

struct Variant {
  std::string integrator;
  IntegratorOptions options;
  std::string label;  // what distinguishes it: "newton-tol 0.001", "iterations 10", ...
  // The options the definition set, as the tables' option_* columns (empty
  // where not set): the report reads these, not the label.
  std::optional<double> newton_tol, substeps, iterations, chebyshev, rtol;
  std::string solver;
};

struct SampledStep {
  long step;
  Vector x, v;        // the reference's state at step k
  Vector x_next;      // its step k + 1 (tight implicit Euler)
  Vector x_true;      // the true motion over dt from (x, v)
};

struct Case {
  Scene scene;
  std::once_flag once;
  std::vector<SampledStep> samples;
  std::string error;  // the reference failed
};

class SolverErrorExperiment final : public Experiment {
 public:
  explicit SolverErrorExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "cases", "runs", "dt", "steps",
                  "every", "reference_tol"});
    dt_ = d.positive("dt");
    steps_ = d.count("steps", 30, 1, 100000);
    every_ = d.count("every", 5, 1, 100000);
    reference_tol_ = d.positive("reference_tol", 1e-9);
    for (const DefinitionObject& c : d.objects("cases")) {
      c.allow_only({"scene", "parameters"});
      auto entry = std::make_unique<Case>();
      entry->scene = definition_scene(c);
      cases_.push_back(std::move(entry));
    }
    for (const DefinitionObject& r : d.objects("runs")) {
      r.allow_only({"integrator", "newton_tol", "solver", "iterations", "substeps", "chebyshev",
                    "rtol", "atol"});
      Variant v;
      v.integrator = definition_integrator(r, "integrator");
      std::string label;
      auto note = [&](const std::string& text) { label += (label.empty() ? "" : "; ") + text; };
      if (r.has("newton_tol")) {
        v.options.newton_tol = r.positive("newton_tol");
        v.newton_tol = v.options.newton_tol;
        note("newton-tol " + format_number(v.options.newton_tol));
      }
      if (r.has("solver")) {
        if (!parse_solver(r.string("solver"), v.options.solver)) {
          r.fail("solver", "expected \"newton\" or \"quasi-newton\"");
        }
        note(to_string(v.options.solver));
        v.solver = to_string(v.options.solver);
      }
      if (r.has("substeps")) {
        v.options.substeps = r.count("substeps", 1, 1, 100000);
        v.substeps = v.options.substeps;
        note("substeps " + std::to_string(v.options.substeps));
      }
      if (r.has("iterations")) {
        v.options.iterations = r.count("iterations", 1, 1, 100000);
        v.iterations = v.options.iterations;
        note("iterations " + std::to_string(v.options.iterations));
      }
      if (r.has("chebyshev")) {
        v.options.chebyshev = r.number("chebyshev");
        if (!(v.options.chebyshev > 0.0 && v.options.chebyshev < 1.0)) {
          r.fail("chebyshev", "expected a spectral radius in (0, 1)");
        }
        note("chebyshev " + format_number(v.options.chebyshev));
        v.chebyshev = v.options.chebyshev;
      }
      if (r.has("rtol")) {
        v.options.rtol = r.positive("rtol");
        v.rtol = v.options.rtol;
        note("rtol " + format_number(v.options.rtol));
      }
      if (r.has("atol")) v.options.atol = r.positive("atol");
      v.label = label;
      variants_.push_back(std::move(v));
    }
    check_task_count(d, "runs", static_cast<double>(task_count()));
    const double samples = std::ceil(static_cast<double>(steps_) / every_);
    check_output_rows(d, "runs", static_cast<double>(task_count()) * (samples + 1.0));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"case", "scene", "integrator", "variant", "option_newton_tol", "option_solver",
                  "option_substeps", "option_iterations", "option_chebyshev", "option_rtol", "dt",
                  "step", "t", "status", "solver_error", "total_error", "discretization_error",
                  "wall_seconds", "iterations", "failure"}},
            {"runs", {"case", "scene", "integrator", "variant", "option_newton_tol",
                      "option_solver", "option_substeps", "option_iterations", "option_chebyshev",
                      "option_rtol", "dt", "status", "t_final", "energy_initial", "energy_lost",
                      "max_strain", "wall_seconds_per_step", "failure", "warnings"}}};
  }

  std::size_t task_count() const override { return cases_.size() * variants_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    Case& c = *cases_[index / variants_.size()];
    const Variant& variant = variants_[index % variants_.size()];
    std::call_once(c.once, [&] { prepare(c); });
    const std::string prefix = Row().add(static_cast<long>(index / variants_.size()))
                                   .add(c.scene.name).add(variant.integrator).add(variant.label)
                                   .add(variant.newton_tol).add(variant.solver)
                                   .add(variant.substeps).add(variant.iterations)
                                   .add(variant.chebyshev).add(variant.rtol)
                                   .add(dt_).str();
    // A model of its own: a model's scratch arrays serve one thread at a time.
    const Model model(c.scene);
    TaskOutput out;
    out.rows.resize(2);
    out.rows[1].push_back(whole_run(model, variant, prefix));
    if (!c.error.empty()) {
      out.rows[0].push_back(Row().raw(prefix).add_empty().add_empty().add("failed").add_empty()
                                .add_empty().add_empty().add_empty().add_empty()
                                .add("the reference: " + c.error).str());
      return out;
    }
    for (const SampledStep& s : c.samples) {
      std::unique_ptr<Integrator> integrator = make_integrator(variant.integrator);
      const double t = s.step * dt_;
      Row row;
      row.raw(prefix).add(s.step).add(t);
      StepResult r = integrator->initialize(model, t, s.x, s.v, variant.options);
      double wall = 0.0;
      if (r.ok) {
        const auto start = std::chrono::steady_clock::now();
        r = integrator->advance_to(t + dt_);
        wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      const double discretization = (s.x_next - s.x_true).lpNorm<Eigen::Infinity>();
      if (!r.ok || !integrator->x().allFinite()) {
        row.add("failed").add_empty().add_empty().add(discretization).add(wall).add_empty()
            .add(r.ok ? std::string("a non-finite state") : r.message);
      } else {
        const Vector& x = integrator->x();
        row.add("completed").add((x - s.x_next).lpNorm<Eigen::Infinity>())
            .add((x - s.x_true).lpNorm<Eigen::Infinity>()).add(discretization).add(wall)
            .add(integrator->stats().newton_iterations).add("");
      }
      out.rows[0].push_back(row.str());
    }
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json cases = nlohmann::json::array();
    for (const auto& c : cases_) cases.push_back({{"scene", scene_as_json(c->scene)}});
    nlohmann::json runs = nlohmann::json::array();
    for (const Variant& v : variants_) {
      runs.push_back({{"integrator", v.integrator}, {"variant", v.label}});
    }
    return {{"cases", cases}, {"runs", runs}, {"dt", dt_}, {"steps", steps_},
            {"every", every_}, {"reference_tol", reference_tol_}};
  }

 private:
  // The largest spring strain |l - L| / L at any output.
  class StrainWatch final : public Observer {
   public:
    explicit StrainWatch(const Model& model) : model_(model) {}
    void observe(double, const Vector& x, const Vector&) override {
      const Eigen::MatrixXd p = model_.scene_positions(x);
      for (const Spring& s : model_.scene().get<Springs>()) {
        if (!(s.rest > 0.0)) continue;
        const double l = (p.row(s.i) - p.row(s.j)).norm();
        max_strain = std::max(max_strain, std::abs(l - s.rest) / s.rest);
      }
    }
    double max_strain = 0.0;

   private:
    const Model& model_;
  };

  // The run from the scene's initial state over `steps` steps (fixed-step
  // methods only): its row of the runs table.
  std::string whole_run(const Model& model, const Variant& variant,
                        const std::string& prefix) const {
    Row row;
    row.raw(prefix);
    if (make_integrator(variant.integrator)->info().adaptive) {
      return row.add("skipped").add_empty().add_empty().add_empty().add_empty().add_empty()
          .add("adaptive methods are not run whole").add_empty().str();
    }
    RunSettings run;
    run.integrator = variant.integrator;
    run.dt = dt_;
    run.t_end = steps_ * dt_;
    run.options = variant.options;
    StrainWatch strain(model);
    const RunResult r = simulate(model, run, {&strain});
    const double springs = static_cast<double>(model.scene().get<Springs>().size());
    return row.add(to_string(r.status)).add(r.t_final).add(r.energy_initial)
        .add(r.energy_initial - r.energy_final)
        .add(springs > 0 ? strain.max_strain : std::numeric_limits<double>::quiet_NaN())
        .add(r.stats.steps > 0 ? r.wall_seconds / static_cast<double>(r.stats.steps)
                               : std::numeric_limits<double>::quiet_NaN())
        .add(r.failure).add(warnings_cell(r)).str();
  }

  // The tight implicit Euler trajectory and, at the sampled steps, the true
  // motion over dt.
  void prepare(Case& c) const {
    const Model model(c.scene);
    IntegratorOptions tight;
    tight.newton_tol = reference_tol_;
    tight.max_newton = 1000;
    std::unique_ptr<Integrator> euler = make_integrator("implicit-euler");
    StepResult r = euler->initialize(model, 0.0, model.initial_positions(),
                                     model.initial_velocities(), tight);
    const double w_max = max_angular_frequency(model);
    const int substeps = std::max(1, static_cast<int>(std::ceil(dt_ * w_max / 0.1)));
    for (long k = 0; r.ok && k < steps_; ++k) {
      const Vector x = euler->x(), v = euler->v();
      r = euler->advance_to((k + 1) * dt_);
      if (!r.ok || k % every_ != 0) continue;
      std::unique_ptr<Integrator> rk4 = make_integrator("rk4");
      StepResult rr = rk4->initialize(model, k * dt_, x, v, {});
      for (int j = 1; rr.ok && j <= substeps; ++j) {
        rr = rk4->advance_to(k * dt_ + dt_ * j / substeps);
      }
      if (!rr.ok) {
        c.error = "the true motion (rk4 at dt / " + std::to_string(substeps) + "): " + rr.message;
        return;
      }
      c.samples.push_back({k, x, v, euler->x(), rk4->x()});
    }
    if (!r.ok) c.error = r.message;
  }

  double dt_ = 0.0;
  int steps_ = 0, every_ = 1;
  double reference_tol_ = 1e-9;
  std::vector<std::unique_ptr<Case>> cases_;
  std::vector<Variant> variants_;
};

}  // namespace

std::unique_ptr<Experiment> make_solver_error_experiment(const DefinitionObject& d) {
  return std::make_unique<SolverErrorExperiment>(d);
}

const ExperimentKind& solver_error_experiment_kind() {
  static const ExperimentKind kind{"solver-error", &make_solver_error_experiment};
  return kind;
}

}  // namespace springlab
