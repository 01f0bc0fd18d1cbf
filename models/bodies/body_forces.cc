// The external forces on rigid bodies (bodies.h, docs/physics.md "Rigid
// bodies (affine bodies)"), each an element kind with no scene key of its
// own: gravity on the centre of mass, and the planes' contact, Coulomb
// friction and normal damping (each body's contact_damping) at the bodies'
// surface vertices.
//
// A surface vertex with rest coordinates X is at x = p + A X: its Jacobian
// with respect to the body's unknowns q = (p, a_1, a_2, a_3) is
//   dx/dq = [I, X_1 I, X_2 I, X_3 I] = w^T (x) I,   w = (1, X_1, X_2, X_3),
// so a force f at the vertex is the generalized force w_alpha f on
// unknown alpha, and a vertex Jacobian B = df/dx (or df/dv: the vertex
// velocity is dp/dt + dA/dt X with the same map) is the 4 x 4 block matrix
// w_alpha w_beta B. The per-point formulas are those of particles
// (planes.cc, friction_force.cc, contact_potential.h), unchanged.
//
// Gravity: integral rho g . x dV = m g . p (the first moment vanishes in the
// principal frame), so F_p = m g, nothing on the a_i, potential -m g . p.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <sstream>

#include "models/bodies/bodies.h"
#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"
#include "models/springs/gravity.h"

namespace springlab {

const ElementKind& gravity_kind();  // gravity_force.cc
const ElementKind& plane_kind();    // planes.cc
const ElementKind& friction_kind(); // friction_force.cc
// bodies.cc: a random box; strained (A not a rotation) or not.
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained);

namespace {

// ---- Gravity on the centre of mass. ----

class BodyGravityForce final : public ForceTerm {
 public:
  BodyGravityForce(const BodyLayout& layout, const Eigen::Vector3d& g) {
    for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
      if (layout.first[b] < 0) continue;
      for (int r = 0; r < 3; ++r) weight_.emplace_back(layout.first[b] * 3 + r, layout.bodies[b].mass.mass * g[r]);
    }
  }
  std::string_view name() const override { return "body gravity"; }
  bool conservative() const override { return true; }
  bool stiff() const override { return false; }
  bool constant() const override { return true; }
  void add_force(const Configuration&, double* f) const override {
    for (const auto& [k, w] : weight_) f[k] += w;
  }
  double potential_energy(const Configuration& c) const override {
    double energy = 0.0;
    for (const auto& [k, w] : weight_) energy -= w * c.x[k];
    return energy;
  }

 private:
  std::vector<std::pair<int, double>> weight_;  // (coordinate of p, m g_r)
};

std::unique_ptr<ForceTerm> make_body_gravity(const Scene& scene, const ParticleOrder& order) {
  const Eigen::Vector3d& g = scene.get<Gravity>().acceleration;
  if (g.isZero() || body_pseudo_particles(scene) == 0) return nullptr;
  return std::make_unique<BodyGravityForce>(body_layout(scene, order), g);
}

// ---- Surface vertices. ----

// One surface vertex of a free body.
struct Vertex {
  int first;   // the body's p pseudo-particle
  int body;    // scene index of the body
  int index;   // vertex index within the body's surface
  double w[4]; // 1, X_1, X_2, X_3
};

std::vector<Vertex> free_vertices(const BodyLayout& layout) {
  std::vector<Vertex> out;
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    if (layout.first[b] < 0) continue;
    const std::vector<Eigen::Vector3d>& X = layout.bodies[b].X;
    for (std::size_t v = 0; v < X.size(); ++v) {
      out.push_back({layout.first[b], static_cast<int>(b), static_cast<int>(v),
                     {1.0, X[v].x(), X[v].y(), X[v].z()}});
    }
  }
  return out;
}

// x = p + A X = sum_alpha w_alpha q_alpha (likewise the velocity from v).
Eigen::Vector3d vertex_point(const Vertex& s, const double* q) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int a = 0; a < 4; ++a) {
    for (int r = 0; r < 3; ++r) x[r] += s.w[a] * q[(s.first + a) * 3 + r];
  }
  return x;
}

// The 16 blocks of each body (the map couples all four unknowns).
void declare_body_blocks(const std::vector<Vertex>& vertices, JacobianPatternBuilder& builder) {
  int last = -1;
  for (const Vertex& s : vertices) {
    if (s.first == last) continue;
    last = s.first;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) builder.add_block(s.first + a, s.first + b);
    }
  }
}
std::vector<BlockSlot> find_body_slots(const std::vector<Vertex>& vertices,
                                       const SparseMatrix& pattern) {
  std::vector<BlockSlot> slots;
  for (const Vertex& s : vertices) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) slots.push_back(find_block_slot(pattern, 3, s.first + a, s.first + b));
    }
  }
  return slots;
}
// Adds w_alpha w_beta B to the blocks of vertex k.
void add_vertex_block(double* values, const std::vector<BlockSlot>& slots, std::size_t k,
                      const Vertex& s, const double (&B)[3][3]) {
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      add_block<3>(values, slots[k * 16 + static_cast<std::size_t>(a * 4 + b)], B, s.w[a] * s.w[b]);
    }
  }
}

