#include "models/fluids/sph_particles.h"

#include <algorithm>
#include <cmath>

#include "models/core/scene.h"

namespace springlab {

SphParticles::SphParticles(const Fluid& fluid, std::vector<int> index, std::vector<double> mass,
                           int dim, std::vector<char> fixed)
    : index_(std::move(index)),
      mass_(std::move(mass)),
      dim_(dim),
      kernel_(kSmoothingPerSpacing * fluid.spacing, dim),
      eos_{fluid.density, fluid.speed_of_sound},
      fixed_(std::move(fixed)) {
  if (fixed_.empty()) fixed_.assign(index_.size(), 0);
}

void SphParticles::update(const double* x) {
  const std::size_t n = index_.size(), d = static_cast<std::size_t>(dim_);
  bool same = valid_ && x_.size() == n * d;
  x_.resize(n * d);
  for (std::size_t a = 0; a < n; ++a) {
    const double* p = x + static_cast<std::size_t>(index_[a]) * d;
    for (std::size_t r = 0; r < d; ++r) {
      // (Bitwise: a NaN position is never "the same".)
      same = same && x_[a * d + r] == p[r];
      x_[a * d + r] = p[r];
    }
  }
  if (same) return;
  valid_ = true;
  ++generation_;
  const double support = kernel_.support();
  const double support2 = support * support;
  auto distance2 = [&](std::size_t a, std::size_t b, double* sep) {
    double r2 = 0.0;
    for (std::size_t r = 0; r < d; ++r) {
      sep[r] = x_[a * d + r] - x_[b * d + r];
      r2 += sep[r] * sep[r];
    }
    return r2;
  };
  if (!list_holds()) {
    grid_.build(x_.data(), static_cast<int>(n), dim_, (1.0 + kSkin) * support);
    searched_x_ = x_;
    list_.clear();
    fixed_density_.assign(n, 0.0);
    for (const auto& [a, b] : grid_.pairs()) {
      const std::size_t ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
      if (!fixed_[ua] || !fixed_[ub]) {
        list_.emplace_back(a, b);
        continue;
      }
      double sep[3];
      const double r2 = distance2(ua, ub, sep);
      if (!(r2 < support2)) continue;
      const double w = kernel_.value(std::sqrt(r2));
      fixed_density_[ua] += mass_[ub] * w;
      fixed_density_[ub] += mass_[ua] * w;
    }
  }
  // The list's pairs within the support, in its order.
  pairs_.clear();
  separation_.clear();
  distance_.clear();
  for (const auto& [a, b] : list_) {
    const std::size_t ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    double sep[3];
    const double r2 = distance2(ua, ub, sep);
    if (!(r2 < support2)) continue;
    pairs_.emplace_back(a, b);
    separation_.insert(separation_.end(), sep, sep + d);
    distance_.push_back(std::sqrt(r2));
  }
  density_.resize(n);
  const double w0 = kernel_.value(0.0);
  for (std::size_t a = 0; a < n; ++a) density_[a] = mass_[a] * w0 + fixed_density_[a];
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    const std::size_t a = static_cast<std::size_t>(pairs_[k].first);
    const std::size_t b = static_cast<std::size_t>(pairs_[k].second);
    const double w = kernel_.value(distance_[k]);
    density_[a] += mass_[b] * w;
    density_[b] += mass_[a] * w;
  }
}

bool SphParticles::list_holds() const {
  if (searched_x_.empty() || searched_x_.size() != x_.size()) return false;
  // Two particles each moved by at most kSkin h came at most 2 kSkin h =
  // kSkin 2h closer: a pair now within 2h was within (1 + kSkin) 2h.
  const double limit = kSkin * 0.5 * kernel_.support();
  const double limit2 = limit * limit;
  const std::size_t d = static_cast<std::size_t>(dim_);
  for (std::size_t a = 0; a < x_.size(); a += d) {
    double move2 = 0.0;
    for (std::size_t r = 0; r < d; ++r) {
      const double m = x_[a + r] - searched_x_[a + r];
      move2 += m * m;
    }
    if (!(move2 <= limit2)) return false;  // a NaN included: search again
  }
  return true;
}

SphParticles make_sph_particles(const Scene& scene, const Fluid& fluid,
                                const std::vector<int>& internal_of_scene) {
  std::vector<int> index;
  std::vector<double> mass;
  std::vector<char> fixed;
  for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
    index.push_back(internal_of_scene[static_cast<std::size_t>(s)]);
    mass.push_back(scene.particles[static_cast<std::size_t>(s)].mass);
    fixed.push_back(scene.particles[static_cast<std::size_t>(s)].fixed ? 1 : 0);
  }
  return SphParticles(fluid, std::move(index), std::move(mass), scene.dimension,
                      std::move(fixed));
}

double lattice_mass(double rho0, double spacing, int dimension) {
  const CubicSpline w(kSmoothingPerSpacing * spacing, dimension);
  double sum = 0.0;
  const int reach = 3;  // 3 l > the support 2.6 l
  for (int i = -reach; i <= reach; ++i) {
    for (int j = -reach; j <= reach; ++j) {
      for (int k = dimension == 3 ? -reach : 0; k <= (dimension == 3 ? reach : 0); ++k) {
        sum += w.value(spacing * std::sqrt(double(i * i + j * j + k * k)));
      }
    }
  }
  return rho0 / sum;
}

std::shared_ptr<SphParticles> shared_sph_particles(const Scene& scene, std::size_t k,
                                                   const ParticleOrder& order) {
  const std::string key = "fluid " + std::to_string(k);
  if (auto made = std::dynamic_pointer_cast<SphParticles>(order.find_shared(key))) return made;
  auto particles = std::make_shared<SphParticles>(
      make_sph_particles(scene, scene.get<Fluids>()[k], order.internal_of_scene));
  order.shared.emplace_back(key, particles);
  return particles;
}

FluidFields fluid_fields(const Scene& scene, const Fluid& fluid, const double* x) {
  std::vector<int> identity(scene.particles.size());
  for (std::size_t s = 0; s < identity.size(); ++s) identity[s] = static_cast<int>(s);
  SphParticles particles = make_sph_particles(scene, fluid, identity);
  particles.update(x);
  FluidFields out;
  out.density = particles.density();
  for (double rho : out.density) out.pressure.push_back(particles.eos().pressure(rho));
  return out;
}

}  // namespace springlab
