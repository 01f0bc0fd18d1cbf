// The "tetrahedron" element kind: the "tetrahedra" key of a 3-D scene
// (docs/physics.md "Finite elements"), solids with F 3 x 3. Its force is fem_force.cc; its energy,
// W Psi(F) with W the rest volume, is in the "elastic" column with the triangles'.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "models/core/element_kind.h"
#include "models/fem/fem.h"
#include "models/fem/fem_elements.h"

namespace springlab {
namespace {

void check_dimension(const Reporter& r, const Scene& scene) {
  if (scene.dimension != 3) {
    r.fail("tetrahedra", "need a 3-D scene (this one is " + std::to_string(scene.dimension) +
                             "-D; use triangles)");
  }
}

const MaterialSpec& material_of(const Scene& scene, const Tetrahedron& t) {
  return scene.get<Materials>()[static_cast<std::size_t>(t.material)];
}

void read_tetrahedra(const Json& document, const Reporter& r, Scene& scene) {
  if (document.contains("tetrahedra") && document.at("tetrahedra").is_array() &&
      !document.at("tetrahedra").empty()) {
    check_dimension(r, scene);
  }
  read_elements<Tetrahedron>(document, r, scene, "tetrahedra",
                             [&](const std::string& where, const Tetrahedron& t) {
                               check_rest_shape(r, where, rest_shape(rest_positions(scene, t), 3),
                                                3);
                               check_material_stability(r, material_of(scene, t), true);
                               check_initial_orientation(r, where, material_of(scene, t),
                                                         rest_positions(scene, t),
                                                         initial_positions(scene, t), 3);
                             });
}

void validate_tetrahedra(const Scene& scene, const Reporter& r) {
  if (!scene.get<Tetrahedra>().empty()) check_dimension(r, scene);
  validate_elements<Tetrahedron>(scene, r, "tetrahedra",
                                 [&](const std::string& where, const Tetrahedron& t) {
                                   check_rest_shape(
                                       r, where, rest_shape(rest_positions(scene, t), 3), 3);
                                   check_material_stability(r, material_of(scene, t), true);
                                   check_initial_orientation(r, where, material_of(scene, t),
                                                             rest_positions(scene, t),
                                                             initial_positions(scene, t), 3);
                                 });
}

void write_tetrahedra(const Scene& scene,
                      std::vector<std::pair<std::string, std::string>>& entries) {
  write_elements<Tetrahedron>(scene, "tetrahedra", entries);
}

std::unique_ptr<ForceTerm> make_tetrahedron_force(const Scene& scene,
                                                  const ParticleOrder& order) {
  return make_elements_force<Tetrahedron>(scene, order, "tetrahedron");
}

double signed_volume(const std::vector<Eigen::Vector3d>& p) {
  return (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
}

// Tetrahedra on node quadruples of the random particles (3-D only), each
// with its own random material; rest positions near (kAny) or at
// (kDefinite) x, and only well-shaped, uninverted ones are kept.
void add_random_tetrahedra(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.dimension != 3) return;
  // The best-shaped quadruples of the six particles (by their current
  // volume over their longest edge cubed), the first two acceptable ones.
  std::vector<std::pair<double, std::array<int, 4>>> quads;
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b)
      for (int c = b + 1; c < 6; ++c)
        for (int d = c + 1; d < 6; ++d) {
          std::vector<Eigen::Vector3d> x;
          for (int n : {a, b, c, d}) x.push_back(scene.particles[static_cast<std::size_t>(n)].x);
          const double quality = std::abs(signed_volume(x)) / std::pow(rest_shape(x, 3).scale, 3);
          quads.push_back({-quality, {a, b, c, d}});
        }
  std::sort(quads.begin(), quads.end());
  give_rest_positions(scene, rng, states);
  int added = 0;
  for (const auto& [quality, nodes] : quads) {
    if (added == 2) break;
    Tetrahedron t;
    t.nodes = nodes;
    const std::vector<Eigen::Vector3d> X = rest_positions(scene, t);
    std::vector<Eigen::Vector3d> x;
    for (int n : nodes) x.push_back(scene.particles[static_cast<std::size_t>(n)].x);
    const RestShape rest = rest_shape(X, 3);
    const double v_rest = signed_volume(X), v_now = signed_volume(x);
    if (!(rest.W > 1e-3 * std::pow(rest.scale, 3)) || !(v_rest * v_now > 0.0) ||
        !(std::abs(v_now / v_rest) > 0.2)) {
      continue;
    }
    t.material = add_random_material(scene, rng, false);
    scene.block<Tetrahedra>().push_back(t);
    ++added;
  }
}

std::size_t count_tetrahedra(const Scene& scene) { return scene.get<Tetrahedra>().size(); }

// The kind's part of the model's memory (memory_estimate.h): 192 bytes a
// tetrahedron (measured: 176 on block n = 30 with symplectic Euler); once
// the pattern is built, its slots and what it keeps of its last dF/dx (600
// bytes) and 12 off-diagonal blocks, an edge's shared by about four (a
// Kuhn mesh: 7 edges a node, 5.4 tetrahedra a node).
void tetrahedron_memory(const Scene& scene, MemoryEstimate& out) {
  const std::size_t n = scene.get<Tetrahedra>().size();
  if (n == 0) return;
  const double tetrahedra = static_cast<double>(n);
  MemoryPart part;
  part.what = std::to_string(n) + " tetrahedra";
  part.bytes = 192.0 * tetrahedra;
  part.pattern_blocks = 12.0 * tetrahedra;
  part.distinct_blocks = 3.0 * tetrahedra;
  part.slot_bytes = 600.0 * tetrahedra;
  out.parts.push_back(std::move(part));
}

void tetrahedron_cells(const Scene& scene, std::vector<Cell>& out) {
  for (const Tetrahedron& t : scene.get<Tetrahedra>()) out.push_back({.size = 4, .nodes = t.nodes});
}

}  // namespace

const ElementKind& tetrahedron_kind() {
  static const ElementKind kind = {
      .name = "tetrahedron",
      .refers_to_particles = true,
      .keys = {{.name = "tetrahedra", .cap = kMaxSceneElements, .count = count_tetrahedra}},
      .read = read_tetrahedra,
      .validate = validate_tetrahedra,
      .write = write_tetrahedra,
      .make = make_tetrahedron_force,
      .energy = {.name = "elastic", .counts_with_spring = true},
      .memory = tetrahedron_memory,
      .cells = tetrahedron_cells,
      .add_random = add_random_tetrahedra,
  };
  return kind;
}

}  // namespace springlab
