// The "triangle" element kind: the "triangles" key of a scene (docs/physics.md "Finite elements").
// In a 2-D scene a triangle is a plane-strain solid (F 2 x 2); in a 3-D scene a
// membrane (F 3 x 2: in-plane stretch and shear, no bending), where the
// linear model is refused. Its force is fem_force.cc; its energy, W Psi(F)
// with W the rest area x the material's thickness, is in the "elastic"
// column with the tetrahedra's.
#include "models/core/element_kind.h"
#include "models/fem/fem.h"
#include "models/fem/fem_elements.h"

namespace springlab {
namespace {

void check_triangle(const Reporter& r, const std::string& where, const Scene& scene,
                    const Triangle& t) {
  const MaterialSpec& m = scene.get<Materials>()[static_cast<std::size_t>(t.material)];
  if (scene.dimension == 3 && !find_material_model(m.model)->membranes) {
    r.fail(field(where, "material"),
           json_string(m.name) + " is " + m.model +
               ", which is not defined for membranes (triangles in a 3-D scene)");
  }
  check_rest_shape(r, where, rest_shape(rest_positions(scene, t), scene.dimension), 2);
  if (scene.dimension == 2) {  // (a membrane's J = sqrt(det C) is never negative)
    check_initial_orientation(r, where, m, rest_positions(scene, t), initial_positions(scene, t), 2);
  }
}

void read_triangles(const Json& document, const Reporter& r, Scene& scene) {
  read_elements<Triangle>(document, r, scene, "triangles",
                          [&](const std::string& where, const Triangle& t) {
                            check_triangle(r, where, scene, t);
                          });
}

void validate_triangles(const Scene& scene, const Reporter& r) {
  validate_elements<Triangle>(scene, r, "triangles",
                              [&](const std::string& where, const Triangle& t) {
                                check_triangle(r, where, scene, t);
                              });
}

void write_triangles(const Scene& scene,
                     std::vector<std::pair<std::string, std::string>>& entries) {
  write_elements<Triangle>(scene, "triangles", entries);
}

std::unique_ptr<ForceTerm> make_triangle_force(const Scene& scene, const ParticleOrder& order) {
  return make_elements_force<Triangle>(scene, order, "triangle");
}

// Triangles on node triples of the random particles, each with its own
// random material; rest positions near (kAny) or at (kDefinite) x, and only
// well-shaped, uninverted ones are kept.
void add_random_triangles(Scene& scene, std::mt19937& rng, RandomStates states) {
  // The first three acceptable triples of the six particles.
  std::vector<std::array<int, 3>> triples;
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b)
      for (int c = b + 1; c < 6; ++c) triples.push_back({a, b, c});
  give_rest_positions(scene, rng, states);
  int added = 0;
  for (const auto& nodes : triples) {
    if (added == 3) break;
    Triangle t;
    t.nodes = nodes;
    std::vector<Eigen::Vector3d> X = rest_positions(scene, t), x;
    for (int n : nodes) x.push_back(scene.particles[static_cast<std::size_t>(n)].x);
    const RestShape rest = rest_shape(X, scene.dimension), now = rest_shape(x, scene.dimension);
    if (!(rest.W > 0.02 * rest.scale * rest.scale) || !(now.W > 0.02 * now.scale * now.scale)) {
      continue;
    }
    if (scene.dimension == 2) {
      // Same orientation at rest and now (J > 0).
      const double d_rest = (X[1] - X[0]).head<2>().x() * (X[2] - X[0]).y() -
                            (X[1] - X[0]).y() * (X[2] - X[0]).x();
      const double d_now = (x[1] - x[0]).x() * (x[2] - x[0]).y() -
                           (x[1] - x[0]).y() * (x[2] - x[0]).x();
      if (d_rest * d_now <= 0.0) continue;
    }
    t.material = add_random_material(scene, rng, scene.dimension == 3);
    scene.block<Triangles>().push_back(t);
    ++added;
  }
}

std::size_t count_triangles(const Scene& scene) { return scene.get<Triangles>().size(); }

// The kind's part of the model's memory (memory_estimate.h): 256 bytes a
// triangle (measured: 245 on the 500 x 500 membrane with symplectic Euler,
// the scene's two copies and the term's element); once the pattern is
// built, its 9 slots and 6 off-diagonal blocks, each edge's shared with the
// triangle across it.
void triangle_memory(const Scene& scene, MemoryEstimate& out) {
  const std::size_t n = scene.get<Triangles>().size();
  if (n == 0) return;
  const double triangles = static_cast<double>(n);
  MemoryPart part;
  part.what = std::to_string(n) + " triangles";
  part.bytes = 256.0 * triangles;
  part.pattern_blocks = 6.0 * triangles;
  part.distinct_blocks = 3.0 * triangles;
  part.slot_bytes = 160.0 * triangles;
  out.parts.push_back(std::move(part));
}

void triangle_cells(const Scene& scene, std::vector<Cell>& out) {
  for (const Triangle& t : scene.get<Triangles>()) {
    out.push_back({.size = 3, .nodes = {t.nodes[0], t.nodes[1], t.nodes[2], 0}});
  }
}

}  // namespace

const ElementKind& triangle_kind() {
  static const ElementKind kind = {
      .name = "triangle",
      .refers_to_particles = true,
      .keys = {{.name = "triangles", .cap = kMaxSceneElements, .count = count_triangles}},
      .read = read_triangles,
      .validate = validate_triangles,
      .write = write_triangles,
      .make = make_triangle_force,
      .energy = {.name = "elastic", .counts_with_spring = true},
      .memory = triangle_memory,
      .cells = triangle_cells,
      .add_random = add_random_triangles,
  };
  return kind;
}

}  // namespace springlab
