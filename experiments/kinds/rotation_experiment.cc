// rotation: linear elasticity's failure under large rotation, against the
// rotation-invariant models (docs/physics.md "Finite elements"). Every registered
// material model runs every scenario of one built-in scene with a `model`
// parameter (the shipped definition: the block, without gravity):
//   - spinning: the rigid velocity field v = w x X. Linear elasticity
//     measures strain by eps = (F + F^T)/2 - I, which an infinitesimal
//     rotation F = I + t [w]x does not change; so the linear block feels no
//     force, every particle keeps its velocity in a straight line, and the
//     block swells at no energy: its radius of gyration about the centre of
//     mass grows as sqrt((r_h^2 (1 + (w t)^2) + r_v^2) / (r_h^2 + r_v^2))
//     (r_h, r_v: its horizontal and vertical parts at rest). A
//     rotation-invariant model keeps it near 1 (the centrifugal stretch);
//   - turned: the starting pose rotated by theta from the rest shape, at
//     rest. A rotation-invariant model sees no strain and stays put; the
//     linear one stores the ghost energy V 2 (mu + lambda) (1 - cos theta)^2
//     (a rotation about one axis: eps = (cos theta - 1) on the two axes it
//     turns) and its ghost forces set it vibrating.
// One task per (scenario, model, integrator); a row per output with the
// kinetic and elastic energy and the radius of gyration relative to its
// starting value.
#include <cmath>
#include <memory>
#include <string>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "models/materials/material.h"
#include "models/model/energy_layout.h"

namespace springlab {
namespace {

// The radius of gyration about the centre of mass, sqrt(sum m |x - c|^2 / sum m).
double gyration_radius(const Eigen::MatrixXd& positions, const std::vector<Particle>& particles) {
  Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(positions.cols());
  double mass = 0.0;
  for (Eigen::Index i = 0; i < positions.rows(); ++i) {
    const double m = particles[static_cast<std::size_t>(i)].mass;
    c += m * positions.row(i);
    mass += m;
  }
  c /= mass;
  double sum = 0.0;
  for (Eigen::Index i = 0; i < positions.rows(); ++i) {
    sum += particles[static_cast<std::size_t>(i)].mass * (positions.row(i) - c).squaredNorm();
  }
  return std::sqrt(sum / mass);
}

class RotationRows final : public Observer {
 public:
  RotationRows(const Model& model, std::string prefix, std::vector<std::string>& rows)
      : model_(model), energies_(model.energies(model.initial_positions(),
                                                model.initial_velocities())),
        kinetic_(model.energy_layout().find("kinetic")),
        elastic_(model.energy_layout().find("elastic")),
        r0_(gyration_radius(model.scene_positions(model.initial_positions()),
                            model.scene().particles)),
        prefix_(std::move(prefix)), rows_(rows) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    model_.energies(x, v, energies_);
    const std::vector<double>& e = energies_.values();
    const double elastic = elastic_ < e.size() ? e[elastic_] : 0.0;
    const double gyration =
        gyration_radius(model_.scene_positions(x), model_.scene().particles) / r0_;
    rows_.push_back(Row().raw(prefix_).add(t).add(e[kinetic_]).add(elastic).add(gyration).str());
    elastic_max = std::max(elastic_max, elastic);
    gyration_max = std::max(gyration_max, gyration);
    gyration_last = gyration;
  }

  double elastic_max = 0.0, gyration_max = 0.0, gyration_last = 1.0;

