// The experiment kinds by the name a definition's "kind" gives, in the
// one registration idiom of springlab (models/core/registry.h). Adding a
// kind: its file (a factory and `const ExperimentKind& NAME_experiment_kind()`
// at its end, experiment.h) and one line X(ExperimentKind, NAME_experiment_kind)
// in this table.
#include "experiments/kinds/experiment.h"
#include "models/core/registry.h"

#define SPRINGLAB_EXPERIMENT_KINDS(X)                 \
  X(ExperimentKind, energy_experiment_kind)           \
  X(ExperimentKind, convergence_experiment_kind)      \
  X(ExperimentKind, work_precision_experiment_kind)   \
  X(ExperimentKind, stability_experiment_kind)        \
  X(ExperimentKind, damping_budget_experiment_kind)   \
  X(ExperimentKind, cloth_showcase_experiment_kind)   \
  X(ExperimentKind, stability_region_experiment_kind) \
  X(ExperimentKind, step_energy_experiment_kind)      \
  X(ExperimentKind, motion_experiment_kind)           \
  X(ExperimentKind, contact_experiment_kind)          \
  X(ExperimentKind, mode_experiment_kind)             \
  X(ExperimentKind, rotation_experiment_kind)         \
  X(ExperimentKind, solver_error_experiment_kind)     \
  X(ExperimentKind, spectral_experiment_kind)         \
  X(ExperimentKind, rigid_experiment_kind)            \
  X(ExperimentKind, fluid_experiment_kind)

namespace springlab {

SPRINGLAB_REGISTRY(ExperimentKind, SPRINGLAB_EXPERIMENT_KINDS, experiment_registry)

std::vector<const ExperimentKind*> experiment_kinds() { return experiment_registry().entries(); }

}  // namespace springlab
