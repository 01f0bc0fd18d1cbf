// Coulomb friction and normal damping between rigid bodies (docs/physics.md
// "Contact between bodies"): at every contact of body_body_contact.cc (a's material point
// X_a, b's X_b, the normal n from b's to a's, the gap d: body_contacts.h)
// smoothed Coulomb friction as with the planes (friction_force.cc; IPC, Li
// et al. 2020, sec. 5.2) at a's point x_a, on its velocity relative to b's
// material point Y_b under it (x_a = p_b + A_b Y_b, i.e.
// Y_b = X_b + d A_b^-1 n), so that both bodies feel it at one place and
// the pair exerts no torque:
//
//   v_rel = (p_a' + A_a' X_a) - (p_b' + A_b' Y_b) = sum_u c_u v_u,
//   c = (1, X_a, -1, -Y_b) on the pair's 8 pseudo-particles,
//   v_t = T v_rel,  T = I - n n^T,
//   f = -mu f_n g(|v_t|) v_t  on a, -f on b, both at x_a,
//
// with mu = sqrt(mu_a mu_b) (each body's "friction") and the contact's
// normal force f_n = -phi'(d). The generalized force on unknown u is
// F_u = c_u f.
//
// Within an implicit step (lagged, MechanicalSystem::lag_normal_forces) the
// contacts, their f_n, T, X_a and Y_b are the step start's
// (BodyContactFinder::step_contacts), and friction is F = -dW/dv of
// W(v) = sum mu f_n f0(|T v_rel|), with no x-dependence:
//   dF_u/dv_w = -mu f_n c_u c_w G T,   G = g I + (g'/y) v_t v_t^T.
// Live, everything moves with x: f_n through the distance D, n and X_a
// through the closest points (BodyContactFinder::derivatives gives dD/dq,
// dn/dq, dX_a/dq), and Y_b = A_b^-1 (x_a - p_b) with them:
//   dY_b/dq = A_b^-1 (C + A_a dX_a/dq),   C = [c_u I] (dx_a - dp_b - dA_b Y_b),
//   dv_rel/dq = A_a' dX_a/dq - A_b' dY_b/dq,
//   dv_t/dq = T dv_rel/dq - (n . v_rel) dn/dq - n v_rel^T dn/dq,
//   df/dq = -mu (g v_t (df_n/dq)^T + f_n G dv_t/dq),  df_n/dq = -phi'' dD/dq,
//   dF_u/dq = c_u df/dq + f dc_u/dq.
//
// Normal damping (after Hunt and Crossley 1975; contact_potential.h) acts at
// the same place with alpha = (alpha_a + alpha_b) / 2 (each body's
// "contact_damping"): f += -f_n g_n v_n n, v_n = n . v_rel, g_n = alpha at
// low speed (normal_damping). Lagged, it adds f_n f0(|v_n|) to W and
// -f_n f1'(|v_n|) n n^T to df/dv_rel (f1' = d(g_n v_n)/dv_n); live,
//   df/dq += -(g_n v_n n (df_n/dq)^T + f_n f1' n dv_n/dq + f_n g_n v_n dn/dq),
//   dv_n/dq = n^T dv_rel/dq + v_rel^T dn/dq.
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_contacts.h"
#include "models/bodies/body_pair_blocks.h"
#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"
#include "models/springs/gravity.h"

namespace springlab {

// body_body_contact.cc: two boxes of their own within the contact distance
// (apart in kDefinite states); whether a scene's bodies meet.
void add_random_body_pair(Scene& scene, std::mt19937& rng, RandomStates states);
bool has_body_contacts(const Scene& scene);

namespace {

class BodyBodyFrictionForce final : public ForceTerm {
 public:
  BodyBodyFrictionForce(const Scene& scene, const BodyLayout& layout, const ParticleOrder& order)
      : finder_(scene, layout), law_(scene.get<Contact>()), eps_(scene.get<Contact>().smoothing),
        g_(scene.get<Gravity>().acceleration.norm()),
        begin_(3 * static_cast<std::size_t>(order.first_own(kBodyKind))),
        count_(3 * static_cast<std::size_t>(layout.pseudo_particles)) {
    finder_.place(nullptr);
    blocks_.set(BodyPairBlocks::first_pairs(finder_, law_.distance, fixed_pattern_));
  }