// ---- Contact with the planes. ----

class BodyContactForce final : public ForceTerm {
 public:
  BodyContactForce(const BodyLayout& layout, const Planes& planes, const Contact& contact)
      : vertices_(free_vertices(layout)), law_(contact) {
    for (Plane p : planes) {
      p.normal.normalize();
      planes_.push_back(p);
    }
  }

  std::string_view name() const override { return "body contact"; }
  bool conservative() const override { return true; }
  bool forbids_states() const override { return law_.model == ContactModel::kBarrier; }
  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "rigid bodies' contact has no projective form; use implicit-euler or another Newton "
          "method";
    return false;
  }

  void add_force(const Configuration& c, double* f) const override {
    for_each_contact(c, [&](std::size_t, const Vertex& s, const Plane& p, const ContactPhi& phi) {
      for (int a = 0; a < 4; ++a) {
        for (int r = 0; r < 3; ++r) f[(s.first + a) * 3 + r] -= s.w[a] * phi.slope * p.normal[r];
      }
    });
  }
  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for_each_contact(c, [&](std::size_t, const Vertex&, const Plane&, const ContactPhi& phi) {
      sum += phi.value;
    });
    return sum;
  }
  std::string forbidden_state(const Configuration& c) const override {
    if (law_.model != ContactModel::kBarrier) return {};
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      for (const Vertex& s : vertices_) {
        const double d = planes_[k].normal.dot(vertex_point(s, c.x) - planes_[k].point);
        if (!(d > 0.0)) {
          std::ostringstream why;
          why << "vertex " << s.index << " of body " << s.body << " stepped through plane " << k
              << " (gap " << d << " m), where the barrier's energy is infinite";
          return why.str();
        }
      }
    }
    return {};
  }
  double admissible_fraction(const Configuration& c, const double* dx) const override {
    double fraction = std::numeric_limits<double>::infinity();
    if (law_.model != ContactModel::kBarrier) return fraction;
    for (const Plane& p : planes_) {
      for (const Vertex& s : vertices_) {
        const double approach = p.normal.dot(vertex_point(s, dx));
        if (approach < 0.0) {
          fraction = std::min(fraction, p.normal.dot(vertex_point(s, c.x) - p.point) / -approach);
        }
      }
    }
    return std::max(fraction, 0.0);
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    declare_body_blocks(vertices_, builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_ = find_body_slots(vertices_, pattern);
  }
  // d2 phi / dq2 = phi'' (w (x) n)(w (x) n)^T: negative semidefinite force Jacobian.
  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    for_each_contact(c, [&](std::size_t k, const Vertex& s, const Plane& p, const ContactPhi& phi) {
      double B[3][3];
      for (int r = 0; r < 3; ++r) {
        for (int q = 0; q < 3; ++q) B[r][q] = -phi.curvature * p.normal[r] * p.normal[q];
      }
      add_vertex_block(dfdx, slots_, k, s, B);
    });
  }

 private:
  template <typename Visit>
  void for_each_contact(const Configuration& c, Visit visit) const {
    for (const Plane& p : planes_) {
      for (std::size_t k = 0; k < vertices_.size(); ++k) {
        const Vertex& s = vertices_[k];
        const ContactPhi phi = law_(p.normal.dot(vertex_point(s, c.x) - p.point));
        if (phi.value != 0.0 || phi.slope != 0.0) visit(k, s, p, phi);
      }
    }
  }

  std::vector<Vertex> vertices_;
  Planes planes_;
  ContactLaw law_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_body_contact(const Scene& scene, const ParticleOrder& order) {
  if (scene.get<Planes>().empty() || body_pseudo_particles(scene) == 0) return nullptr;
  return std::make_unique<BodyContactForce>(body_layout(scene, order),
                                            scene.get<Planes>(), scene.get<Contact>());
}

// ---- Coulomb friction with the planes (friction_force.cc's law at each vertex), and
// the normal damping of the body's contacts (contact_potential.h): per vertex in
// contact, f = -f_n (mu g(|v_t|) v_t + g_n(|v_n|) v_n n) (g_n: normal_damping's g).
// Live its dF/dx adds the normal force's change, phi''(d) (mu g v_t + g_n v_n n) n^T. ----

