// What the two finite-element kinds (triangles.cc, tetrahedra.cc) share:
// reading and checking an element's nodes and material, its rest shape
// (Dm, W; docs/physics.md "Finite elements"), the lumped masses, and the force term (fem_force.cc).
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "models/core/element_kind.h"
#include "models/fem/fem.h"
#include "models/materials/material.h"

namespace springlab {

// The rest shape of one element from its nodes' rest positions X: the
// matrix G (nodes x k) with F = sum_j x_j g_j^T (g_j its rows; G's rows
// below the first are the rows of Dm^-1 and the first is minus their sum),
// and W, the rest area x thickness (triangles) or rest volume. k is the
// element's own dimension: 2 for triangles (a membrane's Dm is taken in an
// orthonormal frame of its rest plane), 3 for tetrahedra.
struct RestShape {
  Eigen::MatrixXd G;
  double W = 0.0;
  double scale = 0.0;  // the longest rest edge, for the degeneracy check
};
RestShape rest_shape(const std::vector<Eigen::Vector3d>& X, int dimension);

// Reads `"nodes": [...]` of `count` particles, each a whole index below
// particle_count, none repeated.
std::vector<int> read_element_nodes(const Reporter& r, const std::string& where, const Json& j,
                                    std::size_t count, std::size_t particle_count);
// The same checks on a built element.
void check_element_nodes(const Reporter& r, const std::string& where, const int* nodes,
                         std::size_t count, std::size_t particle_count);
// The index of `name` in the scene's materials, or a refusal naming them.
int find_material(const Reporter& r, const std::string& where, const Materials& materials,
                  const std::string& name);
// A rest area/volume of zero (W below 1e-12 of the longest edge^k) is refused.
void check_rest_shape(const Reporter& r, const std::string& where, const RestShape& shape, int k);

// A solid element (2-D triangle, tetrahedron) whose initial positions are
// inverted relative to its rest shape (det F <= 0) while its model has no
// energy there (neo-Hookean): refused, naming the element and its J.
void check_initial_orientation(const Reporter& r, const std::string& where,
                               const MaterialSpec& m, const std::vector<Eigen::Vector3d>& X,
                               const std::vector<Eigen::Vector3d>& x, int k);

// A material's Poisson ratio where its model has a stable rest state
// (MaterialFacts::min_poisson, materials_kind.cc): refused, naming
// materials.<name>.poisson, the model's range and why. `tetrahedra`: the
// material is used by a tetrahedron (some models are unstable there only).
void check_material_stability(const Reporter& r, const MaterialSpec& m, bool tetrahedra);

// Particles without a "mass" in `document` that belong to an element whose
// material has a density get the lumped mass sum_e rho W_e / (nodes of e)
// over the scene's triangles and tetrahedra (docs/physics.md "Finite elements"). Each element
// kind's reader calls it once its elements are in; it recomputes from all of them.
void lump_masses(const Json& document, const Reporter& r, Scene& scene);
// sum_e rho W_e / (nodes of e) per particle (0 where no element with a
// density touches it): what lump_masses gives, for scenes built in code.
std::vector<double> lumped_masses(const Scene& scene);

// The elements of one kind as the force term sees them.
struct ElementBlock {
  std::string_view name;  // "triangle"
  int nodes = 3;
  std::vector<std::vector<int>> node_lists = {};  // scene indices
  std::vector<int> materials = {};
  // Tetrahedra take the fixed-size force (tet_force.cc) unless this asks for
  // the plain one every shape has (fem_force.cc), which the tests compare
  // it with.
  bool reference = false;
};
// What the two element force terms (fem_force.cc, tet_force.cc) share,
// from each element's rest shape as the term stores it (shape() below):
// an element's energy is conservative, forbids states where a material has
// no energy (neo-Hookean, J <= 0), couples every pair of its free nodes in
// dF/dx, and has the forms the fast solvers ask for, built when asked
// (FastSolverViews::projective_form and laplacian_form):
//   - projective: corotated elements store the as-rigid-as-possible energy
//     W mu |F - R|^2 = w/2 |F - R|^2, w = 2 mu W, R the nearest rotation
//     (Bouaziz et al. 2014's strain constraint, exactly), and for lambda > 0
//     Bouaziz's volume constraint in place of lambda/2 (J - 1)^2 (not a
//     squared distance to a set): w = k lambda W, projected on J = 1, the
//     same stiffness at rest (docs/integrators.md "Fast solvers"); every other material
//     has none, and the form says which to use instead;
//   - Laplacian (quasi-Newton's initial Hessian), every material: weight
//     (lambda + 2 mu) W, the constrained (P-wave) modulus, the stiffness of
//     a stretch along one direction at rest.
class ElementTerm : public ForceTerm {
 public:
  ElementTerm(const Scene& scene, const ParticleOrder& order, const ElementBlock& block);
  bool conservative() const override { return true; }
  bool forbids_states() const override { return forbids_states_; }
  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override;
  bool projective_elements(std::vector<ProjectiveElement>& out, Refusal& why) const override;
  bool laplacian_elements(std::vector<ProjectiveElement>& out) const override;
  // Vertex block descent (models/vertex_blocks.h; fem_vertex_blocks.cc):
  // per particle, the plain element force and its 3 x 3 (d x d) block from
  // the material's dP, and the cap that keeps a solid uninverted where its
  // material has no energy at J <= 0.
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool definite,
                         const VertexBlocks& out) const override;
  double vertex_admissible_fraction(const Configuration& c, int particle,
                                    const double* dx) const override;

