// mode: what each integrator does to one vibration mode -- the period error
// and the numerical damping of the slowest mode of a clamped scene (the
// beam's first bending mode), against the mode's own frequency w1 from the
// modal analysis (models/model/modal_analysis.h: the smallest eigenvalue of
// M^-1 K at rest).
//
// The scene starts at rest shape + a phi1 (phi1 the mode's shape, scaled so
// that its largest displacement is `amplitude`), at rest, without gravity,
// and runs `periods` periods 2 pi / w1 at `steps_per_period` steps each. An
// output's modal coordinate is q = phi1^T M (x - X) (phi1^T M phi1 = 1), in
// units of its starting value (q(0) = 1), and q' its rate:
//   - the period is read off the zero crossings of q (linear interpolation
//     between outputs): 2 (t_last - t_first) / (crossings - 1);
//   - the amplitude per period is exp(s T) with s the least-squares slope of
//     log r(t), r = sqrt(q^2 + (q'/w1)^2) the mode's phase-space radius
//     (1 for the exact motion at every t), over every output.
// The series table keeps q and q'/w1 at about 50 outputs per period (every
// ceil(steps_per_period / 50)-th output).
//
// The prediction: on a linear model every linear fixed-step method treats
// each mode on its own, as it treats one oscillator of that frequency. So
// the same integrator's amplification matrix on the oscillator
// x'' = -w1^2 x is measured from its own steps (experiments/analysis/spectral.h);
// with principal eigenvalues rho e^(+-i theta), the mode's period is
// 2 pi h / theta and its amplitude per period rho^(2 pi / theta). Adaptive
// methods change their step as they go and have none.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/output_files.h"
#include "experiments/analysis/spectral.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/springs/gravity.h"
#include "models/model/modal_analysis.h"

namespace springlab {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The mode's period and amplitude per period, as a method with step map A
// carries them (A from one step on the oscillator of frequency w).
struct StepMapPrediction {
  double period = kNaN;
  double amplitude_per_period = kNaN;
};

StepMapPrediction predict(const std::string& integrator, double w, double h,
                          const IntegratorOptions& options) {
  // The eigenvalues of the method's own step on x'' = -w^2 x (spectral.h:
  // also for methods that carry more than (x, v), the Newmark family's a_n
  // and BDF2's previous step): lambda = exp(w h / (1 + e) (-xi +- i)), with
  // e the relative period error and xi the damping ratio.
  StepMapPrediction p;
  StepSpectrum s;
  try {
    s = step_spectrum(integrator, options, w * h);
  } catch (const std::runtime_error&) {
    return p;  // a step of the method failed on the oscillator: no prediction
  }
  if (!std::isfinite(s.period_error) || !std::isfinite(s.damping_ratio)) return p;  // no period
  p.period = 2.0 * std::numbers::pi / w * (1.0 + s.period_error);
  p.amplitude_per_period = std::exp(-2.0 * std::numbers::pi * s.damping_ratio);
  return p;
}

// The modal coordinate at every output: one row each, and the zero
// crossings and log-radius fit read off them.
class ModeWatch final : public Observer {
 public:
  ModeWatch(const Vector& rest, const Vector& weight, double w, long keep_every,
            std::string prefix, std::vector<std::string>& rows)
      : rest_(rest), weight_(weight), w_(w), keep_every_(keep_every),
        prefix_(std::move(prefix)), rows_(rows) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    const double q = weight_.dot(x - rest_), dq = weight_.dot(v);
    if (outputs_++ % keep_every_ == 0) rows_.push_back(Row().raw(prefix_).add(t).add(q).add(dq / w_).str());
    if (has_previous_ && (q_previous_ < 0.0) != (q < 0.0)) {
      const double crossing = t_previous_ + (t - t_previous_) * q_previous_ / (q_previous_ - q);
      if (crossings_ == 0) first_crossing_ = crossing;
      last_crossing_ = crossing;
      ++crossings_;
    }
    has_previous_ = true;
    q_previous_ = q;
    t_previous_ = t;
    const double r = std::sqrt(q * q + dq * dq / (w_ * w_));
    if (r > 0.0 && std::isfinite(r)) {
      const double y = std::log(r);
      ++n_;
      st_ += t;
      sy_ += y;
      stt_ += t * t;
      sty_ += t * y;
    }
  }

  double period() const {
    return crossings_ >= 3 ? 2.0 * (last_crossing_ - first_crossing_) / (crossings_ - 1) : kNaN;
  }
  // The least-squares slope of log r against t.
  double decay_rate() const {
    const double n = static_cast<double>(n_);
    const double d = n * stt_ - st_ * st_;
    return n_ >= 2 && d > 0.0 ? (n * sty_ - st_ * sy_) / d : kNaN;
  }

 private:
  const Vector& rest_;
  const Vector& weight_;  // q = weight . (x - X)
  double w_;
  long keep_every_;  // a series row for every keep_every-th output
  long outputs_ = 0;
  std::string prefix_;
  std::vector<std::string>& rows_;
  bool has_previous_ = false;
  double q_previous_ = 0.0, t_previous_ = 0.0;
  int crossings_ = 0;
  double first_crossing_ = 0.0, last_crossing_ = 0.0;
  long n_ = 0;
  double st_ = 0.0, sy_ = 0.0, stt_ = 0.0, sty_ = 0.0;
};

