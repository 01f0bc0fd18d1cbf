#include "models/force_registry.h"

namespace springlab {

// Each factory lives in its force's own file.
std::unique_ptr<ForceTerm> make_spring_force(const Scene&, const ParticleOrder&);
std::unique_ptr<ForceTerm> make_spring_damping_force(const Scene&, const ParticleOrder&);
std::unique_ptr<ForceTerm> make_drag_force(const Scene&, const ParticleOrder&);
std::unique_ptr<ForceTerm> make_gravity_force(const Scene&, const ParticleOrder&);
std::unique_ptr<ForceTerm> make_wind_force(const Scene&, const ParticleOrder&);

const std::vector<ForceKind>& force_kinds() {
  static const std::vector<ForceKind> kinds = {
      {"spring", &make_spring_force},
      {"spring-damping", &make_spring_damping_force},
      {"drag", &make_drag_force},
      {"gravity", &make_gravity_force},
      {"wind", &make_wind_force},
  };
  return kinds;
}

}  // namespace springlab
