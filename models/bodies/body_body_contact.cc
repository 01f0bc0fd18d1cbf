// Contact between rigid bodies (docs/physics.md "Contact between bodies"):
// any two bodies (boxes, cylinders, closed meshes) meet through the
// distances of their surfaces' pieces (body_contacts.h: each vertex against
// the other surface, each feature edge against the other's), with the
// scene's contact model on each contact's gap d:
//   barrier:  phi(d) = kappa b(d), b = -(d - dhat)^2 ln(d / dhat) on (0, dhat)
//             (IPC, Li et al. 2020), +infinity at d <= 0;
//   penalty:  phi(d) = k_c/2 (delta - d)^2 on [0, delta), delta the contact
//             distance (a skin), +infinity at d < 0 (contact_potential.h).
// An element kind with no scene key of its own, energy column `contact`.
// Friction between bodies is body_body_friction.cc.
//
// Two ways of evaluating it:
//   - Live (explicit methods, energies, outputs): the contacts found at the
//     evaluated state itself, each gap its pieces' distance D. The energy
//     sum phi(D) is continuous (a contact enters at D = dhat or delta, where
//     phi = 0); the force -phi'(D) grad D with grad D = w_u n
//     (body_contacts.h); the Jacobian -(phi'' grad D grad D^T + phi'
//     hess D), hess D through the closest points' motion
//     (BodyContactFinder::derivatives).
//   - Within an implicit step (ForceTerm::lag): the contacts found at the
//     step's start, each kept as two material points and a frozen normal
//     (Lan et al. 2022, Affine Body Dynamics, sec. 5), so that its gap
//     d = n . (x_a - x_b) is linear in the pair's 24 unknowns: the energy's
//     Hessian phi'' grad d grad d^T is positive semidefinite and the exact
//     one, and the step that closes a gap has a closed form (the line
//     search's cap, admissible_fraction). The contacts are searched as far
//     as each body can move in the step at its start velocity
//     (BodyContactFinder::step_contacts), so that a gap that closes within
//     the step is among them.
// In both, a state where the surfaces interpenetrate (an edge through a
// triangle, a body inside another: BodyContactFinder::overlap) or a gap
// closes has infinite energy: the line search never accepts it, and an
// explicit method that steps there ends diverged, saying which bodies.
//
// Which pairs of bodies are looked at: a broad phase (sweep and prune), and
// the Jacobian's blocks are every pair's up to 16 bodies, beyond that they
// follow the pairs near each other (ForceTerm::pattern_varies;
// body_pair_blocks.h): time and memory grow with the bodies and their
// contacts, not with the square of the bodies.
//
// The gap is unchanged by translating and rotating both bodies together
// (it is a distance, or n . (x_a - x_b) with n turned alike), so the pair
// force conserves the total linear and angular momentum.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <utility>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_contacts.h"
#include "models/bodies/body_pair_blocks.h"
#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"
#include "models/springs/gravity.h"

namespace springlab {

const ElementKind& plane_kind();  // planes.cc
// bodies.cc: a random box; strained (A not a rotation) or not.
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained);

namespace {

// w_u of the gap's gradient dd/dq_u = w_u n: (1, X_a, -1, -X_b).
std::array<double, 8> gap_weights(const BodyContact& k) {
  return {1.0, k.Xa.x(), k.Xa.y(), k.Xa.z(), -1.0, -k.Xb.x(), -k.Xb.y(), -k.Xb.z()};
}

class BodyBodyContactForce final : public ForceTerm {
 public:
  BodyBodyContactForce(const Scene& scene, const BodyLayout& layout, const ParticleOrder& order)
      : finder_(scene, layout), law_(scene.get<Contact>()),
        g_(scene.get<Gravity>().acceleration.norm()),
        begin_(3 * static_cast<std::size_t>(order.first_own(kBodyKind))),
        count_(3 * static_cast<std::size_t>(layout.pseudo_particles)) {
    finder_.place(nullptr);
    blocks_.set(BodyPairBlocks::first_pairs(finder_, law_.distance, fixed_pattern_));
  }

