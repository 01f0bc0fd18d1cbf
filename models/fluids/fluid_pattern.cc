#include "models/fluids/fluid_pattern.h"

namespace springlab {

void FluidPattern::follow(const std::vector<std::shared_ptr<SphParticles>>& fluids,
                          const double* x_all) const {
  found_ = true;
  pending_ = {};
  pairs_.assign(fluids.size(), NeighbourGrid());
  found_at_.assign(fluids.size(), {});
  for (std::size_t f = 0; f < fluids.size(); ++f) {
    const SphParticles& fluid = *fluids[f];
    std::vector<double>& x0 = found_at_[f];
    x0.resize(static_cast<std::size_t>(fluid.size() * dim_));
    for (int a = 0; a < fluid.size(); ++a) {
      for (int r = 0; r < dim_; ++r) {
        x0[static_cast<std::size_t>(a * dim_ + r)] = x_all[fluid.index(a) * dim_ + r];
      }
    }
    pairs_[f].build(x0.data(), fluid.size(), dim_, (reach_ + kSkin) * fluid.kernel().support());
  }
}

bool FluidPattern::holds(const std::vector<std::shared_ptr<SphParticles>>& fluids,
                         const double* x_all) const {
  if (!found_) return false;
  for (std::size_t f = 0; f < fluids.size(); ++f) {
    const SphParticles& fluid = *fluids[f];
    const double limit = 0.5 * kSkin * fluid.kernel().support();
    const std::vector<double>& x0 = found_at_[f];
    for (int a = 0; a < fluid.size(); ++a) {
      double d2 = 0.0;
      for (int r = 0; r < dim_; ++r) {
        const double d = x_all[fluid.index(a) * dim_ + r] - x0[static_cast<std::size_t>(a * dim_ + r)];
        d2 += d * d;
      }
      if (!(d2 <= limit * limit)) return false;
    }
  }
  return true;
}

void FluidPattern::declare(const std::vector<std::shared_ptr<SphParticles>>& fluids,
                           JacobianPatternBuilder& builder, int free_particles) const {
  if (!found_) {
    const std::vector<double> x_all = std::move(pending_);
    follow(fluids, x_all.data());
  }
  for (std::size_t f = 0; f < fluids.size(); ++f) {
    const SphParticles& fluid = *fluids[f];
    for (const auto& [a, b] : pairs_[f].pairs()) {
      declare_pair_blocks(builder, fluid.index(a), fluid.index(b), free_particles);
    }
  }
}

std::vector<double> internal_positions(const Scene& scene, const ParticleOrder& order) {
  const int dim = order.dim;
  std::vector<double> x(order.scene_of_internal.size() * static_cast<std::size_t>(dim), 0.0);
  for (std::size_t p = 0; p < order.scene_of_internal.size(); ++p) {
    const int s = order.scene_of_internal[p];
    if (s < 0) continue;
    for (int r = 0; r < dim; ++r) {
      x[p * static_cast<std::size_t>(dim) + static_cast<std::size_t>(r)] =
          scene.particles[static_cast<std::size_t>(s)].x[r];
    }
  }
  return x;
}

}  // namespace springlab
