// Gravity, F_i = m_i g on every free particle, potential V = -sum m_i g.x_i
// (SPEC §2: a fixed particle neither moves nor stores energy). Constant, so
// both Jacobians are zero and it declares no blocks.
#include <memory>
#include <vector>

#include "models/force_registry.h"

namespace springlab {
namespace {

class GravityForce final : public ForceTerm {
 public:
  explicit GravityForce(std::vector<double> weight) : weight_(std::move(weight)) {}

  std::string_view name() const override { return "gravity"; }
  bool conservative() const override { return true; }
  bool stiff() const override { return false; }
  bool constant() const override { return true; }
  EnergyKind energy_kind() const override { return EnergyKind::kGravity; }

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

}  // namespace

std::unique_ptr<ForceTerm> make_gravity_force(const Scene& scene, const ParticleOrder& order) {
  if (scene.gravity.isZero()) return nullptr;
  std::vector<double> weight(static_cast<std::size_t>(order.free_particles * order.dim));
  for (int p = 0; p < order.free_particles; ++p) {
    const double m = scene.particles[static_cast<std::size_t>(order.scene_of_internal[p])].mass;
    for (int r = 0; r < order.dim; ++r) weight[p * order.dim + r] = m * scene.gravity[r];
  }
  return std::make_unique<GravityForce>(std::move(weight));
}

}  // namespace springlab