  std::string_view name() const override { return "body-body contact"; }
  bool conservative() const override { return true; }
  bool forbids_states() const override { return true; }
  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "contact between rigid bodies has no projective form; use implicit-euler or another "
          "Newton method";
    return false;
  }

  double potential_energy(const Configuration& c) const override {
    const std::vector<BodyContact>& contacts = current(c.x);
    double sum = 0.0;
    for (const BodyContact& k : contacts) {
      const double d = gap(k, c.x);
      if (law_.forbidden_between_bodies(d)) return std::numeric_limits<double>::infinity();
      sum += law_.between_bodies(d).value;
    }
    if (overlap(c.x).found()) return std::numeric_limits<double>::infinity();
    return sum;
  }

  void add_force(const Configuration& c, double* f) const override {
    for (const BodyContact& k : current(c.x)) {
      const ContactPhi phi = law_.between_bodies(gap(k, c.x));
      // Live, no force where the gap has closed (phi' is NaN there): an
      // explicit step that lands there ends with the interpenetration named
      // (forbidden_state), not with a NaN. Within an implicit step the NaN
      // stays: the line search rejects such a trial at once.
      if (phi.slope == 0.0 || (!lagged_ && std::isnan(phi.slope))) continue;
      const std::array<int, 8> index = BodyPairBlocks::unknowns(finder_, k.a, k.b);
      const std::array<double, 8> w = gap_weights(k);
      for (std::size_t u = 0; u < 8; ++u) {
        if (index[u] < 0) continue;
        for (int r = 0; r < 3; ++r) f[3 * index[u] + r] -= phi.slope * w[u] * k.n[r];
      }
    }
  }

  std::string forbidden_state(const Configuration& c) const override {
    std::ostringstream why;
    for (const BodyContact& k : current(c.x)) {
      const double d = gap(k, c.x);
      if (law_.forbidden_between_bodies(d)) {
        why << "body " << k.a << " and body " << k.b << " met (gap " << d << " m), where "
            << (law_.model == ContactModel::kBarrier ? "the barrier's" : "contact's")
            << " energy is infinite";
        return why.str();
      }
    }
    const BodyOverlap o = overlap(c.x);
    if (o.found()) return o.text() + ": bodies may not interpenetrate";
    return {};
  }

  double admissible_fraction(const Configuration& c, const double* dx) const override {
    double fraction = std::numeric_limits<double>::infinity();
    for (const BodyContact& k : current(c.x)) {
      const double approach = rate(k, dx);
      if (approach < 0.0) fraction = std::min(fraction, gap(k, c.x) / -approach);
    }
    return std::max(fraction, 0.0);
  }

  void lag(const Configuration* c, double h) override {
    lagged_ = false;
    if (c == nullptr) return;
    place(c->x);
    finder_.step_contacts(law_.distance, c->v, h, g_, frozen_);
    lagged_ = true;
  }

  // The contacts found again at an iterate c of the step's solve, each a
  // plane through its pieces' closest points at c, in place of the kept
  // ones (follow_lagged_contacts). A kept plane holds its two material
  // points apart along its normal of the step's start; as the bodies move
  // (an edge sliding along another, a box turning on its edge) other points
  // of the same pieces come closer than those, and the surfaces cross
  // (BodyContactFinder::overlap) where no kept gap closes: the iterate is
  // then pinned there. Found again at c, the planes are those of the pieces'
  // distances there. Not where a gap found at c is closed (the kept
  // contacts let c be reached, the new ones would give it no energy).
  // c null: the contacts of before the last call again.
  bool follow_lag(const Configuration* c, double h) override {
    if (!lagged_) return false;
    if (c == nullptr) {
      frozen_.swap(found_);
      return true;
    }
    place(c->x);
    finder_.step_contacts(law_.distance, c->v, h, g_, found_);
    for (const BodyContact& k : found_) {
      if (law_.forbidden_between_bodies(k.d)) return false;
    }
    frozen_.swap(found_);
    return true;
  }

