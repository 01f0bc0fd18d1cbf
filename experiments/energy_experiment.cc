// energy: mechanical energy over time for every integrator on the same scene
// and step — explicit growth, symplectic bounded oscillation, implicit
// decay, adaptive flat. One task per (case, integrator).
#include <memory>

#include "experiments/experiment.h"
#include "experiments/experiment_support.h"

namespace springlab {
namespace {

struct EnergyCase {
  Scene scene;
  double dt, t_end;
  int every;
};

class EnergyRows final : public Observer {
 public:
  EnergyRows(const MassSpringModel& model, std::string prefix, std::vector<std::string>& rows)
      : model_(model), prefix_(std::move(prefix)), rows_(rows) {}
  void observe(double t, const Vector& x, const Vector& v) override {
    const Energies e = model_.energies(x, v);
    rows_.push_back(Row().raw(prefix_).add(t).add(e.kinetic).add(e.spring).add(e.gravity)
                        .add(e.total()).str());
  }

 private:
  const MassSpringModel& model_;
  std::string prefix_;
  std::vector<std::string>& rows_;
};

class EnergyExperiment final : public Experiment {
 public:
  explicit EnergyExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "cases"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "all");
    for (const DefinitionObject& c : d.objects("cases")) {
      c.allow_only({"scene", "parameters", "dt", "t_end", "every"});
      cases_.push_back({definition_scene(c), c.positive("dt"), c.positive("t_end"),
                        c.count("every", 1, 1, 1000000)});
      check_time_grid(c, "dt", cases_.back().dt, cases_.back().t_end);
    }
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "kinetic", "spring", "gravity", "total"}},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps", "force_evals",
                      "wall_seconds", "energy_initial", "energy_final", "energy_scale"}}};
  }

  std::size_t task_count() const override { return cases_.size() * integrators_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const EnergyCase& c = cases_[index / integrators_.size()];
    const std::string& name = integrators_[index % integrators_.size()];
    const MassSpringModel model(c.scene);
    RunSettings s;
    s.integrator = name;
    s.dt = c.dt;
    s.t_end = c.t_end;
    s.every = c.every;
    s.options = options_;
    TaskOutput out;
    out.rows.resize(2);
    const std::string prefix = Row().add(c.scene.name).add(name).add(c.dt).str();
    EnergyRows rows(model, prefix, out.rows[0]);
    const RunResult r = simulate(model, s, {&rows});
    Row run;
    run.raw(prefix).add(to_string(r.status));
    if (r.diverged_at) {
      run.add(*r.diverged_at);
    } else {
      run.add_empty();
    }
    run.add(r.stats.steps).add(r.stats.force_evals).add(r.wall_seconds).add(r.energy_initial)
        .add(r.energy_final).add(model.energy_scale());
    out.rows[1].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json scenes = nlohmann::json::array();
    for (const EnergyCase& c : cases_) {
      scenes.push_back({{"scene", scene_as_json(c.scene)}, {"dt", c.dt}, {"t_end", c.t_end}});
    }
    return {{"integrators", integrators_}, {"cases", scenes}};
  }

 private:
  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  std::vector<EnergyCase> cases_;
};

}  // namespace

std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject& d) {
  return std::make_unique<EnergyExperiment>(d);
}

}  // namespace springlab
