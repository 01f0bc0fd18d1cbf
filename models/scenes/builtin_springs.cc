// The built-in mass-spring scenes (docs/scenes.md "Built-in scenes"): the
// course's hanging spring, the oscillator whose exact solution is known, a
// chain and a cloth. Each is a generator from named parameters to a Scene
// and its registry entry (scene_entry.h).
#include <cstddef>

#include "models/contact/contact.h"
#include "models/scenes/scene_entry.h"
#include "models/core/decimal_text.h"
#include "models/springs/drag.h"
#include "models/springs/gravity.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"

namespace springlab {

namespace {

using Values = SceneValues;

Particle particle_at(const Eigen::Vector3d& x, double mass, bool fixed) {
  Particle p;
  p.x = x;
  p.mass = mass;
  p.fixed = fixed;
  return p;
}

Spring spring_between(int i, int j, double k, double rest) {
  Spring s;
  s.i = i;
  s.j = j;
  s.k = k;
  s.rest = rest;
  return s;
}

// The course's example: x0 fixed, the mass hanging undeformed at x0 + (0,-L).
Scene build_spring(const Values& p) {
  Scene scene;
  scene.dimension = 2;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Drag>().gamma = p.at("drag");
  scene.particles = {particle_at({0.0, 0.0, 0.0}, p.at("mass"), true),
                     particle_at({0.0, -p.at("rest"), 0.0}, p.at("mass"), false)};
  scene.block<Springs>() = {spring_between(0, 1, p.at("k"), p.at("rest"))};
  return scene;
}

// x(t) = rest + amplitude cos(sqrt(k/m) t): the reference for accuracy tests.
Scene build_oscillator(const Values& p) {
  const double rest = p.at("rest");
  const double amplitude = p.at("amplitude");
  if (!(rest + amplitude > 0)) {
    throw SceneError(
        "scene 'oscillator': parameter 'amplitude' must satisfy rest + amplitude > 0 (got rest " +
        shortest_decimal(rest) + ", amplitude " + shortest_decimal(amplitude) + ")");
  }
  Scene scene;
  scene.dimension = 2;
  scene.particles = {particle_at({0.0, 0.0, 0.0}, p.at("mass"), true),
                     particle_at({rest + amplitude, 0.0, 0.0}, p.at("mass"), false)};
  scene.block<Springs>() = {spring_between(0, 1, p.at("k"), rest)};
  return scene;
}

Scene build_chain(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double spacing = p.at("length") / (n - 1);
  // Released stretched (and without gravity) the chain stays in its linear
  // regime: the stability experiment's case, where an instability must grow
  // to the blow-up energy before particles could pass through each other.
  const double placed = spacing * (1.0 + p.at("stretch"));
  const bool horizontal = p.at("horizontal") == 1.0;
  Scene scene;
  scene.dimension = 2;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Drag>().gamma = p.at("drag");
  Springs& springs = scene.block<Springs>();
  scene.particles.reserve(static_cast<std::size_t>(n));
  springs.reserve(static_cast<std::size_t>(n - 1));
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = horizontal ? Eigen::Vector3d(i * placed, 0.0, 0.0)
                                         : Eigen::Vector3d(0.0, -i * placed, 0.0);
    scene.particles.push_back(particle_at(x, p.at("mass"), i == 0));
    if (i > 0) springs.push_back(spring_between(i - 1, i, p.at("k"), spacing));
  }
  return scene;
}

// n x n grid in the x-z plane, (r, c) -> index r n + c, hung from (0,0) and
// (0,n-1). Springs: structural (rows, then columns), shear (both diagonals of
// each cell), bend (skip one: rows, then columns).
Scene build_cloth(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double spacing = p.at("size") / (n - 1);
  const double particle_mass = p.at("mass") / (static_cast<double>(n) * n);
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -9.81, 0.0};
  scene.block<Drag>().gamma = p.at("drag");
  if (p.at("wind") != 0.0) {
    // Coefficient = particle mass: each particle relaxes to the wind in 1 s.
    scene.block<Wind>() = Wind{{0.0, 0.0, p.at("wind")}, particle_mass, 0.5, 0.5};
  }
  Springs& springs = scene.block<Springs>();
  const auto count = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  scene.particles.reserve(count);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const bool fixed = r == 0 && (c == 0 || c == n - 1);
      scene.particles.push_back(particle_at({c * spacing, 0.0, r * spacing}, particle_mass, fixed));
    }
  }
  auto index = [n](int r, int c) { return r * n + c; };
  auto join = [&](int a, int b, double k) {
    const double rest = (scene.particles[a].x - scene.particles[b].x).norm();
    springs.push_back(spring_between(a, b, k, rest));
  };
  springs.reserve(count * 6);
  const double k = p.at("k"), k_shear = p.at("k_shear"), k_bend = p.at("k_bend");
  for (int r = 0; r < n; ++r)
    for (int c = 0; c + 1 < n; ++c) join(index(r, c), index(r, c + 1), k);
  for (int r = 0; r + 1 < n; ++r)
    for (int c = 0; c < n; ++c) join(index(r, c), index(r + 1, c), k);
  for (int r = 0; r + 1 < n; ++r) {
    for (int c = 0; c + 1 < n; ++c) {
      join(index(r, c), index(r + 1, c + 1), k_shear);
      join(index(r, c + 1), index(r + 1, c), k_shear);
    }
  }
  for (int r = 0; r < n; ++r)
    for (int c = 0; c + 2 < n; ++c) join(index(r, c), index(r, c + 2), k_bend);
  for (int r = 0; r + 2 < n; ++r)
    for (int c = 0; c < n; ++c) join(index(r, c), index(r + 2, c), k_bend);
  if (p.at("ground") > 0.0) {
    // The ground: the plane y = -ground under the hanging cloth, which
    // swings down onto it and folds there (docs/physics.md "Contact with planes").
    Plane plane;
    plane.point = {0.0, -p.at("ground"), 0.0};
    plane.friction = p.at("friction");
    scene.block<Planes>().push_back(plane);
    Contact& contact = scene.block<Contact>();
    contact.model = p.at("contact") == 1.0 ? ContactModel::kBarrier : ContactModel::kPenalty;
    contact.stiffness = p.at("contact_stiffness");
  }
  return scene;
}

