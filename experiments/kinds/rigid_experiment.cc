// rigid: the tumbling box (an affine body, docs/physics.md "Rigid bodies
// (affine bodies)") under a set of integrators, against the exact rigid body
// (rigid_reference.h), and the affine body's convergence to it as the
// rigidity kappa grows. Three kinds of task:
//   - one per integrator: the box at the definition's dt to t_end; a row per
//     output with the energy E / E_0, the angular momentum's relative drift
//     |L - L_0| / |L_0| (about the centre of mass), the distance of A from a
//     rotation |A^T A - I|_F, the cosine between the body's middle principal
//     axis a_m and L (the reference's beside it) and |A - R_ref|_F; and a
//     summary row with the flip period measured on the run: the mean time
//     between successive reversals of the spin axis, i.e. sign changes of
//     a_m . L (for the rigid body I_m w_m, the component of the angular
//     momentum along the middle axis), each located by linear interpolation
//     between two steps;
//   - one per kappa: `kappa_integrator` at the small step `kappa_dt` to
//     `kappa_t_end`: the largest |A - R_ref|_F, the largest strain and the
//     flip period's error against the reference's;
//   - one per case of the optional "pile" (a scene of bodies meeting
//     bodies, box-pile by default, under an integrator at a step, as the
//     definition lists them): a row every `sample` seconds with the top body's
//     height (its centre's y: the scene's last body), the energy, kinetic
//     energy and the smallest gap between two bodies' surfaces, and a
//     summary row (status, Newton iterations per step, the final height
//     and energy, the smallest gap over the run);
//   - one per (kappa, limit integrator): the largest stable step
//     (find_max_stable_dt, stability.h) beside the theory: the rigidity's
//     fastest mode. Around A = I, E = kappa V |A^T A - I|^2 is
//     4 kappa V |sym dA|^2, so stretching a_i alone (mass J_i) has stiffness
//     8 kappa V and the shear pairs of a_i, a_j have
//     w^2 = 4 kappa V (1 / J_i + 1 / J_j), never more: the fastest is
//     w_kappa = sqrt(8 kappa V / min J_i), and a method with a stability
//     interval w h <= c (verlet: c = 2) has h < c / w_kappa.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/output_files.h"
#include "experiments/analysis/rigid_reference.h"
#include "experiments/analysis/stability.h"
#include "models/bodies/bodies.h"
#include "models/model/modal_analysis.h"
#include "models/model/energy_layout.h"
#include "models/bodies/body_contacts.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab {
namespace {

// What the tasks need of the scene's first body.
struct BoxFacts {
  RigidBody body;
  int first = 0;
  Eigen::Vector3d I;  // principal moments I_i = sum J - J_i
  int middle = 1;
  Eigen::Vector3d w_body;  // body-frame angular velocity at t = 0
};

BoxFacts box_facts(const Model& model) {
  const BodyLayout layout = body_layout(model.scene(), model.particle_order());
  BoxFacts f;
  f.body = layout.bodies.at(0);
  f.first = layout.first.at(0);
  const Eigen::Vector3d& J = f.body.mass.J;
  f.I = Eigen::Vector3d::Constant(J.sum()) - J;
  f.middle = middle_axis(f.I);
  // dA/dt = [omega]x A, A a rotation: omega_body = A^T omega.
  const Eigen::Matrix3d W = f.body.Adot0 * f.body.A0.transpose();
  f.w_body = f.body.A0.transpose() * Eigen::Vector3d(W(2, 1), W(0, 2), W(1, 0));
  return f;
}

// The fastest rigidity mode at A = I (the header's derivation).
double rigidity_frequency(const RigidBody& b) {
  return std::sqrt(8.0 * b.rigidity * b.mass.volume / b.mass.J.minCoeff());
}

// Watches a run at every step; writes a row every `every`-th step (and at
// t_end) when `rows` is set.
class RigidWatch final : public Observer {
 public:
  RigidWatch(const Model& model, const BoxFacts& f, double reference_step, double t_end,
             int every, std::string prefix, std::vector<std::string>* rows)
      : model_(model), f_(f),
        reference_(f.I, f.w_body, f.body.A0, reference_step, f.middle),
        energies_(model.energies(model.initial_positions(), model.initial_velocities())),
        rigidity_(model.energy_layout().find("rigidity")), t_end_(t_end), every_(every),
        prefix_(std::move(prefix)), rows_(rows) {
    E0_ = energies_.total();
    L0_ = state(model.initial_positions(), model.initial_velocities()).angular_momentum_about_centre;
  }