 private:
  const Model& model_;
  Energies energies_;
  std::size_t kinetic_, elastic_;  // positions in the model's energy layout
  double r0_;
  std::string prefix_;
  std::vector<std::string>& rows_;
};

struct Scenario {
  std::string title;
  std::vector<Scene> scenes;  // one per material model, in registry order
};

class RotationExperiment final : public Experiment {
 public:
  explicit RotationExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "scene", "parameters", "scenarios", "dt", "t_end", "every"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "all");
    dt_ = d.positive("dt");
    t_end_ = d.positive("t_end");
    every_ = d.count("every", 1, 1, 1000000);
    check_time_grid(d, "dt", dt_, t_end_);
    SceneTotals totals;
    for (const DefinitionObject& s : d.objects("scenarios")) {
      s.allow_only({"title", "parameters"});
      Scenario scenario;
      scenario.title = s.string("title");
      for (std::size_t m = 0; m < material_models().size(); ++m) {
        auto overrides = s.has("parameters") ? definition_parameters(s)
                                             : std::vector<std::pair<std::string, std::string>>{};
        overrides.emplace_back("model", std::to_string(m));
        scenario.scenes.push_back(definition_scene(d, overrides));
        totals.add(s, "parameters", scenario.scenes.back());
      }
      scenarios_.push_back(std::move(scenario));
    }
    const double steps = static_cast<double>(make_time_grid(dt_, t_end_).steps);
    check_task_count(d, "scenarios", static_cast<double>(task_count()));
    check_output_rows(d, "scenarios",
                      static_cast<double>(task_count()) * (std::floor(steps / every_) + 3.0));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scenario", "scene", "model", "integrator", "dt", "t", "kinetic", "elastic",
                  "gyration"}},
            {"runs", {"scenario", "scene", "model", "integrator", "dt", "status", "diverged_at",
                      "kinetic_initial", "elastic_initial", "elastic_max", "gyration_max",
                      "gyration_final", "steps", "wall_seconds", "failure", "warnings"}}};
  }

  std::size_t task_count() const override {
    return scenarios_.size() * material_models().size() * integrators_.size();
  }

  TaskOutput run_task(std::size_t index) const override {
    const std::size_t models = material_models().size();
    const std::size_t s = index / (models * integrators_.size());
    const std::size_t m = index / integrators_.size() % models;
    const std::string& name = integrators_[index % integrators_.size()];
    const Scene& scene = scenarios_[s].scenes[m];
    const Model model(scene);
    RunSettings run;
    run.integrator = name;
    run.dt = dt_;
    run.t_end = t_end_;
    run.every = every_;
    run.options = options_;
    const std::string prefix = Row().add(static_cast<long>(s)).add(scene.name)
                                   .add(std::string(material_models()[m]->name)).add(name)
                                   .add(dt_).str();
    TaskOutput out;
    out.rows.resize(2);
    RotationRows rows(model, prefix, out.rows[0]);
    const Energies e0 = model.energies(model.initial_positions(), model.initial_velocities());
    const RunResult r = simulate(model, run, {&rows});
    const std::size_t elastic = model.energy_layout().find("elastic");
    Row row;
    row.raw(prefix).add(to_string(r.status)).add(r.diverged_at)
        .add(e0.values()[model.energy_layout().find("kinetic")])
        .add(elastic < e0.values().size() ? e0.values()[elastic] : 0.0).add(rows.elastic_max)
        .add(rows.gyration_max).add(rows.gyration_last).add(r.stats.steps).add(r.wall_seconds)
        .add(r.failure).add(warnings_cell(r));
    out.rows[1].push_back(row.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json scenarios = nlohmann::json::array();
    for (const Scenario& s : scenarios_) {
      nlohmann::json scenes = nlohmann::json::array();
      for (const Scene& scene : s.scenes) scenes.push_back(scene_as_json(scene));
      scenarios.push_back({{"title", s.title}, {"scenes", scenes}});
    }
    std::vector<std::string> models;
    for (const MaterialModel* m : material_models()) models.emplace_back(m->name);
    return {{"integrators", integrators_}, {"models", models}, {"scenarios", scenarios},
            {"dt", dt_},  {"t_end", t_end_}, {"every", every_}};
  }

 private:
  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  std::vector<Scenario> scenarios_;
  double dt_ = 0.0, t_end_ = 0.0;
  int every_ = 1;
};

}  // namespace

std::unique_ptr<Experiment> make_rotation_experiment(const DefinitionObject& d) {
  return std::make_unique<RotationExperiment>(d);
}

const ExperimentKind& rotation_experiment_kind() {
  static const ExperimentKind kind{"rotation", &make_rotation_experiment};
  return kind;
}

}  // namespace springlab
