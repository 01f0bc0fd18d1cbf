// One panel of the lab page (docs/browser-lab.md): a built-in scene under one
// integrator, stepped live. The objects are `springlab run`'s (the scene's
// ElasticModel, the registry's integrator, the divergence rule's
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

#include "experiments/divergence_check.h"
#include "experiments/simulation.h"
#include "integrators/integrator.h"
#include "models/elastic_model.h"
#include "web/cursor_spring.h"

namespace springlab {

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
  // The last good state's positions, scene order, x y z per particle.
  const std::vector<double>& positions() const { return positions_; }

  const ElasticModel& model() const { return *model_; }
  const Integrator& integrator() const { return *integrator_; }
  // The scene's highest angular frequency at its initial state [rad/s].
  double w_max() const { return w_max_; }
  CursorSpring& cursor() { return *cursor_; }

 private:
  void store_good_state();

  std::unique_ptr<ElasticModel> model_;
  double w_max_ = 0.0;
  std::unique_ptr<CursorSpring> cursor_;
  std::unique_ptr<Integrator> integrator_;
  std::unique_ptr<DivergenceCheck> check_;
  RunStatus status_ = RunStatus::kCompleted;
  std::optional<double> diverged_at_;
  std::string failure_;
  double t_ = 0.0, t_base_ = 0.0, dt_ = 0.0;
  long k_ = 0;      // steps since dt last changed
  long steps_ = 0;  // steps in all
  Vector x_good_, v_good_, x_next_, v_next_;
  std::optional<Energies> energies_;
  std::vector<double> positions_;
};

}  // namespace springlab