  BodyState state(const Vector& x, const Vector& v) const {
    return body_state(f_.body, f_.first, x.data(), v.data());
  }

  void observe(double t, const Vector& x, const Vector& v) override {
    // The sweep's stop request reaches the reference too (it can take far
    // more steps than the run it watches).
    if (!reference_.advance_to(t, thread_stop_request())) throw StopRequested();
    const BodyState s = state(x, v);
    model_.energies(x, v, energies_);
    const double E = energies_.total();
    const Eigen::Vector3d& L = s.angular_momentum_about_centre;
    const double drift_L = (L - L0_).norm() / L0_.norm();
    const double drift_E = std::abs(E - E0_) / E0_;
    const double strain = (s.A.transpose() * s.A - Eigen::Matrix3d::Identity()).norm();
    const Eigen::Matrix3d R = reference_.rotation();
    const double error = (s.A - R).norm();
    const Eigen::Vector3d axis = s.A.col(f_.middle);
    const double along = axis.dot(L);
    const double cosine = along / (axis.norm() * L.norm());
    if (calls_ > 0 && ((previous_ > 0.0 && along <= 0.0) || (previous_ < 0.0 && along >= 0.0))) {
      reversals.push_back(t_previous_ + (t - t_previous_) * previous_ / (previous_ - along));
    }
    previous_ = along;
    t_previous_ = t;
    energy_drift_max = std::max(energy_drift_max, drift_E);
    momentum_drift_max = std::max(momentum_drift_max, drift_L);
    strain_max = std::max(strain_max, strain);
    error_max = std::max(error_max, error);
    energy_last = E / E0_;
    if (rows_ != nullptr && (calls_ % every_ == 0 || t == t_end_)) {
      const Eigen::Vector3d Lr = reference_.angular_momentum();
      const double cosine_ref = R.col(f_.middle).dot(Lr) / Lr.norm();
      const double rigidity = rigidity_ < energies_.values().size() ? energies_.values()[rigidity_]
                                                                     : 0.0;
      rows_->push_back(Row().raw(prefix_).add(t).add(E / E0_).add(energies_.kinetic())
                           .add(rigidity).add(drift_L).add(strain).add(cosine).add(cosine_ref)
                           .add(error).str());
    }
    ++calls_;
  }

  // The reference to t_end (its reversals over the whole run).
  const RigidReference& reference_to(double t) {
    if (!reference_.advance_to(std::max(t, reference_.time()), thread_stop_request())) {
      throw StopRequested();
    }
    return reference_;
  }

  double energy_drift_max = 0.0, momentum_drift_max = 0.0, strain_max = 0.0, error_max = 0.0;
  double energy_last = 1.0;
  std::vector<double> reversals;

