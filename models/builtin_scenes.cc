// Built-in scenes (docs/scenes.md "Built-in scenes"): each is a generator from named parameters to
// a Scene, checked afterwards by validate_scene like any scene file.
#include "models/builtin_scenes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "models/contact.h"
#include "models/decimal_text.h"
#include "models/drag.h"
#include "models/gravity.h"
#include "models/springs.h"
#include "models/wind.h"

namespace springlab {

// builtin_solids.cc: the finite-element scenes.
Scene build_beam(const std::map<std::string, double>& p);
Scene build_membrane(const std::map<std::string, double>& p);
Scene build_block(const std::map<std::string, double>& p);
// builtin_contact.cc: the friction scene.
Scene build_slope(const std::map<std::string, double>& p);
// builtin_bodies.cc: the rigid body scenes.
Scene build_tumbling_box(const std::map<std::string, double>& p);
Scene build_box_on_slope(const std::map<std::string, double>& p);
Scene build_box_pile(const std::map<std::string, double>& p);
// builtin_fluids.cc: the fluid scenes.
Scene build_dam_break(const std::map<std::string, double>& p);
Scene build_tank(const std::map<std::string, double>& p);
Scene build_sloshing(const std::map<std::string, double>& p);
Scene build_dam_break_obstacle(const std::map<std::string, double>& p);
double dam_break_obstacle_particles(const std::map<std::string, double>& p);
double dam_break_particles(const std::map<std::string, double>& p);
double tank_particles(const std::map<std::string, double>& p);
Scene build_box_chain(const std::map<std::string, double>& p);

namespace {

// How a parameter's value is restricted (every value must be finite).
enum class Range { kAny, kNonNegative, kPositive, kWhole, kZeroOrOne };

struct ParameterSpec {
  SceneParameter parameter;
  Range range = Range::kAny;
  double min = 0.0;  // kWhole only: inclusive bounds
  double max = 0.0;
};

using Values = std::map<std::string, double>;

// How many particles and springs a generator would make: compared with the
// caps of scene.h before anything is allocated.
struct Counts {
  double particles = 0.0;
  double springs = 0.0;
};

struct Generator {
  BuiltinScene info;
  std::vector<ParameterSpec> specs;
  Scene (*build)(const Values&);
  Counts (*counts)(const Values&) = nullptr;  // nullptr: a fixed, small scene
  const char* size_parameter = nullptr;        // the parameter the counts grow with
};

std::string format_number(double value) { return shortest_decimal(value); }

// The whole text must be one finite decimal number: "", "1x", "nan", "inf",
// " 1" are refused (strtod would accept some of them, or a prefix).
std::optional<double> parse_number(const std::string& text) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+' && last - first > 1 && first[1] != '-') ++first;
  double value = 0.0;
  const char* end = read_decimal(first, last, value);
  if (end != last || !std::isfinite(value)) return std::nullopt;
  return value;
}

// A count as a whole number (format_number would write 1e+07).
std::string format_count(double value) {
  return value == std::floor(value) && std::abs(value) < 1e15
             ? std::to_string(static_cast<long long>(value))
             : format_number(value);
}

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
        format_number(rest) + ", amplitude " + format_number(amplitude) + ")");
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

Counts chain_counts(const Values& p) { return {p.at("n"), p.at("n") - 1}; }

// Particles only (the element caps are far above what the parameters' ranges allow).
Counts beam_counts(const Values& p) {
  const double cross = p.at("dimension") == 3 ? (p.at("ny") + 1) * (p.at("ny") + 1) : p.at("ny") + 1;
  return {(p.at("nx") + 1) * cross, 0.0};
}
Counts membrane_counts(const Values& p) { return {p.at("n") * p.at("n"), 0.0}; }
Counts block_counts(const Values& p) {
  const double side = p.at("n") + 1;
  return {side * side * side, 0.0};
}



