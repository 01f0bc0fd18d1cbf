// The "friction" element kind: Coulomb friction of the planes (docs/physics.md
// "Contact with planes"). It has no scene key of its own: it reads each
// plane's "friction" mu (planes.cc) and the contact's "smoothing" eps_v
// (contact_kind.cc).
//
// A free particle in contact with a plane (phi'(d) != 0, contact_potential.h)
// is pushed out with the normal force magnitude f_n = -phi'(d) >= 0. Friction
// opposes its tangential velocity v_t = T v, T = I - n n^T, with magnitude
// mu f_n, smoothed below the speed eps_v as in IPC (Li et al. 2020, sec. 5.2):
//   F = -mu f_n f1(y) v_t / y,   y = |v_t|,
//   f1(y) = 2 y / eps_v - y^2 / eps_v^2 for y < eps_v, 1 beyond,
// so F = -mu f_n g(y) v_t with g(y) = f1(y) / y = 2/eps_v - y/eps_v^2 (y < eps_v)
// or 1/y. f1 is C^1 (f1'(eps_v) = 0) and f1(0) = 0: a particle that sticks
// (|F_tangential| < mu f_n) creeps at the speed y where f1(y) = |F| / (mu f_n)
// < 1, so below eps_v.
// Jacobians (blocks of the particle with itself):
//   dF/dv = -mu f_n (g T + (g'(y) / y) v_t v_t^T)   symmetric, negative
//           semidefinite (g' / y = -1/(eps_v^2 y) or -1/y^3)
//   dF/dx = -mu g v_t (df_n/dx)^T = mu g phi''(d) v_t n^T   (NOT symmetric)
//
// Lagging. Evaluated live, friction is a force of (x, v) like spring
// damping, with the normal force where every other force is, so the same
// closed forms hold for every integrator; it then derives from no
// potential, and Newton would have to work on ||r|| with sparse LU. So the
// hand-written implicit methods lag f_n (MechanicalSystem::
// lag_normal_forces) from the step's start during their solve, as IPC does
// (the plane's tangent projection T is constant, so only f_n needs it):
// friction is then F = -dW/dv of W(v) = sum mu f_n0 f0(|v_t|), f0' = f1,
// and Newton minimizes the incremental potential with the symmetric
// definite matrix. On a body resting or sliding on a plane f_n does not
// change, and the closed forms are the same. Explicit and adaptive methods
// evaluate it live. Friction's work F.v <= 0 is dissipation, counted with
// drag's in the damping budget.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"

namespace springlab {

const ElementKind& plane_kind();  // planes.cc: a random plane for the instance

namespace {

// A plane with friction, its normal made unit.
struct FrictionPlane {
  Eigen::Vector3d point, normal;
  double mu;
};

class FrictionForce final : public ForceTerm {
 public:
  FrictionForce(std::vector<FrictionPlane> planes, const Contact& contact, int dim,
                int free_particles)
      : planes_(std::move(planes)), law_(contact), eps_(contact.smoothing), dim_(dim),
        free_particles_(free_particles) {}

  std::string_view name() const override { return "friction"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kNonlinear; }
  // Live, dF/dx = mu g phi'' v_t n^T is not symmetric and F has no
  // potential; lagged, F = -dW/dv with
  //   W(v) = sum mu f_n0 f0(|v_t|),  f0(y) = y^2/eps_v - y^3/(3 eps_v^2) (y < eps_v),
  //   y - eps_v/3 beyond  (f0' = f1; IPC's D(v), Li et al. 2020, eq. 15),
  // and dF/dx = 0.
  bool symmetric_jacobians() const override { return lagged_; }
  bool derives_from_potentials() const override { return lagged_; }
  double velocity_potential(const Configuration& c) const override {
    if (!lagged_) return 0.0;
    double sum = 0.0;
    auto f0 = [&](double y) { return friction_potential(y, eps_); };
    if (dim_ == 2) {
      for_each_contact<2>(c, [&](int, double mu, const Sliding<2>& s) { sum += mu * s.f_n * f0(s.y); });
    } else {
      for_each_contact<3>(c, [&](int, double mu, const Sliding<3>& s) { sum += mu * s.f_n * f0(s.y); });
    }
    return sum;
  }
  void lag(const Configuration* c, double) override {
    lagged_ = false;
    if (c == nullptr) return;
    lagged_fn_.assign(planes_.size() * static_cast<std::size_t>(free_particles_), 0.0);
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      for (int i = 0; i < free_particles_; ++i) {
        double d = 0.0;
        for (int r = 0; r < dim_; ++r) {
          d += planes_[k].normal[r] * (c->x[i * dim_ + r] - planes_[k].point[r]);
        }
        const ContactPhi phi = law_(d);
        lagged_fn_[k * static_cast<std::size_t>(free_particles_) + static_cast<std::size_t>(i)] =
            phi.slope != 0.0 ? -phi.slope : 0.0;
      }
    }
    lagged_ = true;
  }

