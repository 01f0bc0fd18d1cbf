#include "experiments/experiment.h"

namespace springlab {

// Each factory lives in its experiment's own file.
std::unique_ptr<Experiment> make_energy_experiment(const DefinitionObject&);

const std::vector<ExperimentKind>& experiment_kinds() {
  static const std::vector<ExperimentKind> kinds = {
      {"energy", &make_energy_experiment},
  };
  return kinds;
}

}  // namespace springlab
