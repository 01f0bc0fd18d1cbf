// The "plane" kind: a scene's "planes" (docs/physics.md "Contact with planes"), half-spaces the
// free particles must not enter, and the contact force that keeps them out. With
// d = n.(x_i - point) the gap of particle i to a plane, each pair stores
// the penalty or barrier potential phi(d) of contact_potential.h (with the
// barrier, an implicit solver's line search on the incremental potential
// never lets a gap close)
// so F_i = -phi'(d) n and dF_i/dx_i = -phi''(d) n n^T; phi'' >= 0 in both,
// so dF/dx is already negative semidefinite (its definite part is itself).
// The energy is the "contact" column.
#include <cmath>
#include <limits>
#include <algorithm>
#include <memory>
#include <sstream>
#include <string>

#include "models/contact/contact.h"
#include "models/contact/contact_potential.h"
#include "models/core/element_kind.h"

namespace springlab {
namespace {

Planes unit_normals(Planes planes) {
  for (Plane& p : planes) p.normal.stableNormalize();  // (no overflow: [0, 1e308, 1e308])
  return planes;
}

class PlaneContactForce final : public ForceTerm {
 public:
  PlaneContactForce(const Planes& planes, const Contact& contact, const ParticleOrder& order)
      : planes_(unit_normals(planes)), law_(contact), dim_(order.dim),
        free_particles_(order.free_particles), scene_of_internal_(order.scene_of_internal) {}

  std::string_view name() const override { return "contact"; }
  bool conservative() const override { return true; }
  bool forbids_states() const override { return law_.model == ContactModel::kBarrier; }

  void add_force(const Configuration& c, double* f) const override {
    for_each_contact(c, [&](int i, const Plane& p, const ContactPhi& phi) {
      for (int r = 0; r < dim_; ++r) f[i * dim_ + r] -= phi.slope * p.normal[r];
    });
  }

  // The barrier is +infinity at d <= 0: the first particle (in the model's
  // order) through a plane.
  std::string forbidden_state(const Configuration& c) const override {
    if (law_.model != ContactModel::kBarrier) return {};
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      for (int i = 0; i < free_particles_; ++i) {
        const double d = gap(c, planes_[k], i);
        if (!(d > 0.0)) {
          std::ostringstream why;
          why << "particle " << scene_of_internal_[static_cast<std::size_t>(i)]
              << " stepped through plane " << k << " (gap " << d
              << " m), where the barrier's energy is infinite";
          return why.str();
        }
      }
    }
    return {};
  }

  // The barrier's gap d + a n.dx_i closes at a = d / (-n.dx_i) where the
  // particle approaches the plane (n.dx_i < 0).
  double admissible_fraction(const Configuration& c, const double* dx) const override {
    double fraction = std::numeric_limits<double>::infinity();
    if (law_.model != ContactModel::kBarrier) return fraction;
    for (const Plane& p : planes_) {
      for (int i = 0; i < free_particles_; ++i) {
        double approach = 0.0;
        for (int r = 0; r < dim_; ++r) approach += p.normal[r] * dx[i * dim_ + r];
        if (approach < 0.0) fraction = std::min(fraction, gap(c, p, i) / -approach);
      }
    }
    return std::max(fraction, 0.0);
  }

  bool plane_constraints(std::vector<PlaneConstraint>& out) const override {
    for (const Plane& p : planes_) {
      PlaneConstraint c;
      c.normal = p.normal;
      c.offset = p.normal.dot(p.point);
      c.stiffness = law_.model == ContactModel::kPenalty ? law_.stiffness : 0.0;
      c.friction = p.friction;
      out.push_back(c);
    }
    return true;
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for_each_contact(c, [&](int, const Plane&, const ContactPhi& phi) { sum += phi.value; });
    return sum;
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    for (int i = 0; i < free_particles_; ++i) slots_.push_back(find_block_slot(pattern, dim_, i, i));
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    for_each_contact(c, [&](int i, const Plane& p, const ContactPhi& phi) {
      const BlockSlot& slot = slots_[static_cast<std::size_t>(i)];
      for (int col = 0; col < dim_; ++col) {
        for (int row = 0; row < dim_; ++row) {
          dfdx[slot.offset[col] + row] -= phi.curvature * p.normal[row] * p.normal[col];
        }
      }
    });
  }

