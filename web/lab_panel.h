// One panel of the lab page (docs/browser-lab.md): a built-in scene under one
// integrator, stepped live. The objects are `springlab run`'s (the scene's
// Model, the registry's integrator, the divergence rule's
// DivergenceCheck); what differs is that the page decides how many steps
// each frame takes, may change dt between two steps, and may pull a
// particle with the mouse (cursor_spring.h). Step k ends at
// t = t_base + k dt, t_base being the time dt last changed.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/driver/divergence_check.h"
#include "experiments/driver/simulation.h"
#include "integrators/core/integrator.h"
#include "models/model/model.h"
#include "web/cursor_spring.h"

namespace springlab {

class VtkBodies;  // experiments/io/vtk_bodies.h (not included: its scene_io.h's Json
                  // would meet lab_api.cc's)

struct PanelSettings {
  std::string scene;                                        // a built-in scene's name
  std::vector<std::pair<std::string, std::string>> params;  // its -p key=value pairs
  std::string integrator;
  IntegratorOptions options;
  double blowup = 1000.0;  // the command line's --blowup
  // The scene's highest angular frequency when known (another panel of the
  // same scene computed it); NaN: computed here (modal_analysis.h).
  double w_max = std::numeric_limits<double>::quiet_NaN();
};

class LabPanel {
 public:
  // Throws SceneError for a bad parameter, std::invalid_argument for an
  // unknown integrator or option, RunRefused where the method refuses the
  // scene (simulation.h).
  explicit LabPanel(const PanelSettings& settings);
  ~LabPanel();

  // Up to `steps` steps of dt; stops at the first that diverges or fails
  // (the panel then keeps its last good state). Returns the steps taken.
  long step(long steps, double dt);

  RunStatus status() const { return status_; }
  std::optional<double> diverged_at() const { return diverged_at_; }
  const std::string& failure() const { return failure_; }
  double t() const { return t_; }
  long steps_taken() const { return steps_; }
  // Kinetic and total energy of the last good state (energies.h).
  double kinetic_energy() const { return energies_->kinetic(); }
  double total_energy() const { return energies_->total(); }
  // What the page draws: the scene's particles, then the rigid bodies'
  // surface vertices x = p + A X (vtk_bodies.h), in scene order.
  int points() const { return points_; }
  // The last good state's positions, x y z per point, and speeds |v| per
  // point (a fluid's particles are coloured by it).
  const std::vector<double>& positions() const { return positions_; }
  const std::vector<double>& speeds() const { return speeds_; }
  // The bodies' surface triangles, numbered as points() (3 per triangle).
  std::vector<int> body_faces() const;

  const Model& model() const { return *model_; }
  const Integrator& integrator() const { return *integrator_; }
  // The scene's highest angular frequency at its initial state [rad/s].
  double w_max() const { return w_max_; }
  CursorSpring& cursor() { return *cursor_; }

 private:
  void store_good_state();

  std::unique_ptr<Model> model_;
  std::unique_ptr<VtkBodies> bodies_;  // null: the scene has no rigid bodies
  int points_ = 0;
  double w_max_ = 0.0;
  std::unique_ptr<CursorSpring> cursor_;
  std::unique_ptr<Integrator> integrator_;
  std::unique_ptr<DivergenceCheck> check_;
  double blowup_ = 1000.0;
  RunStatus status_ = RunStatus::kCompleted;
  std::optional<double> diverged_at_;
  std::string failure_;
  double t_ = 0.0, t_base_ = 0.0, dt_ = 0.0;
  long k_ = 0;      // steps since dt last changed
  long steps_ = 0;  // steps in all
  std::optional<Energies> energies_;
  std::vector<double> positions_, speeds_;
  Eigen::MatrixXd body_x_, body_v_;  // scratch: the bodies' surface vertices
};

}  // namespace springlab