Counts dam_break_counts(const Values& p) { return {dam_break_particles(p), 0.0}; }
Counts tank_counts(const Values& p) { return {tank_particles(p), 0.0}; }
Counts dam_break_obstacle_counts(const Values& p) { return {dam_break_obstacle_particles(p), 0.0}; }

// Structural 2 n (n-1), shear 2 (n-1)^2, bend 2 n (n-2), as build_cloth makes them.
Counts cloth_counts(const Values& p) {
  const double n = p.at("n");
  return {n * n, 2 * n * (n - 1) + 2 * (n - 1) * (n - 1) + 2 * n * (n - 2)};
}

ParameterSpec param(const char* name, double value, const char* meaning, Range range,
                    double min = 0.0, double max = 0.0) {
  return {{name, value, meaning}, range, min, max};
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

// The material parameters of the finite-element scenes.
std::vector<ParameterSpec> material_params(double young, double poisson, double density,
                                           double model) {
  return {param("model", model,
                "material model: 0 linear, 1 corotated, 2 stvk, 3 neo-hookean, "
                "4 stable-neo-hookean",
                Range::kWhole, 0, 4),
          param("young", young, "Young's modulus E [Pa]", Range::kPositive),
          param("poisson", poisson, "Poisson's ratio nu, in (-1, 0.5)", Range::kAny),
          param("density", density, "density [kg/m^3] (lumped masses)", Range::kPositive)};
}

std::vector<ParameterSpec> with(std::vector<ParameterSpec> a, const std::vector<ParameterSpec>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Sorted by name.
const std::vector<Generator>& generators() {
  static const std::vector<Generator> table = [] {
    std::vector<Generator> list = {
        {{"beam",
          "a cantilever clamped at x = 0 bending under gravity: 2-D plane-strain triangles or "
          "3-D tetrahedra",
          {}},
         with({param("dimension", 2, "2: triangles (plane strain), 3: tetrahedra", Range::kWhole,
                     2, 3),
               param("nx", 20, "cells along the length", Range::kWhole, 1, 1000),
               param("ny", 4, "cells across the height (and the depth in 3-D)", Range::kWhole, 1,
                     40),
               param("length", 1, "length [m]", Range::kPositive),
               param("height", 0.1, "height (and depth in 3-D) [m]", Range::kPositive),
               param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]",
                     Range::kAny)},
              material_params(1e7, 0.3, 1000, 3)),
         build_beam, beam_counts, "nx"},
        {{"block",
          "a box of tetrahedra falling onto the ground plane y = 0, spinning about the vertical",
          {}},
         with({param("n", 4, "cells per side (6 tetrahedra each)", Range::kWhole, 1, 60),
               param("size", 0.2, "side length [m]", Range::kPositive),
               param("height", 0.5, "height of its bottom above y = 0 [m]", Range::kAny),
               param("spin", 2, "angular velocity about the vertical [rad/s]", Range::kAny),
               param("angle", 0,
                     "the starting pose turned about the vertical through the centre [degrees] "
                     "(the rest shape is not: a rigid rotation, which only the linear model "
                     "resists)",
                     Range::kAny),
               param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
               param("contact", 0, "ground contact: 0 penalty, 1 barrier (IPC)", Range::kZeroOrOne),
               param("contact_stiffness", 1e4,
                     "penalty k_c or barrier kappa [N/m] (barrier distance 0.01 m)",
                     Range::kPositive)},
              material_params(1e5, 0.3, 1000, 3)),
         build_block, block_counts, "n"},
        {{"chain",
          "n masses in a line joined by springs, the first fixed; hanging under gravity or "
          "released from horizontal",
          {}},
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
         build_chain, chain_counts, "n"},
        {{"cloth",
          "n x n grid in 3-D with structural, shear and bend springs, two top corners fixed, "
          "gravity, optional wind",
          {}},
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
         build_cloth, cloth_counts, "n"},
        {{"membrane",
          "the cloth's set-up made of membrane triangles (in-plane stretch and shear, no "
          "bending) instead of springs",
          {}},
         with({param("n", 16, "particles per side (n x n grid)", Range::kWhole, 2, 1024),
               param("size", 1, "side length [m]", Range::kPositive),
               param("thickness", 0.001, "thickness [m]", Range::kPositive)},
              material_params(1e6, 0.3, 1000, 3)),
         build_membrane, membrane_counts, "n"},
        {{"oscillator",
          "one undamped linear spring, no gravity, mass released stretched: exact solution known",
          {}},
         {param("k", 100, "spring stiffness [N/m]", Range::kPositive),
          param("mass", 1, "mass of the moving particle [kg]", Range::kPositive),
          // Rest 0 makes the spring linear in every direction (F = -k x), so
          // the linear stability analysis holds even as a run blows up; with
          // rest > 0 it is linear only while the mass stays beyond the anchor.
          param("rest", 0, "rest length of the spring [m]; 0 = linear in every direction",
                Range::kNonNegative),
          param("amplitude", 0.1, "initial stretch beyond the rest length [m]", Range::kAny)},
         build_oscillator},
        {{"slope",
          "one particle resting on (or launched down) an inclined plane with Coulomb friction: "
          "sticks when tan(angle) < friction, else slides at g (sin - friction cos)",
          {}},
         {param("angle", 30, "inclination of the plane [degrees], in [0, 90)", Range::kAny),
          param("friction", 0.5, "Coulomb coefficient mu of the plane", Range::kNonNegative),
          param("speed", 0, "initial speed down the slope [m/s]", Range::kAny),
          param("mass", 1, "mass of the particle [kg]", Range::kPositive),
          param("length", 10,
                "length of the slope [m]: a fixed particle marks its foot (it sets the scene's "
                "size in the energy scale E_s)",
                Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c [N/m]", Range::kPositive),
          param("smoothing", 1e-3, "friction's smoothing speed eps_v [m/s]", Range::kPositive)},
         build_slope},
        {{"spring",
          "the course's example: a mass hanging from a fixed point by one spring, with gravity and "
          "drag",
          {}},
         {param("k", 100, "spring stiffness [N/m]", Range::kNonNegative),
          param("mass", 1, "mass of the hanging particle [kg]", Range::kPositive),
          param("rest", 1, "rest length, also the initial length [m]", Range::kPositive),
          param("drag", 0.5, "drag coefficient [kg/s]", Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny)},
         build_spring},
        // builtin_bodies.cc: rigid bodies (affine bodies).
        {{"tumbling-box",
          "a box with three distinct principal moments spun about its middle axis, no gravity: "
          "it flips over and back (the Dzhanibekov effect)",
          {}},
         {param("size_x", 0.3, "side along x, the axis of least inertia [m]", Range::kPositive),
          param("size_y", 0.2, "side along y, the middle axis, spun about [m]", Range::kPositive),
          param("size_z", 0.1, "side along z, the axis of most inertia [m]", Range::kPositive),
          param("spin", 6.283185307179586, "angular velocity about y [rad/s]", Range::kAny),
          param("perturbation", 0.01, "angular velocity about x and z, as a fraction of spin",
                Range::kAny),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa of kappa V |A^T A - I|^2 [Pa]", Range::kPositive)},
         build_tumbling_box},
        {{"box-on-slope",
          "a cube resting on (or launched down) an inclined plane with Coulomb friction: sticks "
          "when tan(angle) < friction, else slides at g (sin - friction cos)",
          {}},
         {param("angle", 20, "inclination of the plane [degrees], in [0, 90)", Range::kAny),
          param("friction", 0.5, "Coulomb coefficient mu of the plane", Range::kNonNegative),
          param("speed", 0, "initial speed down the slope [m/s]", Range::kAny),
          param("size", 0.2, "side of the cube [m]", Range::kPositive),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c per vertex [N/m]",
                Range::kPositive),
          param("smoothing", 1e-3, "friction's smoothing speed eps_v [m/s]", Range::kPositive)},
         build_box_on_slope},
        {{"dam-break",
          "a water column a wide and 2a high released against the wall of a box 5a long "
          "(Martin and Moyce 1952), weakly compressible SPH with wall particles",
          {}},
         with({param("a", 0.1, "width of the column (its height is 2a) [m]", Range::kPositive)},
              fluid_params(0.005, 0.02)),
         build_dam_break, dam_break_counts, "spacing"},
        {{"dam-break-obstacle",
          "MARIN's 3-D dam break onto a box (Kleefsman et al. 2005, SPHERIC test 2): water 1.228 m "
          "long and 0.55 m deep across a tank 3.22 m x 1 m, released against a box on the floor",
          {}},
         {param("spacing", 0.05, "particle spacing l [m] (smoothing length 1.3 l)",
                Range::kPositive),
          param("obstacle", 1, "1: the box on the floor, 0: none", Range::kZeroOrOne),
          param("density", 1000, "rest density rho0 [kg/m^3]", Range::kPositive),
          param("sound", 10, "speed of sound as a multiple of sqrt(g H), H the water's height",
                Range::kPositive),
          param("alpha", 0.02, "viscosity as Monaghan's alpha: nu = alpha h c / (2 (d + 2))",
                Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kPositive)},
         build_dam_break_obstacle, dam_break_obstacle_counts, "spacing"},
        {{"tank",
          "water at rest in a box: it settles to hydrostatic pressure rho0 g depth",
          {}},
         with({param("width", 0.5, "width of the box (and 4x its depth along z in 3-D) [m]",
                     Range::kPositive),
               param("depth", 0.25, "depth of the water [m]", Range::kPositive)},
              fluid_params(0.0125, 0.1)),
         build_tank, tank_counts, "spacing"},
        {{"sloshing",
          "the first standing wave of a tank (period 2 pi / w, w^2 = g k tanh(k H), k = pi / "
          "width), started from rest level with the mode's velocity",
          {}},
         with({param("amplitude", 0.01, "the wave's amplitude at the walls [m]", Range::kAny),
               param("width", 0.5, "width of the box [m]", Range::kPositive),
               param("depth", 0.25, "depth of the water [m]", Range::kPositive)},
              fluid_params(0.0125, 0.02)),
         build_sloshing, tank_counts, "spacing"},
        {{"box-pile",
          "n boxes, each shrink times the one below, turned and tilted, dropped onto one "
          "another and onto the ground, with friction",
          {}},
         {param("n", 3, "number of boxes", Range::kWhole, 1, 1000),
          param("size", 0.2, "longest side of the bottom box (sides size, 0.75 size, 0.5 size) [m]",
                Range::kPositive),
          param("shrink", 0.7, "each box's sides over the one's below, in (0, 1]", Range::kPositive),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("friction", 0.5, "Coulomb coefficient mu of the ground and of every box",
                Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c per vertex [N/m]",
                Range::kPositive)},
         build_box_pile},
        {{"box-chain",
          "n boxes hinged end to end by stiff zero-length springs between body points, the "
          "first to a fixed point, released from horizontal: a multiple pendulum",
          {}},
         {param("n", 3, "number of boxes", Range::kWhole, 1, 1000),
          param("length", 0.2, "length of each box along the chain [m]", Range::kPositive),
          param("width", 0.05, "its two other sides [m]", Range::kPositive),
          param("k", 1e4, "stiffness of each joint's spring [N/m]", Range::kNonNegative),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny)},
         build_box_chain},
    };
    for (Generator& g : list) {
      for (const ParameterSpec& spec : g.specs) g.info.parameters.push_back(spec.parameter);
    }
    std::sort(list.begin(), list.end(),
              [](const Generator& a, const Generator& b) { return a.info.name < b.info.name; });
    return list;
  }();
  return table;
}

