// The forces of the fluid kinds (docs/physics.md "Fluids"): the symmetric
// pressure force (fluid_pressure_force.cc, kind "fluid") and the laminar
// viscosity (fluid_viscosity_force.cc, kind "fluid-viscosity"), and the
// density constraints xpbd projects instead of the pressure force
// (fluid_density_projection.cc).
#pragma once

#include <memory>
#include <vector>

#include "models/core/force_term.h"
#include "models/core/scene.h"
#include "models/core/verdict.h"

namespace springlab {

std::unique_ptr<ForceTerm> make_fluid_pressure_force(const Scene& scene, const ParticleOrder& order);
std::unique_ptr<ForceTerm> make_fluid_viscosity_force(const Scene& scene,
                                                      const ParticleOrder& order);

// The fluids' divergence rule (fluid_verdict.cc; verdict.h).
std::unique_ptr<DivergenceRule> make_fluid_divergence_rule(const Scene& scene,
                                                           const ParticleOrder& order,
                                                           const VerdictScale& scale);
extern const char kFluidDivergenceSentence[];

class SphParticles;
// Position-based fluids' density constraints (fluid_density_projection.cc)
// of these fluids; x_all: every particle's position, internal order (the
// fixed ones' places are read from it).
std::unique_ptr<PositionProjection> make_fluid_density_projection(
    std::vector<SphParticles> fluids, std::vector<double> x_all, int dim, int free_particles);

}  // namespace springlab
