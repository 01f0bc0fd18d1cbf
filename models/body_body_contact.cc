// Contact between rigid bodies (docs/physics.md "Contact between bodies"):
// the surface vertices of each body against every other body that is a box
// (shape "box"), with the planes' penalty phi(d) = k_c/2 min(d, 0)^2
// (models/contact_potential.h). An element kind with no scene key of its
// own; it acts when the scene's contact model is the penalty (the default).
//
// A vertex x = p_a + A_a X of body a is inside box b (half sides h in b's
// principal frame) when its material coordinates Y = A_b^{-1} (x - p_b)
// have |Y_k| < h_k for every k. It is then pushed out through the face of
// b that faces a's centre: with Z = A_b^{-1} (p_a - p_b), the axis i
// maximizing |Z_i| / h_i and the side s = sign(Z_i) (one face per pair,
// so a box resting on a wider one is pushed up by every corner, however
// deep; the vertex's own nearest face would turn sideways once a corner
// sinks deeper than its distance to a side face). That face's plane has
// normal s a_i and passes through p_b + s h_i a_i; the gap is
//   d = s a_i . (x - p_b) - h_i a_i . a_i,
// = s Y_i - h_i < 0 for a rigid A_b (|a_i| = 1, a_i . a_k = 0). d is a
// quadratic polynomial of the unknowns, with gradient
//   dd/dx = s a_i  (to body a's unknowns by w = (1, X), as plane contact),
//   dd/dp_b = -s a_i,   dd/da_i = s (x - p_b) - 2 h_i a_i,
// and Hessian blocks d2d/dx da_i = s I, d2d/dp_b da_i = -s I,
// d2d/da_i2 = -2 h_i I. The force is -phi'(d) grad d and its Jacobian
// -(phi''(d) grad d grad d^T + phi'(d) hess d); Newton's definite part
// keeps the first, semidefinite, term (Gauss-Newton).
//
// d is invariant under translating and rotating everything (x, p, a_i ->
// Q x + t, ...), and so is the face choice, so the pair force conserves
// the total linear and angular momentum. The face switches where two
// |Z_i| / h_i are equal (a's centre over b's edge), where the force jumps.
//
// Two bodies joined by a spring between their points (a joint,
// body_springs.h) do not meet. Left out, and said so in the docs: friction
// between bodies; a cylinder
// or mesh as the body pushed into (only their vertices push into boxes);
// edge-edge crossings with no vertex inside; the barrier model (with it
// bodies do not meet each other).
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "models/bodies.h"
#include "models/body_springs.h"
#include "models/contact.h"
#include "models/contact_potential.h"
#include "models/element_kind.h"

namespace springlab {

const ElementKind& plane_kind();  // planes.cc
// bodies.cc: a random box; strained (A not a rotation) or not.
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained);

namespace {

// One body as the contact sees it: where its unknowns are (or its fixed
// p, A), its surface vertices' X, and for a box its half sides and bounding
// radius in the principal frame.
struct ContactBody {
  int first = -1;  // -1: fixed
  Eigen::Vector3d p0;
  Eigen::Matrix3d A0;
  std::vector<Eigen::Vector3d> X;
  bool box = false;
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  double radius = 0.0;  // max |X| over the vertices

  Eigen::Vector3d p(const double* x) const {
    return first < 0 ? p0 : Eigen::Vector3d(x[3 * first], x[3 * first + 1], x[3 * first + 2]);
  }
  Eigen::Matrix3d A(const double* x) const {
    if (first < 0) return A0;
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i) {
      for (int r = 0; r < 3; ++r) A(r, i) = x[3 * (first + 1 + i) + r];
    }
    return A;
  }
};

// A vertex in contact: the pair, the face (axis i, side s), d's gradient
// on the 8 unknowns (a's p, a_1..3, then b's p, a_1..3; zero where fixed).
struct Touch {
  std::size_t pair;
  int vertex;
  int axis;
  double side;
  ContactPhi phi;
  Eigen::Vector3d x, pb, ai;
};