const Generator* find_generator(const std::string& name) {
  for (const Generator& g : generators()) {
    if (g.info.name == name) return &g;
  }
  return nullptr;
}

// Refuses a scene over the caps of scene.h before it is built.
void check_counts(const std::string& label, const Generator& g, const Values& values) {
  if (g.counts == nullptr) return;
  const Counts counts = g.counts(values);
  auto check = [&](double count, std::size_t cap, const char* what) {
    if (count > static_cast<double>(cap)) {
      const std::string parameter = g.size_parameter;
      throw SceneError(label + ": parameter '" + parameter + "' = " +
                       format_count(values.at(parameter)) + " would make " +
                       format_count(count) + " " + what + ", over the cap of " +
                       std::to_string(cap) + " per scene");
    }
  };
  check(counts.particles, kMaxSceneParticles, "particles");
  check(counts.springs, kMaxSceneSprings, "springs");
}

void check_range(const std::string& label, const ParameterSpec& spec, double value) {
  const std::string prefix = label + ": parameter '" + spec.parameter.name + "' must be ";
  const std::string got = " (got " + format_number(value) + ")";
  switch (spec.range) {
    case Range::kAny:
      break;
    case Range::kNonNegative:
      if (value < 0) throw SceneError(prefix + ">= 0" + got);
      break;
    case Range::kPositive:
      if (value <= 0) throw SceneError(prefix + "> 0" + got);
      break;
    case Range::kWhole:
      if (value != std::floor(value) || value < spec.min || value > spec.max) {
        throw SceneError(prefix + "a whole number in [" +
                         std::to_string(static_cast<long long>(spec.min)) + ", " +
                         std::to_string(static_cast<long long>(spec.max)) + "]" + got);
      }
      break;
    case Range::kZeroOrOne:
      if (value != 0 && value != 1) throw SceneError(prefix + "0 or 1" + got);
      break;
  }
}

}  // namespace

