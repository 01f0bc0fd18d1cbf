// contact: every integrator against the closed forms of contact and
// friction (docs/physics.md "Contact with planes"), over the cases' steps. One task
// per (case, integrator), one row per run: how deep any particle went past
// any plane, the energy change, the cost, and -- where the scene is one free
// particle on one plane under gravity -- the quantity a closed form predicts,
// computed here from the scene itself:
//   - "bounce" (no friction, dropped from rest at gap h > 0, penalty k_c):
//     the deepest penetration, from m g (h + delta) = k_c delta^2 / 2,
//     delta = (m g + sqrt((m g)^2 + 2 k_c m g h)) / k_c;
//   - "slide" (tan(theta) > mu): the acceleration along the slope,
//     g (sin(theta) - mu cos(theta)), measured from the tangential speeds at
//     the last output at or before T/2 and at T;
//   - "stop" (tan(theta) < mu, launched at v0 along the slope): the distance
//     to rest, v0^2 / (2 g (mu cos(theta) - sin(theta)));
//   - "stick" (tan(theta) < mu, at rest): the creep speed of the smoothed
//     friction, eps_v (1 - sqrt(1 - tan(theta) / mu)).
// theta is the angle between the plane's normal and -g.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "models/contact/contact.h"
#include "models/springs/gravity.h"

namespace springlab {
namespace {

// The closed form a case is checked against, read off its scene.
struct Prediction {
  std::string regime;  // "bounce", "slide", "stop", "stick"; empty: none applies
  double theory = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector3d n, down;  // unit normal; unit direction of the tangential motion
  Eigen::Vector3d start;    // the particle's initial position
};

Prediction predict(const Scene& scene) {
  Prediction p;
  const Planes& planes = scene.get<Planes>();
  int free_count = 0, free_index = -1;
  for (std::size_t i = 0; i < scene.particles.size(); ++i) {
    if (!scene.particles[i].fixed) {
      ++free_count;
      free_index = static_cast<int>(i);
    }
  }
  const Eigen::Vector3d g = scene.get<Gravity>().acceleration;
  if (free_count != 1 || planes.size() != 1 || !(g.norm() > 0.0)) return p;
  const Particle& particle = scene.particles[static_cast<std::size_t>(free_index)];
  const Plane& plane = planes[0];
  const Contact& contact = scene.get<Contact>();
  p.n = plane.normal.stableNormalized();
  p.start = particle.x;
  const double g_n = -g.dot(p.n);  // weight per mass pressing into the plane
  if (!(g_n > 0.0)) return p;
  const Eigen::Vector3d g_t = g + g_n * p.n;
  const Eigen::Vector3d v_t = particle.v - particle.v.dot(p.n) * p.n;
  const double mu = plane.friction, tan_theta = g_t.norm() / g_n;
  p.down = g_t.norm() > 0.0 ? g_t.normalized()
                            : (v_t.norm() > 0.0 ? v_t.normalized() : Eigen::Vector3d::Zero());
  const double gap = p.n.dot(particle.x - plane.point);
  if (mu == 0.0) {
    if (contact.model != ContactModel::kPenalty || !(gap > 0.0) || particle.v.norm() != 0.0) {
      return p;
    }
    const double m = particle.mass, k = contact.stiffness_or_default(), w = m * g_n;
    p.regime = "bounce";
    p.theory = (w + std::sqrt(w * w + 2.0 * k * w * gap)) / k;
    return p;
  }
  if (tan_theta > mu) {
    p.regime = "slide";
    p.theory = g_t.norm() - mu * g_n;
  } else if (v_t.norm() > 0.0) {
    p.regime = "stop";
    p.theory = v_t.squaredNorm() / (2.0 * (mu * g_n - g_t.norm()));
  } else {
    p.regime = "stick";
    p.theory = contact.smoothing * (1.0 - std::sqrt(1.0 - tan_theta / mu));
  }
  return p;
}

// What a run shows of contact: the smallest gap of any free particle to any
// plane at any output, and what the prediction measures.
class ContactWatch final : public Observer {
 public:
  ContactWatch(const Model& model, const Prediction& p, double t_end)
      : model_(model), p_(p), t_half_(0.5 * t_end), t_end_(t_end) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    const Eigen::MatrixXd pos = model_.scene_positions(x);
    const Eigen::MatrixXd vel = model_.scene_velocities(v);
    const Scene& scene = model_.scene();
    for (const Plane& plane : scene.get<Planes>()) {
      const Eigen::Vector3d n = plane.normal.stableNormalized();
      for (Eigen::Index i = 0; i < pos.rows(); ++i) {
        if (scene.particles[static_cast<std::size_t>(i)].fixed) continue;
        double d = 0.0;
        for (Eigen::Index r = 0; r < pos.cols(); ++r) d += n[r] * (pos(i, r) - plane.point[r]);
        min_gap = std::min(min_gap, d);
      }
    }
    if (p_.regime.empty()) return;
    Eigen::Vector3d xi = Eigen::Vector3d::Zero(), vi = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < pos.rows(); ++i) {
      if (scene.particles[static_cast<std::size_t>(i)].fixed) continue;
      for (Eigen::Index r = 0; r < pos.cols(); ++r) {
        xi[r] = pos(i, r);
        vi[r] = vel(i, r);
      }
    }
    const double along = (xi - p_.start).dot(p_.down);
    const double speed = (vi - vi.dot(p_.n) * p_.n).norm();
    if (t <= t_half_) {
      t_half_seen_ = t;
      speed_half_ = speed;
    }
    if (t == t_end_) {
      if (p_.regime == "slide") measured = (speed - speed_half_) / (t_end_ - t_half_seen_);
      if (p_.regime == "stop") measured = along;
      if (p_.regime == "stick") measured = along / t_end_;
    }
    if (p_.regime == "bounce") measured = -min_gap;  // the deepest so far
  }

