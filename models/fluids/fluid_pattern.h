// The Jacobian pattern of a fluid force (docs/physics.md "Fluids"): a
// fluid's pairs change as it moves, so a force term cannot declare its
// couplings once. It declares the pairs within `reach` kernel supports plus a
// skin s, found at the positions x0 where it last declared them (a Verlet
// list). While no particle has moved more than s/2 supports from x0, no two
// particles that were farther apart than reach + s can have come within
// reach, so the declared pairs hold every coupling (ForceTerm::pattern_holds);
// when one has, the term declares anew around the new positions
// (ForceTerm::follow_pattern) and the model builds a new pattern.
//   pressure:  couplings between particles with a common neighbour, reach 2
//              (|x_i - x_j| < 2 x 2h = two supports);
//   viscosity: couplings between neighbours, reach 1.
#pragma once

#include <memory>
#include <vector>

#include "models/core/force_term.h"
#include "models/fluids/neighbour_grid.h"
#include "models/core/scene.h"
#include "models/fluids/sph_particles.h"

namespace springlab {

class FluidPattern {
 public:
  // The skin s, in kernel supports.
  static constexpr double kSkin = 0.25;

  // The pairs are found around x_all (every particle, the model's internal
  // order) when first declared: a method that never assembles a Jacobian
  // (the model builds its pattern only when asked) does not pay for them
  // (issue 46.6: a 2-D fluid's pressure pairs, within 2.25 supports, are
  // about 100 a particle, most of the 23 KB a particle an explicit run of
  // the tank took).
  FluidPattern(double reach, int dim, std::vector<double> x_all)
      : reach_(reach), dim_(dim), pending_(std::move(x_all)) {}

  // Finds the declared pairs of each fluid around positions x_all (every
  // particle, the model's internal order).
  void follow(const std::vector<std::shared_ptr<SphParticles>>& fluids, const double* x_all) const;
  // True while no particle has moved more than s/2 supports from where the
  // pairs were found (false before they are).
  bool holds(const std::vector<std::shared_ptr<SphParticles>>& fluids, const double* x_all) const;
  // The pairs' blocks (free particles only), found first where not yet.
  void declare(const std::vector<std::shared_ptr<SphParticles>>& fluids,
               JacobianPatternBuilder& builder, int free_particles) const;

 private:
  double reach_;
  int dim_;
  // Found on first use (a cache of the positions they were found at).
  mutable bool found_ = false;
  mutable std::vector<double> pending_;                // where to find them first
  mutable std::vector<NeighbourGrid> pairs_;            // per fluid
  mutable std::vector<std::vector<double>> found_at_;  // per fluid, local order
};

// Every particle's initial position in the model's internal order (fixed
// particles included; their places hold zeros where the scene has none).
std::vector<double> internal_positions(const Scene& scene, const ParticleOrder& order);

}  // namespace springlab