class ModeExperiment final : public Experiment {
 public:
  explicit ModeExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "scene", "parameters", "amplitude", "periods",
                  "steps_per_period"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "fixed-step");
    amplitude_ = d.positive("amplitude");
    periods_ = d.count("periods", 20, 2, 10000);
    steps_per_period_ = d.positives("steps_per_period");
    scene_ = definition_scene(d);
    if (scene_.get<Gravity>().acceleration.norm() != 0.0) {
      d.fail("scene", "the mode is measured about the rest shape, so the scene needs g = 0");
    }
    const Model rest_model(scene_);
    rest_ = rest_model.initial_positions();
    if (rest_.size() > kMaxModeUnknowns) {
      d.fail("scene", "the mode needs a dense eigensolver: " + std::to_string(rest_.size()) +
                          " unknowns, at most " + std::to_string(kMaxModeUnknowns));
    }
    const Mode mode = lowest_mode(rest_model, rest_, rest_model.initial_velocities());
    if (!(mode.w > 0.0)) {
      d.fail("scene", "the scene's slowest mode has no positive frequency (is it held anywhere?)");
    }
    w_ = mode.w;
    // x(0) = X + a phi / max|phi|; q = phi^T M (x - X) max|phi| / a.
    const double scale = amplitude_ / mode.phi.cwiseAbs().maxCoeff();
    const Vector displaced = rest_ + scale * mode.phi;
    weight_ = rest_model.mass().cwiseProduct(mode.phi) / scale;
    const Eigen::MatrixXd positions = rest_model.scene_positions(displaced);
    for (std::size_t i = 0; i < scene_.particles.size(); ++i) {
      Particle& p = scene_.particles[i];
      p.X = p.rest_position();
      for (int r = 0; r < scene_.dimension; ++r) p.x[r] = positions(static_cast<Eigen::Index>(i), r);
      p.v.setZero();
    }
    for (double s : steps_per_period_) {
      if (s < 2.0) d.fail("steps_per_period", "at least 2 steps per period");
      check_time_grid(d, "steps_per_period", period_exact() / s, periods_ * period_exact());
    }
    double rows = 0.0;
    for (double s : steps_per_period_) {
      rows += static_cast<double>(integrators_.size()) * (periods_ * s / series_every(s) + 3.0);
    }
    check_output_rows(d, "steps_per_period", rows);
    w_max_ = max_angular_frequency(rest_model);
    check_task_count(d, "steps_per_period",
                     static_cast<double>(integrators_.size() * steps_per_period_.size()));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "steps_per_period", "dt", "status", "diverged_at", "w",
                  "period_exact", "period", "period_predicted", "amplitude_per_period",
                  "amplitude_per_period_predicted", "steps", "force_evals", "wall_seconds",
                  "failure", "warnings"}},
            {"series", {"scene", "integrator", "steps_per_period", "dt", "t", "q", "dq_over_w"}}};
  }

  std::size_t task_count() const override {
    return integrators_.size() * steps_per_period_.size();
  }

  TaskOutput run_task(std::size_t index) const override {
    const double s = steps_per_period_[index / integrators_.size()];
    const std::string& name = integrators_[index % integrators_.size()];
    RunSettings run;
    run.integrator = name;
    run.dt = period_exact() / s;
    run.t_end = periods_ * period_exact();
    run.options = options_;
    const std::string prefix = Row().add(scene_.name).add(name).add(s).add(run.dt).str();
    const Model model(scene_);
    TaskOutput out;
    out.rows.resize(2);
    ModeWatch watch(rest_, weight_, w_, series_every(s), prefix, out.rows[1]);
    const RunResult r = simulate(model, run, {&watch});
    const bool completed = r.status == RunStatus::kCompleted;
    const bool adaptive = make_integrator(name)->info().adaptive;
    const StepMapPrediction p = adaptive ? StepMapPrediction{} : predict(name, w_, run.dt, options_);
    const double period = completed ? watch.period() : kNaN;
    Row row;
    row.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(w_).add(period_exact())
        .add(period).add(p.period)
        .add(completed ? std::exp(watch.decay_rate() * period) : kNaN)
        .add(p.amplitude_per_period).add(r.stats.steps).add(r.stats.force_evals)
        .add(r.wall_seconds).add(r.failure).add(warnings_cell(r));
    out.rows[0].push_back(row.str());
    return out;
  }

  nlohmann::json settings() const override {
    return {{"integrators", integrators_},
            {"scene", scene_as_json(scene_)},
            {"amplitude", amplitude_},
            {"periods", periods_},
            {"steps_per_period", steps_per_period_},
            {"w", w_},
            {"w_max", w_max_},
            {"period_exact", period_exact()}};
  }

 private:
  double period_exact() const { return 2.0 * std::numbers::pi / w_; }
  // The series keeps about kSeriesPerPeriod outputs per period.
  static constexpr double kSeriesPerPeriod = 50.0;
  static long series_every(double steps_per_period) {
    return std::max(1L, static_cast<long>(std::ceil(steps_per_period / kSeriesPerPeriod)));
  }

  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  double amplitude_ = 0.0;
  int periods_ = 0;
  std::vector<double> steps_per_period_;
  Scene scene_;      // displaced into the mode, at rest
  Vector rest_;      // the rest shape's unknowns
  Vector weight_;    // q = weight . (x - X)
  double w_ = 0.0;   // the mode's angular frequency [rad/s]
  double w_max_ = 0.0;  // the fastest mode's, which limits the explicit methods
};

}  // namespace

std::unique_ptr<Experiment> make_mode_experiment(const DefinitionObject& d) {
  return std::make_unique<ModeExperiment>(d);
}

const ExperimentKind& mode_experiment_kind() {
  static const ExperimentKind kind{"mode", &make_mode_experiment};
  return kind;
}

}  // namespace springlab
