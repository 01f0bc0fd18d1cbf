// The "gravity" element kind: the scene key "gravity" (docs/physics.md "Scene files") and the
// force F_i = m_i g on every free particle, potential V = -sum m_i g.x_i
// (docs/physics.md "The physics": a fixed particle neither moves nor stores energy). Constant, so
// both Jacobians are zero and it declares no blocks.
#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include "models/core/element_kind.h"
#include "models/springs/gravity.h"

namespace springlab {
namespace {

class GravityForce final : public ForceTerm {
 public:
  explicit GravityForce(std::vector<double> weight) : weight_(std::move(weight)) {}

  std::string_view name() const override { return "gravity"; }
  bool conservative() const override { return true; }
  bool stiff() const override { return false; }
  bool constant() const override { return true; }

  void add_force(const Configuration&, double* f) const override {
    for (std::size_t k = 0; k < weight_.size(); ++k) f[k] += weight_[k];
  }

  double potential_energy(const Configuration& c) const override {
    double energy = 0.0;
    for (std::size_t k = 0; k < weight_.size(); ++k) energy -= weight_[k] * c.x[k];
    return energy;
  }

 private:
  std::vector<double> weight_;  // m_p g_r for each free coordinate
};

std::unique_ptr<ForceTerm> make_gravity_force(const Scene& scene, const ParticleOrder& order) {
  const Eigen::Vector3d& g = scene.get<Gravity>().acceleration;
  if (g.isZero()) return nullptr;
  std::vector<double> weight(static_cast<std::size_t>(order.free_particles * order.dim));
  for (int p = 0; p < order.free_particles; ++p) {
    const double m = scene.particles[static_cast<std::size_t>(order.scene_of_internal[p])].mass;
    for (int r = 0; r < order.dim; ++r) weight[p * order.dim + r] = m * g[r];
  }
  return std::make_unique<GravityForce>(std::move(weight));
}

void read_gravity(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("gravity")) return;
  scene.block<Gravity>().acceleration =
      read_vector(r, "gravity", document.at("gravity"), scene.dimension);
}

void validate_gravity(const Scene& scene, const Reporter& r) {
  check_vector(r, "gravity", scene.get<Gravity>().acceleration, scene.dimension);
}

// Always written (zero when absent), so a scene file shows that it has none.
void write_gravity(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  entries.emplace_back("gravity", json_vector(scene.get<Gravity>().acceleration,
                                              std::clamp(scene.dimension, 0, 3)));
}

// docs/command-line.md "The command line": a particle can fall the diameter d of the scene, gaining
// |g| d per kg.
double gravity_energy_scale(const Scene& scene, double diameter) {
  return scene.get<Gravity>().acceleration.norm() * diameter;
}

void add_random_gravity(Scene& scene, std::mt19937& rng, RandomStates) {
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  Eigen::Vector3d& g = scene.block<Gravity>().acceleration;
  for (int r = 0; r < scene.dimension; ++r) g[r] = u(rng);
}

}  // namespace

const ElementKind& gravity_kind() {
  static const ElementKind kind = {
      .name = "gravity",
      .keys = {{.name = "gravity"}},
      .read = read_gravity,
      .validate = validate_gravity,
      .write = write_gravity,
      .make = make_gravity_force,
      .energy = {.name = "gravity", .always = true},
      .energy_scale_per_mass = gravity_energy_scale,
      .add_random = add_random_gravity,
  };
  return kind;
}

}  // namespace springlab
