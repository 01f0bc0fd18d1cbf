// One fluid's particles as smoothed particle hydrodynamics sees them at a
// configuration (docs/physics.md "Fluids"): the pairs closer than the
// kernel's support 2h (a uniform-grid search, neighbour_grid.h), each pair's
// separation, and the densities by summation
//   rho_i = sum_j m_j W(|x_i - x_j|, h)      (j = i included)
// (Monaghan 1992; Monaghan 2005, the summation density).
// The pressure and viscosity forces and the output read it. It keeps what it
// found for the last positions: evaluating the same positions again (the
// model's terms one after the other, energies after forces) costs a
// comparison, not a search. And new positions near the last search's cost
// a pass over a list, not a search: the search finds the pairs within the
// support plus a skin, (1 + kSkin) 2h, and while no particle has moved
// more than kSkin h (half the skin) since, every pair within 2h is among
// them (a Verlet list: Verlet 1967), so the pairs are that list filtered by
// distance, in its order. An implicit step's Newton iterates and line
// search trials move the particles by less than that at 1 ms: one search a
// step instead of one per evaluation.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "models/fluids/fluids.h"
#include "models/core/force_term.h"
#include "models/fluids/neighbour_grid.h"
#include "models/fluids/sph_kernel.h"

namespace springlab {

class SphParticles final : public SharedByTerms {
 public:
  // `index[a]`: where local particle a's coordinates start in the arrays
  // update() reads, divided by dim (the model's internal index, or the scene
  // index); `mass[a]` its mass.
  // `fixed[a]`: local particle a never moves (a wall's; empty: none is).
  SphParticles(const Fluid& fluid, std::vector<int> index, std::vector<double> mass, int dim,
               std::vector<char> fixed = {});

  // Finds the pairs and densities at positions x (particle p at x[p * dim]).
  void update(const double* x);

  int size() const { return static_cast<int>(index_.size()); }
  int dim() const { return dim_; }
  int index(int a) const { return index_[static_cast<std::size_t>(a)]; }
  double mass(int a) const { return mass_[static_cast<std::size_t>(a)]; }
  const CubicSpline& kernel() const { return kernel_; }
  const TaitEquation& eos() const { return eos_; }
  // Local positions (a at local_x()[a * dim]) of the last update.
  const double* local_x() const { return x_.data(); }

  // The skin of the search, as a fraction of the support 2h.
  static constexpr double kSkin = 0.25;

  // Pairs (a, b), a < b, with |x_a - x_b| < 2h and a or b free (two fixed
  // particles exert nothing that moves anything; their share of each
  // other's density is summed once per search); separation x_a - x_b at
  // separation(k) (dim values), its length at distance(k).
  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  const double* separation(std::size_t k) const { return &separation_[k * dim_]; }
  double distance(std::size_t k) const { return distance_[k]; }
  const std::vector<double>& density() const { return density_; }
  // Counts the updates that found new pairs and densities (a cache of
  // something computed from them is current while this is unchanged).
  long generation() const { return generation_; }

 private:
  std::vector<int> index_;
  std::vector<double> mass_;
  int dim_;
  CubicSpline kernel_;
  TaitEquation eos_;
  std::vector<double> x_;
  bool valid_ = false;
  long generation_ = 0;
  std::vector<char> fixed_;        // per local particle: 1 for a wall's, which never moves
  NeighbourGrid grid_;             // the search
  // The pairs within (1 + kSkin) 2h of searched_x_ with a free particle,
  // and each particle's density from fixed partners within 2h when it is
  // fixed itself (the walls' own share, constant).
  std::vector<std::pair<int, int>> list_;
  std::vector<double> fixed_density_;
  std::vector<double> searched_x_;  // the positions of the last search (local order; empty: none)
  std::vector<std::pair<int, int>> pairs_;
  std::vector<double> separation_, distance_, density_;
  // Whether the last search's list still holds every pair within 2h at x_.
  bool list_holds() const;
};

// The local particles of `fluid` in a model's internal order (`internal` of
// each scene index) with their masses.
SphParticles make_sph_particles(const Scene& scene, const Fluid& fluid,
                                const std::vector<int>& internal_of_scene);

// Those of the scene's fluid number k for one model's terms: made on the
// first call, then the same object (ParticleOrder::shared, key "fluid k"), so that terms
// evaluated at one configuration share its search.
std::shared_ptr<SphParticles> shared_sph_particles(const Scene& scene, std::size_t k,
                                                   const ParticleOrder& order);

}  // namespace springlab