 protected:
  // Element e as its term stores it: internal node indices, G (nodes x k,
  // rows g_j), W (with a triangle's thickness), the material's model and
  // Lame parameters.
  struct Shape {
    std::vector<int> nodes;
    Eigen::MatrixXd G;
    double W = 0.0;
    const MaterialModel* model = nullptr;
    Lame lame;
  };
  virtual std::size_t element_count() const = 0;
  virtual Shape shape(std::size_t e) const = 0;

 private:
  // Each element as its particles' vertex blocks read it (built at the
  // first vertex block), and each free particle's elements (its node slot
  // in each) at [vertex_first_[p], vertex_first_[p + 1]).
  struct VertexShape {
    std::array<int, 4> nodes{};
    int count = 0;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 3> G;
    double W = 0.0;
    const MaterialModel* model = nullptr;
    Lame lame;
  };
  struct VertexElement {
    int element;
    int slot;
  };
  void build_vertex_elements() const;
  Mat vertex_deformation(const Configuration& c, const VertexShape& e) const;
  mutable std::vector<VertexShape> vertex_shapes_;
  mutable std::vector<int> vertex_first_;
  mutable std::vector<VertexElement> vertex_elements_;

  int free_particles_;
  bool forbids_states_ = false;
  std::string_view kind_;
  Materials materials_;           // the scene's, for messages
  std::vector<int> material_of_;  // per element
};

std::unique_ptr<ForceTerm> make_element_force(const Scene& scene, const ParticleOrder& order,
                                              const ElementBlock& block);
std::unique_ptr<ForceTerm> make_tetrahedron_element_force(const Scene& scene,
                                                          const ParticleOrder& order,
                                                          const ElementBlock& block);