 private:
  const Model& model_;
  const BoxFacts& f_;
  RigidReference reference_;
  Energies energies_;
  std::size_t rigidity_;
  double t_end_;
  int every_;
  std::string prefix_;
  std::vector<std::string>* rows_;
  double E0_ = 0.0;
  Eigen::Vector3d L0_;
  long calls_ = 0;
  double previous_ = 0.0, t_previous_ = 0.0;
};

std::optional<double> period_of(const std::vector<double>& reversals) {
  if (reversals.size() < 2) return std::nullopt;
  return flip_period(reversals);
}
std::optional<double> first_of(const std::vector<double>& reversals) {
  if (reversals.empty()) return std::nullopt;
  return reversals.front();
}
std::optional<double> error_of(const std::optional<double>& period,
                               const std::optional<double>& reference) {
  if (!period || !reference) return std::nullopt;
  return (*period - *reference) / *reference;
}

// Watches a run of the pile at every step: the top body's height, the
// energy and the smallest gap between bodies (within 0.1 m), with a row
// at every state at least `sample` seconds after the last row's (and at
// t_end).
class PileWatch final : public Observer {
 public:
  PileWatch(const Model& model, double t_end, double sample, std::string prefix,
            std::vector<std::string>& rows)
      : model_(model), layout_(body_layout(model.scene(), model.particle_order())),
        finder_(model.scene(), layout_),
        energies_(model.energies(model.initial_positions(), model.initial_velocities())),
        t_end_(t_end), sample_(sample), prefix_(std::move(prefix)), rows_(rows) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    // (The bodies' unknowns are in x, after the free particles.)
    finder_.place(x.data());
    std::vector<BodyContact> contacts;
    finder_.all_contacts(0.1, contacts);
    double gap = INFINITY;
    for (const BodyContact& k : contacts) gap = std::min(gap, k.d);
    smallest_gap = std::min(smallest_gap, gap);
    const std::size_t top = layout_.bodies.size() - 1;
    top_height = body_state(layout_.bodies[top], layout_.first[top], x.data(), v.data()).p.y();
    model_.energies(x, v, energies_);
    energy = energies_.total();
    if (t >= next_ || t == t_end_) {
      next_ = t + sample_ * (1.0 - 1e-9);
      Row row;
      row.raw(prefix_).add(t).add(top_height).add(energy).add(energies_.kinetic());
      if (std::isfinite(gap)) {
        row.add(gap);
      } else {
        row.add_empty();
      }
      rows_.push_back(row.str());
    }
  }

  double smallest_gap = INFINITY, top_height = 0.0, energy = 0.0;

 private:
  const Model& model_;
  BodyLayout layout_;
  BodyContactFinder finder_;
  Energies energies_;
  double t_end_, sample_, next_ = 0.0;
  std::string prefix_;
  std::vector<std::string>& rows_;
};

