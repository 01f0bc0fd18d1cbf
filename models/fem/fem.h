// Finite elements in a scene (docs/physics.md "Finite elements"): the blocks of scene data of the
// "material" kind (materials_kind.cc), the "triangle" kind (triangles.cc)
// and the "tetrahedron" kind (tetrahedra.cc). Their force, W Psi(F) per
// element with F = Ds Dm^-1, is fem_force.cc.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace springlab {

// One entry of a scene's "materials": a model (models/materials/) with its
// parameters.
struct MaterialSpec {
  std::string name;    // the key elements refer to it by
  std::string model;   // "neo-hookean", ...
  double young = 0.0;  // E > 0 [Pa]
  double poisson = 0.0;  // -1 < nu < 0.5
  // rho > 0 [kg/m^3]: lumped masses (docs/physics.md "Finite elements").
  std::optional<double> density;
  std::optional<double> thickness;  // t > 0 [m], triangles only; absent: 1
  double thickness_or_one() const { return thickness.value_or(1.0); }
};
using Materials = std::vector<MaterialSpec>;

// Elements name their particles (scene indices) and their material (an
// index into the scene's Materials).
struct Triangle {
  std::array<int, 3> nodes{};
  int material = 0;
};
using Triangles = std::vector<Triangle>;

struct Tetrahedron {
  std::array<int, 4> nodes{};
  int material = 0;
};
using Tetrahedra = std::vector<Tetrahedron>;

// At most this many elements of each kind, and materials, per scene.
inline constexpr std::size_t kMaxSceneElements = 2'000'000;
inline constexpr std::size_t kMaxSceneMaterials = 10'000;

}  // namespace springlab
