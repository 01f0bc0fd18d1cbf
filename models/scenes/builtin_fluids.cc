// The built-in fluid scenes (docs/scenes.md "Built-in scenes"): `dam-break`
// (Martin and Moyce's collapsing column), `dam-break-obstacle` (MARIN's 3-D
// dam break onto a box, SPHERIC test 2), `tank` (water at rest) and
// `sloshing` (the first mode of a tank). Each is one fluid (fluids.h) on a
// square (cubic) lattice of spacing l: the water's particles first, then
// the walls' -- kWallLayers layers of fixed particles continuing the
// lattice outside the box (floor y < 0, sides x < 0 and x > width, and in
// 3-D z < 0 and z > depth; the dam break's lid above the walls' top), so a
// particle next to a wall has a full kernel of neighbours. y is up in 2-D
// and 3-D, gravity (0, -g, 0).
//
// Masses: m = rho0 / S, S = sum over the lattice of W(|k| l), so that an
// interior particle's density by summation is rho0 exactly at t = 0.
// Speed of sound: c = `sound` sqrt(g H), H the water's height (10 keeps the
// Mach number |v|/c near 0.1 for the speeds sqrt(g H) of waves and 0.2 for a
// dam break's front, density within about 1 % and 4 %). Viscosity: from
// Monaghan's artificial-viscosity parameter alpha, nu = alpha h c / (2 (d + 2))
// (Monaghan 2005, Rep. Prog. Phys. 68:1703, the shear viscosity his term
// corresponds to; alpha = 0.01-0.1 in dam-break codes).
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "models/fluids/fluids.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/fluids/sph_kernel.h"

#include "models/scenes/scene_entry.h"

