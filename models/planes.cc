// The "plane" kind: a scene's "planes" (README "Contact with planes"), half-spaces the free
// particles must not enter, and the contact force that keeps them out. With
// d = n.(x_i - point) the gap of particle i to a plane, each pair stores
//   penalty:  phi(d) = k_c/2 min(d, 0)^2                      (any d)
//   barrier:  phi(d) = kappa b(d), b(d) = -(d - dhat)^2 ln(d / dhat)
//             for 0 < d < dhat, 0 beyond, +infinity for d <= 0
//             (IPC, Li et al. 2020: an implicit solver's line search on the
//             incremental potential then never lets a gap close)
// so F_i = -phi'(d) n and dF_i/dx_i = -phi''(d) n n^T; phi'' >= 0 in both,
// so dF/dx is already negative semidefinite (its definite part is itself).
// The energy is the "contact" column.
#include <cmath>
#include <algorithm>
#include <limits>
#include <memory>

#include "models/contact.h"
#include "models/element_kind.h"

namespace springlab {
namespace {

struct Phi {
  double value, slope, curvature;  // phi, phi', phi''
};

Phi penalty(double k, double d) {
  if (d >= 0.0) return {0.0, 0.0, 0.0};
  return {0.5 * k * d * d, k * d, k};
}

// b = -(d - h)^2 ln(d/h); b' = -2 (d - h) ln(d/h) - (d - h)^2 / d;
// b'' = -2 ln(d/h) - 4 (d - h)/d + (d - h)^2 / d^2.
Phi barrier(double kappa, double h, double d) {
  if (d >= h) return {0.0, 0.0, 0.0};
  if (!(d > 0.0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {std::numeric_limits<double>::infinity(), nan, nan};
  }
  const double e = d - h, l = std::log(d / h);
  return {-kappa * e * e * l, kappa * (-2.0 * e * l - e * e / d),
          kappa * (-2.0 * l - 4.0 * e / d + e * e / (d * d))};
}

Planes unit_normals(Planes planes) {
  for (Plane& p : planes) p.normal.normalize();
  return planes;
}

class PlaneContactForce final : public ForceTerm {
 public:
  PlaneContactForce(const Planes& planes, const Contact& contact, int dim, int free_particles)
      : planes_(unit_normals(planes)), model_(contact.model), stiffness_(contact.stiffness_or_default()),
        distance_(contact.distance_or_default()), dim_(dim), free_particles_(free_particles) {}

  std::string_view name() const override { return "contact"; }
  bool conservative() const override { return true; }
  bool forbids_states() const override { return model_ == ContactModel::kBarrier; }

  void add_force(const Configuration& c, double* f) const override {
    for_each_contact(c, [&](int i, const Plane& p, const Phi& phi) {
      for (int r = 0; r < dim_; ++r) f[i * dim_ + r] -= phi.slope * p.normal[r];
    });
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for_each_contact(c, [&](int, const Plane&, const Phi& phi) { sum += phi.value; });
    return sum;
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    for (int i = 0; i < free_particles_; ++i) slots_.push_back(find_block_slot(pattern, dim_, i, i));
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    for_each_contact(c, [&](int i, const Plane& p, const Phi& phi) {
      const BlockSlot& slot = slots_[static_cast<std::size_t>(i)];
      for (int col = 0; col < dim_; ++col) {
        for (int row = 0; row < dim_; ++row) {
          dfdx[slot.offset[col] + row] -= phi.curvature * p.normal[row] * p.normal[col];
        }
      }
    });
  }

 private:
  // Calls visit(particle, plane, phi) for every free particle and plane
  // with a nonzero phi.
  template <typename Visit>
  void for_each_contact(const Configuration& c, Visit visit) const {
    for (const Plane& p : planes_) {
      for (int i = 0; i < free_particles_; ++i) {
        double d = 0.0;
        for (int r = 0; r < dim_; ++r) d += p.normal[r] * (c.x[i * dim_ + r] - p.point[r]);
        const Phi phi = model_ == ContactModel::kPenalty ? penalty(stiffness_, d)
                                                         : barrier(stiffness_, distance_, d);
        if (phi.value != 0.0 || phi.slope != 0.0) visit(i, p, phi);
      }
    }
  }

  Planes planes_;
  ContactModel model_;
  double stiffness_, distance_;
  int dim_, free_particles_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_plane_force(const Scene& scene, const ParticleOrder& order) {
  const Planes& planes = scene.get<Planes>();
  if (planes.empty()) return nullptr;
  return std::make_unique<PlaneContactForce>(planes, scene.get<Contact>(), order.dim,
                                             order.free_particles);
}

void check_plane(const Reporter& r, const std::string& where, const Plane& p, int dimension) {
  check_vector(r, field(where, "point"), p.point, dimension);
  check_vector(r, field(where, "normal"), p.normal, dimension);
  check_nonnegative(r, field(where, "friction"), p.friction);
  if (p.friction != 0.0) {
    r.fail(field(where, "friction"),
           "Coulomb friction is not available yet: give 0 or leave it out");
  }
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
    if (!(n.norm() > 0.0) || !std::isfinite(n.norm())) {
      r.fail(field(where, "normal"), "must be a nonzero vector");
    }
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
    if (!(planes[k].normal.norm() > 0.0) || !std::isfinite(planes[k].normal.norm())) {
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