// The definite part of an element's stiffness K = dF/dx (docs/physics.md "Finite
// elements"): the element's Hessian -K with its negative eigenvalues set to
// zero (Teran et al. 2005 do this per singular value; per element is
// simpler and also definite). K is left as it is where it already is
// semidefinite, so the definite part is exactly dF/dx there.
template <typename Matrix>
void make_definite(Matrix& K) {
  const Matrix H = -0.5 * (K + K.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix> eig(H);
  const auto& lambda = eig.eigenvalues();
  const double size = lambda.cwiseAbs().maxCoeff();
  if (lambda.minCoeff() >= -1e-12 * size) return;
  const Matrix& Q = eig.eigenvectors();
  K = -(Q * lambda.cwiseMax(0.0).asDiagonal() * Q.transpose());
}

// ---- The element arrays ("triangles", "tetrahedra"): each element
// {"nodes": [N particle indices], "material": name}. One reader, checker and
// writer for both kinds; `check(where, element)` adds a kind's own checks.

template <typename Element>
std::vector<Eigen::Vector3d> rest_positions(const Scene& scene, const Element& e) {
  std::vector<Eigen::Vector3d> X;
  for (int n : e.nodes) X.push_back(scene.particles[static_cast<std::size_t>(n)].rest_position());
  return X;
}
template <typename Element>
std::vector<Eigen::Vector3d> initial_positions(const Scene& scene, const Element& e) {
  std::vector<Eigen::Vector3d> x;
  for (int n : e.nodes) x.push_back(scene.particles[static_cast<std::size_t>(n)].x);
  return x;
}

template <typename Element, typename Check>
void read_elements(const Json& document, const Reporter& r, Scene& scene, const char* key,
                   Check check) {
  if (!document.contains(key)) return;
  const Json& list = document.at(key);
  require_array(r, key, list);
  std::vector<Element>& out = scene.block<std::vector<Element>>();
  for (std::size_t e = 0; e < list.size(); ++e) {
    const std::string where = element(key, e);
    require_object(r, where, list[e]);
    check_keys(r, where, list[e], {"nodes", "material"}, {"nodes", "material"});
    Element el;
    const std::vector<int> nodes =
        read_element_nodes(r, where, list[e], el.nodes.size(), scene.particles.size());
    std::copy(nodes.begin(), nodes.end(), el.nodes.begin());
    if (!list[e].at("material").is_string()) {
      r.fail(field(where, "material"), "expected a material's name (a string)");
    }
    el.material = find_material(r, where, scene.get<Materials>(),
                                list[e].at("material").get<std::string>());
    check(where, el);
    out.push_back(el);
  }
  lump_masses(document, r, scene);
}

template <typename Element, typename Check>
void validate_elements(const Scene& scene, const Reporter& r, const char* key, Check check) {
  const std::vector<Element>& elements = scene.get<std::vector<Element>>();
  for (std::size_t e = 0; e < elements.size(); ++e) {
    const std::string where = element(key, e);
    const Element& el = elements[e];
    check_element_nodes(r, where, el.nodes.data(), el.nodes.size(), scene.particles.size());
    if (el.material < 0 ||
        static_cast<std::size_t>(el.material) >= scene.get<Materials>().size()) {
      r.fail(field(where, "material"), "no such material");
    }
    check(where, el);
  }
}

template <typename Element>
void write_elements(const Scene& scene, const char* key,
                    std::vector<std::pair<std::string, std::string>>& entries) {
  const std::vector<Element>* elements = scene.find<std::vector<Element>>();
  if (elements == nullptr || elements->empty()) return;
  JsonLines lines;
  for (const Element& el : *elements) {
    std::string nodes;
    for (int n : el.nodes) nodes += (nodes.empty() ? "" : ", ") + std::to_string(n);
    lines.add("{\"nodes\": [" + nodes + "], \"material\": " +
              json_string(scene.get<Materials>()[static_cast<std::size_t>(el.material)].name) +
              "}");
  }
  entries.emplace_back(key, lines.str());
}

// The force term of one kind's elements (nullptr without any).
template <typename Element>
std::unique_ptr<ForceTerm> make_elements_force(const Scene& scene, const ParticleOrder& order,
                                               std::string_view name) {
  ElementBlock block{.name = name, .nodes = static_cast<int>(Element{}.nodes.size())};
  for (const Element& el : scene.get<std::vector<Element>>()) {
    block.node_lists.emplace_back(el.nodes.begin(), el.nodes.end());
    block.materials.push_back(el.material);
  }
  return make_element_force(scene, order, block);
}

// A random material (any model; `membranes`: one defined for membranes)
// added to the scene's materials; returns its index.
int add_random_material(Scene& scene, std::mt19937& rng, bool membranes);
// Gives every particle a rest position, unless an earlier kind's random
// instance did: X = x (kDefinite: elements start at rest, their Hessians
// semidefinite) or x under a random uniform deformation plus a little noise.
void give_rest_positions(Scene& scene, std::mt19937& rng, RandomStates states);

}  // namespace springlab
