// fluid: the dam break (docs/scenes.md "dam-break", docs/physics.md "Fluids
// (SPH)") under a list of integrators, beside Martin and Moyce's (1952)
// measured surge front, and the explicit step limit against the speed of
// sound. Two kinds of task:
//   - one per run {"integrator", "dt", "substeps", "iterations"}: the
//     column of width a released at t = 0, observed at every step. A row
//     every `sample` seconds (and at the end): T = t sqrt(2 g / a), the
//     front Z = z / a (z: the water's largest x plus half a spacing, the
//     wall behind the column at x = 0), the energies (kinetic, gravity, the
//     equation of state's pressure energy, their total), the viscous work
//     W_v = -int F_visc . v dt (trapezoid rule on every step), and what is
//     left, the numerical part E(t) + W_v(t) - E(0): for an exact solution
//     the total falls by exactly the viscous work (as in the damping-budget
//     experiment). A summary row per run: Z at T = 2 against the measured
//     front there, the fastest front (between samples) against Ritter's
//     dry-bed bound 2 sqrt(g H), H = 2a (in these variables Z <= 1 + 2 T),
//     the largest compression rho / rho0 - 1, and the cost: CPU seconds of
//     the run's thread per simulated second, the observer's own work (the
//     viscous power at every step, the rows) left out;
//   - one per (sound, limit integrator): the largest stable step
//     (find_max_stable_dt, stability.h) of the dam break with c = sound
//     sqrt(g H), beside two theories: the acoustic mode at rest, 2 / w_max
//     (w_max of the linearization with the equation of state's stiffness
//     c^2 at rho0: the scene's rho0 is lowered by 1e-9 so that the water at
//     rest is on that side of the Tait law's kink, a change of one part in
//     1e9 in its pressures), and the CFL form h_t <= C h / (c + |v|max)
//     (Monaghan 1994): C = h_t (c + |v|max) / h from the largest stable
//     step and the largest particle speed of a run at 0.25 h / c over
//     `t_end` (the flow's own speed: near the limit, a trial that stays
//     under the divergence rule can still throw a few particles).
// The measured points are read from the CSV file `reference` (next to the
// definition; '#' lines are its source) into the "reference" table. An
// optional "gauges" part adds a 3-D run's water heights at fixed points
// against a measurement (MARIN's dam break onto a box, SPHERIC test 2:
// fluid_gauges.h), as the last task.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "experiments/analysis/stability.h"
#include "experiments/io/output_files.h"
#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/kinds/fluid_gauges.h"
#include "experiments/kinds/fluid_measures.h"
#include "experiments/kinds/reference_file.h"
#include "models/fluids/fluids.h"
#include "models/model/energy_layout.h"
#include "models/springs/gravity.h"