  bool pattern_varies() const override { return !fixed_pattern_; }
  std::string pattern_change() const override {
    return "bodies come near other bodies (more than " + std::to_string(kAllPairsBodies) +
           " bodies)";
  }
  bool pattern_holds(const Configuration& c) const override {
    for (const BodyContact& k : current(c.x)) {
      if (!blocks_.covers(k.a, k.b)) return false;
    }
    return true;
  }
  void follow_pattern(const Configuration& c) override {
    std::vector<std::pair<int, int>> needed;
    for (const BodyContact& k : current(c.x)) {
      needed.emplace_back(std::min(k.a, k.b), std::max(k.a, k.b));
    }
    place(c.x);
    blocks_.set(BodyPairBlocks::near_pairs(finder_, law_.distance, std::move(needed)));
  }
  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    blocks_.declare(finder_, builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override { blocks_.bind(finder_, pattern); }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx != nullptr) add_stiffness(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    add_stiffness(c, dfdx, true);
  }

 private:
  // The contacts at x: the step's (lagged), else those found at x.
  const std::vector<BodyContact>& current(const double* x) const {
    if (lagged_) return frozen_;
    if (!live_valid_ || !placed_at(x)) {
      place(x);
      finder_.all_contacts(law_.distance, live_);
      live_valid_ = true;
    }
    return live_;
  }

  // Places the bodies at x unless they are there already.
  void place(const double* x) const {
    if (placed_at(x)) return;
    finder_.place(x);
    placed_.assign(x + begin_, x + begin_ + count_);
    live_valid_ = false;
  }
  bool placed_at(const double* x) const {
    return placed_.size() == count_ &&
           std::memcmp(placed_.data(), x + begin_, count_ * sizeof(double)) == 0;
  }
  BodyOverlap overlap(const double* x) const {
    place(x);
    return finder_.overlap();
  }

  // n . (x_a - x_b) at x (for a live contact: its distance D at x).
  double gap(const BodyContact& k, const double* x) const {
    if (!lagged_) return k.d;
    const auto& a = finder_.surface(k.a);
    const auto& b = finder_.surface(k.b);
    return k.n.dot(a.p(x) + a.A(x) * k.Xa - b.p(x) - b.A(x) * k.Xb);
  }
  // Its rate along a step dx (fixed bodies do not move).
  double rate(const BodyContact& k, const double* dx) const {
    const auto& a = finder_.surface(k.a);
    const auto& b = finder_.surface(k.b);
    Eigen::Vector3d move = Eigen::Vector3d::Zero();
    if (a.first >= 0) move += a.p(dx) + a.A(dx) * k.Xa;
    if (b.first >= 0) move -= b.p(dx) + b.A(dx) * k.Xb;
    return k.n.dot(move);
  }


  // -(phi'' grad d grad d^T + phi' hess d), grad d = w (x) n; hess d only
  // live and not definite (within a step d is linear).
  void add_stiffness(const Configuration& c, double* dfdx, bool definite) const {
    const std::vector<BodyContact>& contacts = current(c.x);
    for (const BodyContact& k : contacts) {
      const ContactPhi phi = law_.between_bodies(gap(k, c.x));
      if (phi.curvature == 0.0 && phi.slope == 0.0) continue;
      const std::array<double, 8> w = gap_weights(k);
      const Eigen::Matrix3d nn = k.n * k.n.transpose();
      for (int u = 0; u < 8; ++u) {
        for (int v = 0; v < 8; ++v) {
          blocks_.add(dfdx, k.a, k.b, u, v, nn, -phi.curvature * w[u] * w[v]);
        }
      }
      if (definite || lagged_ || phi.slope == 0.0 || !(k.d > 0.0)) continue;
      place(c.x);
      const BodyContactFinder::Derivatives d = finder_.derivatives(k);
      for (int u = 0; u < 8; ++u) {
        for (int v = 0; v < 8; ++v) {
          blocks_.add(dfdx, k.a, k.b, u, v, d.hessian.block<3, 3>(3 * u, 3 * v), -phi.slope);
        }
      }
    }
  }

