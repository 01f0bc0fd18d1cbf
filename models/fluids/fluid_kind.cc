// The "fluid" element kind: the scene key "fluids" (docs/physics.md "Scene
// files", "Fluids"), its checks, and the pressure force of its particles
// (fluid_pressure_force.cc), whose equation-of-state energy is the
// "pressure" column. Each fluid is
//   {"particles": [first, count], "density": rho0, "spacing": l,
//    "speed_of_sound": c, "viscosity": nu, "kernel": "cubic-spline"}
// (viscosity 0 and kernel "cubic-spline" when absent), or the block form
// with "box": [[x0, y0(, z0)], [x1, y1(, z1)]] instead of "particles",
// which fills the box with new particles at the spacing (fill_box).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "models/core/element_kind.h"
#include "models/fluids/fluid_forces.h"
#include "models/fluids/fluid_pattern.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_kernel.h"

namespace springlab {
namespace {

// Two particles of a fluid at exactly the same place: its first such pair
// (scene indices, smaller first), found by sorting its particles by position.
bool coincident_pair(const Scene& scene, const Fluid& f, int& i, int& j) {
  std::vector<int> order(static_cast<std::size_t>(f.count));
  std::iota(order.begin(), order.end(), f.first);
  auto at = [&](int s) { return scene.particles[static_cast<std::size_t>(s)].x; };
  auto less = [&](int a, int b) {
    const Eigen::Vector3d xa = at(a), xb = at(b);
    for (int r = 0; r < 3; ++r) {
      if (xa[r] != xb[r]) return xa[r] < xb[r];
    }
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  bool found = false;
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (at(order[k - 1]) != at(order[k])) continue;
    const int a = std::min(order[k - 1], order[k]), b = std::max(order[k - 1], order[k]);
    if (!found || a < i || (a == i && b < j)) {
      i = a;
      j = b;
      found = true;
    }
  }
  return found;
}

void check_fluid(const Reporter& r, const std::string& where, const Fluid& f, const Scene& scene) {
  check_positive(r, field(where, "density"), f.density);
  check_positive(r, field(where, "spacing"), f.spacing);
  check_positive(r, field(where, "speed_of_sound"), f.speed_of_sound);
  check_nonnegative(r, field(where, "viscosity"), f.viscosity);
  // What double precision holds: the lattice's particle mass rho0 l^d and
  // the scale of the kernel's gradient, ~ l^-(d+1), normal and finite (at
  // spacing 1e-150 the particles were massless and the gradients infinite).
  const double mass = lattice_mass(f.density, f.spacing, scene.dimension);
  const double volume_and_gradient = std::pow(f.spacing, scene.dimension + 1);
  if (!(mass >= std::numeric_limits<double>::min()) || !std::isfinite(mass) ||
      !(volume_and_gradient >= std::numeric_limits<double>::min()) ||
      !std::isfinite(volume_and_gradient)) {
    r.fail(field(where, "spacing"),
           shortest_text(f.spacing) + " m with density " + shortest_text(f.density) +
               " kg/m^" + std::to_string(scene.dimension) + " gives particles of mass " +
               shortest_text(mass) +
               " kg and kernel gradients of order spacing^-" + std::to_string(scene.dimension + 1) +
               ": outside what double precision holds");
  }
  const std::size_t n = scene.particles.size();
  check_particle_index(r, where, "particles[0]", f.first, n);
  if (f.count < 1) r.fail(field(where, "particles[1]"), "must be at least 1 (got " + std::to_string(f.count) + ")");
  check_particle_index(r, where, "particles[1]", static_cast<double>(f.first) + f.count - 1, n);
  int i = 0, j = 0;
  if (coincident_pair(scene, f, i, j)) {
    r.fail(where, "particles " + std::to_string(i) + " and " + std::to_string(j) +
                      " are at exactly the same place: SPH needs distinct positions (its "
                      "pairs' directions are undefined); move one of them");
  }
}

void check_disjoint(const Reporter& r, const Fluids& fluids) {
  for (std::size_t k = 0; k < fluids.size(); ++k) {
    for (std::size_t m = 0; m < k; ++m) {
      const Fluid &a = fluids[m], &b = fluids[k];
      if (a.first < b.first + b.count && b.first < a.first + a.count) {
        r.fail(element("fluids", k), "its particles overlap those of fluids[" + std::to_string(m) +
                                         "]: a particle belongs to one fluid");
      }
    }
  }
}

// The block form {"box": [[x0, y0(, z0)], [x1, y1(, z1)]], "spacing": l}:
// the box's lattice of cells of side l (round((x1 - x0) / l) along each
// axis, at least 1), one free particle at rest at each cell's centre, of
// mass lattice_mass (fluids.h), appended to the scene's particles; the
// fluid is that run of particles.
void fill_box(const Reporter& r, const std::string& where, const Json& box, Fluid& f,
              Scene& scene) {
  require_array(r, where, box);
  if (box.size() != 2) {
    r.fail(where, "must be [[corner], [corner]] (got " + std::to_string(box.size()) + " entries)");
  }
  const int dim = scene.dimension;
  const Eigen::Vector3d lo = read_vector(r, where + "[0]", box[0], dim);
  const Eigen::Vector3d hi = read_vector(r, where + "[1]", box[1], dim);
  double total = 1.0;
  std::array<long, 3> cells{1, 1, 1};
  for (int k = 0; k < dim; ++k) {
    if (!(hi[k] > lo[k])) {
      r.fail(where, "its second corner must lie above its first along every axis (axis " +
                        std::to_string(k) + ": " + shortest_text(lo[k]) + " to " +
                        shortest_text(hi[k]) + ")");
    }
    const double n = std::max(1.0, std::round((hi[k] - lo[k]) / f.spacing));
    total *= n;
    if (!(total <= static_cast<double>(kMaxSceneParticles - scene.particles.size()))) {
      r.fail(where, "would make more than " + std::to_string(kMaxSceneParticles) +
                        " particles in the scene at this spacing");
    }
    cells[static_cast<std::size_t>(k)] = static_cast<long>(n);
  }
  const double mass = lattice_mass(f.density, f.spacing, dim);
  f.first = static_cast<int>(scene.particles.size());
  for (long k = 0; k < cells[2]; ++k) {
    for (long j = 0; j < cells[1]; ++j) {
      for (long i = 0; i < cells[0]; ++i) {
        Particle p;
        p.x = lo + f.spacing * Eigen::Vector3d(i + 0.5, j + 0.5, dim == 3 ? k + 0.5 : 0.0);
        if (dim == 2) p.x.z() = 0.0;
        p.mass = mass;
        scene.particles.push_back(p);
      }
    }
  }
  f.count = static_cast<int>(scene.particles.size()) - f.first;
}

void read_fluids(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("fluids")) return;
  const Json& list = document.at("fluids");
  require_array(r, "fluids", list);
  if (list.size() > kMaxSceneFluids) {
    r.fail("fluids", "more than " + std::to_string(kMaxSceneFluids) + " fluids");
  }
  Fluids& out = scene.block<Fluids>();
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string where = element("fluids", k);
    const Json& j = list[k];
    require_object(r, where, j);
    check_keys(r, where, j,
               {"particles", "box", "density", "spacing", "speed_of_sound", "viscosity", "kernel"},
               {"density", "spacing", "speed_of_sound"});
    if (j.contains("particles") == j.contains("box")) {
      r.fail(where, "needs either \"particles\": [first, count] or \"box\": [[corner], "
                    "[corner]] (exactly one)");
    }
    Fluid f;
    f.density = read_number(r, field(where, "density"), j.at("density"));
    f.spacing = read_number(r, field(where, "spacing"), j.at("spacing"));
    if (j.contains("box")) {
      check_positive(r, field(where, "density"), f.density);
      check_positive(r, field(where, "spacing"), f.spacing);
      fill_box(r, field(where, "box"), j.at("box"), f, scene);
    } else {
      const std::string range = field(where, "particles");
      require_array(r, range, j.at("particles"));
      if (j.at("particles").size() != 2) {
        r.fail(range, "must be [first, count] (got " + std::to_string(j.at("particles").size()) +
                          " numbers)");
      }
      const double first = read_number(r, range + "[0]", j.at("particles")[0]);
      const double count = read_number(r, range + "[1]", j.at("particles")[1]);
      f.first = check_particle_index(r, where, "particles[0]", first, scene.particles.size());
      if (count != std::floor(count) || count < 1) {
        r.fail(range + "[1]", "must be a whole number >= 1 (got " + shortest_text(count) + ")");
      }
      check_particle_index(r, where, "particles[1]", first + count - 1, scene.particles.size());
      f.count = static_cast<int>(count);
    }
    f.speed_of_sound = read_number(r, field(where, "speed_of_sound"), j.at("speed_of_sound"));
    if (j.contains("viscosity")) f.viscosity = read_number(r, field(where, "viscosity"), j.at("viscosity"));
    if (j.contains("kernel")) {
      const Json& kernel = j.at("kernel");
      if (!kernel.is_string() || kernel.get<std::string>() != "cubic-spline") {
        r.fail(field(where, "kernel"),
               "unknown kernel " + (kernel.is_string() ? "'" + printable(kernel.get<std::string>()) + "'"
                                                       : kernel.dump()) +
                   " (known: cubic-spline)");
      }
    }
    check_fluid(r, where, f, scene);
    out.push_back(f);
  }
  check_disjoint(r, out);
}

