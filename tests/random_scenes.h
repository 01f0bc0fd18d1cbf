// Random scenes for the derivative tests, made from the element kinds' own
// random instances (ElementKind::add_random): a new kind is in them by
// registering it.
#pragma once

#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "models/core/element_kind.h"
#include "models/core/scene.h"
#include "models/model/element_registry.h"

namespace springlab::testing {

// Six particles at random places near a line (p + U(-1, 1) per coordinate),
// random velocities, masses 1 + p/2, particle 2 fixed.
inline void add_random_particles(Scene& s, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 6;
  for (int p = 0; p < n; ++p) {
    Particle particle;
    for (int r = 0; r < s.dimension; ++r) {
      particle.x[r] = u(rng) + p;
      particle.v[r] = u(rng);
    }
    particle.mass = 1.0 + 0.5 * p;
    particle.fixed = p == 2;
    s.particles.push_back(particle);
  }
}

// Random particles plus a random instance of each of `kinds`, in order.
inline Scene random_scene(const std::vector<const ElementKind*>& kinds, int dim, unsigned seed,
                          RandomStates states = RandomStates::kAny) {
  std::mt19937 rng(seed);
  Scene s;
  s.name = "random";
  s.dimension = dim;
  add_random_particles(s, rng);
  for (const ElementKind* kind : kinds) {
    if (kind->add_random != nullptr) kind->add_random(s, rng, states);
  }
  return s;
}

// The registered kind named `name` (it must exist).
inline const ElementKind& kind_named(std::string_view name) {
  for (const ElementKind* kind : element_kinds()) {
    if (kind->name == name) return *kind;
  }
  throw std::logic_error("no element kind named " + std::string(name));
}

// Every registered kind at once.
inline Scene random_scene(int dim, unsigned seed, RandomStates states = RandomStates::kAny) {
  return random_scene(element_kinds(), dim, seed, states);
}

}  // namespace springlab::testing
