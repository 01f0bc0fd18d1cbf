// Contact between rigid bodies (docs/physics.md "Contact between bodies"):
// the surface vertices of each body against every other body that is a box
// (shape "box"), with the planes' penalty phi(d) = k_c/2 min(d, 0)^2
// (models/contact/contact_potential.h) on the gap d through the face of the box
// that faces the other body's centre (the geometry: body_pairs.h). An
// element kind with no scene key of its own; it acts when the scene's
// contact model is the penalty (the default). Friction between bodies is
// body_body_friction.cc.
//
// d is a quadratic polynomial of the pair's unknowns, with the gradient of
// body_pairs.h and Hessian blocks d2d/dq_alpha da_i = s w_alpha I (alpha
// one of a's unknowns, w = (1, X)), d2d/dp_b da_i = -s I, d2d/da_i2 =
// -2 h_i I. The force is -phi'(d) grad d and its Jacobian
// -(phi''(d) grad d grad d^T + phi'(d) hess d); Newton's definite part
// keeps the first, semidefinite, term (Gauss-Newton).
//
// d is invariant under translating and rotating everything (x, p, a_i ->
// Q x + t, ...), and so is the face choice, so the pair force conserves
// the total linear and angular momentum. The force jumps where the face
// switches (two |Z_i| / h_i equal: a's centre over b's edge) and where a
// vertex through the face leaves it sideways (|Y_k| = h_k).
//
// Left out, and said so in the docs: a cylinder or mesh as the body pushed
// into (only their vertices push into boxes); edge-edge crossings with no
// vertex inside; the barrier model (with it bodies do not meet each other).
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_pairs.h"
#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"

namespace springlab {

const ElementKind& plane_kind();  // planes.cc
// bodies.cc: a random box; strained (A not a rotation) or not.
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained);

namespace {

class BodyBodyContactForce final : public ForceTerm {
 public:
  BodyBodyContactForce(const Scene& scene, const BodyLayout& layout, const Contact& contact)
      : pairs_(scene, layout), law_(contact) {}

  std::string_view name() const override { return "body-body contact"; }
  bool conservative() const override { return true; }
  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "contact between rigid bodies has no projective form; use implicit-euler or another "
          "Newton method";
    return false;
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for_each_touch(c, [&](const BodyPairs::Touch&, const ContactPhi& phi) { sum += phi.value; });
    return sum;
  }

  void add_force(const Configuration& c, double* f) const override {
    for_each_touch(c, [&](const BodyPairs::Touch& t, const ContactPhi& phi) {
      const auto grad = pairs_.gap_gradient(t);
      const auto& index = pairs_.pairs()[t.pair].index;
      for (std::size_t u = 0; u < 8; ++u) {
        if (index[u] < 0) continue;
        for (int r = 0; r < 3; ++r) f[3 * index[u] + r] -= phi.slope * grad[u][r];
      }
    });
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    pairs_.declare_blocks(builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override { slots_ = pairs_.find_slots(pattern); }
  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx != nullptr) add_stiffness(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    add_stiffness(c, dfdx, true);
  }

 private:
  template <typename Visit>
  void for_each_touch(const Configuration& c, Visit visit) const {
    if (law_.model != ContactModel::kPenalty) return;
    pairs_.for_each_inside(c.x, [&](const BodyPairs::Touch& t) {
      const ContactPhi phi = law_(t.d);
      if (phi.value != 0.0 || phi.slope != 0.0) visit(t, phi);
    });
  }

  // -(phi'' grad d grad d^T + phi' hess d); the definite part keeps the first.
  void add_stiffness(const Configuration& c, double* dfdx, bool definite) const {
    for_each_touch(c, [&](const BodyPairs::Touch& t, const ContactPhi& phi) {
      const BodyPairs::Pair& pair = pairs_.pairs()[t.pair];
      const auto grad = pairs_.gap_gradient(t);
      const BlockSlot* slots = slots_.data() + t.pair * 64;
      double K[3][3];
      for (std::size_t u = 0; u < 8; ++u) {
        if (pair.index[u] < 0) continue;
        for (std::size_t w = 0; w < 8; ++w) {
          if (pair.index[w] < 0) continue;
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) K[r][q] = grad[u][r] * grad[w][q];
          }
          add_block<3>(dfdx, slots[8 * u + w], K, -phi.curvature);
        }
      }
      if (definite) return;
      // hess d: s w_alpha I between a's unknown alpha and b's a_i, -s I
      // between p_b and a_i, -2 h_i I on a_i.
      const double h = pairs_.member(pair.b).half[t.axis];
      const std::size_t ai = 5 + static_cast<std::size_t>(t.axis);
      const double I[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      auto add_identity = [&](std::size_t u, std::size_t w, double s) {
        if (pair.index[u] < 0 || pair.index[w] < 0) return;
        add_block<3>(dfdx, slots[8 * u + w], I, -phi.slope * s);
      };
      for (std::size_t alpha = 0; alpha < 4; ++alpha) {
        add_identity(alpha, ai, t.side * t.c[alpha]);
        add_identity(ai, alpha, t.side * t.c[alpha]);
      }
      add_identity(4, ai, -t.side);
      add_identity(ai, 4, -t.side);
      add_identity(ai, ai, -2.0 * h);
    });
  }

