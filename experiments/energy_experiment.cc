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

class EnergyExperiment final : public TimedCasesExperiment {
 public:
  explicit EnergyExperiment(const DefinitionObject& d) : TimedCasesExperiment(d) {}

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "kinetic", "spring", "gravity", "total"}},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps", "force_evals",
                      "wall_seconds", "energy_initial", "energy_final", "energy_scale"}}};
  }

  TaskOutput run_task(std::size_t index) const override {
    const Task t = task(index);
    const MassSpringModel model(t.c.scene);
    TaskOutput out;
    out.rows.resize(2);
    EnergyRows rows(model, t.prefix, out.rows[0]);
    const RunResult r = simulate(model, t.run, {&rows});
    Row run;
    run.raw(t.prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(r.stats.force_evals).add(r.wall_seconds).add(r.energy_initial).add(r.energy_final)
        .add(model.energy_scale());
    out.rows[1].push_back(run.str());
    return out;
  }
};

}  // namespace

std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject& d) {
  return std::make_unique<EnergyExperiment>(d);
}

}  // namespace springlab
