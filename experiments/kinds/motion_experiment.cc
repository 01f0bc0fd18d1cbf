// motion: the runs the report's player shows moving (docs/experiments-and-report.md "The report's
// player"). Every integrator runs every case; each output frame records
// every particle's position, then every rigid body's surface vertices'
// (vtk_bodies.h: x = p + A X, numbered after the particles), and the total
// energy. A run that diverges also
// records, from a rerun that only a non-finite state stops, its first frames
// past the blow-up bound: the player draws the explosion until it leaves the
// picture, then marks the run. One task per (case, integrator).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/vtk_bodies.h"
#include "models/core/element_kind.h"
#include "models/model/element_registry.h"

namespace springlab {
namespace {

// Output frames recorded past the blow-up bound of a diverged run.
constexpr int kPastBlowupFrames = 3;

class MotionRows final : public Observer {
 public:
  MotionRows(const Model& model, std::string prefix, TaskOutput& out)
      : model_(model), bodies_(model.scene(), model.particle_order().first_own(kBodyKind)),
        prefix_(std::move(prefix)), out_(out) {}
  void observe(double t, const Vector& x, const Vector& v) override {
    if (t < from_ || !x.allFinite() || !v.allFinite()) return;
    const Eigen::MatrixXd p = model_.scene_positions(x);
    Eigen::MatrixXd surface, unused;
    bodies_.states(x, v, surface, unused);
    auto add = [&](long i, const Eigen::MatrixXd& m, Eigen::Index k) {
      Row row;
      row.raw(prefix_).add(t).add(past_blowup_).add(i);
      for (int r = 0; r < 3; ++r) row.add(r < m.cols() ? m(k, r) : 0.0);
      out_.rows[0].push_back(row.str());
    };
    for (Eigen::Index i = 0; i < p.rows(); ++i) add(static_cast<long>(i), p, i);
    for (Eigen::Index k = 0; k < surface.rows(); ++k) add(static_cast<long>(p.rows() + k), surface, k);
    Row frame;
    frame.raw(prefix_).add(t).add(past_blowup_).add(model_.energies(x, v).total());
    out_.rows[1].push_back(frame.str());
  }
  // From now on: only frames at t >= from, marked past the blow-up bound.
  void past_blowup_from(double from) {
    from_ = from;
    past_blowup_ = 1;
  }

 private:
  const Model& model_;
  VtkBodies bodies_;
  std::string prefix_;
  TaskOutput& out_;
  double from_ = -std::numeric_limits<double>::infinity();
  int past_blowup_ = 0;
};

class MotionExperiment final : public TimedCasesExperiment {
 public:
  explicit MotionExperiment(const DefinitionObject& d) : TimedCasesExperiment(d) {
    // Every frame holds every point (particles and bodies' surface
    // vertices): rows = frames x (points + 1).
    const double integrators = static_cast<double>(definition_integrators(d, "integrators", "all").size());
    double rows = 0.0;
    for (std::size_t k = 0; k < cases().size(); ++k) {
      const TimedCase& c = cases()[k];
      const double steps = static_cast<double>(make_time_grid(c.dt, c.t_end).steps);
      const double frames = std::floor(steps / c.every) + 2.0 + kPastBlowupFrames;
      const double points = static_cast<double>(c.scene.particles.size()) +
                            VtkBodies(c.scene, 0).points();
      rows += integrators * (frames * (points + 1.0) + 1.0);
      check_output_rows(d, "cases[" + std::to_string(k) + "]", rows);
    }
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "past_blowup", "i", "x", "y", "z"}},
            {"frames", {"scene", "integrator", "dt", "t", "past_blowup", "energy"}},
            {"runs", {"scene", "integrator", "dt", "status", "diverged_at", "steps", "wall_seconds",
                      "energy_initial", "energy_scale", "failure", "warnings"}}};
  }

  TaskOutput run_task(std::size_t index) const override {
    const Task t = task(index);
    const Model model(t.c.scene);
    TaskOutput out;
    out.rows.resize(3);
    MotionRows rows(model, t.prefix, out);
    const RunResult r = simulate(model, t.run, {&rows});
    if (r.status == RunStatus::kDiverged && r.diverged_at) {
      // The same steps again, stopped only by a non-finite state, for the
      // first output frames past the divergence.
      // It ends at the kPastBlowupFrames-th output time after the last
      // good state (output times: every K-th step of the grid).
      const TimeGrid grid = make_time_grid(t.run.dt, t.run.t_end);
      const long good_steps = std::lround(r.t_final / t.run.dt);
      const long every = t.run.every;
      const long end = (good_steps / every + kPastBlowupFrames) * every;
      RunSettings past = t.run;
      past.blowup = std::numeric_limits<double>::infinity();
      past.t_end = grid.at(std::min(end, grid.steps));
      rows.past_blowup_from(r.t_final + 1e-9 * t.run.dt);
      simulate(model, past, {&rows});
    }
    Row run;
    run.raw(t.prefix).add(to_string(r.status)).add(r.diverged_at).add(r.stats.steps)
        .add(r.wall_seconds).add(r.energy_initial).add(model.energy_scale()).add(r.failure)
        .add(warnings_cell(r));
    out.rows[2].push_back(run.str());
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json s = TimedCasesExperiment::settings();
    // What the player draws of each case's scene: each element's particles
    // (springs as lines, triangles, tetrahedra), and which are fixed; with
    // bodies, the number of points a frame has (particles, then the
    // bodies' surface vertices) and the bodies' surface triangles ("faces",
    // counter-clockwise seen from outside), drawn as filled polygons.
    for (std::size_t k = 0; k < cases().size(); ++k) {
      const Scene& scene = cases()[k].scene;
      nlohmann::json cells = nlohmann::json::array();
      for (const Cell& c : scene_cells(scene)) {
        cells.push_back(std::vector<int>(c.nodes.begin(), c.nodes.begin() + c.size));
      }
      s["cases"][k]["cells"] = std::move(cells);
      const VtkBodies bodies(scene, 0);
      if (bodies.points() == 0) continue;
      std::vector<Cell> triangles;
      bodies.append_cells(static_cast<int>(scene.particles.size()), triangles);
      nlohmann::json faces = nlohmann::json::array();
      for (const Cell& c : triangles) faces.push_back({c.nodes[0], c.nodes[1], c.nodes[2]});
      s["cases"][k]["points"] = static_cast<long>(scene.particles.size()) + bodies.points();
      s["cases"][k]["faces"] = std::move(faces);
    }
    return s;
  }
};

}  // namespace

std::unique_ptr<Experiment> make_motion_experiment(const DefinitionObject& d) {
  return std::make_unique<MotionExperiment>(d);
}

const ExperimentKind& motion_experiment_kind() {
  static const ExperimentKind kind{"motion", &make_motion_experiment};
  return kind;
}

}  // namespace springlab