  // Vertex block descent (models/vertex_blocks.h): F_p = -phi'(d) n and
  // dF_p/dx_p = -phi''(d) n n^T per plane (already semidefinite), and the
  // barrier's cap: particle p alone closes a gap at d / (-n.dx).
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool,
                         const VertexBlocks& out) const override {
    for (int n = 0; n < count; ++n) {
      const int i = particles[n];
      for (const Plane& p : planes_) {
        const ContactPhi phi = law_(gap(c, p, i));
        if (phi.value == 0.0 && phi.slope == 0.0) continue;
        for (int r = 0; r < dim_; ++r) {
          out.f[n * dim_ + r] -= phi.slope * p.normal[r];
          for (int q = 0; q < dim_; ++q) {
            out.dfdx[n * dim_ * dim_ + r * dim_ + q] -= phi.curvature * p.normal[r] * p.normal[q];
          }
        }
      }
    }
  }
  double vertex_admissible_fraction(const Configuration& c, int i,
                                    const double* dx) const override {
    double fraction = std::numeric_limits<double>::infinity();
    if (law_.model != ContactModel::kBarrier) return fraction;
    for (const Plane& p : planes_) {
      double approach = 0.0;
      for (int r = 0; r < dim_; ++r) approach += p.normal[r] * dx[r];
      if (approach < 0.0) fraction = std::min(fraction, gap(c, p, i) / -approach);
    }
    return std::max(fraction, 0.0);
  }

 private:
  // Calls visit(particle, plane, phi) for every free particle and plane
  // with a nonzero phi.
  template <typename Visit>
  void for_each_contact(const Configuration& c, Visit visit) const {
    for (const Plane& p : planes_) {
      for (int i = 0; i < free_particles_; ++i) {
        const ContactPhi phi = law_(gap(c, p, i));
        if (phi.value != 0.0 || phi.slope != 0.0) visit(i, p, phi);
      }
    }
  }

  // d = n.(x_i - point)
  double gap(const Configuration& c, const Plane& p, int i) const {
    double d = 0.0;
    for (int r = 0; r < dim_; ++r) d += p.normal[r] * (c.x[i * dim_ + r] - p.point[r]);
    return d;
  }

  Planes planes_;
  ContactLaw law_;
  int dim_, free_particles_;
  std::vector<int> scene_of_internal_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_plane_force(const Scene& scene, const ParticleOrder& order) {
  const Planes& planes = scene.get<Planes>();
  if (planes.empty()) return nullptr;
  return std::make_unique<PlaneContactForce>(planes, scene.get<Contact>(), order);
}

void check_plane(const Reporter& r, const std::string& where, const Plane& p, int dimension) {
  check_vector(r, field(where, "point"), p.point, dimension);
  check_vector(r, field(where, "normal"), p.normal, dimension);
  check_nonnegative(r, field(where, "friction"), p.friction);
}

void read_planes(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("planes")) return;
  const Json& list = document.at("planes");
  require_array(r, "planes", list);
  Planes& out = scene.block<Planes>();
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string where = element("planes", k);
    require_object(r, where, list[k]);
    check_keys(r, where, list[k], {"point", "normal", "friction"}, {"point", "normal"});
    Plane p;
    p.point = read_vector(r, field(where, "point"), list[k].at("point"), scene.dimension);
    const Eigen::Vector3d n =
        read_vector(r, field(where, "normal"), list[k].at("normal"), scene.dimension);
    // (Its largest component, not its norm: the norm of a finite vector
    // may overflow, as [0, 1e308, 1e308]'s does.)
    if (!(n.cwiseAbs().maxCoeff() > 0.0)) r.fail(field(where, "normal"), "must be a nonzero vector");
    p.normal = n;  // as given (so the file round-trips); the force normalizes it
    if (list[k].contains("friction")) {
      p.friction = read_number(r, field(where, "friction"), list[k].at("friction"));
    }
    check_plane(r, where, p, scene.dimension);
    out.push_back(p);
  }
}

