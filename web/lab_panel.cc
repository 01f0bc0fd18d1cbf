#include "web/lab_panel.h"

#include <cmath>

#include "experiments/io/vtk_bodies.h"
#include "integrators/registry/registry.h"
#include "models/bodies/bodies.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/modal_analysis.h"

namespace springlab {

namespace {
constexpr Eigen::Index kPageDenseUnknowns = 600;
}  // namespace

LabPanel::LabPanel(const PanelSettings& settings) {
  model_ = std::make_unique<Model>(make_builtin_scene(settings.scene, settings.params));
  points_ = model_->particle_count();
  if (!model_->scene().get<Bodies>().empty()) {
    bodies_ = std::make_unique<VtkBodies>(model_->scene(), model_->free_particle_count());
    points_ += bodies_->points();
  }
  // Above a few hundred unknowns, by power iteration: the dense eigensolver
  // (n^3) took 8-14 s in the page for the default fluid scenes' 1600 unknowns.
  w_max_ = std::isnan(settings.w_max) ? max_angular_frequency(*model_, kPageDenseUnknowns)
                                      : settings.w_max;
  cursor_ = std::make_unique<CursorSpring>(*model_, w_max_);
  integrator_ = make_integrator(settings.integrator);
  if (std::string why = integrator_->check_options(settings.options, model_->dofs());
      !why.empty()) {
    throw std::invalid_argument(why);
  }
  const StepResult start = integrator_->initialize(
      *cursor_, 0.0, model_->initial_positions(), model_->initial_velocities(), settings.options);
  if (!start.ok) throw RunRefused(start.message, start.refused);
  energies_.emplace(model_->energies(model_->initial_positions(), model_->initial_velocities()));
  check_ = std::make_unique<DivergenceCheck>(*model_, settings.blowup * model_->energy_scale(),
                                             *energies_, integrator_->overshoot_steps());
  blowup_ = settings.blowup;
  store_good_state();
}

LabPanel::~LabPanel() = default;

std::vector<int> LabPanel::body_faces() const {
  std::vector<int> faces;
  if (!bodies_) return faces;
  std::vector<Cell> cells;
  bodies_->append_cells(model_->particle_count(), cells);
  for (const Cell& c : cells) faces.insert(faces.end(), c.nodes.begin(), c.nodes.begin() + 3);
  return faces;
}

void LabPanel::store_good_state() {
  const Vector x_good = check_->x_good(), v_good = check_->v_good();
  model_->energies(x_good, v_good, *energies_);
  positions_.assign(static_cast<std::size_t>(points_) * 3, 0.0);
  speeds_.assign(static_cast<std::size_t>(points_), 0.0);
  // One row per point: x y (z) into positions_, |v| into speeds_.
  auto put = [&](const Eigen::MatrixXd& x, const Eigen::MatrixXd& v, Eigen::Index first) {
    for (Eigen::Index s = 0; s < x.rows(); ++s) {
      for (Eigen::Index r = 0; r < x.cols(); ++r) positions_[(first + s) * 3 + r] = x(s, r);
      speeds_[first + s] = v.row(s).norm();
    }
  };
  put(model_->scene_positions(x_good), model_->scene_velocities(v_good), 0);
  if (bodies_) {
    bodies_->states(x_good, v_good, body_x_, body_v_);
    put(body_x_, body_v_, model_->particle_count());
  }
}

long LabPanel::step(long steps, double dt) {
  if (status_ != RunStatus::kCompleted || steps <= 0) return 0;
  if (!(dt > 0.0)) throw std::invalid_argument("dt must be a positive number");
  if (dt != dt_) {  // a new grid from here
    t_base_ = t_;
    k_ = 0;
    dt_ = dt;
  }
  long taken = 0;
  // The loop of simulate() (experiments/driver/simulation.cc), one step at a time.
  for (; taken < steps; ++taken) {
    const double t = t_base_ + static_cast<double>(k_ + 1) * dt_;
    const StepResult step = integrator_->advance_to(t);
    if (!step.ok) {
      status_ = RunStatus::kFailed;
      failure_ = step.message;
      diverged_at_ = t;
      break;
    }
    if (const auto verdict = check_->judge(integrator_->x(), integrator_->v(), t)) {
      status_ = RunStatus::kDiverged;
      diverged_at_ = t;
      failure_ = verdict_text(*verdict, *model_,
                              {integrator_->name(), blowup_, integrator_->overshoot_steps()},
                              integrator_->x(), integrator_->v());
      break;
    }
    ++k_;
    ++steps_;
    t_ = t;
  }
  store_good_state();
  return taken;
}

}  // namespace springlab