SceneCounts chain_counts(const SceneValues& p) { return {p.at("n"), p.at("n") - 1}; }

// Structural 2 n (n-1), shear 2 (n-1)^2, bend 2 n (n-2), as build_cloth makes them.
SceneCounts cloth_counts(const SceneValues& p) {
  const double n = p.at("n");
  return {n * n, 2 * n * (n - 1) + 2 * (n - 1) * (n - 1) + 2 * n * (n - 2)};
}

}  // namespace

const SceneEntry& chain_scene() {
  static const SceneEntry entry = scene_entry(
      "chain",
          "n masses in a line joined by springs, the first fixed; hanging under gravity or "
          "released from horizontal",
         {param("n", 10, "number of particles, the first one fixed", Range::kWhole, 2, 1e7),
          param("k", 1000, "stiffness of each spring [N/m]", Range::kNonNegative),
          param("mass", 0.1, "mass of each particle [kg]", Range::kPositive),
          param("length", 1, "total rest length of the chain [m]", Range::kPositive),
          param("drag", 0, "drag coefficient per particle [kg/s]", Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("horizontal", 0, "0: hanging straight down, 1: released from horizontal",
                Range::kZeroOrOne),
          param("stretch", 0, "initial strain: released with springs (1 + stretch) x rest long",
                Range::kNonNegative)},
         build_chain, chain_counts, "n");
  return entry;
}

const SceneEntry& cloth_scene() {
  static const SceneEntry entry = scene_entry(
      "cloth",
          "n x n grid in 3-D with structural, shear and bend springs, two top corners fixed, "
          "gravity, optional wind",
         {param("n", 16, "particles per side (n x n grid)", Range::kWhole, 2, 2048),
          param("k", 1000, "structural spring stiffness [N/m]", Range::kNonNegative),
          param("k_shear", 1000, "shear (diagonal) spring stiffness [N/m]", Range::kNonNegative),
          param("k_bend", 100, "bend (skip-one) spring stiffness [N/m]", Range::kNonNegative),
          param("mass", 1, "mass of the whole cloth, split evenly over the particles [kg]",
                Range::kPositive),
          param("size", 1, "side length [m]", Range::kPositive),
          param("drag", 0, "drag coefficient per particle [kg/s]", Range::kNonNegative),
          param("wind", 0, "mean wind speed along +z, 0 for no wind [m/s]", Range::kAny),
          param("ground", 0,
                "depth of a ground plane below the fixed corners, 0 for none [m] (the cloth "
                "swings down onto it)",
                Range::kNonNegative),
          param("friction", 0.3, "Coulomb coefficient mu of the ground", Range::kNonNegative),
          param("contact", 0, "ground contact: 0 penalty, 1 barrier (IPC)", Range::kZeroOrOne),
          param("contact_stiffness", 1e4,
                "penalty k_c or barrier kappa [N/m] (barrier distance 0.01 m)",
                Range::kPositive)},
         build_cloth, cloth_counts, "n");
  return entry;
}

const SceneEntry& oscillator_scene() {
  static const SceneEntry entry = scene_entry(
      "oscillator",
          "one undamped linear spring, no gravity, mass released stretched: exact solution known",
         {param("k", 100, "spring stiffness [N/m]", Range::kPositive),
          param("mass", 1, "mass of the moving particle [kg]", Range::kPositive),
          // Rest 0 makes the spring linear in every direction (F = -k x), so
          // the linear stability analysis holds even as a run blows up; with
          // rest > 0 it is linear only while the mass stays beyond the anchor.
          param("rest", 0, "rest length of the spring [m]; 0 = linear in every direction",
                Range::kNonNegative),
          param("amplitude", 0.1, "initial stretch beyond the rest length [m]", Range::kAny)},
         build_oscillator);
  return entry;
}

const SceneEntry& spring_scene() {
  static const SceneEntry entry = scene_entry(
      "spring",
          "the course's example: a mass hanging from a fixed point by one spring, with gravity and "
          "drag",
         {param("k", 100, "spring stiffness [N/m]", Range::kNonNegative),
          param("mass", 1, "mass of the hanging particle [kg]", Range::kPositive),
          param("rest", 1, "rest length, also the initial length [m]", Range::kPositive),
          param("drag", 0.5, "drag coefficient [kg/s]", Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny)},
         build_spring);
  return entry;
}

}  // namespace springlab
