// energy: mechanical energy over time for every integrator on the same scene
// and step — explicit growth, symplectic bounded oscillation, implicit
// decay, adaptive flat. One task per (case, integrator).
#include <memory>

#include "experiments/experiment.h"
#include "experiments/experiment_support.h"

namespace springlab {
namespace {

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
    cases_ = read_timed_cases(d);
    check_timed_case_rows(d, cases_, integrators_.size());
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "kinetic", "spring", "gravity", "total"}},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps", "force_evals",
                      "wall_seconds", "energy_initial", "energy_final", "energy_scale"}}};
  }

  std::size_t task_count() const override { return cases_.size() * integrators_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const TimedCase& c = cases_[index / integrators_.size()];
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
    run.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(r.stats.force_evals).add(r.wall_seconds).add(r.energy_initial).add(r.energy_final)
        .add(model.energy_scale());
    out.rows[1].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    return {{"integrators", integrators_}, {"cases", timed_cases_json(cases_)}};
  }

 private:
  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  std::vector<TimedCase> cases_;
};

}  // namespace

std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject& d) {
  return std::make_unique<EnergyExperiment>(d);
}

}  // namespace springlab