  double min_gap = std::numeric_limits<double>::infinity();
  double measured = std::numeric_limits<double>::quiet_NaN();

 private:
  const Model& model_;
  const Prediction& p_;
  double t_half_, t_end_;
  double t_half_seen_ = 0.0;  // the last output time at or before T/2
  double speed_half_ = std::numeric_limits<double>::quiet_NaN();
};

class ContactExperiment final : public TimedCasesExperiment {
 public:
  explicit ContactExperiment(const DefinitionObject& d) : TimedCasesExperiment(d) {
    for (std::size_t k = 0; k < cases().size(); ++k) {
      if (cases()[k].scene.get<Planes>().empty()) {
        d.fail("cases", "case " + std::to_string(k) +
                            ": the scene has no planes, and the contact experiment measures contact");
      }
      predictions_.push_back(predict(cases()[k].scene));
    }
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"case", "scene", "integrator", "dt", "status", "t_final", "regime", "measured",
                  "theory", "min_gap", "energy_change", "steps", "newton_iterations",
                  "wall_seconds", "failure", "warnings"}}};
  }

  TaskOutput run_task(std::size_t index) const override {
    const Task t = task(index);
    const std::size_t case_index = index / (task_count() / cases().size());
    const Prediction& p = predictions_[case_index];
    const Model model(t.c.scene);
    RunSettings run = t.run;
    // Every output of the grid: the bounce's deepest point and the speeds
    // at T/2 and T are read at output times.
    run.every = 1;
    ContactWatch watch(model, p, run.t_end);
    const RunResult r = simulate(model, run, {&watch});
    const bool completed = r.status == RunStatus::kCompleted;
    TaskOutput out;
    out.rows.resize(1);
    Row row;
    row.add(static_cast<long>(case_index)).raw(t.prefix).add(to_string(r.status)).add(r.t_final)
        .add(p.regime)
        .add(completed ? watch.measured : std::numeric_limits<double>::quiet_NaN())
        .add(p.theory).add(watch.min_gap).add(r.energy_final - r.energy_initial)
        .add(r.stats.steps).add(r.stats.newton_iterations).add(r.wall_seconds).add(r.failure).add(warnings_cell(r));
    out.rows[0].push_back(row.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json s = TimedCasesExperiment::settings();
    for (std::size_t k = 0; k < cases().size(); ++k) {
      s["cases"][k]["regime"] = predictions_[k].regime;
      if (!predictions_[k].regime.empty()) s["cases"][k]["theory"] = predictions_[k].theory;
    }
    return s;
  }

 private:
  std::vector<Prediction> predictions_;
};

}  // namespace

std::unique_ptr<Experiment> make_contact_experiment(const DefinitionObject& d) {
  return std::make_unique<ContactExperiment>(d);
}

const ExperimentKind& contact_experiment_kind() {
  static const ExperimentKind kind{"contact", &make_contact_experiment};
  return kind;
}

}  // namespace springlab