  BodyPairs pairs_;
  ContactLaw law_;
  std::vector<BlockSlot> slots_;
};

}  // namespace

// Two bodies or more, one a box, one free, and the penalty model.
bool has_body_contacts(const Scene& scene) {
  const Bodies& bodies = scene.get<Bodies>();
  if (bodies.size() < 2 || scene.get<Contact>().model != ContactModel::kPenalty) return false;
  const bool any_box = std::any_of(bodies.begin(), bodies.end(),
                                   [](const Body& b) { return b.shape == Body::Shape::kBox; });
  return any_box && body_pseudo_particles(scene) > 0;
}

// The barrier does not act between bodies yet (issue 46.13): a scene whose
// bodies could meet is refused in one line instead of letting them pass
// through each other silently.
void check_no_barrier_between_bodies(const Scene& scene, const Reporter& r) {
  const Bodies& bodies = scene.get<Bodies>();
  if (bodies.size() < 2 || scene.get<Contact>().model != ContactModel::kBarrier) return;
  const bool any_box = std::any_of(bodies.begin(), bodies.end(),
                                   [](const Body& b) { return b.shape == Body::Shape::kBox; });
  if (!any_box || body_pseudo_particles(scene) == 0) return;
  r.fail("contact.model",
         "\"barrier\" acts between bodies and planes only, not between the scene's " +
             std::to_string(bodies.size()) +
             " bodies (they would pass through each other): use \"penalty\" for bodies that "
             "touch one another");
}
void read_no_barrier_between_bodies(const Json&, const Reporter& r, Scene& scene) {
  check_no_barrier_between_bodies(scene, r);
}

std::unique_ptr<ForceTerm> make_body_body_contact(const Scene& scene, const ParticleOrder& order) {
  if (!has_body_contacts(scene)) return nullptr;
  return std::make_unique<BodyBodyContactForce>(scene, body_layout(scene, order.free_particles),
                                                scene.get<Contact>());
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
  // Bodies meet only under the penalty model (the barrier is refused
  // between bodies: check_no_barrier_between_bodies).
  scene.block<Contact>().model = ContactModel::kPenalty;
  const std::size_t first = scene.get<Bodies>().size();
  add_random_body_with(scene, rng, states, false);
  add_random_body_with(scene, rng, states, false);
  Bodies& bodies = scene.block<Bodies>();
  Body& one = bodies[first];
  Body& two = bodies[first + 1];
  // 10 m above the first plane, 5 m along it per body the scene had.
  Eigen::Vector3d base(0.0, 0.0, 20.0), along = Eigen::Vector3d::UnitX();
  if (!scene.get<Planes>().empty()) {
    const Plane& plane = scene.get<Planes>().front();
    const Eigen::Vector3d n = plane.normal.normalized();
    base += plane.point + (10.0 - n.dot(base)) * n;
    along = n.unitOrthogonal();
  }
  base += 5.0 * static_cast<double>(first) * along;
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

void body_body_contact_memory(const Scene& scene, MemoryEstimate& out);  // body_pair_memory.cc

const ElementKind& body_body_contact_kind() {
  static const ElementKind kind = {
      .name = "body-body-contact",
      .refers_to_particles = true,
      .read = read_no_barrier_between_bodies,
      .validate = check_no_barrier_between_bodies,
      .make = make_body_body_contact,
      .energy = {.name = "contact", .counts_with_spring = true, .present = has_body_contacts},
      .memory = body_body_contact_memory,  // body_pair_memory.cc
      .add_random = add_random_body_pair,
  };
  return kind;
}

}  // namespace springlab