class RigidExperiment final : public Experiment {
 public:
  explicit RigidExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "scene", "parameters", "dt", "t_end", "every", "reference_step",
                  "kappa", "kappa_integrator", "kappa_dt", "kappa_t_end", "limit_integrators",
                  "limit_periods", "limit_rel_tol", "pile"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "fixed-step");
    dt_ = d.positive("dt");
    t_end_ = d.positive("t_end");
    every_ = d.count("every", 1, 1, 1000000);
    check_time_grid(d, "dt", dt_, t_end_);
    reference_step_ = d.positive("reference_step", 1e-5);
    if (reference_step_ > dt_) d.fail("reference_step", "must not exceed dt");
    check_reference_steps(d, t_end_, "t_end");
    scene_ = definition_scene(d);
    const auto& bodies = scene_.get<Bodies>();
    if (bodies.empty() || bodies.front().fixed) {
      d.fail("scene", "needs a free body (the first body is compared with the rigid body)");
    }
    if (d.has("kappa")) {
      kappa_ = d.positives("kappa");
      for (double k : kappa_) {
        kappa_scenes_.push_back(definition_scene(d, {{"rigidity", format_number(k)}}));
      }
      kappa_integrator_ = d.has("kappa_integrator") ? definition_integrator(d, "kappa_integrator")
                                                    : std::string("rk4");
      kappa_dt_ = d.positive("kappa_dt", dt_);
      kappa_t_end_ = d.positive("kappa_t_end", t_end_);
      check_time_grid(d, "kappa_dt", kappa_dt_, kappa_t_end_);
      if (reference_step_ > kappa_dt_) d.fail("reference_step", "must not exceed kappa_dt");
      check_reference_steps(d, kappa_t_end_, "kappa_t_end");
      if (d.has("limit_integrators")) {
        limit_integrators_ = definition_integrators(d, "limit_integrators", "");
      }
      limit_periods_ = d.positive("limit_periods", 100.0);
      // A search runs limit_periods periods of the rigidity mode at its
      // smallest step 1e-2 / w: 200 pi steps a period (run_limit).
      if (!(limit_periods_ * 200.0 * std::numbers::pi <= 1e9)) {
        d.fail("limit_periods", "a search's run at its smallest step (1e-2 / w) would take " +
                                    format_count(limit_periods_ * 200.0 * std::numbers::pi) +
                                    " steps (200 pi a period), over the cap of 1e9 per run");
      }
      limit_rel_tol_ = d.positive("limit_rel_tol", 1e-2);
    }
    if (d.has("pile")) read_pile(d.object("pile"));
    const double steps = static_cast<double>(make_time_grid(dt_, t_end_).steps);
    check_task_count(d, "integrators", static_cast<double>(task_count()));
    check_output_rows(d, "integrators",
                      static_cast<double>(integrators_.size()) * (std::floor(steps / every_) + 3.0));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"integrator", "dt", "t", "energy", "kinetic", "rigidity", "momentum_drift",
                  "strain", "axis", "axis_reference", "orientation_error"}},
            {"runs", {"integrator", "dt", "status", "diverged_at", "energy_final",
                      "energy_drift_max", "momentum_drift_max", "strain_max",
                      "orientation_error_max", "reversals", "first_reversal", "flip_period",
                      "reference_first_reversal", "reference_flip_period", "period_error",
                      "steps", "wall_seconds", "failure", "warnings"}},
            {"kappa", {"kappa", "integrator", "dt", "t_end", "status", "strain_max",
                       "orientation_error_max", "energy_drift_max", "momentum_drift_max",
                       "flip_period", "reference_flip_period", "period_error"}},
            {"limits", {"kappa", "integrator", "w_formula", "w_max", "dt_theory",
                        "dt_max_stable", "lo", "hi", "ratio", "outcome"}},
            {"pile", {"integrator", "dt", "t", "top_height", "energy", "kinetic",
                      "smallest_gap"}},
            {"pile_runs", {"integrator", "dt", "status", "diverged_at", "steps",
                           "newton_per_step", "top_height_final", "energy_initial",
                           "energy_final", "smallest_gap", "wall_seconds", "failure"}}};
  }

  std::size_t task_count() const override {
    return integrators_.size() + kappa_.size() * (1 + limit_integrators_.size()) +
           pile_cases_.size();
  }

  TaskOutput run_task(std::size_t index) const override {
    TaskOutput out;
    out.rows.resize(6);
    const std::size_t rigid_tasks = task_count() - pile_cases_.size();
    if (index >= rigid_tasks) {
      run_pile(pile_cases_[index - rigid_tasks], out);
    } else if (index < integrators_.size()) {
      run_main(integrators_[index], out);
    } else if (index < integrators_.size() + kappa_.size()) {
      run_kappa(index - integrators_.size(), out);
    } else {
      const std::size_t k = index - integrators_.size() - kappa_.size();
      run_limit(k / limit_integrators_.size(), limit_integrators_[k % limit_integrators_.size()],
                out);
    }
    return out;
  }

  nlohmann::json settings() const override {
    const Model model(scene_);
    const BoxFacts f = box_facts(model);
    const RigidBody& b = f.body;
    return {{"integrators", integrators_}, {"dt", dt_}, {"t_end", t_end_}, {"every", every_},
            {"reference_step", reference_step_}, {"scene", scene_as_json(scene_)},
            {"body", {{"mass", b.mass.mass}, {"volume", b.mass.volume},
                      {"J", {b.mass.J[0], b.mass.J[1], b.mass.J[2]}},
                      {"I", {f.I[0], f.I[1], f.I[2]}}, {"middle_axis", f.middle},
                      {"rigidity", b.rigidity}, {"w_rigidity", rigidity_frequency(b)},
                      {"omega_body", {f.w_body[0], f.w_body[1], f.w_body[2]}}}},
            {"kappa", kappa_}, {"kappa_integrator", kappa_integrator_}, {"kappa_dt", kappa_dt_},
            {"kappa_t_end", kappa_t_end_}, {"limit_integrators", limit_integrators_},
            {"limit_periods", limit_periods_}, {"limit_rel_tol", limit_rel_tol_},
            {"pile", pile_json()}};
  }

 private:
  RunSettings settings_for(const std::string& name, double dt, double t_end) const {
    RunSettings run;
    run.integrator = name;
    run.dt = dt;
    run.t_end = t_end;
    run.every = 1;  // the watch sees every step and writes every every_-th
    run.options = options_;
    return run;
  }

  void run_main(const std::string& name, TaskOutput& out) const {
    const Model model(scene_);
    const BoxFacts f = box_facts(model);
    const std::string prefix = Row().add(name).add(dt_).str();
    RigidWatch watch(model, f, reference_step_, t_end_, every_, prefix, &out.rows[0]);
    const RunResult r = simulate(model, settings_for(name, dt_, t_end_), {&watch});
    const RigidReference& ref = watch.reference_to(t_end_);
    const std::optional<double> period = period_of(watch.reversals);
    const std::optional<double> ref_period = period_of(ref.reversals());
    Row row;
    row.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(watch.energy_last)
        .add(watch.energy_drift_max).add(watch.momentum_drift_max).add(watch.strain_max)
        .add(watch.error_max).add(static_cast<long>(watch.reversals.size()))
        .add(first_of(watch.reversals)).add(period).add(first_of(ref.reversals()))
        .add(ref_period).add(error_of(period, ref_period)).add(r.stats.steps)
        .add(r.wall_seconds).add(r.failure).add(warnings_cell(r));
    out.rows[1].push_back(row.str());
  }

  void run_kappa(std::size_t k, TaskOutput& out) const {
    const Model model(kappa_scenes_[k]);
    const BoxFacts f = box_facts(model);
    RigidWatch watch(model, f, reference_step_, kappa_t_end_, 1, "", nullptr);
    const RunResult r = simulate(model, settings_for(kappa_integrator_, kappa_dt_, kappa_t_end_),
                                 {&watch});
    const RigidReference& ref = watch.reference_to(kappa_t_end_);
    const std::optional<double> period = period_of(watch.reversals);
    const std::optional<double> ref_period = period_of(ref.reversals());
    Row row;
    row.add(kappa_[k]).add(kappa_integrator_).add(kappa_dt_).add(kappa_t_end_)
        .add(to_string(r.status)).add(watch.strain_max).add(watch.error_max)
        .add(watch.energy_drift_max).add(watch.momentum_drift_max).add(period).add(ref_period)
        .add(error_of(period, ref_period));
    out.rows[2].push_back(row.str());
  }

  void run_limit(std::size_t k, const std::string& name, TaskOutput& out) const {
    const Model model(kappa_scenes_[k]);
    const BoxFacts f = box_facts(model);
    const double w_formula = rigidity_frequency(f.body);
    const double w = max_angular_frequency(model);
    StabilitySettings s;
    s.run.integrator = name;
    s.run.t_end = limit_periods_ * 2.0 * std::numbers::pi / w;
    s.run.options = options_;
    s.dt_min = 1e-2 / w;
    s.dt_max = 1e2 / w;
    s.rel_tol = limit_rel_tol_;
    const StabilityResult r = find_max_stable_dt(model, s);
    const char* outcome = r.outcome == StabilityOutcome::kBracketed ? "bracketed"
                          : r.outcome == StabilityOutcome::kStableUpToDtMax ? "stable-up-to-dt-max"
                                                                             : "unstable-at-dt-min";
    Row row;
    row.add(kappa_[k]).add(name).add(w_formula).add(w).add(r.theory.dt).add(r.max_stable_dt)
        .add(r.lo).add(r.hi);
    if (r.theory.dt && *r.theory.dt > 0.0) {
      row.add(r.max_stable_dt / *r.theory.dt);
    } else {
      row.add_empty();
    }
    out.rows[3].push_back(row.add(outcome).str());
  }

  // The pile: {"scene", "parameters", "cases": [{"integrator", "dt"}, ...],
  // "t_end", "sample"}.
  struct PileCase {
    std::string integrator;
    double dt = 0.0;
  };
  void read_pile(const DefinitionObject& p) {
    p.allow_only({"scene", "parameters", "cases", "t_end", "sample"});
    pile_scene_ = definition_scene(p);
    if (pile_scene_.get<Bodies>().size() < 2) p.fail("scene", "needs two bodies or more");
    pile_t_end_ = p.positive("t_end");
    pile_sample_ = p.positive("sample", 0.02);
    for (const DefinitionObject& c : p.objects("cases")) {
      c.allow_only({"integrator", "dt"});
      PileCase pc{definition_integrator(c, "integrator"), c.positive("dt")};
      check_time_grid(c, "dt", pc.dt, pile_t_end_);
      pile_cases_.push_back(pc);
    }
  }
  nlohmann::json pile_json() const {
    if (pile_cases_.empty()) return nullptr;
    nlohmann::json cases = nlohmann::json::array();
    for (const PileCase& c : pile_cases_) cases.push_back({{"integrator", c.integrator}, {"dt", c.dt}});
    return {{"scene", scene_as_json(pile_scene_)}, {"t_end", pile_t_end_},
            {"sample", pile_sample_}, {"cases", cases},
            {"bodies", pile_scene_.get<Bodies>().size()}};
  }
  void run_pile(const PileCase& c, TaskOutput& out) const {
    const Model model(pile_scene_);
    const std::string prefix = Row().add(c.integrator).add(c.dt).str();
    PileWatch watch(model, pile_t_end_, pile_sample_, prefix, out.rows[4]);
    const RunResult r = simulate(model, settings_for(c.integrator, c.dt, pile_t_end_), {&watch});
    const double steps = static_cast<double>(r.stats.steps);
    Row row;
    row.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(steps > 0.0 ? static_cast<double>(r.stats.newton_iterations) / steps : 0.0)
        .add(watch.top_height).add(r.energy_initial).add(watch.energy);
    if (std::isfinite(watch.smallest_gap)) {
      row.add(watch.smallest_gap);
    } else {
      row.add_empty();
    }
    out.rows[5].push_back(row.add(r.wall_seconds).add(r.failure).str());
  }

  // The reference's steps to `t_end` (each run's watch advances its own
  // reference that far): over the cap of steps per run, refused at load.
  void check_reference_steps(const DefinitionObject& d, double t_end, const char* over) const {
    const double steps = t_end / reference_step_;
    if (!(steps <= 1e9)) {
      d.fail("reference_step", format_number(reference_step_) + " s would take the reference " +
                                   format_count(steps) + " steps to " + over + " = " +
                                   format_number(t_end) + " s, over the cap of 1e9 per run");
    }
  }

  IntegratorOptions options_;
  std::vector<std::string> integrators_, limit_integrators_;
  Scene pile_scene_;
  std::vector<PileCase> pile_cases_;
  double pile_t_end_ = 0.0;
  double pile_sample_ = 0.02;
  double dt_ = 0.0, t_end_ = 0.0, reference_step_ = 1e-5;
  int every_ = 1;
  Scene scene_;
  std::vector<double> kappa_;
  std::vector<Scene> kappa_scenes_;
  std::string kappa_integrator_ = "rk4";
  double kappa_dt_ = 0.0, kappa_t_end_ = 0.0, limit_periods_ = 100.0, limit_rel_tol_ = 1e-2;
};

}  // namespace

std::unique_ptr<Experiment> make_rigid_experiment(const DefinitionObject& d) {
  return std::make_unique<RigidExperiment>(d);
}

const ExperimentKind& rigid_experiment_kind() {
  static const ExperimentKind kind{"rigid", &make_rigid_experiment};
  return kind;
}

}  // namespace springlab