void validate_fluids(const Scene& scene, const Reporter& r) {
  const Fluids& fluids = scene.get<Fluids>();
  if (fluids.size() > kMaxSceneFluids) {
    r.fail("fluids", "more than " + std::to_string(kMaxSceneFluids) + " fluids");
  }
  for (std::size_t k = 0; k < fluids.size(); ++k) check_fluid(r, element("fluids", k), fluids[k], scene);
  check_disjoint(r, fluids);
}

void write_fluids(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr || fluids->empty()) return;
  JsonLines lines;
  for (const Fluid& f : *fluids) {
    lines.add("{\"particles\": [" + std::to_string(f.first) + ", " + std::to_string(f.count) +
              "], \"density\": " + json_number(f.density) + ", \"spacing\": " +
              json_number(f.spacing) + ", \"speed_of_sound\": " + json_number(f.speed_of_sound) +
              ", \"viscosity\": " + json_number(f.viscosity) + ", \"kernel\": \"cubic-spline\"}");
  }
  entries.emplace_back("fluids", lines.str());
}

// The kind's part of the model's memory (memory_estimate.h), per fluid
// particle (walls included): its SPH arrays and its pairs within the
// kernel's support 2h (2h = 2.6 spacings: about 10.6 pairs a particle in
// 2-D, 36.8 in 3-D on a lattice; a pair holds its two indices, its
// separation and distance; a quarter more for the vectors' spare capacity).
// Measured, whole processes (peak resident, symplectic Euler, the
// particles' own arrays included): the 790,646-particle tank (2-D) 792 MB
// (1.08 GB with --json), a 83,018-particle tank 93 MB, a 47,888-particle
// 3-D dam break 96 MB. 448 bytes a particle besides the pairs (its SPH
// arrays and the neighbour grid's cells) give 1.10 GB, 115 MB and 141 MB:
// the estimate errs high, never low, on all three. The neighbour list
// (sph_particles.h) keeps, besides, the search's pairs within (1 + kSkin) 2h
// twice (the grid's and the list's, 8 bytes each): the 83,018-particle tank
// 94 -> 122 MB measured, 143 MB estimated. Once the pattern is built,
// the pressure's blocks couple the particles within 2.25 supports (107 in
// 2-D, 838 in 3-D: fluid_pattern.h), the viscosity's within 1.25, and each
// term keeps its pairs (8 bytes).
void fluid_memory(const Scene& scene, MemoryEstimate& out) {
  const Fluids* fluids = scene.find<Fluids>();
  if (fluids == nullptr || fluids->empty()) return;
  const int dim = scene.dimension;
  auto within = [dim](double spacings) {  // lattice points in a ball of that radius
    return dim == 2 ? std::numbers::pi * spacings * spacings
                    : 4.0 / 3.0 * std::numbers::pi * spacings * spacings * spacings;
  };
  const double support = 2.0 * kSmoothingPerSpacing;  // in spacings
  double particles = 0.0, blocks = 0.0, distinct = 0.0, slots = 0.0;
  for (const Fluid& f : *fluids) {
    const double n = static_cast<double>(f.count);
    particles += n;
    const double pressure = within((2.0 + FluidPattern::kSkin) * support);
    const double viscosity = f.viscosity > 0.0 ? within((1.0 + FluidPattern::kSkin) * support) : 0.0;
    blocks += n * (pressure + viscosity);
    distinct += n * pressure;
    slots += n * 0.5 * (pressure + viscosity) * sizeof(std::pair<int, int>);
  }
  MemoryPart part;
  part.what = std::to_string(static_cast<long long>(particles)) + " fluid particles";
  part.bytes = particles * (448.0 + 1.25 * 0.5 *
                                        (within(support) * (16.0 + 8.0 * dim) +
                                         within((1.0 + SphParticles::kSkin) * support) * 16.0));
  part.pattern_blocks = blocks;
  part.distinct_blocks = distinct;
  part.slot_bytes = slots;
  out.parts.push_back(std::move(part));
}