void validate_planes(const Scene& scene, const Reporter& r) {
  const Planes& planes = scene.get<Planes>();
  for (std::size_t k = 0; k < planes.size(); ++k) {
    const std::string where = element("planes", k);
    check_plane(r, where, planes[k], scene.dimension);
    if (!(planes[k].normal.cwiseAbs().maxCoeff() > 0.0)) {
      r.fail(field(where, "normal"), "must be a nonzero vector");
    }
  }
}

void write_planes(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  const Planes* planes = scene.find<Planes>();
  if (planes == nullptr || planes->empty()) return;
  JsonLines lines;
  for (const Plane& p : *planes) {
    lines.add("{\"point\": " + json_vector(p.point, scene.dimension) +
              ", \"normal\": " + json_vector(p.normal, scene.dimension) +
              ", \"friction\": " + json_number(p.friction) + "}");
  }
  entries.emplace_back("planes", lines.str());
}

// A plane with a random normal placed so that some particles are in
// contact: past it (penalty) or within the barrier's distance (barrier,
// every gap positive).
}  // namespace

void check_barrier_start(const Scene& scene, const Reporter& r) {
  const Contact* contact = scene.find<Contact>();
  const Planes* planes = scene.find<Planes>();
  if (contact == nullptr || planes == nullptr || contact->model != ContactModel::kBarrier) return;
  for (std::size_t k = 0; k < planes->size(); ++k) {
    const Plane& p = (*planes)[k];
    const Eigen::Vector3d n = p.normal.stableNormalized();
    for (std::size_t i = 0; i < scene.particles.size(); ++i) {
      if (scene.particles[i].fixed) continue;
      const double d = n.dot(scene.particles[i].x - p.point);
      if (!(d > 0.0)) {
        r.fail(element("planes", k),
               "particle " + std::to_string(i) + " starts " + (d == 0.0 ? "on" : "inside") +
                   " the plane (gap " + shortest_text(d) +
                   " m), where the barrier's energy is infinite: with contact model "
                   "\"barrier\" every free particle must start outside every plane");
      }
    }
  }
}

namespace {

void add_random_planes(Scene& scene, std::mt19937& rng, RandomStates) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int r = 0; r < scene.dimension; ++r) n[r] = g(rng);
  n.normalize();
  std::vector<double> heights;
  for (const Particle& p : scene.particles) heights.push_back(n.dot(p.x));
  std::sort(heights.begin(), heights.end());
  const Contact& c = scene.get<Contact>();
  Plane plane;
  plane.normal = n;
  const double level = c.model == ContactModel::kPenalty
                           ? 0.5 * (heights[2] + heights[3])               // half the particles past it
                           : heights[0] - 0.3 * c.distance_or_default();  // all gaps > 0
  plane.point = level * n;
  scene.block<Planes>().push_back(plane);
}

std::size_t count_planes(const Scene& scene) { return scene.get<Planes>().size(); }

}  // namespace

const ElementKind& plane_kind() {
  static const ElementKind kind = {
      .name = "plane",
      .keys = {{.name = "planes", .cap = kMaxScenePlanes, .count = count_planes}},
      .read = read_planes,
      .validate = validate_planes,
      .write = write_planes,
      .make = make_plane_force,
      .energy = {.name = "contact", .counts_with_spring = true},
      .add_random = add_random_planes,
  };
  return kind;
}

}  // namespace springlab
