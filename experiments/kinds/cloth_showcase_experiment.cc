// cloth-showcase: the cloth at a few frame times for a few integrators at
// one step size — one where explicit Euler explodes and implicit Euler stays
// calm. A run that diverges also records its last good states and, from a
// rerun that only a non-finite state stops, the first states past the
// blow-up bound: the frames before and of the explosion.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"

namespace springlab {
namespace {

// Good states: the requested frames, and for a run that stops early its last
// kLastGoodFrames states (the frames before the divergence).
constexpr int kLastGoodFrames = 2;
// A diverged run is continued with only non-finite states stopping it, for
// kPastBlowupFrames steps from the first state past the blow-up bound: what
// the explosion looks like (past_blowup = 1 in the table).
constexpr int kPastBlowupFrames = 2;

class FrameRows final : public Observer {
 public:
  FrameRows(const Model& model, std::string prefix, const std::vector<double>& frames,
            std::vector<std::string>& rows)
      : model_(model), prefix_(std::move(prefix)), frames_(frames), rows_(rows) {}

  void observe(double t, const Vector& x, const Vector&) override {
    const bool frame = std::any_of(frames_.begin(), frames_.end(), [&](double f) {
      return std::abs(t - f) <= 1e-9 * std::max(1.0, f);
    });
    if (frame) write(t, x, 0);
    recent_.push_back({t, x, frame});
    if (recent_.size() > kLastGoodFrames) recent_.erase(recent_.begin());
  }
  // A run that ended early: its last good states not written as frames.
  void finish(const RunResult& run) {
    if (run.status == RunStatus::kCompleted) return;
    for (const Recent& r : recent_) {
      if (!r.written) write(r.t, r.x, 0);
    }
  }
  // A state past the blow-up bound.
  void write_past_blowup(double t, const Vector& x) { write(t, x, 1); }

 private:
  struct Recent {
    double t;
    Vector x;
    bool written;
  };

  void write(double t, const Vector& x, int past_blowup) {
    const Eigen::MatrixXd p = model_.scene_positions(x);
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      Row row;
      row.raw(prefix_).add(t).add(static_cast<long>(i));
      for (int r = 0; r < 3; ++r) row.add(r < p.cols() ? p(i, r) : 0.0);
      row.add(past_blowup);
      rows_.push_back(row.str());
    }
  }

  const Model& model_;
  std::string prefix_;
  const std::vector<double>& frames_;
  std::vector<std::string>& rows_;
  std::vector<Recent> recent_;
};

// Records the states from `from` on (a rerun past the blow-up bound).
class PastBlowupRows final : public Observer {
 public:
  PastBlowupRows(FrameRows& rows, double from) : rows_(rows), from_(from) {}
  void observe(double t, const Vector& x, const Vector&) override {
    if (t >= from_ && x.allFinite()) rows_.write_past_blowup(t, x);
  }

 private:
  FrameRows& rows_;
  double from_;
};

class ClothShowcaseExperiment final : public Experiment {
 public:
  explicit ClothShowcaseExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                  "newton_tol", "scene", "parameters", "dt", "frames"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "all");
    scene_ = definition_scene(d);
    dt_ = d.positive("dt");
    frames_ = d.positives("frames");
    frames_.insert(frames_.begin(), 0.0);
    for (std::size_t k = 1; k < frames_.size(); ++k) {
      const double steps = frames_[k] / dt_;
      if (std::abs(steps - std::round(steps)) > 1e-9 || frames_[k] <= frames_[k - 1]) {
        d.fail("frames", "must increase and be whole multiples of dt");
      }
    }
    check_time_grid(d, "dt", dt_, frames_.back());
    // Each run writes every frame (and its last good states and the states
    // past the blow-up bound) of every particle.
    check_output_rows(d, "frames",
                      static_cast<double>(integrators_.size()) *
                          (static_cast<double>(frames_.size() + kLastGoodFrames +
                                               kPastBlowupFrames) *
                               static_cast<double>(scene_.particles.size()) +
                           1.0));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "i", "x", "y", "z", "past_blowup"}},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps",
                      "wall_seconds"}}};
  }

  std::size_t task_count() const override { return integrators_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const std::string& name = integrators_[index];
    const Model model(scene_);
    RunSettings s;
    s.integrator = name;
    s.dt = dt_;
    s.t_end = frames_.back();
    s.options = options_;
    TaskOutput out;
    out.rows.resize(2);
    const std::string prefix = Row().add(scene_.name).add(name).add(dt_).str();
    FrameRows frames(model, prefix, frames_, out.rows[0]);
    const RunResult r = simulate(model, s, {&frames});
    frames.finish(r);
    if (r.status == RunStatus::kDiverged && r.diverged_at) {
      // The same steps again, stopped only by a non-finite state.
      RunSettings past = s;
      past.blowup = std::numeric_limits<double>::infinity();
      past.t_end = std::min(frames_.back(), *r.diverged_at + (kPastBlowupFrames - 1) * dt_);
      PastBlowupRows rows(frames, *r.diverged_at - 1e-9 * dt_);
      simulate(model, past, {&rows});
    }
    Row run;
    run.raw(prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(r.wall_seconds);
    out.rows[1].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(scene_.particles.size()))));
    return {{"integrators", integrators_}, {"n", n}, {"dt", dt_}, {"frames", frames_},
            {"scene", scene_as_json(scene_)}};
  }

 private:
  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  Scene scene_;
  double dt_ = 0.0;
  std::vector<double> frames_;
};

}  // namespace

std::unique_ptr<Experiment> make_cloth_showcase_experiment(const DefinitionObject& d) {
  return std::make_unique<ClothShowcaseExperiment>(d);
}

const ExperimentKind& cloth_showcase_experiment_kind() {
  static const ExperimentKind kind{"cloth-showcase", &make_cloth_showcase_experiment};
  return kind;
}

}  // namespace springlab
