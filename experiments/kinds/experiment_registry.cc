#include "experiments/kinds/experiment.h"

namespace springlab {

// Each factory lives in its experiment's own file.
std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_convergence_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_work_precision_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_stability_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_damping_budget_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_cloth_showcase_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_stability_region_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_step_energy_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_motion_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_contact_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_mode_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_rotation_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_solver_error_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_spectral_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_rigid_experiment(const DefinitionObject&);
std::unique_ptr<Experiment> make_fluid_experiment(const DefinitionObject&);

const std::vector<ExperimentKind>& experiment_kinds() {
  static const std::vector<ExperimentKind> kinds = {
      {"energy", &make_energy_experiment},
      {"convergence", &make_convergence_experiment},
      {"work-precision", &make_work_precision_experiment},
      {"stability", &make_stability_experiment},
      {"damping-budget", &make_damping_budget_experiment},
      {"cloth-showcase", &make_cloth_showcase_experiment},
      {"stability-region", &make_stability_region_experiment},
      {"step-energy", &make_step_energy_experiment},
      {"motion", &make_motion_experiment},
      {"contact", &make_contact_experiment},
      {"mode", &make_mode_experiment},
      {"rotation", &make_rotation_experiment},
      {"solver-error", &make_solver_error_experiment},
      {"spectral", &make_spectral_experiment},
      {"rigid", &make_rigid_experiment},
      {"fluid", &make_fluid_experiment},
  };
  return kinds;
}

}  // namespace springlab