namespace springlab {
namespace {

struct Reference {
  std::vector<double> T, Z;
  std::string source;  // the file's '#' lines, joined
  std::string file;
};

Reference read_reference(const DefinitionObject& d) {
  const ReferenceLines lines = read_reference_lines(d);
  Reference r;
  r.file = lines.file;
  r.source = lines.source;
  bool header = false;
  for (const auto& [number, line] : lines.lines) {
    if (!header) {
      if (line != "T,Z") d.fail("reference", r.file + " line " + std::to_string(number) +
                                                 ": the header must be T,Z");
      header = true;
      continue;
    }
    std::istringstream fields(line);
    double T = 0.0, Z = 0.0;
    char comma = 0;
    if (!(fields >> T >> comma >> Z) || comma != ',' || !(fields >> std::ws).eof() ||
        !std::isfinite(T) || !std::isfinite(Z) || (!r.T.empty() && !(T > r.T.back()))) {
      d.fail("reference", r.file + " line " + std::to_string(number) +
                              ": expected 'T,Z', T increasing (got '" + line + "')");
    }
    r.T.push_back(T);
    r.Z.push_back(Z);
  }
  if (r.T.size() < 2) d.fail("reference", r.file + ": needs at least two points");
  return r;
}

// What the observer needs of the dam break: the water (free particles of
// the first fluid, internal indices), a, g, the spacing, the total water
// mass.
struct DamBreak {
  std::vector<int> water;
  double a = 0.0, g = 0.0, spacing = 0.0, rho0 = 0.0, c = 0.0, h = 0.0, water_mass = 0.0;
  double time_scale() const { return std::sqrt(2.0 * g / a); }  // T = t sqrt(2 g / a)
  double ritter() const { return 2.0 * std::sqrt(g * 2.0 * a); }
};

DamBreak dam_break_facts(const Model& model, double a) {
  DamBreak f;
  const Scene& scene = model.scene();
  const Fluid& fluid = scene.get<Fluids>().front();
  f.a = a;
  f.g = scene.get<Gravity>().acceleration.norm();
  f.spacing = fluid.spacing;
  f.rho0 = fluid.density;
  f.c = fluid.speed_of_sound;
  f.h = kSmoothingPerSpacing * fluid.spacing;
  for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
    const int p = model.particle_order().internal_of_scene[static_cast<std::size_t>(s)];
    if (p < model.free_particle_count()) {
      f.water.push_back(p);
      f.water_mass += scene.particles[static_cast<std::size_t>(s)].mass;
    }
  }
  return f;
}

// Watches a run at every step: the viscous work, the front, a row every
// `sample` seconds.
class DamBreakWatch final : public Observer {
 public:
  DamBreakWatch(const Model& model, const DamBreak& f, double sample, std::string prefix,
                std::vector<std::string>& rows)
      : model_(model), f_(f), sample_(sample), prefix_(std::move(prefix)), rows_(rows),
        energies_(model.energies(model.initial_positions(), model.initial_velocities())),
        viscous_(model.energy_layout().find("viscous-work")),
        gravity_(model.energy_layout().find("gravity")),
        pressure_(model.energy_layout().find("pressure")) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    const double start = thread_cpu_seconds();
    observe_state(t, x, v);
    cpu_seconds += thread_cpu_seconds() - start;
  }

  // The last state gets a row too.
  void finish() {
    if (!last_written_ && calls_ > 0) write(pending_.first, pending_.second, x_last_, v_last_);
  }

  std::vector<double> T, Z;  // at the rows
  double energy_initial = 0.0, numerical_last = 0.0, work_last = 0.0, compression_max = 0.0;
  double cpu_seconds = 0.0;  // spent observing

 private:
  void observe_state(double t, const Vector& x, const Vector& v) {
    const double power = viscous_ < model_.energy_layout().columns.size()
                             ? model_.column_power(viscous_, t, x, v)
                             : 0.0;
    if (calls_ > 0) work_ -= 0.5 * (t - t_previous_) * (power + power_previous_);
    power_previous_ = power;
    t_previous_ = t;
    const int dim = model_.dimension();
    double most = -INFINITY;
    for (int p : f_.water) most = std::max(most, x[p * dim]);
    const double Z = (most + 0.5 * f_.spacing) / f_.a;
    if (calls_ == 0 || t >= next_ - 1e-12 * sample_) {
      write(t, Z, x, v);
      next_ = (std::floor(t / sample_ + 1e-9) + 1.0) * sample_;
      last_written_ = true;
    } else {
      last_written_ = false;
      pending_ = {t, Z};
      x_last_ = x;
      v_last_ = v;
    }
    ++calls_;
  }