  // The fast solvers apply friction with the planes' constraints.
  bool plane_constraints(std::vector<PlaneConstraint>&) const override { return true; }

  void add_force(const Configuration& c, double* f) const override {
    if (dim_ == 2) add_force_d<2>(c, f); else add_force_d<3>(c, f);
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    for (int i = 0; i < free_particles_; ++i) slots_.push_back(find_block_slot(pattern, dim_, i, i));
  }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    if (dim_ == 2) add_jacobians_d<2>(c, dfdx, dfdv); else add_jacobians_d<3>(c, dfdx, dfdv);
  }

  // Vertex block descent (models/vertex_blocks.h): the same force and
  // blocks per particle (lagged during vbd's step, as during Newton's).
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool definite,
                         const VertexBlocks& out) const override {
    if (dim_ == 2) add_vertex_blocks_d<2>(c, particles, count, definite, out);
    else add_vertex_blocks_d<3>(c, particles, count, definite, out);
  }

 private:
  template <int D>
  void add_vertex_blocks_d(const Configuration& c, const int* particles, int count,
                           bool definite, const VertexBlocks& out) const {
    for (int n = 0; n < count; ++n) {
      const int i = particles[n];
      for_particle<D>(c, i, [&](double mu, const Sliding<D>& s) {
        for (int r = 0; r < D; ++r) {
          out.f[n * D + r] -= mu * s.f_n * s.g * s.vt[r];
          for (int q = 0; q < D; ++q) {
            const double T_rq = (r == q ? 1.0 : 0.0) - s.n[r] * s.n[q];
            if (out.dfdv != nullptr) {
              out.dfdv[n * D * D + r * D + q] -=
                  mu * s.f_n * (s.g * T_rq + s.g_over_y * s.vt[r] * s.vt[q]);
            }
            // Live, the normal force's change: not symmetric, left out of
            // the definite block.
            if (!definite && s.curvature != 0.0) {
              out.dfdx[n * D * D + r * D + q] += mu * s.g * s.curvature * s.vt[r] * s.n[q];
            }
          }
        }
      });
    }
  }

  // One particle in contact with one plane: what both the force and the
  // Jacobians need.
  template <int D>
  struct Sliding {
    double n[D], vt[D];
    double y;           // |v_t|
    double g;           // f1(y) / y
    double g_over_y;    // g'(y) / y (0 at y = 0, where v_t v_t^T = 0)
    double f_n;         // the normal force: -phi'(d), or the lagged one
    double curvature;   // phi''(d) (0 when lagged: f_n does not depend on x)
  };

  // Calls visit(particle, mu, sliding) for every free particle in contact
  // with a plane that has friction.
  template <int D, typename Visit>
  void for_each_contact(const Configuration& c, Visit visit) const {
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      for (int i = 0; i < free_particles_; ++i) {
        Sliding<D> s;
        if (sliding<D>(c, k, i, s)) visit(i, planes_[k].mu, s);
      }
    }
  }
  // The same for one particle, over the planes: visit(mu, sliding).
  template <int D, typename Visit>
  void for_particle(const Configuration& c, int i, Visit visit) const {
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      Sliding<D> s;
      if (sliding<D>(c, k, i, s)) visit(planes_[k].mu, s);
    }
  }
  // Particle i on plane k: false when not in contact.
  template <int D>
  bool sliding(const Configuration& c, std::size_t k, int i, Sliding<D>& s) const {
    const FrictionPlane& p = planes_[k];
    double d = 0.0, vn = 0.0;
    for (int r = 0; r < D; ++r) {
      s.n[r] = p.normal[r];
      d += s.n[r] * (c.x[i * D + r] - p.point[r]);
      vn += s.n[r] * c.v[i * D + r];
    }
    if (lagged_) {
      s.f_n = lagged_fn_[k * static_cast<std::size_t>(free_particles_) + static_cast<std::size_t>(i)];
      s.curvature = 0.0;
      if (s.f_n == 0.0) return false;  // not in contact at the lagged state
    } else {
      const ContactPhi phi = law_(d);
      if (phi.value == 0.0 && phi.slope == 0.0) return false;  // not in contact
      s.f_n = -phi.slope;
      s.curvature = phi.curvature;
    }
    double y2 = 0.0;
    for (int r = 0; r < D; ++r) {
      s.vt[r] = c.v[i * D + r] - vn * s.n[r];
      y2 += s.vt[r] * s.vt[r];
    }
    const FrictionWeight w = friction_weight(y2, eps_);
    s.y = w.y;
    s.g = w.g;
    s.g_over_y = w.g_over_y;
    return true;
  }

  template <int D>
  void add_force_d(const Configuration& c, double* f) const {
    for_each_contact<D>(c, [&](int i, double mu, const Sliding<D>& s) {
      for (int r = 0; r < D; ++r) f[i * D + r] -= mu * s.f_n * s.g * s.vt[r];
    });
  }

  template <int D>
  void add_jacobians_d(const Configuration& c, double* dfdx, double* dfdv) const {
    for_each_contact<D>(c, [&](int i, double mu, const Sliding<D>& s) {
      const BlockSlot& slot = slots_[static_cast<std::size_t>(i)];
      const double f_n = s.f_n;
      if (dfdv != nullptr) {
        double B[D][D];
        for (int r = 0; r < D; ++r) {
          for (int q = 0; q < D; ++q) {
            const double T_rq = (r == q ? 1.0 : 0.0) - s.n[r] * s.n[q];
            B[r][q] = -mu * f_n * (s.g * T_rq + s.g_over_y * s.vt[r] * s.vt[q]);
          }
        }
        add_block<D>(dfdv, slot, B, 1.0);
      }
      if (dfdx != nullptr && s.curvature != 0.0) {
        double B[D][D];
        for (int r = 0; r < D; ++r) {
          for (int q = 0; q < D; ++q) B[r][q] = mu * s.g * s.curvature * s.vt[r] * s.n[q];
        }
        add_block<D>(dfdx, slot, B, 1.0);
      }
    });
  }

  std::vector<FrictionPlane> planes_;
  ContactLaw law_;
  double eps_;
  bool lagged_ = false;
  std::vector<double> lagged_fn_;  // per (plane, free particle) while lagged
  int dim_, free_particles_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_friction_force(const Scene& scene, const ParticleOrder& order) {
  std::vector<FrictionPlane> planes;
  for (const Plane& p : scene.get<Planes>()) {
    if (p.friction > 0.0) planes.push_back({p.point, p.normal.stableNormalized(), p.friction});
  }
  if (planes.empty()) return nullptr;
  return std::make_unique<FrictionForce>(std::move(planes), scene.get<Contact>(), order.dim,
                                         order.free_particles);
}

// Gives every plane a friction coefficient (adding a random plane when the
// scene has none) and a smoothing speed comparable to the random
// velocities, so that particles both stick (y < eps_v) and slide.
void add_random_friction(Scene& scene, std::mt19937& rng, RandomStates states) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (scene.get<Planes>().empty()) plane_kind().add_random(scene, rng, states);
  for (Plane& p : scene.block<Planes>()) p.friction = 0.2 + 0.6 * u(rng);
  scene.block<Contact>().smoothing = 0.4 + 0.6 * u(rng);
}

// Friction's kind is read after the particles and the planes: the check
// that needs both, a barrier's start outside every plane, runs here.
void read_barrier_start(const Json&, const Reporter& r, Scene& scene) {
  check_barrier_start(scene, r);
}
void validate_barrier_start(const Scene& scene, const Reporter& r) {
  check_barrier_start(scene, r);
}

}  // namespace

const ElementKind& friction_kind() {
  static const ElementKind kind = {
      .name = "friction",
      .refers_to_particles = true,
      .read = read_barrier_start,
      .validate = validate_barrier_start,
      .make = make_friction_force,
      .add_random = add_random_friction,
  };
  return kind;
}

}  // namespace springlab