  std::string_view name() const override { return "body-body friction"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kNonlinear; }
  bool symmetric_jacobians() const override { return lagged_; }
  bool derives_from_potentials() const override { return lagged_; }

  double velocity_potential(const Configuration& c) const override {
    if (!lagged_) return 0.0;
    double sum = 0.0;
    for (const Sliding& s : frozen_) {
      const Eigen::Vector3d v_rel = relative_velocity(s, c.v);
      const double y = (s.T * v_rel).norm();
      sum += s.mu * s.f_n * friction_potential(y, eps_) +
             s.f_n * normal_damping(s.alpha, s.n.dot(v_rel)).potential;
    }
    return sum;
  }

  void lag(const Configuration* c, double h) override {
    lagged_ = false;
    frozen_.clear();
    if (c == nullptr) return;
    place(c->x);
    std::vector<BodyContact> contacts;
    finder_.step_contacts(law_.distance, c->v, h, g_, contacts);
    for (const BodyContact& k : contacts) {
      Sliding s;
      if (sliding(k, c->x, s)) frozen_.push_back(s);
    }
    lagged_ = true;
  }

  void add_force(const Configuration& c, double* f) const override {
    visit(c, [&](const Sliding& s, const BodyContact*) {
      const Eigen::Vector3d v_rel = relative_velocity(s, c.v);
      const Eigen::Vector3d vt = s.T * v_rel;
      const FrictionWeight fw = friction_weight(vt.squaredNorm(), eps_);
      const double vn = s.n.dot(v_rel);
      const Eigen::Vector3d force = pair_force(s, fw, vt, vn, normal_damping(s.alpha, vn));
      const std::array<int, 8> index = BodyPairBlocks::unknowns(finder_, s.a, s.b);
      for (std::size_t u = 0; u < 8; ++u) {
        if (index[u] < 0) continue;
        for (int r = 0; r < 3; ++r) f[3 * index[u] + r] += s.w[u] * force[r];
      }
    });
  }