class BodyFrictionForce final : public ForceTerm {
 public:
  // `planes`: those it acts on (make_body_friction chooses them).
  BodyFrictionForce(const BodyLayout& layout, const Planes& planes, const Contact& contact,
                    std::vector<double> alpha)
      : vertices_(free_vertices(layout)), planes_(planes), law_(contact),
        eps_(contact.smoothing), alpha_(std::move(alpha)) {
    for (Plane& p : planes_) p.normal.normalize();
  }

  std::string_view name() const override { return "body friction"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kNonlinear; }
  bool symmetric_jacobians() const override { return lagged_; }
  bool derives_from_potentials() const override { return lagged_; }
  bool plane_constraints(std::vector<PlaneConstraint>&) const override { return false; }

  double velocity_potential(const Configuration& c) const override {
    if (!lagged_) return 0.0;
    double sum = 0.0;
    for_each_contact(c, [&](std::size_t, const Vertex&, const Sliding& s) {
      sum += s.mu * s.f_n * friction_potential(s.y, eps_) + s.f_n * s.damp.potential;
    });
    return sum;
  }
  void lag(const Configuration* c, double) override {
    lagged_ = false;
    if (c == nullptr) return;
    lagged_fn_.assign(planes_.size() * vertices_.size(), 0.0);
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const ContactPhi phi =
            law_(planes_[k].normal.dot(vertex_point(vertices_[i], c->x) - planes_[k].point));
        lagged_fn_[k * vertices_.size() + i] = phi.slope != 0.0 ? -phi.slope : 0.0;
      }
    }
    lagged_ = true;
  }

  void add_force(const Configuration& c, double* f) const override {
    for_each_contact(c, [&](std::size_t, const Vertex& v, const Sliding& s) {
      for (int a = 0; a < 4; ++a) {
        for (int r = 0; r < 3; ++r) {
          f[(v.first + a) * 3 + r] -= v.w[a] * s.mu * s.f_n * s.g * s.vt[r] +
                                      v.w[a] * s.f_n * s.damp.g * s.un * s.n[r];
        }
      }
    });
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    declare_body_blocks(vertices_, builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_ = find_body_slots(vertices_, pattern);
  }
  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    for_each_contact(c, [&](std::size_t k, const Vertex& v, const Sliding& s) {
      if (dfdv != nullptr) {
        double B[3][3];
        for (int r = 0; r < 3; ++r) {
          for (int q = 0; q < 3; ++q) {
            const double T = (r == q ? 1.0 : 0.0) - s.n[r] * s.n[q];
            B[r][q] = -s.mu * s.f_n * (s.g * T + s.g_over_y * s.vt[r] * s.vt[q]) -
                      s.f_n * s.damp.slope * s.n[r] * s.n[q];
          }
        }
        add_vertex_block(dfdv, slots_, k, v, B);
      }
      if (dfdx != nullptr && s.curvature != 0.0) {
        double B[3][3];
        for (int r = 0; r < 3; ++r) {
          for (int q = 0; q < 3; ++q) {
            B[r][q] = s.mu * s.g * s.curvature * s.vt[r] * s.n[q] +
                      s.curvature * s.damp.g * s.un * s.n[r] * s.n[q];
          }
        }
        add_vertex_block(dfdx, slots_, k, v, B);
      }
    });
  }

 private:
  struct Sliding {
    Eigen::Vector3d n, vt;
    double un;  // n . v at the vertex
    double mu, alpha, y, g, g_over_y, f_n, curvature;
    NormalDamping damp;  // contact_potential.h, at un
  };

  template <typename Visit>
  void for_each_contact(const Configuration& c, Visit visit) const {
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      const Plane& p = planes_[k];
      for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const Vertex& v = vertices_[i];
        Sliding s;
        s.n = p.normal;
        s.mu = p.friction;
        s.alpha = alpha_[static_cast<std::size_t>(v.body)];
        if (s.mu == 0.0 && s.alpha == 0.0) continue;
        if (lagged_) {
          s.f_n = lagged_fn_[k * vertices_.size() + i];
          s.curvature = 0.0;
          if (s.f_n == 0.0) continue;
        } else {
          const ContactPhi phi = law_(p.normal.dot(vertex_point(v, c.x) - p.point));
          if (phi.value == 0.0 && phi.slope == 0.0) continue;
          s.f_n = -phi.slope;
          s.curvature = phi.curvature;
        }
        const Eigen::Vector3d u = vertex_point(v, c.v);
        s.un = s.n.dot(u);
        s.damp = normal_damping(s.alpha, s.un);
        s.vt = u - s.un * s.n;
        const FrictionWeight w = friction_weight(s.vt.squaredNorm(), eps_);
        s.y = w.y;
        s.g = w.g;
        s.g_over_y = w.g_over_y;
        visit(i, v, s);
      }
    }
  }

  std::vector<Vertex> vertices_;
  Planes planes_;
  ContactLaw law_;
  double eps_;
  std::vector<double> alpha_;  // each body's contact damping (scene order)
  bool lagged_ = false;
  std::vector<double> lagged_fn_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_body_friction(const Scene& scene, const ParticleOrder& order) {
  const Planes& planes = scene.get<Planes>();
  std::vector<double> alpha;
  // (A fixed body has no vertices here: its alpha acts only through the
  // free body it meets, in body_body_friction.cc.)
  for (const Body& b : scene.get<Bodies>()) alpha.push_back(b.fixed ? 0.0 : b.contact_damping);
  // Every plane when a free body is damped; else those with friction.
  const bool damped = std::any_of(alpha.begin(), alpha.end(), [](double a) { return a > 0.0; });
  Planes acting;
  for (const Plane& p : planes) {
    if (damped || p.friction > 0.0) acting.push_back(p);
  }
  if (acting.empty() || body_pseudo_particles(scene) == 0) return nullptr;
  return std::make_unique<BodyFrictionForce>(body_layout(scene, order), acting,
                                             scene.get<Contact>(), std::move(alpha));
}