const std::vector<BuiltinScene>& builtin_scenes() {
  static const std::vector<BuiltinScene> scenes = [] {
    std::vector<BuiltinScene> out;
    for (const Generator& g : generators()) out.push_back(g.info);
    return out;
  }();
  return scenes;
}

bool is_builtin_scene(const std::string& name) { return find_generator(name) != nullptr; }

Scene make_builtin_scene(const std::string& name,
                         const std::vector<std::pair<std::string, std::string>>& overrides) {
  const Generator* generator = find_generator(name);
  if (generator == nullptr) {
    std::string names;
    for (const Generator& g : generators()) names += (names.empty() ? "" : ", ") + g.info.name;
    throw SceneError("unknown built-in scene '" + name + "' (built-in scenes: " + names + ")");
  }
  const std::string label = "scene '" + name + "'";
  Values values;
  for (const ParameterSpec& spec : generator->specs)
    values[spec.parameter.name] = spec.parameter.default_value;

  // Each value is checked as given; a key given twice keeps the last value.
  for (const auto& [key_binding, text] : overrides) {
    const std::string& key = key_binding;  // clang 14 cannot capture a structured binding
    const auto spec = std::find_if(generator->specs.begin(), generator->specs.end(),
                                   [&](const ParameterSpec& s) { return s.parameter.name == key; });
    if (spec == generator->specs.end()) {
      std::string names;
      for (const ParameterSpec& s : generator->specs)
        names += (names.empty() ? "" : ", ") + s.parameter.name;
      throw SceneError(label + ": unknown parameter '" + key + "' (parameters: " + names + ")");
    }
    const std::optional<double> value = parse_number(text);
    if (!value)
      throw SceneError(label + ": parameter '" + key + "' must be a finite number (got '" + text +
                       "')");
    check_range(label, *spec, *value);
    values[key] = *value;
  }

  check_counts(label, *generator, values);
  Scene scene = generator->build(values);
  scene.name = name;
  validate_scene(scene, label);  // a safety net: a generator bug is reported, not simulated
  return scene;
}

}  // namespace springlab
