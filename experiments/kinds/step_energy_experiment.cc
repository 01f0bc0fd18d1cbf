// step-energy: the energy change of every step next to the number of
// compressed springs, for integrator variants run side by side -- made to
// show why linear-implicit Euler (Baraff-Witkin) gains energy on a folding
// cloth while its definite-stiffness variant (Choi and Ko 2002) and
// implicit Euler do not.
//
// One linearized step solves (M - h^2 K) dv = h (F + h K v) with the
// stiffness K = -dF/dx at the start of the step. A compressed spring's
// sideways stiffness k (1 - L/l) is negative; where it outweighs the mass
// over the step, h^2 k (L/l - 1) > m, the spring alone makes M - h^2 K
// indefinite, and a linear step on a mode of negative stiffness lambda
// multiplies it by 1 / (1 - h^2 lambda / m): growth with alternating sign
// for 1 < h^2 lambda / m < 2, where the nonlinear springs saturate instead.
// Measured on cloth 48 at 1/60 s (the shipped definition): 300-700 such
// springs at every step of both variants; the exact one's energy falls for
// 43 steps, then changes sign from step to step with growing amplitude and
// blows up at t = 0.8 s; the definite one (its matrix at least M) falls all
// the way. On the 16 x 16 cloth at h = 0.1 both gain at the first steps,
// before any spring is compressed (the tangent of a spring at its rest
// length has no sideways stiffness, so the cloth falls freely for a step and
// stretches its springs); only the exact one then blows up.
//
// Each entry of "runs" is an integrator with its options ("stiffness":
// "exact" or "definite"); one task per (case, run).
#include <algorithm>
#include <cmath>
#include <memory>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "integrators/registry/registry.h"
#include "models/springs/springs.h"

namespace springlab {
namespace {

struct RunVariant {
  std::string integrator;
  Stiffness stiffness = Stiffness::kExact;
};

// A row per step: the total energy, its change over the step, the springs
// shorter than their rest length, and those of them whose negative sideways
// stiffness makes the exact step matrix indefinite by itself.
class StepRows final : public Observer {
 public:
  StepRows(const Model& model, double dt, std::string prefix,
           std::vector<std::string>& rows)
      : model_(model), dt_(dt), prefix_(std::move(prefix)), rows_(rows) {}
  void observe(double t, const Vector& x, const Vector& v) override {
    const double total = model_.energies(x, v).total();
    const Eigen::MatrixXd p = model_.scene_positions(x);
    const std::vector<Particle>& particles = model_.scene().particles;
    long compressed = 0, indefinite = 0;
    for (const Spring& s : model_.scene().get<Springs>()) {
      const double l = (p.row(s.i) - p.row(s.j)).norm();
      if (!(s.k > 0.0 && l < s.rest)) continue;
      ++compressed;
      // The spring's negative sideways stiffness over the step outweighs the
      // mass of a free end, h^2 k (L/l - 1) > m: alone it makes the exact
      // step matrix M - h^2 K indefinite.
      const double negative = dt_ * dt_ * s.k * (s.rest / l - 1.0);
      double mass = INFINITY;
      for (int end : {s.i, s.j}) {
        const Particle& q = particles[static_cast<std::size_t>(end)];
        if (!q.fixed) mass = std::min(mass, q.mass);
      }
      if (negative > mass) ++indefinite;
    }
    Row row;
    row.raw(prefix_).add(step_).add(t).add(total);
    if (step_ == 0) {
      row.add_empty();
    } else {
      row.add(total - previous_);
      if (total > previous_) ++gaining_;
    }
    rows_.push_back(row.add(compressed).add(indefinite).str());
    previous_ = total;
    ++step_;
  }
  long gaining_steps() const { return gaining_; }

 private:
  const Model& model_;
  double dt_;
  std::string prefix_;
  std::vector<std::string>& rows_;
  long step_ = 0;
  long gaining_ = 0;
  double previous_ = 0.0;
};

class StepEnergyExperiment final : public Experiment {
 public:
  explicit StepEnergyExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "runs", "rtol", "atol",
                  "newton_tol", "cases"});
    options_ = definition_options(d);
    for (const DefinitionObject& r : d.objects("runs")) {
      r.allow_only({"integrator", "stiffness"});
      RunVariant variant;
      variant.integrator = definition_integrator(r, "integrator");
      if (!parse_stiffness(r.string("stiffness", "exact"), variant.stiffness)) {
        r.fail("stiffness", "expected \"exact\" or \"definite\"");
      }
      runs_.push_back(variant);
    }
    cases_ = read_timed_cases(d);
    for (TimedCase& c : cases_) c.every = 1;  // a row per step
    check_timed_case_rows(d, cases_, runs_.size());
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "stiffness", "dt", "step", "t", "total", "change",
                  "compressed", "indefinite_springs"}},
            {"runs", {"scene", "integrator", "stiffness", "dt", "status", "diverged_at", "steps",
                      "springs", "gaining_steps", "wall_seconds", "energy_initial",
                      "energy_final", "energy_scale"}}};
  }

  std::size_t task_count() const override { return cases_.size() * runs_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const TimedCase& c = cases_[index / runs_.size()];
    const RunVariant& variant = runs_[index % runs_.size()];
    const Model model(c.scene);
    RunSettings s;
    s.integrator = variant.integrator;
    s.dt = c.dt;
    s.t_end = c.t_end;
    s.options = options_;
    s.options.stiffness = variant.stiffness;
    TaskOutput out;
    out.rows.resize(2);
    const std::string prefix = Row()
                                   .add(c.scene.name)
                                   .add(variant.integrator)
                                   .add(to_string(variant.stiffness))
                                   .add(c.dt)
                                   .str();
    StepRows rows(model, c.dt, prefix, out.rows[0]);
    const RunResult r = simulate(model, s, {&rows});
    long springs = 0;
    for (const Spring& spring : c.scene.get<Springs>()) springs += spring.k > 0.0 ? 1 : 0;
    Row run;
    run.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps).add(springs)
        .add(rows.gaining_steps()).add(r.wall_seconds).add(r.energy_initial).add(r.energy_final)
        .add(model.energy_scale());
    out.rows[1].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json runs = nlohmann::json::array();
    nlohmann::json names = nlohmann::json::array();
    for (const RunVariant& v : runs_) {
      runs.push_back({{"integrator", v.integrator}, {"stiffness", to_string(v.stiffness)}});
      names.push_back(v.integrator);
    }
    return {{"integrators", names}, {"runs", runs}, {"cases", timed_cases_json(cases_)}};
  }

 private:
  IntegratorOptions options_;
  std::vector<RunVariant> runs_;
  std::vector<TimedCase> cases_;
};

}  // namespace

std::unique_ptr<Experiment> make_step_energy_experiment(const DefinitionObject& d) {
  return std::make_unique<StepEnergyExperiment>(d);
}

const ExperimentKind& step_energy_experiment_kind() {
  static const ExperimentKind kind{"step-energy", &make_step_energy_experiment};
  return kind;
}

}  // namespace springlab
