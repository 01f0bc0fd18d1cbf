// The forces of the fluid kinds (docs/physics.md "Fluids"): the symmetric
// pressure force (fluid_pressure_force.cc, kind "fluid") and the laminar
// viscosity (fluid_viscosity_force.cc, kind "fluid-viscosity").
#pragma once

#include <memory>

#include "models/force_term.h"
#include "models/scene.h"

namespace springlab {

std::unique_ptr<ForceTerm> make_fluid_pressure_force(const Scene& scene, const ParticleOrder& order);
std::unique_ptr<ForceTerm> make_fluid_viscosity_force(const Scene& scene,
                                                      const ParticleOrder& order);

}  // namespace springlab
