// The fluids' divergence rule (verdict.h; docs/command-line.md
// "Divergence"): a fluid has diverged when
//   - a water particle (a free particle of the fluid) lies further outside
//     its walls' box than the fluid's size L, the walls' box being the
//     bounding box of the fluid's fixed particles (its walls) at t = 0 and L
//     the largest side of the box of all its particles (water and walls) at
//     t = 0: water that left the tank (flung out by a blow-up, or through a
//     wall); above an open top, L allows for a splash (dam-break -p lid=0
//     at spacing 0.01: 0.31 m over walls 0.27 m high with symplectic Euler
//     at 0.5 ms, L = 0.55 m);
//   - or a water particle lies further behind a contact plane than L (any
//     plane of the scene);
//   - or a water particle's density is more than kDensityBound (100 %)
//     above the rest density rho0: water squeezed to half its volume, which
//     no weakly compressible run is near (the built-in scenes keep it within
//     a few percent: fluids.h), and which the Tait pressure makes
//     18 rho0 c^2.
// A fluid without walls and planes is judged by its density (and the
// driver's energy rule) alone: it may fall or spread freely.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "models/fluids/fluid_forces.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_particles.h"
#include "models/core/verdict.h"

namespace springlab {
namespace {

constexpr double kDensityBound = 1.0;  // rho / rho0 - 1

class FluidDivergenceRule final : public DivergenceRule {
 public:
  struct Water {
    std::shared_ptr<SphParticles> particles;  // the model's (shared with its forces)
    std::vector<int> scene_index;             // of each local particle
    bool has_walls = false;
    Eigen::Vector3d lo, hi;  // the walls' box (or the fluid's initial box)
    double margin = 0.0;     // L: the largest side of the fluid's initial box
  };

  FluidDivergenceRule(std::vector<Water> water, std::vector<PlaneConstraint> planes, int dim,
                      int free)
      : water_(std::move(water)), planes_(std::move(planes)), dim_(dim), free_(free) {}

  void measure(const Configuration& c, double, std::vector<Verdict>& out) const override {
    Verdict outside{.rule = VerdictRule::kFluidOutside, .value = 0.0, .bound = 0.0};
    Verdict density{.rule = VerdictRule::kFluidDensity, .value = -INFINITY, .bound = kDensityBound};
    bool any_place_rule = false;
    for (const Water& w : water_) {
      SphParticles& fluid = *w.particles;
      fluid.update(c.x);  // (the energy's evaluation at this state searched already)
      for (int a = 0; a < fluid.size(); ++a) {
        const int i = fluid.index(a);
        if (i >= free_) continue;  // a wall particle
        const int where = w.scene_index[static_cast<std::size_t>(a)];
        const double error = fluid.density()[static_cast<std::size_t>(a)] / fluid.eos().rho0 - 1.0;
        if (error > density.value) {
          density.value = error;
          density.where = where;
        }
        const double* x = c.x + static_cast<std::ptrdiff_t>(i) * dim_;
        // How far beyond the bound (<= 0 within it), relative to the margin,
        // so that fluids of several sizes compare: value and bound are in
        // metres of the worst one.
        auto consider = [&](double beyond, int plane, int side) {
          if (beyond - w.margin > outside.value - outside.bound || !any_place_rule) {
            outside.value = beyond;
            outside.bound = w.margin;
            outside.where = where;
            outside.plane = plane;
            outside.side = side;
            any_place_rule = true;
          }
        };
        if (w.has_walls) {
          double d2 = 0.0, furthest = 0.0;
          int side = -1;
          for (int r = 0; r < dim_; ++r) {
            const double below = w.lo[r] - x[r], above = x[r] - w.hi[r];
            const double d = std::max({below, above, 0.0});
            d2 += d * d;
            if (d > furthest) {
              furthest = d;
              side = 2 * r + (above > below ? 1 : 0);
            }
          }
          consider(std::sqrt(d2), -1, side);
        }
        for (std::size_t k = 0; k < planes_.size(); ++k) {
          double gap = -planes_[k].offset;
          for (int r = 0; r < dim_; ++r) gap += planes_[k].normal[r] * x[r];
          consider(std::max(-gap, 0.0), static_cast<int>(k), -1);
        }
      }
    }
    if (any_place_rule) out.push_back(outside);
    if (density.where >= 0) out.push_back(density);
  }

 private:
  std::vector<Water> water_;
  std::vector<PlaneConstraint> planes_;
  int dim_, free_;
};

}  // namespace

// The rule in one sentence (ElementKind::divergence_sentence).
const char kFluidDivergenceSentence[] =
    "fluids: a water particle further outside its walls' box, or further behind a contact "
    "plane, than the fluid's size (the largest side of its particles' box at t = 0), or a water "
    "particle's density more than 100 % above the rest density";

std::unique_ptr<DivergenceRule> make_fluid_divergence_rule(const Scene& scene,
                                                           const ParticleOrder& order,
                                                           const VerdictScale& scale) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr || fluids->empty()) return nullptr;
  std::vector<FluidDivergenceRule::Water> water;
  for (std::size_t k = 0; k < fluids->size(); ++k) {
    const Fluid& f = (*fluids)[k];
    FluidDivergenceRule::Water w;
    w.particles = shared_sph_particles(scene, k, order);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    Eigen::Vector3d all_lo = lo, all_hi = hi;
    for (int s = f.first; s < f.first + f.count; ++s) {
      const Particle& p = scene.particles[static_cast<std::size_t>(s)];
      w.scene_index.push_back(s);
      all_lo = all_lo.cwiseMin(p.x);
      all_hi = all_hi.cwiseMax(p.x);
      if (!p.fixed) continue;
      w.has_walls = true;
      lo = lo.cwiseMin(p.x);
      hi = hi.cwiseMax(p.x);
    }
    w.lo = w.has_walls ? lo : all_lo;
    w.hi = w.has_walls ? hi : all_hi;
    for (int r = 0; r < scene.dimension; ++r) w.margin = std::max(w.margin, all_hi[r] - all_lo[r]);
    water.push_back(std::move(w));
  }
  return std::make_unique<FluidDivergenceRule>(std::move(water), scale.planes, order.dim,
                                               order.free_particles);
}

}  // namespace springlab