class BodyBodyContactForce final : public ForceTerm {
 public:
  BodyBodyContactForce(const Scene& scene, const BodyLayout& layout, const Contact& contact)
      : law_(contact) {
    const Bodies& bodies = scene.get<Bodies>();
    for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
      const RigidBody& rb = layout.bodies[b];
      ContactBody c;
      c.first = layout.first[b];
      c.p0 = rb.p0;
      c.A0 = rb.A0;
      c.X = rb.X;
      c.box = bodies[b].shape == Body::Shape::kBox;
      for (const Eigen::Vector3d& X : rb.X) {
        c.half = c.half.cwiseMax(X.cwiseAbs());
        c.radius = std::max(c.radius, X.norm());
      }
      bodies_.push_back(std::move(c));
    }
    // Bodies joined by a spring (a joint) do not meet: a hinge's boxes
    // touch at the joint, where contact would fight the spring.
    std::set<std::pair<int, int>> joined;
    for (const BodySpring& s : scene.get<BodySprings>()) {
      if (s.i.is_body() && s.j.is_body()) {
        joined.insert({std::min(s.i.body, s.j.body), std::max(s.i.body, s.j.body)});
      }
    }
    for (std::size_t a = 0; a < bodies_.size(); ++a) {
      for (std::size_t b = 0; b < bodies_.size(); ++b) {
        if (a == b || !bodies_[b].box) continue;
        const int lo = static_cast<int>(std::min(a, b)), hi = static_cast<int>(std::max(a, b));
        if (joined.count({lo, hi}) != 0) continue;
        if (bodies_[a].first < 0 && bodies_[b].first < 0) continue;
        pairs_.push_back({static_cast<int>(a), static_cast<int>(b), {}});
      }
    }
  }

  std::string_view name() const override { return "body-body contact"; }
  bool conservative() const override { return true; }
  bool projective_elements(std::vector<ProjectiveElement>&, std::string& why) const override {
    why = "contact between rigid bodies has no projective form; use implicit-euler or another "
          "Newton method";
    return false;
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for_each_touch(c, [&](const Touch& t) { sum += t.phi.value; });
    return sum;
  }

  void add_force(const Configuration& c, double* f) const override {
    for_each_touch(c, [&](const Touch& t) {
      const auto grad = gradient(t);
      const int* index = unknowns(t.pair);
      for (int u = 0; u < 8; ++u) {
        if (index[u] < 0) continue;
        for (int r = 0; r < 3; ++r) f[3 * index[u] + r] -= t.phi.slope * grad[u][r];
      }
    });
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (std::size_t k = 0; k < pairs_.size(); ++k) {
      const int* index = unknowns(k);
      for (int u = 0; u < 8; ++u) {
        for (int w = 0; w < 8; ++w) {
          if (index[u] >= 0 && index[w] >= 0) builder.add_block(index[u], index[w]);
        }
      }
    }
  }
  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.assign(pairs_.size() * 64, BlockSlot{});
    for (std::size_t k = 0; k < pairs_.size(); ++k) {
      const int* index = unknowns(k);
      for (int u = 0; u < 8; ++u) {
        for (int w = 0; w < 8; ++w) {
          if (index[u] >= 0 && index[w] >= 0) {
            slots_[k * 64 + static_cast<std::size_t>(u * 8 + w)] =
                find_block_slot(pattern, 3, index[u], index[w]);
          }
        }
      }
    }
  }
  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx != nullptr) add_stiffness(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    add_stiffness(c, dfdx, true);
  }

 private:
  struct Pair {
    int a, b;  // the vertices' body, the box
    int index[8];
  };

  const int* unknowns(std::size_t k) const { return pairs_[k].index; }

  // d's gradient on the 8 unknowns: w_alpha s a_i for a's, then
  // -s a_i on p_b and s (x - p_b) - 2 h_i a_i on a_i of b.
  std::array<Eigen::Vector3d, 8> gradient(const Touch& t) const {
    const Pair& pair = pairs_[t.pair];
    const Eigen::Vector3d& X = bodies_[static_cast<std::size_t>(pair.a)].X[static_cast<std::size_t>(t.vertex)];
    const double h = bodies_[static_cast<std::size_t>(pair.b)].half[t.axis];
    std::array<Eigen::Vector3d, 8> g;
    for (Eigen::Vector3d& v : g) v.setZero();
    const Eigen::Vector3d n = t.side * t.ai;
    g[0] = n;
    for (int i = 0; i < 3; ++i) g[1 + i] = X[i] * n;
    g[4] = -n;
    g[5 + t.axis] = t.side * (t.x - t.pb) - 2.0 * h * t.ai;
    return g;
  }

  void add_stiffness(const Configuration& c, double* dfdx, bool definite) const {
    for_each_touch(c, [&](const Touch& t) {
      const Pair& pair = pairs_[t.pair];
      const auto grad = gradient(t);
      double K[3][3];
      // -phi'' grad grad^T
      for (int u = 0; u < 8; ++u) {
        if (pair.index[u] < 0) continue;
        for (int w = 0; w < 8; ++w) {
          if (pair.index[w] < 0) continue;
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) K[r][q] = grad[u][r] * grad[w][q];
          }
          add_block<3>(dfdx, slots_[t.pair * 64 + static_cast<std::size_t>(u * 8 + w)], K,
                       -t.phi.curvature);
        }
      }
      if (definite) return;
      // -phi' hess d: s I between a's unknowns (w_alpha) and b's a_i, -s I
      // between p_b and a_i, -2 h_i I on a_i.
      const Eigen::Vector3d& X =
          bodies_[static_cast<std::size_t>(pair.a)].X[static_cast<std::size_t>(t.vertex)];
      const double w[4] = {1.0, X.x(), X.y(), X.z()};
      const double h = bodies_[static_cast<std::size_t>(pair.b)].half[t.axis];
      const int ai = 5 + t.axis;
      auto add_identity = [&](int u, int v, double s) {
        if (pair.index[u] < 0 || pair.index[v] < 0) return;
        const double I[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        add_block<3>(dfdx, slots_[t.pair * 64 + static_cast<std::size_t>(u * 8 + v)], I,
                     -t.phi.slope * s);
      };
      for (int alpha = 0; alpha < 4; ++alpha) {
        add_identity(alpha, ai, t.side * w[alpha]);
        add_identity(ai, alpha, t.side * w[alpha]);
      }
      add_identity(4, ai, -t.side);
      add_identity(ai, 4, -t.side);
      add_identity(ai, ai, -2.0 * h);
    });
  }

  template <typename Visit>
  void for_each_touch(const Configuration& c, Visit visit) const {
    if (law_.model != ContactModel::kPenalty) return;
    for (std::size_t k = 0; k < pairs_.size(); ++k) {
      const ContactBody& a = bodies_[static_cast<std::size_t>(pairs_[k].a)];
      const ContactBody& b = bodies_[static_cast<std::size_t>(pairs_[k].b)];
      const Eigen::Vector3d pa = a.p(c.x), pb = b.p(c.x);
      const Eigen::Matrix3d Aa = a.A(c.x), Ab = b.A(c.x);
      // Bounding spheres (radii scaled by the largest column stretch).
      const double reach_a = a.radius * Aa.colwise().norm().maxCoeff();
      const double reach_b = b.radius * Ab.colwise().norm().maxCoeff();
      if ((pa - pb).norm() > reach_a + reach_b) continue;
      const Eigen::PartialPivLU<Eigen::Matrix3d> inverse(Ab);
      // The face of b facing a's centre: Z = A_b^{-1} (p_a - p_b), axis i
      // maximizing |Z_i| / h_i, side sign(Z_i).
      const Eigen::Vector3d Z = inverse.solve(pa - pb);
      int axis = 0;
      (Z.cwiseAbs().cwiseQuotient(b.half)).maxCoeff(&axis);
      const double side = Z[axis] >= 0.0 ? 1.0 : -1.0;
      for (std::size_t v = 0; v < a.X.size(); ++v) {
        const Eigen::Vector3d x = pa + Aa * a.X[v];
        const Eigen::Vector3d Y = inverse.solve(x - pb);
        if (!(Y.cwiseAbs().array() < b.half.array()).all()) continue;  // outside b
        Touch t;
        t.pair = k;
        t.vertex = static_cast<int>(v);
        t.axis = axis;
        t.side = side;
        t.x = x;
        t.pb = pb;
        t.ai = Ab.col(axis);
        const double d = t.side * t.ai.dot(x - pb) - b.half[axis] * t.ai.squaredNorm();
        t.phi = law_(d);
        if (t.phi.value == 0.0 && t.phi.slope == 0.0) continue;
        visit(t);
      }
    }
  }

 public:
  // The pairs' unknowns, once the bodies are known (called by the factory).
  void index_pairs() {
    for (Pair& pair : pairs_) {
      const int ends[2] = {bodies_[static_cast<std::size_t>(pair.a)].first,
                           bodies_[static_cast<std::size_t>(pair.b)].first};
      for (int e = 0; e < 2; ++e) {
        for (int u = 0; u < 4; ++u) pair.index[4 * e + u] = ends[e] < 0 ? -1 : ends[e] + u;
      }
    }
  }

 private:
  ContactLaw law_;
  std::vector<ContactBody> bodies_;
  std::vector<Pair> pairs_;
  std::vector<BlockSlot> slots_;
};