  bool pattern_varies() const override { return !fixed_pattern_; }
  std::string pattern_change() const override {
    return "bodies come near other bodies (more than " + std::to_string(kAllPairsBodies) +
           " bodies)";
  }
  bool pattern_holds(const Configuration& c) const override {
    bool holds = true;
    visit(c, [&](const Sliding& s, const BodyContact*) { holds = holds && blocks_.covers(s.a, s.b); });
    return holds;
  }
  void follow_pattern(const Configuration& c) override {
    std::vector<std::pair<int, int>> needed;
    visit(c, [&](const Sliding& s, const BodyContact*) {
      needed.emplace_back(std::min(s.a, s.b), std::max(s.a, s.b));
    });
    place(c.x);
    blocks_.set(BodyPairBlocks::near_pairs(finder_, law_.distance, std::move(needed)));
  }
  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    blocks_.declare(finder_, builder);
  }
  void bind_jacobian(const SparseMatrix& pattern) override { blocks_.bind(finder_, pattern); }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    visit(c, [&](const Sliding& s, const BodyContact* live) {
      const Eigen::Vector3d v_rel = relative_velocity(s, c.v);
      const Eigen::Vector3d vt = s.T * v_rel;
      const FrictionWeight fw = friction_weight(vt.squaredNorm(), eps_);
      const Eigen::Matrix3d G =
          fw.g * Eigen::Matrix3d::Identity() + fw.g_over_y * vt * vt.transpose();
      // (Lagged, s.n is the step's normal; live, the contact's own: the same.)
      const double vn = s.n.dot(v_rel);
      const NormalDamping damp = normal_damping(s.alpha, vn);
      if (dfdv != nullptr) {
        // df/dv_rel
        const Eigen::Matrix3d D =
            -s.mu * s.f_n * G * s.T - s.f_n * damp.slope * s.n * s.n.transpose();
        for (int u = 0; u < 8; ++u) {
          for (int w = 0; w < 8; ++w) blocks_.add(dfdv, s.a, s.b, u, w, D, s.w[u] * s.w[w]);
        }
      }
      if (dfdx == nullptr || live == nullptr || !(live->d > 0.0)) return;
      // Live: through f_n, n and the material points (the header's chain).
      place(c.x);
      const BodyContactFinder::Derivatives d = finder_.derivatives(*live);
      const ContactPhi phi = law_.between_bodies(live->d);
      const Eigen::Matrix<double, 1, 24> dfn = -phi.curvature * d.gradient.transpose();
      const Eigen::Matrix3d Adot_a = velocity_matrix(s.a, c.v), Adot_b = velocity_matrix(s.b, c.v);
      Eigen::Matrix<double, 3, 24> dYb = finder_.surface(s.a).A(c.x) * d.dXa;
      for (int u = 0; u < 8; ++u) dYb.block<3, 3>(0, 3 * u).diagonal().array() += s.w[u];
      dYb = s.B * dYb;
      const Eigen::Matrix<double, 3, 24> dv_rel = Adot_a * d.dXa - Adot_b * dYb;
      const Eigen::Vector3d& n = live->n;
      const Eigen::Matrix<double, 3, 24> dvt =
          s.T * dv_rel - n.dot(v_rel) * d.dn - n * (v_rel.transpose() * d.dn);
      const Eigen::Matrix<double, 1, 24> dvn = n.transpose() * dv_rel + v_rel.transpose() * d.dn;
      const Eigen::Matrix<double, 3, 24> df =
          -s.mu * (fw.g * vt * dfn + s.f_n * G * dvt) -
          (damp.g * vn * n * dfn + s.f_n * damp.slope * n * dvn + s.f_n * damp.g * vn * d.dn);
      const Eigen::Vector3d force = pair_force(s, fw, vt, vn, damp);
      for (int u = 0; u < 8; ++u) {
        // dw_u/dq: 0 for p's; the material point's row for the a_i's.
        Eigen::Matrix<double, 1, 24> dw = Eigen::Matrix<double, 1, 24>::Zero();
        if (u >= 1 && u <= 3) dw = d.dXa.row(u - 1);
        if (u >= 5) dw = -dYb.row(u - 5);
        const Eigen::Matrix<double, 3, 24> dF = s.w[u] * df + force * dw;
        for (int w = 0; w < 8; ++w) {
          blocks_.add(dfdx, s.a, s.b, u, w, dF.block<3, 3>(0, 3 * w), 1.0);
        }
      }
    });
  }

 private:
  // One contact with friction, and what its force needs.
  struct Sliding {
    int a = 0, b = 0;
    std::array<double, 8> w{};  // c = (1, X_a, -1, -Y_b)
    Eigen::Vector3d Yb;
    Eigen::Matrix3d B;          // A_b^-1
    Eigen::Matrix3d T;
    Eigen::Vector3d n;
    double mu = 0.0, alpha = 0.0, f_n = 0.0;
  };

  // f = -f_n (mu g(|v_t|) v_t + g_n(|v_n|) v_n n), on a at x_a.
  static Eigen::Vector3d pair_force(const Sliding& s, const FrictionWeight& fw,
                                    const Eigen::Vector3d& vt, double vn,
                                    const NormalDamping& damp) {
    return -s.mu * s.f_n * fw.g * vt - s.f_n * damp.g * vn * s.n;
  }

  // The contact's friction and damping at x, if it has any (mu > 0 or
  // alpha > 0, and a normal force).
  bool sliding(const BodyContact& k, const double* x, Sliding& s) const {
    const BodyContactFinder::Surface &a = finder_.surface(k.a), &b = finder_.surface(k.b);
    const double mu = std::sqrt(a.friction * b.friction);
    const double alpha = 0.5 * (a.contact_damping + b.contact_damping);
    if (!(mu > 0.0) && !(alpha > 0.0)) return false;
    const ContactPhi phi = law_.between_bodies(k.d);
    if (!(phi.slope < 0.0)) return false;  // (also skips a closed gap's NaN)
    s.a = k.a;
    s.b = k.b;
    s.B = finder_.surface(k.b).A(x).inverse();
    s.Yb = k.Xb + k.d * s.B * k.n;
    s.w = {1.0, k.Xa.x(), k.Xa.y(), k.Xa.z(), -1.0, -s.Yb.x(), -s.Yb.y(), -s.Yb.z()};
    s.T = Eigen::Matrix3d::Identity() - k.n * k.n.transpose();
    s.n = k.n;
    s.mu = mu;
    s.alpha = alpha;
    s.f_n = -phi.slope;
    return true;
  }

