// The "wind" element kind: the scene key "wind" (docs/physics.md "Scene files") and wind with
// gusts (docs/physics.md "The physics"): F_i = c_w (w(t) - v_i) on every free particle,
//   w(t) = w0 (1 + gust sin(2 pi f t)).
// It depends on t (so integrators must evaluate it at their stage times) and
// relaxes each particle's velocity toward the wind: dF/dv = -c_w I, dF/dx = 0.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "models/core/element_kind.h"
#include "models/springs/wind.h"

namespace springlab {
namespace {

class WindForce final : public ForceTerm {
 public:
  WindForce(const Wind& wind, int dim, int free_particles)
      : wind_(wind), dim_(dim), free_particles_(free_particles) {}

  std::string_view name() const override { return "wind"; }
  bool conservative() const override { return false; }
  bool stiff() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kDiagonal; }

  void add_force(const Configuration& c, double* f) const override {
    double w[3];
    wind_at(c.t, w);
    for (int p = 0; p < free_particles_; ++p) {
      for (int r = 0; r < dim_; ++r) {
        const int k = p * dim_ + r;
        f[k] += wind_.coefficient * (w[r] - c.v[k]);
      }
    }
  }

  // F = -dW/dv with W(t, v) = c_w sum_i |v_i - w(t)|^2 / 2.
  bool derives_from_potentials() const override { return true; }
  double velocity_potential(const Configuration& c) const override {
    double w[3];
    wind_at(c.t, w);
    double sum = 0.0;
    for (int p = 0; p < free_particles_; ++p) {
      for (int r = 0; r < dim_; ++r) {
        const double relative = c.v[p * dim_ + r] - w[r];
        sum += relative * relative;
      }
    }
    return 0.5 * wind_.coefficient * sum;
  }

  // The particles' diagonal only (rigid bodies' unknowns follow them).
  void bind_jacobian(const SparseMatrix& pattern) override {
    diagonal_ = diagonal_slots(pattern);
    diagonal_.resize(static_cast<std::size_t>(free_particles_ * dim_));
  }

  // Vertex block descent (models/vertex_blocks.h): F_p = c_w (w(t) - v_p),
  // dF_p/dv_p = -c_w I.
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool,
                         const VertexBlocks& out) const override {
    double w[3];
    wind_at(c.t, w);
    for (int n = 0; n < count; ++n) {
      for (int r = 0; r < dim_; ++r) {
        out.f[n * dim_ + r] += wind_.coefficient * (w[r] - c.v[particles[n] * dim_ + r]);
        if (out.dfdv != nullptr) out.dfdv[n * dim_ * dim_ + r * dim_ + r] -= wind_.coefficient;
      }
    }
  }

  void add_jacobians(const Configuration&, double*, double* dfdv) const override {
    if (dfdv == nullptr) return;
    for (int slot : diagonal_) dfdv[slot] -= wind_.coefficient;
  }

 private:
  void wind_at(double t, double (&w)[3]) const {
    const double gust = 1.0 + wind_.gust * std::sin(2.0 * std::numbers::pi * wind_.frequency * t);
    for (int r = 0; r < dim_; ++r) w[r] = wind_.velocity[r] * gust;
  }

  Wind wind_;
  int dim_;
  int free_particles_;
  std::vector<int> diagonal_;
};

std::unique_ptr<ForceTerm> make_wind_force(const Scene& scene, const ParticleOrder& order) {
  const Wind* wind = scene.find<Wind>();
  if (wind == nullptr || wind->coefficient == 0.0) return nullptr;
  return std::make_unique<WindForce>(*wind, order.dim, order.free_particles);
}

void read_wind(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("wind")) return;
  const Json& j = document.at("wind");
  require_object(r, "wind", j);
  check_keys(r, "wind", j, {"velocity", "coefficient", "gust", "frequency"}, {"velocity"});
  Wind wind;
  wind.velocity = read_vector(r, "wind.velocity", j.at("velocity"), scene.dimension);
  auto optional_rate = [&](const char* key, double& out) {
    if (!j.contains(key)) return;
    out = read_number(r, field("wind", key), j.at(key));
    check_nonnegative(r, field("wind", key), out);
  };
  optional_rate("coefficient", wind.coefficient);
  optional_rate("gust", wind.gust);
  optional_rate("frequency", wind.frequency);
  scene.block<Wind>() = wind;
}

void validate_wind(const Scene& scene, const Reporter& r) {
  const Wind* wind = scene.find<Wind>();
  if (wind == nullptr) return;
  check_vector(r, "wind.velocity", wind->velocity, scene.dimension);
  check_nonnegative(r, "wind.coefficient", wind->coefficient);
  check_nonnegative(r, "wind.gust", wind->gust);
  check_nonnegative(r, "wind.frequency", wind->frequency);
}

void write_wind(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  const Wind* w = scene.find<Wind>();
  if (w == nullptr) return;
  entries.emplace_back("wind", "{\"velocity\": " +
                                   json_vector(w->velocity, std::clamp(scene.dimension, 0, 3)) +
                                   ", \"coefficient\": " + json_number(w->coefficient) +
                                   ", \"gust\": " + json_number(w->gust) +
                                   ", \"frequency\": " + json_number(w->frequency) + "}");
}

// docs/command-line.md "The command line": the wind can bring a particle to its largest speed
// |w_max| = |w0| (1 + gust), a kinetic energy of |w_max|^2 / 2 per kg.
double wind_energy_scale(const Scene& scene, double) {
  const Wind* wind = scene.find<Wind>();
  if (wind == nullptr) return 0.0;
  const double w_max = wind->velocity.norm() * (1.0 + std::abs(wind->gust));
  return 0.5 * w_max * w_max;
}

void add_random_wind(Scene& scene, std::mt19937& rng, RandomStates) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Wind& wind = scene.block<Wind>();
  for (int r = 0; r < scene.dimension; ++r) wind.velocity[r] = 4.0 * u(rng) - 2.0;
  wind.coefficient = 0.1 + 0.3 * u(rng);
  wind.gust = 0.5 * u(rng);
  wind.frequency = 0.2 + 2.0 * u(rng);
}

}  // namespace

const ElementKind& wind_kind() {
  static const ElementKind kind = {
      .name = "wind",
      .keys = {{.name = "wind"}},
      .read = read_wind,
      .validate = validate_wind,
      .write = write_wind,
      .make = make_wind_force,
      .energy_scale_per_mass = wind_energy_scale,
      .feeds_energy = true,
      .add_random = add_random_wind,
  };
  return kind;
}

}  // namespace springlab
