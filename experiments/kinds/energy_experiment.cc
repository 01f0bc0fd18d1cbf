// energy: mechanical energy over time for every integrator on the same scene
// and step — explicit growth, symplectic bounded oscillation, implicit
// decay, adaptive flat. One task per (case, integrator).
#include <memory>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "models/model/energy_layout.h"

namespace springlab {
namespace {

// One row per output time: the energies in the table's columns (the union
// over the experiment's scenes; a column this scene lacks is 0).
class EnergyRows final : public Observer {
 public:
  EnergyRows(const Model& model, const EnergyLayout& table, std::string prefix,
             std::vector<std::string>& rows)
      : model_(model), energies_(model.energies(model.initial_positions(),
                                                model.initial_velocities())),
        prefix_(std::move(prefix)), rows_(rows) {
    for (const std::string& column : table.columns) {
      position_.push_back(model.energy_layout().find(column));
    }
  }
  void observe(double t, const Vector& x, const Vector& v) override {
    model_.energies(x, v, energies_);
    Row row;
    row.raw(prefix_).add(t);
    const std::vector<double>& values = energies_.values();
    for (std::size_t p : position_) row.add(p < values.size() ? values[p] : 0.0);
    rows_.push_back(row.str());
  }

 private:
  const Model& model_;
  Energies energies_;
  std::vector<std::size_t> position_;  // of each table column in the model's layout
  std::string prefix_;
  std::vector<std::string>& rows_;
};

class EnergyExperiment final : public TimedCasesExperiment {
 public:
  explicit EnergyExperiment(const DefinitionObject& d) : TimedCasesExperiment(d) {
    std::vector<const Scene*> scenes;
    for (const TimedCase& c : cases()) scenes.push_back(&c.scene);
    energy_columns_ = energy_layout(scenes);
  }

  std::vector<TableSpec> tables() const override {
    std::vector<std::string> columns = {"scene", "integrator", "dt", "t"};
    columns.insert(columns.end(), energy_columns_.columns.begin(), energy_columns_.columns.end());
    return {{"", columns},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps", "force_evals",
                      "wall_seconds", "energy_initial", "energy_final", "energy_scale"}}};
  }

  TaskOutput run_task(std::size_t index) const override {
    const Task t = task(index);
    const Model model(t.c.scene);
    TaskOutput out;
    out.rows.resize(2);
    EnergyRows rows(model, energy_columns_, t.prefix, out.rows[0]);
    const RunResult r = simulate(model, t.run, {&rows});
    Row run;
    run.raw(t.prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(r.stats.force_evals).add(r.wall_seconds).add(r.energy_initial).add(r.energy_final)
        .add(model.energy_scale());
    out.rows[1].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json s = TimedCasesExperiment::settings();
    s["energy_columns"] = energy_columns_.columns;
    return s;
  }

 private:
  EnergyLayout energy_columns_;  // of the table: the union over the cases' scenes
};

}  // namespace

std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject& d) {
  return std::make_unique<EnergyExperiment>(d);
}

const ExperimentKind& energy_experiment_kind() {
  static const ExperimentKind kind{"energy", &make_energy_experiment};
  return kind;
}

}  // namespace springlab