  mutable BodyContactFinder finder_;
  ContactLaw law_;
  double g_;
  std::size_t begin_, count_;  // the bodies' unknowns in the state
  bool lagged_ = false;
  std::vector<BodyContact> frozen_;
  std::vector<BodyContact> found_;  // follow_lag's: the contacts kept before
  mutable std::vector<BodyContact> live_;
  mutable bool live_valid_ = false;
  mutable std::vector<double> placed_;
  BodyPairBlocks blocks_;
  bool fixed_pattern_ = false;  // every pair declared (BodyPairBlocks::every_pair)
};

}  // namespace

// Two bodies or more, one of them free.
bool has_body_contacts(const Scene& scene) {
  return scene.get<Bodies>().size() >= 2 && body_pseudo_particles(scene) > 0;
}

namespace {

std::unique_ptr<ForceTerm> make_body_body_contact(const Scene& scene, const ParticleOrder& order) {
  if (!has_body_contacts(scene)) return nullptr;
  return std::make_unique<BodyBodyContactForce>(scene, body_layout(scene, order),
                                                order);
}

// Bodies must start apart: not interpenetrating, and with the barrier not
// touching either (its energy is infinite at a zero gap).
void check_bodies_apart(const Scene& scene, const Reporter& r) {
  if (!has_body_contacts(scene)) return;
  BodyContactFinder finder(scene, body_layout(scene, 0));
  finder.place(nullptr);
  const BodyOverlap o = finder.overlap();
  if (o.found()) {
    r.fail(element("bodies", static_cast<std::size_t>(o.a)),
           "starts interpenetrating body " + std::to_string(o.b) + " (" + o.text() +
               "), which contact between bodies does not allow: move them apart");
  }
  const Contact& contact = scene.get<Contact>();
  if (contact.model != ContactModel::kBarrier) return;
  std::vector<BodyContact> touching;
  finder.all_contacts(contact.distance_or_default(), touching);
  for (const BodyContact& k : touching) {
    if (!(k.d > 0.0)) {
      r.fail(element("bodies", static_cast<std::size_t>(k.a)),
             "starts touching body " + std::to_string(k.b) + " (gap " + shortest_text(k.d) +
                 " m), where the barrier's energy is infinite: with contact model \"barrier\" "
                 "bodies must start apart");
    }
  }
}

void read_body_contacts(const Json&, const Reporter& r, Scene& scene) {
  check_bodies_apart(scene, r);
}

}  // namespace

// Random instances: two boxes of their own, above the scene's first plane
// and away from the other bodies. In kAny states the second box's face
// nearest the first lies 0.3 of the contact distance below the first's
// lowest vertex along that face's normal, under the face's middle: a
// contact inside the distance, the surfaces apart. In kDefinite states
// (where Newton's definite part must be exact) they are apart.
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
  // Two's +y face (a box: principal frame = mesh frame), turned by its A0.
  const Eigen::Vector3d half = 0.5 * two.size;
  const Eigen::Vector3d normal = b.A0.col(1).normalized();
  double lowest = INFINITY;
  Eigen::Vector3d vertex;
  for (const Eigen::Vector3d& X : a.X) {
    const Eigen::Vector3d x = a.p0 + a.A0 * X;
    if (normal.dot(x) < lowest) {
      lowest = normal.dot(x);
      vertex = x;
    }
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double gap = 0.3 * scene.get<Contact>().distance_or_default();
  const Eigen::Vector3d Y(0.2 * half.x() * u(rng), half.y(), 0.2 * half.z() * u(rng));
  two.position = vertex - gap * normal - b.A0 * Y;
}

void body_body_contact_memory(const Scene& scene, MemoryEstimate& out);  // body_pair_memory.cc

const ElementKind& body_body_contact_kind() {
  static const ElementKind kind = {
      .name = "body-body-contact",
      .refers_to_particles = true,
      .read = read_body_contacts,
      .validate = check_bodies_apart,
      .make = make_body_body_contact,
      .energy = {.name = "contact", .counts_with_spring = true, .present = has_body_contacts},
      .memory = body_body_contact_memory,  // body_pair_memory.cc
      .add_random = add_random_body_pair,
  };
  return kind;
}

}  // namespace springlab