// Random instances: a body (and gravity, planes, friction) when the scene
// has none yet. Unstrained (A a rotation: no rigidity energy), so that the
// kind's own potential is the whole of its column.
void ensure_body(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.dimension == 3 && scene.get<Bodies>().empty()) add_random_body_with(scene, rng, states, false);
}
// (In 2-D, which has no bodies, the particles' gravity or planes only.)
void add_random_body_gravity(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.get<Gravity>().acceleration.isZero()) gravity_kind().add_random(scene, rng, states);
  ensure_body(scene, rng, states);
}
// With the barrier, every free body's surface must start outside every
// plane (gap > 0), as every free particle must (check_barrier_start,
// planes.cc): refused naming the plane, the body and its vertex. (It was a
// run that "diverged at t = 0: the initial energy is not finite".)
void check_body_barrier_start(const Scene& scene, const Reporter& r) {
  const Contact* contact = scene.find<Contact>();
  const Planes* planes = scene.find<Planes>();
  const Bodies* bodies = scene.find<Bodies>();
  if (contact == nullptr || planes == nullptr || bodies == nullptr ||
      contact->model != ContactModel::kBarrier || planes->empty()) {
    return;
  }
  for (std::size_t b = 0; b < bodies->size(); ++b) {
    if ((*bodies)[b].fixed) continue;
    const RigidBody body = rigid_body((*bodies)[b]);
    for (std::size_t k = 0; k < planes->size(); ++k) {
      const Plane& p = (*planes)[k];
      const Eigen::Vector3d n = p.normal.stableNormalized();
      for (std::size_t i = 0; i < body.X.size(); ++i) {
        const double d = n.dot(body.p0 + body.A0 * body.X[i] - p.point);
        if (!(d > 0.0)) {
          r.fail(element("planes", k),
                 "body " + std::to_string(b) + " starts " + (d == 0.0 ? "on" : "inside") +
                     " the plane (its vertex " + std::to_string(i) + " at gap " +
                     shortest_text(d) +
                     " m), where the barrier's energy is infinite: with contact model "
                     "\"barrier\" every free body must start outside every plane");
        }
      }
    }
  }
}
void read_body_barrier_start(const Json&, const Reporter& r, Scene& scene) {
  check_body_barrier_start(scene, r);
}

void add_random_body_contact(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.get<Planes>().empty()) plane_kind().add_random(scene, rng, states);
  ensure_body(scene, rng, states);
}
void add_random_body_friction(Scene& scene, std::mt19937& rng, RandomStates states) {
  friction_kind().add_random(scene, rng, states);  // planes with mu, a smoothing speed
  ensure_body(scene, rng, states);
  // Normal damping on the bodies' contacts (alpha v_n of order 1).
  std::uniform_real_distribution<double> u(0.5, 2.0);
  for (Body& b : scene.block<Bodies>()) b.contact_damping = u(rng);
}

}  // namespace

const ElementKind& body_gravity_kind() {
  static const ElementKind kind = {
      .name = "body-gravity",
      .refers_to_particles = true,
      .make = make_body_gravity,
      .energy = {.name = "gravity", .always = true},
      .add_random = add_random_body_gravity,
  };
  return kind;
}

const ElementKind& body_contact_kind() {
  static const ElementKind kind = {
      .name = "body-contact",
      .refers_to_particles = true,
      .read = read_body_barrier_start,
      .validate = check_body_barrier_start,
      .make = make_body_contact,
      .energy = {.name = "contact", .counts_with_spring = true},
      .add_random = add_random_body_contact,
  };
  return kind;
}

const ElementKind& body_friction_kind() {
  static const ElementKind kind = {
      .name = "body-friction",
      .refers_to_particles = true,
      .make = make_body_friction,
      .add_random = add_random_body_friction,
  };
  return kind;
}

}  // namespace springlab