namespace springlab {
namespace {

using Values = SceneValues;

constexpr int kWallLayers = 3;  // >= the support 2h = 2.6 l

// The box's lattice: nx x ny_wall (x nz) cells inside, the water's nx_water x
// ny_water (x nz) of them from the corner at the origin, and an obstacle:
// the cells [lo, hi) along each axis (none when empty) filled with fixed
// particles, as the walls.
struct Box {
  int dim = 2;
  double l = 1.0;
  int nx = 1, ny_wall = 1, nz = 1;  // nz: 1 in 2-D
  bool lid = false;                 // kWallLayers layers closing the box above ny_wall
  int nx_water = 1, ny_water = 1;
  int water_from = 0;  // the water's first cell along x
  std::array<int, 3> obstacle_lo{0, 0, 0}, obstacle_hi{0, 0, 0};
  bool in_obstacle(int i, int j, int k) const {
    return i >= obstacle_lo[0] && i < obstacle_hi[0] && j >= obstacle_lo[1] &&
           j < obstacle_hi[1] && k >= obstacle_lo[2] && k < obstacle_hi[2];
  }
  double count_obstacle() const {
    double n = 1.0;
    for (int r = 0; r < 3; ++r) n *= std::max(0, obstacle_hi[r] - obstacle_lo[r]);
    return n;
  }
  double count_water() const { return static_cast<double>(nx_water) * ny_water * nz; }
  double count_walls() const {
    const double z_out = dim == 3 ? nz + 2.0 * kWallLayers : 1.0;
    return (nx + 2.0 * kWallLayers) * (ny_wall + kWallLayers * (lid ? 2.0 : 1.0)) * z_out -
           static_cast<double>(nx) * ny_wall * nz;
  }
};

// (At most 1e8: a scene that large is refused by its particle count.)
int cells(double length, double l) {
  return static_cast<int>(std::clamp(std::round(length / l), 1.0, 1e8));
}

Eigen::Vector3d site(const Box& b, int i, int j, int k) {
  return {(i + 0.5) * b.l, (j + 0.5) * b.l, b.dim == 3 ? (k + 0.5) * b.l : 0.0};
}

// The water's particles, then the walls', as one fluid.
Scene fill_box(const Box& b, const Values& p, double water_height) {
  const double rho0 = p.at("density"), g = p.at("g");
  const double mass = lattice_mass(rho0, b.l, b.dim);
  Scene scene;
  scene.dimension = b.dim;
  scene.block<Gravity>().acceleration = {0.0, -g, 0.0};
  const int k_lo = b.dim == 3 ? 0 : 0, k_hi = b.dim == 3 ? b.nz : 1;
  for (int k = k_lo; k < k_hi; ++k) {
    for (int j = 0; j < b.ny_water; ++j) {
      for (int i = b.water_from; i < b.water_from + b.nx_water; ++i) {
        Particle q;
        q.x = site(b, i, j, k);
        q.mass = mass;
        scene.particles.push_back(q);
      }
    }
  }
  const int water = static_cast<int>(scene.particles.size());
  const int wk_lo = b.dim == 3 ? -kWallLayers : 0, wk_hi = b.dim == 3 ? b.nz + kWallLayers : 1;
  for (int k = wk_lo; k < wk_hi; ++k) {
    for (int j = -kWallLayers; j < b.ny_wall + (b.lid ? kWallLayers : 0); ++j) {
      for (int i = -kWallLayers; i < b.nx + kWallLayers; ++i) {
        const bool inside = i >= 0 && i < b.nx && j >= 0 && j < b.ny_wall &&
                            (b.dim == 2 || (k >= 0 && k < b.nz));
        if (inside && !b.in_obstacle(i, j, k)) continue;
        Particle q;
        q.x = site(b, i, j, k);
        q.mass = mass;
        q.fixed = true;
        scene.particles.push_back(q);
      }
    }
  }
  Fluid f;
  f.first = 0;
  f.count = static_cast<int>(scene.particles.size());
  (void)water;
  f.density = rho0;
  f.spacing = b.l;
  f.speed_of_sound = p.at("sound") * std::sqrt(std::abs(g) * water_height);
  const double h = kSmoothingPerSpacing * b.l;
  f.viscosity = p.at("alpha") * h * f.speed_of_sound / (2.0 * (b.dim + 2));
  scene.block<Fluids>().push_back(f);
  return scene;
}

Box dam_break_box(const Values& p) {
  const double a = p.at("a"), l = p.at("spacing");
  Box b;
  b.dim = static_cast<int>(p.at("dimension"));
  b.l = l;
  b.nx = cells(5.0 * a, l);
  b.ny_wall = cells(p.at("walls") * a, l);
  b.lid = p.at("lid") != 0.0;
  b.nz = b.dim == 3 ? cells(0.5 * a, l) : 1;
  b.nx_water = cells(a, l);
  b.ny_water = cells(2.0 * a, l);
  return b;
}

Box tank_box(const Values& p, double width, double depth) {
  const double l = p.at("spacing");
  Box b;
  b.dim = static_cast<int>(p.at("dimension"));
  b.l = l;
  b.nx = cells(width, l);
  b.ny_wall = cells(1.5 * depth, l);
  b.nz = b.dim == 3 ? cells(0.25 * width, l) : 1;
  b.nx_water = b.nx;
  b.ny_water = cells(depth, l);
  return b;
}

}  // namespace

// Martin and Moyce (1952): a column a wide and 2a high against the wall
// x = 0 of a box 5a long, released at t = 0. The box is closed by a lid at
// the walls' top (as SPHERIC's dam-break tanks are): the accurate methods
// throw water up the far wall higher than the walls (symplectic Euler at its
// acoustic step 0.73 m, BDF2 at 1/60 s 0.47 m, over walls 0.25 m high),
// which an open box lets fall outside, ending the run (docs/physics.md
// "Implicit steps on a fluid"); `lid=0` opens it.
Scene build_dam_break(const Values& p) {
  const Box b = dam_break_box(p);
  Scene scene = fill_box(b, p, b.ny_water * b.l);
  scene.name = "dam-break";
  return scene;
}

Scene build_tank(const Values& p) {
  const Box b = tank_box(p, p.at("width"), p.at("depth"));
  Scene scene = fill_box(b, p, b.ny_water * b.l);
  scene.name = "tank";
  return scene;
}

// The tank's water at rest, given the velocity of its first standing mode
// (linear theory, k = pi / L, H the depth, y up from the floor):
//   eta = A cos(k x) sin(w t),  w^2 = g k tanh(k H),
//   u = -(A w / sinh(k H)) sin(k x) cosh(k y),
//   v =  (A w / sinh(k H)) cos(k x) sinh(k y)     at t = 0,
// so the surface rises at x = 0 to A after a quarter period.
Scene build_sloshing(const Values& p) {
  const Box b = tank_box(p, p.at("width"), p.at("depth"));
  const double L = b.nx * b.l, H = b.ny_water * b.l;
  Scene scene = fill_box(b, p, H);
  scene.name = "sloshing";
  const double k = std::numbers::pi / L;
  const double w = std::sqrt(std::abs(p.at("g")) * k * std::tanh(k * H));
  const double scale = p.at("amplitude") * w / std::sinh(k * H);
  for (Particle& q : scene.particles) {
    if (q.fixed) continue;
    q.v.x() = -scale * std::sin(k * q.x.x()) * std::cosh(k * q.x.y());
    q.v.y() = scale * std::cos(k * q.x.x()) * std::sinh(k * q.x.y());
  }
  return scene;
}

// The dam break with an obstacle of MARIN (Kleefsman et al. 2005, J.
// Comput. Phys. 206:363; SPHERIC test 2, Issa and Violeau 2006), in 3-D, in
// the experiment's coordinates: a tank 3.22 m long (x) and 1 m across (z),
// walls 1 m high, the water 1.228 m long and 0.55 m deep across the tank's
// width against its far end x = 3.22 m, and a box on the floor at x in
// [0.6635, 0.8245], z in [0.2955, 0.6985], 0.161 m high. Every length is
// rounded to whole cells of the spacing.
namespace {

Box dam_break_obstacle_box(const Values& p) {
  const double l = p.at("spacing");
  Box b;
  b.dim = 3;
  b.l = l;
  b.nx = cells(3.22, l);
  b.ny_wall = cells(1.0, l);
  b.nz = cells(1.0, l);
  b.nx_water = cells(1.228, l);
  b.ny_water = cells(0.55, l);
  b.nx_water = std::min(b.nx_water, b.nx);
  b.water_from = b.nx - b.nx_water;
  if (p.at("obstacle") != 0.0) {
    // Its faces at the nearest cell boundaries, at least one cell each way.
    auto at = [l](double x) { return static_cast<int>(std::clamp(std::round(x / l), 0.0, 1e8)); };
    b.obstacle_lo = {at(0.6635), 0, at(0.2955)};
    b.obstacle_hi = {std::max(b.obstacle_lo[0] + 1, at(0.8245)), std::max(1, at(0.161)),
                     std::max(b.obstacle_lo[2] + 1, at(0.6985))};
  }
  return b;
}

}  // namespace

Scene build_dam_break_obstacle(const Values& p) {
  const Box b = dam_break_obstacle_box(p);
  Scene scene = fill_box(b, p, b.ny_water * b.l);
  scene.name = "dam-break-obstacle";
  return scene;
}

double dam_break_obstacle_particles(const Values& p) {
  const Box b = dam_break_obstacle_box(p);
  return b.count_water() + b.count_walls() + b.count_obstacle();
}

double dam_break_particles(const Values& p) {
  const Box b = dam_break_box(p);
  return b.count_water() + b.count_walls();
}
double tank_particles(const Values& p) {
  const Box b = tank_box(p, p.at("width"), p.at("depth"));
  return b.count_water() + b.count_walls();
}

namespace {

SceneCounts dam_break_counts(const SceneValues& p) { return {dam_break_particles(p), 0.0}; }
SceneCounts tank_counts(const SceneValues& p) { return {tank_particles(p), 0.0}; }
SceneCounts dam_break_obstacle_counts(const SceneValues& p) {
  return {dam_break_obstacle_particles(p), 0.0};
}

// The fluid scenes' shared parameters (builtin_fluids.cc).
std::vector<ParameterSpec> fluid_params(double spacing, double alpha) {
  return {param("spacing", spacing, "particle spacing l [m] (smoothing length 1.3 l)",
                Range::kPositive),
          param("dimension", 2, "2: particles in the x-y plane, 3: in space", Range::kWhole, 2, 3),
          param("density", 1000, "rest density rho0 [kg/m^3]", Range::kPositive),
          param("sound", 10, "speed of sound as a multiple of sqrt(g H), H the water's height",
                Range::kPositive),
          param("alpha", alpha, "viscosity as Monaghan's alpha: nu = alpha h c / (2 (d + 2))",
                Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kPositive)};
}

}  // namespace

const SceneEntry& dam_break_scene() {
  static const SceneEntry entry = scene_entry(
      "dam-break",
          "a water column a wide and 2a high released against the wall of a box 5a long "
          "(Martin and Moyce 1952), weakly compressible SPH with wall particles",
         with({param("a", 0.1, "width of the column (its height is 2a) [m]", Range::kPositive),
               param("walls", 2.5, "height of the box's walls as a multiple of a",
                     Range::kPositive),
               param("lid", 1,
                     "1: a lid closes the box at the walls' top, 0: open (water thrown higher "
                     "than the walls spills over them)",
                     Range::kZeroOrOne)},
              fluid_params(0.005, 0.02)),
         build_dam_break, dam_break_counts, "spacing");
  return entry;
}

const SceneEntry& dam_break_obstacle_scene() {
  static const SceneEntry entry = scene_entry(
      "dam-break-obstacle",
      "MARIN's 3-D dam break onto a box (Kleefsman et al. 2005, SPHERIC test 2): water 1.228 m "
      "long and 0.55 m deep across a tank 3.22 m x 1 m, released against a box on the floor",
      {param("spacing", 0.05, "particle spacing l [m] (smoothing length 1.3 l)", Range::kPositive),
       param("obstacle", 1, "1: the box on the floor, 0: none", Range::kZeroOrOne),
       param("density", 1000, "rest density rho0 [kg/m^3]", Range::kPositive),
       param("sound", 10, "speed of sound as a multiple of sqrt(g H), H the water's height",
             Range::kPositive),
       param("alpha", 0.02, "viscosity as Monaghan's alpha: nu = alpha h c / (2 (d + 2))",
             Range::kNonNegative),
       param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kPositive)},
      build_dam_break_obstacle, dam_break_obstacle_counts, "spacing");
  return entry;
}

const SceneEntry& sloshing_scene() {
  static const SceneEntry entry = scene_entry(
      "sloshing",
          "the first standing wave of a tank (period 2 pi / w, w^2 = g k tanh(k H), k = pi / "
          "width), started from rest level with the mode's velocity",
         with({param("amplitude", 0.01, "the wave's amplitude at the walls [m]", Range::kAny),
               param("width", 0.5, "width of the box [m]", Range::kPositive),
               param("depth", 0.25, "depth of the water [m]", Range::kPositive)},
              fluid_params(0.0125, 0.02)),
         build_sloshing, tank_counts, "spacing");
  return entry;
}

const SceneEntry& tank_scene() {
  static const SceneEntry entry = scene_entry(
      "tank",
          "water at rest in a box: it settles to hydrostatic pressure rho0 g depth",
         with({param("width", 0.5, "width of the box (and 4x its depth along z in 3-D) [m]",
                     Range::kPositive),
               param("depth", 0.25, "depth of the water [m]", Range::kPositive)},
              fluid_params(0.0125, 0.1)),
         build_tank, tank_counts, "spacing");
  return entry;
}

}  // namespace springlab
