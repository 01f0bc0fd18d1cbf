// The built-in finite-element scenes (docs/physics.md "Finite elements"): beam, membrane, block.
// How each mesh is split into elements:
//   - a grid cell (2-D) becomes two triangles split along a diagonal that
//     alternates from cell to cell (so the mesh has no preferred direction);
//   - a grid cube (3-D) becomes six tetrahedra around its main diagonal
//     (Kuhn's subdivision: one per ordering of the three axes), which
//     matches the neighbouring cubes face by face.
// Masses are the lumped masses of the elements (docs/physics.md "Finite elements"), computed here.
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "models/contact/contact.h"
#include "models/fem/fem.h"
#include "models/fem/fem_elements.h"
#include "models/springs/gravity.h"
#include "models/materials/material.h"

#include "models/scenes/scene_entry.h"

namespace springlab {

using Values = SceneValues;

namespace {

// The material of a built-in scene from its parameters (model: an index
// into the registry, as `springlab list` prints).
int add_material(Scene& scene, const Values& p, double thickness = 0.0) {
  MaterialSpec m;
  m.name = "material";
  m.model = std::string(material_models()[static_cast<std::size_t>(p.at("model"))]->name);
  m.young = p.at("young");
  m.poisson = p.at("poisson");
  m.density = p.at("density");
  if (thickness > 0.0) m.thickness = thickness;
  Materials& materials = scene.block<Materials>();
  materials.push_back(m);
  return static_cast<int>(materials.size()) - 1;
}

void set_lumped_masses(Scene& scene) {
  const std::vector<double> lumped = lumped_masses(scene);
  for (std::size_t i = 0; i < lumped.size(); ++i) {
    if (lumped[i] > 0.0) scene.particles[i].mass = lumped[i];
  }
}

Particle at(const Eigen::Vector3d& x, bool fixed) {
  Particle particle;
  particle.x = x;
  particle.fixed = fixed;
  return particle;
}

// Two triangles per cell of an (nx + 1) x (ny + 1) node grid, node (i, j)
// at index(i, j); the diagonal alternates with (i + j) % 2. Counter-
// clockwise in the grid's (i, j) plane.
template <typename Index>
void grid_triangles(int nx, int ny, Index index, int material, Triangles& out) {
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1),
                d = index(i, j + 1);
      if ((i + j) % 2 == 0) {
        out.push_back({{a, b, c}, material});
        out.push_back({{a, c, d}, material});
      } else {
        out.push_back({{a, b, d}, material});
        out.push_back({{b, c, d}, material});
      }
    }
  }
}

// Six tetrahedra per cube of an (nx + 1) x (ny + 1) x (nz + 1) node grid:
// from corner (0,0,0) to (1,1,1) along each ordering of the axes.
template <typename Index>
void grid_tetrahedra(int nx, int ny, int nz, Index index, int material, Tetrahedra& out) {
  static const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nz; ++k) {
        for (const auto& order : orders) {
          int corner[3] = {i, j, k};
          Tetrahedron t;
          t.material = material;
          t.nodes[0] = index(corner[0], corner[1], corner[2]);
          for (int s = 0; s < 3; ++s) {
            ++corner[order[s]];
            t.nodes[s + 1] = index(corner[0], corner[1], corner[2]);
          }
          out.push_back(t);
        }
      }
    }
  }
}

}  // namespace

// A cantilever of length L along x, clamped at x = 0 (the nodes there are
// fixed), bending under gravity (-y): 2-D, a plane-strain strip of height h
// in triangles; 3-D, a bar of square section h x h in tetrahedra.
Scene build_beam(const Values& p) {
  const int dim = static_cast<int>(p.at("dimension"));
  const int nx = static_cast<int>(p.at("nx")), ny = static_cast<int>(p.at("ny"));
  const double L = p.at("length"), h = p.at("height");
  Scene scene;
  scene.dimension = dim;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  const int material = add_material(scene, p);
  const int nz = dim == 3 ? ny : 0;
  auto index = [&](int i, int j, int k) { return (i * (ny + 1) + j) * (nz + 1) + k; };
  for (int i = 0; i <= nx; ++i) {
    for (int j = 0; j <= ny; ++j) {
      for (int k = 0; k <= nz; ++k) {
        const Eigen::Vector3d x(L * i / nx, h * j / ny - h / 2, dim == 3 ? h * k / nz - h / 2 : 0);
        scene.particles.push_back(at(x, i == 0));
      }
    }
  }
  if (dim == 2) {
    grid_triangles(nx, ny, [&](int i, int j) { return index(i, j, 0); }, material,
                   scene.block<Triangles>());
  } else {
    grid_tetrahedra(nx, ny, nz, index, material, scene.block<Tetrahedra>());
  }
  set_lumped_masses(scene);
  return scene;
}

// The cloth's set-up (an n x n sheet in the x-z plane, hung from its two
// top corners, under gravity) made of membrane triangles instead of springs.
Scene build_membrane(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double size = p.at("size");
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -9.81, 0.0};
  const int material = add_material(scene, p, p.at("thickness"));
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const bool fixed = r == 0 && (c == 0 || c == n - 1);
      scene.particles.push_back(at({c * size / (n - 1), 0.0, r * size / (n - 1)}, fixed));
    }
  }
  grid_triangles(n - 1, n - 1, [&](int c, int r) { return r * n + c; }, material,
                 scene.block<Triangles>());
  set_lumped_masses(scene);
  return scene;
}