std::size_t count_fluids(const Scene& scene) { return scene.get<Fluids>().size(); }

// For the shared tests: every particle one fluid of spacing 1 (the random
// particles lie about 1 apart, so most pairs are within the support 2.6),
// with a viscosity. kAny: rho0 at 0.7-0.9 of the largest density, so the
// densest particles are compressed by at most 1.4 (pressures of the order of
// rho0 c^2, whose central differences keep their digits) and the others
// have none (a random density is never within round-off of the kink at
// rho0). kDefinite: rho0 above every density: no pressure, so -dF/dx = 0
// is semidefinite.
void add_random_fluid(Scene& scene, std::mt19937& rng, RandomStates states) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Fluid f;
  f.first = 0;
  f.count = static_cast<int>(scene.particles.size());
  f.spacing = 1.0;
  f.speed_of_sound = 1.0 + u(rng);
  f.viscosity = 0.1 + 0.2 * u(rng);
  const CubicSpline w(kSmoothingPerSpacing * f.spacing, scene.dimension);
  double lowest = INFINITY, highest = 0.0;
  for (const Particle& p : scene.particles) {
    double rho = 0.0;
    for (const Particle& q : scene.particles) rho += q.mass * w.value((p.x - q.x).norm());
    lowest = std::min(lowest, rho);
    highest = std::max(highest, rho);
  }
  (void)lowest;
  f.density = states == RandomStates::kAny ? (0.7 + 0.2 * u(rng)) * highest : 2.0 * highest;
  scene.block<Fluids>().push_back(f);
}

}  // namespace

// (fluid_viscosity_force.cc: the viscosity of a scene's fluids.)
bool scene_has_viscous_fluid(const Scene& scene) {
  for (const Fluid& f : scene.get<Fluids>()) {
    if (f.viscosity > 0.0) return true;
  }
  return false;
}

const ElementKind& fluid_kind() {
  static const ElementKind kind = {
      .name = "fluid",
      .refers_to_particles = true,
      .keys = {{.name = "fluids", .cap = kMaxSceneFluids, .count = count_fluids}},
      .read = read_fluids,
      .validate = validate_fluids,
      .write = write_fluids,
      .make = make_fluid_pressure_force,
      .energy = {.name = "pressure", .counts_with_spring = true},
      .divergence_rule = make_fluid_divergence_rule,
      .divergence_sentence = kFluidDivergenceSentence,
      .memory = fluid_memory,
      .add_random = add_random_fluid,
  };
  return kind;
}

}  // namespace springlab