  void write(double t, double Z, const Vector& x, const Vector& v) {
    model_.energies(x, v, energies_);
    const double total = energies_.total();
    if (calls_ == 0) energy_initial = total;
    const auto value = [&](std::size_t column) {
      return column < energies_.values().size() ? energies_.values()[column] : 0.0;
    };
    const Eigen::MatrixXd positions = model_.scene_positions(x);
    std::vector<double> flat(static_cast<std::size_t>(positions.size()));
    for (Eigen::Index s = 0; s < positions.rows(); ++s) {
      for (Eigen::Index r = 0; r < positions.cols(); ++r) {
        flat[static_cast<std::size_t>(s * positions.cols() + r)] = positions(s, r);
      }
    }
    const Fluid& fluid = model_.scene().get<Fluids>().front();
    const FluidFields fields = fluid_fields(model_.scene(), fluid, flat.data());
    double compression = 0.0;
    for (double rho : fields.density) compression = std::max(compression, rho / fluid.density - 1.0);
    compression_max = std::max(compression_max, compression);
    const double numerical = total + work_ - energy_initial;
    numerical_last = numerical;
    work_last = work_;
    T.push_back(t * f_.time_scale());
    this->Z.push_back(Z);
    rows_.push_back(Row().raw(prefix_).add(t).add(t * f_.time_scale()).add(Z)
                        .add(energies_.kinetic()).add(value(gravity_)).add(value(pressure_))
                        .add(total).add(work_).add(numerical).add(compression).str());
  }

  const Model& model_;
  const DamBreak& f_;
  double sample_;
  std::string prefix_;
  std::vector<std::string>& rows_;
  Energies energies_;
  std::size_t viscous_, gravity_, pressure_;
  long calls_ = 0;
  double work_ = 0.0, power_previous_ = 0.0, t_previous_ = 0.0, next_ = 0.0;
  bool last_written_ = true;
  std::pair<double, double> pending_;
  Vector x_last_, v_last_;
};

// The largest particle speed a run reaches.
class SpeedWatch final : public Observer {
 public:
  explicit SpeedWatch(int dim) : dim_(dim) {}
  void observe(double, const Vector&, const Vector& v) override {
    for (Eigen::Index p = 0; p + dim_ <= v.size(); p += dim_) {
      double s2 = 0.0;
      for (int r = 0; r < dim_; ++r) s2 += v[p + r] * v[p + r];
      if (std::sqrt(s2) > fastest) fastest = std::sqrt(s2);
    }
  }
  double fastest = 0.0;

 private:
  int dim_;
};

struct RunSpec {
  std::string integrator;
  double dt = 0.0;
  int substeps = 0, iterations = 0;
};