  Eigen::Vector3d relative_velocity(const Sliding& s, const double* v) const {
    const std::array<int, 8> index = BodyPairBlocks::unknowns(finder_, s.a, s.b);
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (std::size_t u = 0; u < 8; ++u) {
      if (index[u] < 0) continue;
      for (int r = 0; r < 3; ++r) out[r] += s.w[u] * v[3 * index[u] + r];
    }
    return out;
  }
  Eigen::Matrix3d velocity_matrix(int body, const double* v) const {
    const BodyContactFinder::Surface& s = finder_.surface(body);
    return s.first < 0 ? Eigen::Matrix3d::Zero() : s.A(v);
  }

  // Each contact with friction at c: the step's (lagged; no live contact),
  // else those found at c.x with the live contact.
  template <typename Visit>
  void visit(const Configuration& c, Visit visit_one) const {
    if (lagged_) {
      for (const Sliding& s : frozen_) visit_one(s, nullptr);
      return;
    }
    place(c.x);
    if (!live_valid_) {
      finder_.all_contacts(law_.distance, live_);
      live_valid_ = true;
    }
    for (const BodyContact& k : live_) {
      Sliding s;
      if (sliding(k, c.x, s)) visit_one(s, &k);
    }
  }

  void place(const double* x) const {
    if (placed_.size() == count_ &&
        std::memcmp(placed_.data(), x + begin_, count_ * sizeof(double)) == 0) {
      return;
    }
    finder_.place(x);
    placed_.assign(x + begin_, x + begin_ + count_);
    live_valid_ = false;
  }


  mutable BodyContactFinder finder_;
  ContactLaw law_;
  double eps_, g_;
  std::size_t begin_, count_;
  bool lagged_ = false;
  std::vector<Sliding> frozen_;
  mutable std::vector<BodyContact> live_;
  mutable bool live_valid_ = false;
  mutable std::vector<double> placed_;
  BodyPairBlocks blocks_;
  bool fixed_pattern_ = false;  // every pair declared (BodyPairBlocks::every_pair)
};

}  // namespace

// Whether the term exists (body_pair_memory.cc counts its pairs likewise).
bool has_body_friction(const Scene& scene) {
  if (!has_body_contacts(scene)) return false;
  int rough = 0;
  bool damped = false;
  for (const Body& b : scene.get<Bodies>()) {
    rough += b.friction > 0.0 ? 1 : 0;
    damped = damped || b.contact_damping > 0.0;
  }
  return rough >= 2 || damped;
}

namespace {

std::unique_ptr<ForceTerm> make_body_body_friction(const Scene& scene,
                                                   const ParticleOrder& order) {
  if (!has_body_friction(scene)) return nullptr;
  return std::make_unique<BodyBodyFrictionForce>(scene, body_layout(scene, order),
                                                 order);
}

// Random instances: body-body contact's pair, then a friction coefficient
// for every body.
void add_random_body_friction_pair(Scene& scene, std::mt19937& rng, RandomStates states) {
  add_random_body_pair(scene, rng, states);
  if (scene.dimension != 3) return;
  std::uniform_real_distribution<double> u(0.3, 0.8), alpha(0.5, 2.0);
  for (Body& b : scene.block<Bodies>()) {
    b.friction = u(rng);
    b.contact_damping = alpha(rng);  // normal damping too (alpha v_n of order 1)
  }
}

}  // namespace

void body_body_friction_memory(const Scene& scene, MemoryEstimate& out);  // body_pair_memory.cc

const ElementKind& body_body_friction_kind() {
  static const ElementKind kind = {
      .name = "body-body-friction",
      .refers_to_particles = true,
      .make = make_body_body_friction,
      .memory = body_body_friction_memory,  // body_pair_memory.cc
      .add_random = add_random_body_friction_pair,
  };
  return kind;
}

}  // namespace springlab