// Two bodies or more, one a box, one free, and the penalty model.
bool has_body_contacts(const Scene& scene) {
  const Bodies& bodies = scene.get<Bodies>();
  if (bodies.size() < 2 || scene.get<Contact>().model != ContactModel::kPenalty) return false;
  const bool any_box = std::any_of(bodies.begin(), bodies.end(),
                                   [](const Body& b) { return b.shape == Body::Shape::kBox; });
  return any_box && body_pseudo_particles(scene) > 0;
}

std::unique_ptr<ForceTerm> make_body_body_contact(const Scene& scene, const ParticleOrder& order) {
  if (!has_body_contacts(scene)) return nullptr;
  auto term = std::make_unique<BodyBodyContactForce>(
      scene, body_layout(scene, order.free_particles), scene.get<Contact>());
  term->index_pairs();
  return term;
}

// Random instances: two boxes of their own, above the scene's first plane
// (so the barrier's gaps stay positive; under the barrier they do not
// meet) and away from the other bodies. In kAny states one of the first
// box's vertices is 10 % of the second's half side deep inside it, near
// the middle of its +y face (pushed out through the face that faces the
// first's centre, whichever that is); in kDefinite states (where Newton's
// Gauss-Newton part would have to be exact) they are apart.
void add_random_body_pair(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.dimension != 3) {
    // (In 2-D, which has no bodies: the column's energy from the planes.)
    if (scene.get<Planes>().empty()) plane_kind().add_random(scene, rng, states);
    return;
  }
  const std::size_t first = scene.get<Bodies>().size();
  add_random_body_with(scene, rng, states, false);
  add_random_body_with(scene, rng, states, false);
  Bodies& bodies = scene.block<Bodies>();
  Body& one = bodies[first];
  Body& two = bodies[first + 1];
  Eigen::Vector3d base(0.0, 0.0, 20.0);
  if (!scene.get<Planes>().empty()) {
    const Plane& plane = scene.get<Planes>().front();
    base += plane.point + (10.0 - plane.normal.normalized().dot(base)) * plane.normal.normalized();
  }
  one.position = base;
  const RigidBody a = rigid_body(one), b = rigid_body(two);
  if (states == RandomStates::kDefinite) {
    two.position = base + Eigen::Vector3d(0.0, 0.0, 5.0);  // apart
    return;
  }
  const Eigen::Vector3d half = 0.5 * two.size;  // a box: principal frame = mesh frame
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d vertex = a.p0 + a.A0 * a.X[static_cast<std::size_t>(rng() % a.X.size())];
  const Eigen::Vector3d Y(0.2 * half.x() * u(rng), 0.9 * half.y(), 0.2 * half.z() * u(rng));
  two.position = vertex - b.A0 * Y;
}

}  // namespace

const ElementKind& body_body_contact_kind() {
  static const ElementKind kind = {
      .name = "body-body-contact",
      .refers_to_particles = true,
      .make = make_body_body_contact,
      .energy = {.name = "contact", .counts_with_spring = true},
      .has_elements = has_body_contacts,
      .add_random = add_random_body_pair,
  };
  return kind;
}

}  // namespace springlab