class FluidExperiment final : public Experiment {
 public:
  explicit FluidExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "rtol", "atol", "newton_tol",
                  "scene", "parameters", "runs", "t_end", "sample", "reference", "limits",
                  "gauges"});
    options_ = definition_options(d);
    scene_ = definition_scene(d);
    if (!scene_.has<Fluids>() || scene_.get<Fluids>().empty()) {
      d.fail("scene", "needs a fluid (the dam break: a column of water against the wall x = 0)");
    }
    if (!scene_.has<Gravity>() || !(scene_.get<Gravity>().acceleration.norm() > 0.0)) {
      d.fail("scene", "needs gravity (the front is measured in t sqrt(2 g / a))");
    }
    a_ = column_width(d, scene_);
    t_end_ = d.positive("t_end");
    sample_ = d.positive("sample");
    if (sample_ > t_end_) d.fail("sample", "must not exceed t_end");
    reference_ = read_reference(d);
    for (const DefinitionObject& r : d.objects("runs")) {
      r.allow_only({"integrator", "dt", "substeps", "iterations"});
      RunSpec spec;
      spec.integrator = definition_integrator(r, "integrator");
      spec.dt = r.positive("dt");
      spec.substeps = r.count("substeps", 0, 0, 100000);
      spec.iterations = r.count("iterations", 0, 0, 100000);
      check_time_grid(r, "dt", spec.dt, t_end_);
      runs_.push_back(spec);
    }
    if (d.has("limits")) {
      const DefinitionObject l = d.object("limits");
      l.allow_only({"scene", "parameters", "sound", "integrators", "t_end", "rel_tol", "blowup",
                    "dt_max_factor", "periods"});
      sound_ = l.positives("sound");
      for (double s : sound_) {
        Scene scene = definition_scene(l, {{"sound", format_number(s)}});
        if (!scene.has<Fluids>() || scene.get<Fluids>().empty()) {
          l.fail("scene", "needs a fluid");
        }
        // (The header: rho0 just below the water's density at rest.)
        scene.block<Fluids>().front().density *= 1.0 - 1e-9;
        limit_scenes_.push_back(std::move(scene));
      }
      limit_integrators_ = definition_integrators(l, "integrators", "");
      limit_t_end_ = l.positive("t_end");
      // Each search runs to t_end at its smallest step, dt_min = 1e-3 h / c
      // (run_limit): over the cap of steps per run, it is refused now,
      // naming the key, not after the main runs (issue 46.12).
      for (std::size_t k = 0; k < limit_scenes_.size(); ++k) {
        const Fluid& fluid = limit_scenes_[k].get<Fluids>().front();
        const double dt_min = 1e-3 * kSmoothingPerSpacing * fluid.spacing / fluid.speed_of_sound;
        const double steps = limit_t_end_ / dt_min;
        if (!(steps <= 1e9)) {
          l.fail("t_end", format_number(limit_t_end_) + " s would take " + format_count(steps) +
                              " steps at the searches' smallest step dt_min = 1e-3 h / c = " +
                              format_number(dt_min) + " s (sound " + format_number(sound_[k]) +
                              ": c = " + format_number(fluid.speed_of_sound) +
                              " m/s), over the cap of 1e9 per run");
        }
      }
      limit_rel_tol_ = l.positive("rel_tol", 1e-2);
      limit_blowup_ = l.positive("blowup", 1000.0);
      limit_dt_max_factor_ = l.positive("dt_max_factor", 10.0);
      limit_periods_ = l.positive("periods", 20.0);
      limit_a_ = column_width(l, limit_scenes_.front());
    }
    if (d.has("gauges")) gauges_ = std::make_unique<FluidGauges>(d.object("gauges"), options_);
    check_task_count(d, "runs", static_cast<double>(task_count()));
    check_output_rows(d, "runs", static_cast<double>(runs_.size()) * (t_end_ / sample_ + 3.0));
  }

  std::vector<TableSpec> tables() const override {
    std::vector<TableSpec> out = {{"", {"integrator", "dt", "t", "T", "Z", "kinetic", "gravity", "pressure", "total",
                  "viscous_work", "numerical", "compression"}},
            {"runs", {"integrator", "dt", "substeps", "iterations", "status", "diverged_at",
                      "t_final", "steps", "force_evals", "newton_iterations", "wall_seconds",
                      "cpu_seconds", "cost_per_second", "Z_T2", "Z_T2_measured", "Z_T2_error",
                      "front_speed_max", "ritter_speed", "compression_max", "energy_initial",
                      "viscous_work", "numerical", "particles", "failure", "warnings"}},
            {"reference", {"T", "Z"}},
            {"limits", {"sound", "c", "integrator", "particles", "h", "hydrostatic", "w_max",
                        "dt_theory", "C_theory", "dt_max_stable", "lo", "hi", "v_max",
                        "C_measured", "ratio", "outcome"}}};
    for (TableSpec& t : FluidGauges::tables()) out.push_back(std::move(t));
    return out;
  }

  std::size_t task_count() const override {
    return runs_.size() + sound_.size() * limit_integrators_.size() + (gauges_ ? 1 : 0);
  }

  TaskOutput run_task(std::size_t index) const override {
    TaskOutput out;
    out.rows.resize(4 + FluidGauges::tables().size());
    if (gauges_ && index + 1 == task_count()) {
      gauges_->run(out, 4);
    } else if (index < runs_.size()) {
      run_dam_break(runs_[index], out);
      if (index == 0) {
        for (std::size_t k = 0; k < reference_.T.size(); ++k) {
          out.rows[2].push_back(Row().add(reference_.T[k]).add(reference_.Z[k]).str());
        }
      }
    } else {
      const std::size_t k = index - runs_.size();
      run_limit(k / limit_integrators_.size(), limit_integrators_[k % limit_integrators_.size()],
                out);
    }
    return out;
  }

  nlohmann::json settings() const override {
    const Model model(scene_);
    const DamBreak f = dam_break_facts(model, a_);
    nlohmann::json runs = nlohmann::json::array();
    for (const RunSpec& r : runs_) {
      runs.push_back({{"integrator", r.integrator}, {"dt", r.dt}, {"substeps", r.substeps},
                      {"iterations", r.iterations}});
    }
    return {{"runs", runs}, {"t_end", t_end_}, {"sample", sample_},
            {"scene", scene_as_json(scene_)},
            {"dam_break", {{"a", f.a}, {"g", f.g}, {"spacing", f.spacing}, {"density", f.rho0},
                           {"speed_of_sound", f.c}, {"smoothing_length", f.h},
                           {"water_particles", f.water.size()},
                           {"particles", scene_.particles.size()},
                           {"water_mass", f.water_mass},
                           // M g a: the column's potential energy above the floor.
                           {"energy_scale", f.water_mass * f.g * f.a},
                           {"time_scale", f.time_scale()}, {"ritter_speed", f.ritter()}}},
            {"reference", {{"file", reference_.file}, {"source", reference_.source}}},
            {"limits", {{"sound", sound_}, {"integrators", limit_integrators_},
                        {"t_end", limit_t_end_}, {"rel_tol", limit_rel_tol_},
                        {"blowup", limit_blowup_}, {"dt_max_factor", limit_dt_max_factor_},
                        {"periods", limit_periods_},
                        {"a", limit_a_},
                        {"particles", limit_scenes_.empty() ? 0 : limit_scenes_.front().particles.size()}}},
            {"gauges", gauges_ ? gauges_->settings() : nlohmann::json()}};
  }

 private:
  // a: the water's width, from its particles' largest x (plus half a
  // spacing); the wall behind it is x = 0.
  static double column_width(const DefinitionObject& d, const Scene& scene) {
    const Fluid& fluid = scene.get<Fluids>().front();
    double most = -INFINITY, least = INFINITY;
    for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
      const Particle& p = scene.particles[static_cast<std::size_t>(s)];
      if (p.fixed) continue;
      most = std::max(most, p.x.x());
      least = std::min(least, p.x.x());
    }
    if (!(most > -INFINITY) || !(least >= 0.0)) {
      d.fail("scene", "needs free water at x >= 0 (the wall behind the column at x = 0)");
    }
    return most + 0.5 * fluid.spacing;
  }

  void run_dam_break(const RunSpec& spec, TaskOutput& out) const {
    const Model model(scene_);
    const DamBreak f = dam_break_facts(model, a_);
    const std::string prefix = Row().add(spec.integrator).add(spec.dt).str();
    DamBreakWatch watch(model, f, sample_, prefix, out.rows[0]);
    RunSettings run;
    run.integrator = spec.integrator;
    run.dt = spec.dt;
    run.t_end = t_end_;
    run.every = 1;  // the viscous work needs every step
    run.options = options_;
    run.options.substeps = spec.substeps;
    run.options.iterations = spec.iterations;
    const double cpu_start = thread_cpu_seconds();
    const RunResult r = simulate(model, run, {&watch});
    // Without the observer's own work (the viscous power at every step, a
    // density sum at every row).
    const double cpu = thread_cpu_seconds() - cpu_start - watch.cpu_seconds;
    watch.finish();
    // Z at T = 2 (the test's and the comparison point) and the
    // fastest front between rows.
    const std::optional<double> Z2 = interpolate(watch.T, watch.Z, 2.0);
    const std::optional<double> Z2_measured = interpolate(reference_.T, reference_.Z, 2.0);
    std::optional<double> Z2_error;
    if (Z2 && Z2_measured) Z2_error = *Z2 / *Z2_measured - 1.0;
    double fastest = 0.0;
    for (std::size_t k = 1; k < watch.T.size(); ++k) {
      const double dt = (watch.T[k] - watch.T[k - 1]) / f.time_scale();
      if (dt > 0.0) fastest = std::max(fastest, (watch.Z[k] - watch.Z[k - 1]) * f.a / dt);
    }
    const double simulated = r.t_final;
    Row row;
    row.raw(prefix).add(spec.substeps).add(spec.iterations).add(to_string(r.status))
        .add(r.diverged_at).add(r.t_final).add(r.stats.steps).add(r.stats.force_evals)
        .add(r.stats.newton_iterations).add(r.wall_seconds).add(cpu);
    if (simulated > 0.0) row.add(cpu / simulated); else row.add_empty();
    row.add(Z2).add(Z2_measured).add(Z2_error).add(fastest).add(f.ritter())
        .add(watch.compression_max).add(watch.energy_initial).add(watch.work_last)
        .add(watch.numerical_last).add(static_cast<long>(scene_.particles.size())).add(r.failure)
        .add(warnings_cell(r));
    out.rows[1].push_back(row.str());
  }

  void run_limit(std::size_t k, const std::string& name, TaskOutput& out) const {
    const Model model(limit_scenes_[k]);
    const Fluid& fluid = limit_scenes_[k].get<Fluids>().front();
    const double h = kSmoothingPerSpacing * fluid.spacing;
    StabilitySettings s;
    s.run.integrator = name;
    s.run.t_end = limit_t_end_;
    s.run.options = options_;
    s.run.blowup = limit_blowup_;
    s.rel_tol = limit_rel_tol_;
    // Around the acoustic CFL step h / c.
    s.dt_min = 1e-3 * h / fluid.speed_of_sound;
    s.dt_max = limit_dt_max_factor_ * h / fluid.speed_of_sound;
    s.min_periods = limit_periods_;
    const StabilityResult r = find_max_stable_dt(model, s);
    const char* outcome = r.outcome == StabilityOutcome::kBracketed ? "bracketed"
                          : r.outcome == StabilityOutcome::kStableUpToDtMax ? "stable-up-to-dt-max"
                                                                             : "unstable-at-dt-min";
    const double c = fluid.speed_of_sound;
    // The flow's own largest speed: a run at the CFL step 0.25 h / c over
    // the trials' time (near the limit, a trial that stays under the
    // divergence rule can still throw a few particles).
    SpeedWatch flow(model.dimension());
    RunSettings reference = s.run;
    reference.dt = 0.25 * h / fluid.speed_of_sound;
    reference.t_end = limit_t_end_;
    simulate(model, reference, {&flow});
    const double v_max = flow.fastest;
    Row row;
    // The compression at the column's foot at rest, g H / c^2 (H = 2a).
    const double g = limit_scenes_[k].get<Gravity>().acceleration.norm();
    row.add(sound_[k]).add(c).add(name).add(static_cast<long>(limit_scenes_[k].particles.size()))
        .add(h).add(g * 2.0 * limit_a_ / (c * c)).add(r.mode.w).add(r.theory.dt);
    if (r.theory.dt) row.add(*r.theory.dt * c / h); else row.add_empty();
    row.add(r.max_stable_dt).add(r.lo).add(r.hi);
    if (r.lo > 0.0) {
      row.add(v_max).add(r.max_stable_dt * (c + v_max) / h);
    } else {
      row.add_empty().add_empty();
    }
    if (r.theory.dt && *r.theory.dt > 0.0) row.add(r.max_stable_dt / *r.theory.dt); else row.add_empty();
    out.rows[3].push_back(row.add(outcome).str());
  }

  IntegratorOptions options_;
  Scene scene_;
  double a_ = 0.0, t_end_ = 0.0, sample_ = 0.0;
  Reference reference_;
  std::vector<RunSpec> runs_;
  std::vector<double> sound_;
  std::vector<Scene> limit_scenes_;
  std::vector<std::string> limit_integrators_;
  double limit_t_end_ = 0.0, limit_rel_tol_ = 1e-2, limit_a_ = 0.0, limit_blowup_ = 1000.0;
  double limit_dt_max_factor_ = 10.0, limit_periods_ = 20.0;
  std::unique_ptr<FluidGauges> gauges_;  // the 3-D water heights against a measurement
};

}  // namespace

std::unique_ptr<Experiment> make_fluid_experiment(const DefinitionObject& d) {
  return std::make_unique<FluidExperiment>(d);
}

const ExperimentKind& fluid_experiment_kind() {
  static const ExperimentKind kind{"fluid", &make_fluid_experiment};
  return kind;
}

}  // namespace springlab