// A box of side `size` in tetrahedra, its bottom `height` above the ground
// plane y = 0 (docs/physics.md "Contact with planes": penalty or barrier contact), falling under
// gravity and spinning about the vertical at `spin` rad/s, its starting pose turned by
// `angle` degrees from its rest shape: rigid motions, which the
// rotation-invariant models carry without strain and the linear model does
// not (a finite rotation strains it; an infinitesimal one, the spin's
// velocity field, costs it nothing).
Scene build_block(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double size = p.at("size"), height = p.at("height"), spin = p.at("spin");
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  const int material = add_material(scene, p);
  auto index = [&](int i, int j, int k) { return (i * (n + 1) + j) * (n + 1) + k; };
  // The starting pose: the rest shape turned by `angle` about the vertical
  // axis through its centre (x = z = 0).
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(p.at("angle") * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY())
          .toRotationMatrix();
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      for (int k = 0; k <= n; ++k) {
        const Eigen::Vector3d X(size * i / n - size / 2, height + size * j / n,
                                size * k / n - size / 2);
        const Eigen::Vector3d x = turn * X;
        Particle particle = at(x, false);
        if (x != X) particle.X = X;
        particle.v = Eigen::Vector3d(0.0, spin, 0.0).cross(Eigen::Vector3d(x.x(), 0.0, x.z()));
        scene.particles.push_back(particle);
      }
    }
  }
  grid_tetrahedra(n, n, n, index, material, scene.block<Tetrahedra>());
  set_lumped_masses(scene);
  scene.block<Planes>().push_back(Plane{});  // y = 0, normal +y
  Contact& contact = scene.block<Contact>();
  contact.model = p.at("contact") == 1.0 ? ContactModel::kBarrier : ContactModel::kPenalty;
  contact.stiffness = p.at("contact_stiffness");
  return scene;
}

namespace {

// Particles only (the element caps are far above what the parameters' ranges allow).
SceneCounts beam_counts(const SceneValues& p) {
  const double cross = p.at("dimension") == 3 ? (p.at("ny") + 1) * (p.at("ny") + 1) : p.at("ny") + 1;
  return {(p.at("nx") + 1) * cross, 0.0};
}
SceneCounts membrane_counts(const SceneValues& p) { return {p.at("n") * p.at("n"), 0.0}; }
SceneCounts block_counts(const SceneValues& p) {
  const double side = p.at("n") + 1;
  return {side * side * side, 0.0};
}

// The material parameters of the finite-element scenes: the model by its
// name in the material registry (or its index there, as before names).
std::vector<ParameterSpec> material_params(double young, double poisson, double density,
                                           const std::string& model) {
  std::vector<std::string> names;
  std::string meaning = "material model, by name or number:";
  for (const MaterialModel* m : material_models()) {
    meaning += (names.empty() ? " " : ", ") + std::to_string(names.size()) + " " +
               std::string(m->name);
    names.emplace_back(m->name);
  }
  return {choice("model", model, meaning, names),
          param("young", young, "Young's modulus E [Pa]", Range::kPositive),
          param("poisson", poisson, "Poisson's ratio nu, in (-1, 0.5)", Range::kAny),
          param("density", density, "density [kg/m^3] (lumped masses)", Range::kPositive)};
}

}  // namespace

const SceneEntry& beam_scene() {
  static const SceneEntry entry = scene_entry(
      "beam",
          "a cantilever clamped at x = 0 bending under gravity: 2-D plane-strain triangles or "
          "3-D tetrahedra",
         with({param("dimension", 2, "2: triangles (plane strain), 3: tetrahedra", Range::kWhole,
                     2, 3),
               param("nx", 20, "cells along the length", Range::kWhole, 1, 1000),
               param("ny", 4, "cells across the height (and the depth in 3-D)", Range::kWhole, 1,
                     40),
               param("length", 1, "length [m]", Range::kPositive),
               param("height", 0.1, "height (and depth in 3-D) [m]", Range::kPositive),
               param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]",
                     Range::kAny)},
              material_params(1e7, 0.3, 1000, "neo-hookean")),
         build_beam, beam_counts, "nx");
  return entry;
}

const SceneEntry& block_scene() {
  static const SceneEntry entry = scene_entry(
      "block",
          "a box of tetrahedra falling onto the ground plane y = 0, spinning about the vertical",
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
              material_params(1e5, 0.3, 1000, "neo-hookean")),
         build_block, block_counts, "n");
  return entry;
}

const SceneEntry& membrane_scene() {
  static const SceneEntry entry = scene_entry(
      "membrane",
          "the cloth's set-up made of membrane triangles (in-plane stretch and shear, no "
          "bending) instead of springs",
         with({param("n", 16, "particles per side (n x n grid)", Range::kWhole, 2, 1024),
               param("size", 1, "side length [m]", Range::kPositive),
               param("thickness", 0.001, "thickness [m]", Range::kPositive)},
              material_params(1e6, 0.3, 1000, "neo-hookean")),
         build_membrane, membrane_counts, "n");
  return entry;
}

}  // namespace springlab
