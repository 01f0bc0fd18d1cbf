#include "models/fem/fem_elements.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "models/materials/kernels/kinematics.h"

namespace springlab {

RestShape rest_shape(const std::vector<Eigen::Vector3d>& X, int dimension) {
  RestShape shape;
  const int nodes = static_cast<int>(X.size());
  const int k = nodes - 1;
  for (int a = 0; a < nodes; ++a) {
    for (int b = a + 1; b < nodes; ++b) {
      shape.scale = std::max(shape.scale, (X[b] - X[a]).stableNorm());  // (x 1e200: no overflow)
    }
  }
  Eigen::MatrixXd Dm(k, k);
  if (k == 2 && dimension == 3) {
    // A membrane: the rest edges in an orthonormal frame (t1, t2) of the
    // rest triangle's plane.
    const Eigen::Vector3d e1 = X[1] - X[0], e2 = X[2] - X[0];
    const Eigen::Vector3d n = e1.cross(e2);
    if (n.norm() == 0.0 || e1.norm() == 0.0) return shape;  // W = 0: refused
    const Eigen::Vector3d t1 = e1.normalized();
    const Eigen::Vector3d t2 = n.normalized().cross(t1);
    Dm << e1.dot(t1), e2.dot(t1), e1.dot(t2), e2.dot(t2);
  } else {
    for (int c = 0; c < k; ++c) Dm.col(c) = (X[c + 1] - X[0]).head(k);
  }
  const double det = Dm.determinant();
  // W: |det Dm| / 2 (triangle) or / 6 (tetrahedron).
  shape.W = std::abs(det) / (k == 2 ? 2.0 : 6.0);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return shape;
  const Eigen::MatrixXd Dm_inv = Dm.inverse();
  shape.G = Eigen::MatrixXd::Zero(nodes, k);
  shape.G.bottomRows(k) = Dm_inv;
  shape.G.row(0) = -Dm_inv.colwise().sum();
  return shape;
}

std::vector<int> read_element_nodes(const Reporter& r, const std::string& where, const Json& j,
                                    std::size_t count, std::size_t particle_count) {
  const std::string at = field(where, "nodes");
  const Json& list = j.at("nodes");
  require_array(r, at, list);
  if (list.size() != count) {
    r.fail(at, "expected " + std::to_string(count) + " particle indices, got " +
                   std::to_string(list.size()));
  }
  std::vector<int> nodes;
  for (std::size_t n = 0; n < count; ++n) {
    nodes.push_back(check_particle_index(r, where, ("nodes[" + std::to_string(n) + "]").c_str(),
                                         read_number(r, element(at, n), list[n]),
                                         particle_count));
  }
  check_element_nodes(r, where, nodes.data(), count, particle_count);
  return nodes;
}

void check_element_nodes(const Reporter& r, const std::string& where, const int* nodes,
                         std::size_t count, std::size_t particle_count) {
  for (std::size_t a = 0; a < count; ++a) {
    check_particle_index(r, where, ("nodes[" + std::to_string(a) + "]").c_str(), nodes[a],
                         particle_count);
    for (std::size_t b = 0; b < a; ++b) {
      if (nodes[a] == nodes[b]) {
        r.fail(where, "particle " + std::to_string(nodes[a]) + " appears twice in its nodes");
      }
    }
  }
}

int find_material(const Reporter& r, const std::string& where, const Materials& materials,
                  const std::string& name) {
  for (std::size_t m = 0; m < materials.size(); ++m) {
    if (materials[m].name == name) return static_cast<int>(m);
  }
  std::string known;
  for (const MaterialSpec& m : materials) known += (known.empty() ? "" : ", ") + m.name;
  r.fail(field(where, "material"),
         "unknown material " + json_string(name) +
             (known.empty() ? " (the scene has no \"materials\")" : " (materials: " + known + ")"));
}

void check_rest_shape(const Reporter& r, const std::string& where, const RestShape& shape,
                      int k) {
  // Rest positions too large for their area or volume to be a double (x
  // 1e200: W near 1e600) are not a degenerate shape: say so.
  const double extent = std::pow(shape.scale, k);
  if (!std::isfinite(extent) || std::isinf(shape.W)) {
    r.fail(where, std::string("its rest ") + (k == 2 ? "area" : "volume") +
                      " overflows a double (its longest rest edge is " +
                      shortest_text(shape.scale) + " m; rest positions too large)");
  }
  if (!(shape.W > 1e-12 * extent) || shape.G.size() == 0) {
    r.fail(where, std::string("its rest ") + (k == 2 ? "area" : "volume") +
                      " is zero (the rest positions of its nodes are " +
                      (k == 2 ? "collinear" : "coplanar") + ")");
  }
}

void check_initial_orientation(const Reporter& r, const std::string& where,
                               const MaterialSpec& m, const std::vector<Eigen::Vector3d>& X,
                               const std::vector<Eigen::Vector3d>& x, int k) {
  const MaterialModel* model = find_material_model(m.model);
  if (model == nullptr || model->finite_everywhere) return;
  Eigen::MatrixXd Dm(k, k), Ds(k, k);
  for (int c = 0; c < k; ++c) {
    Dm.col(c) = (X[c + 1] - X[0]).head(k);
    Ds.col(c) = (x[c + 1] - x[0]).head(k);
  }
  const double rest = Dm.determinant(), now = Ds.determinant();
  if (!(rest != 0.0) || !std::isfinite(rest) || !std::isfinite(now)) return;  // checked elsewhere
  const double J = now / rest;
  if (!(J > 0.0)) {
    r.fail(where, std::string("its initial shape is ") + (J == 0.0 ? "flat" : "inverted") +
                      " relative to its rest shape (J = " + shortest_text(J) + "), where the " +
                      m.model + " energy of material " + json_string(m.name) +
                      " is infinite (it has none for J <= 0)");
  }
}

namespace {

template <typename Element>
void add_lumped(const Scene& scene, const std::vector<Element>& elements,
                std::vector<double>& lumped) {
  const Materials& materials = scene.get<Materials>();
  for (const Element& e : elements) {
    const MaterialSpec& m = materials[static_cast<std::size_t>(e.material)];
    if (!m.density) continue;
    std::vector<Eigen::Vector3d> X;
    for (int n : e.nodes) X.push_back(scene.particles[static_cast<std::size_t>(n)].rest_position());
    const int nodes = static_cast<int>(e.nodes.size());
    const double W = rest_shape(X, scene.dimension).W * (nodes == 3 ? m.thickness_or_one() : 1.0);
    for (int n : e.nodes) lumped[static_cast<std::size_t>(n)] += *m.density * W / nodes;
  }
}

}  // namespace

std::vector<double> lumped_masses(const Scene& scene) {
  std::vector<double> lumped(scene.particles.size(), 0.0);
  add_lumped(scene, scene.get<Triangles>(), lumped);
  add_lumped(scene, scene.get<Tetrahedra>(), lumped);
  return lumped;
}

void lump_masses(const Json& document, const Reporter& r, Scene& scene) {
  const std::vector<double> lumped = lumped_masses(scene);
  const Json& particles = document.at("particles");
  for (std::size_t p = 0; p < lumped.size(); ++p) {
    if (lumped[p] > 0.0 && !particles[p].contains("mass")) {
      if (!std::isfinite(lumped[p])) {
        r.fail(element("particles", p),
               "its lumped mass (density x rest size / nodes) is not finite: give its \"mass\"");
      }
      scene.particles[p].mass = lumped[p];
    }
  }
}

int add_random_material(Scene& scene, std::mt19937& rng, bool membranes) {
  std::vector<const MaterialModel*> models;
  for (const MaterialModel* m : material_models()) {
    if (!membranes || m->membranes) models.push_back(m);
  }
  std::uniform_int_distribution<std::size_t> pick(0, models.size() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Materials& materials = scene.block<Materials>();
  MaterialSpec m;
  m.name = "random-" + std::to_string(materials.size());
  m.model = std::string(models[pick(rng)]->name);
  m.young = 50.0 + 100.0 * u(rng);
  m.poisson = 0.45 * u(rng);
  if (u(rng) < 0.5) m.thickness = 0.5 + u(rng);
  materials.push_back(m);
  return static_cast<int>(materials.size()) - 1;
}

void give_rest_positions(Scene& scene, std::mt19937& rng, RandomStates states) {
  for (const Particle& p : scene.particles) {
    if (p.X) return;  // an earlier kind's instance gave them already
  }
  // X = A x + noise: a uniform deformation (A = I + U(-0.15, 0.15) per
  // entry, det A > 0) keeps every element's orientation, and a little noise
  // per node makes the elements' states differ.
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix3d A;
  do {
    A = Eigen::Matrix3d::Identity();
    for (int r = 0; r < scene.dimension; ++r) {
      for (int c = 0; c < scene.dimension; ++c) A(r, c) += 0.15 * u(rng);
    }
  } while (!(A.topLeftCorner(scene.dimension, scene.dimension).determinant() > 0.5));
  for (Particle& p : scene.particles) {
    Eigen::Vector3d X = p.x;
    if (states == RandomStates::kAny) {
      X = A * p.x;
      for (int r = 0; r < scene.dimension; ++r) X[r] += 0.02 * u(rng);
    }
    p.X = X;
  }
}

namespace {

Mat nearest_rotation(const Mat& F) { return polar(F).R; }

}  // namespace

ElementTerm::ElementTerm(const Scene& scene, const ParticleOrder& order,
                         const ElementBlock& block)
    : free_particles_(order.free_particles),
      kind_(block.name),
      materials_(scene.get<Materials>()),
      material_of_(block.materials) {
  for (int m : material_of_) {
    const MaterialModel* model = find_material_model(materials_[static_cast<std::size_t>(m)].model);
    forbids_states_ = forbids_states_ || !model->finite_everywhere;
  }
}

void ElementTerm::declare_jacobian_blocks(JacobianPatternBuilder& builder) const {
  const int free = free_particles_;
  for (std::size_t e = 0; e < element_count(); ++e) {
    const std::vector<int> nodes = shape(e).nodes;
    for (int a : nodes) {
      for (int b : nodes) {
        if (a != b && a < free && b < free) builder.add_block(a, b);
      }
    }
  }
}

bool ElementTerm::projective_elements(std::vector<ProjectiveElement>& out,
                                      Refusal& why) const {
  std::vector<ProjectiveElement> mine;
  for (std::size_t e = 0; e < element_count(); ++e) {
    Shape s = shape(e);
    if (s.model->name != "corotated" || s.lame.lambda < 0.0) {
      const MaterialSpec& m = materials_[static_cast<std::size_t>(material_of_[e])];
      std::ostringstream message;
      message << "this scene's " << kind_ << " elements are of material '" << m.name << "' ("
              << m.model << ", poisson " << m.poisson
              << "), which has no projective form; the fast solvers run corotated elements "
                 "with poisson >= 0 (the as-rigid-as-possible energy mu |F - R|^2 plus, for "
                 "poisson > 0, Bouaziz et al. 2014's volume term): use such a material, or "
                 "implicit-euler";
      why.text = message.str();
      // What would make it work: a corotated material (validate_scene
      // already refuses corotated with poisson < 0).
      if (s.model->name != "corotated") why.remedy = {"model", "corotated", ""};
      return false;
    }
    // The volume term's weight: near rest (F = I, or orthonormal columns
    // for a membrane) the distance of F to the set J = 1 is |J - 1| / sqrt(k)
    // to first order (k the columns of F: the set's normal there is the
    // rest F / sqrt(k)), so w/2 dist^2 = W lambda/2 (J - 1)^2 to second
    // order with w = k lambda W.
    const double volume_weight = static_cast<double>(s.G.cols()) * s.lame.lambda * s.W;
    mine.push_back({.nodes = s.nodes,
                    .fixed = {},
                    .G = s.G,
                    .weight = 2.0 * s.lame.mu * s.W,
                    .project = nearest_rotation});
    if (volume_weight > 0.0) {
      mine.push_back({.nodes = std::move(s.nodes),
                      .fixed = {},
                      .G = std::move(s.G),
                      .weight = volume_weight,
                      .project = nearest_unit_volume});
    }
  }
  out.insert(out.end(), mine.begin(), mine.end());
  return true;
}

bool ElementTerm::laplacian_elements(std::vector<ProjectiveElement>& out) const {
  for (std::size_t e = 0; e < element_count(); ++e) {
    Shape s = shape(e);
    out.push_back({.nodes = std::move(s.nodes),
                   .fixed = {},
                   .G = std::move(s.G),
                   .weight = (s.lame.lambda + 2.0 * s.lame.mu) * s.W});
  }
  return true;
}

}  // namespace springlab
