// Drag, the course's F^dp = -gamma v, on every free particle (SPEC §2).
// dF/dv = -gamma I (diagonal), dF/dx = 0. Dissipates power gamma |v|^2.
// Derives from the dissipation potential W(v) = gamma |v|^2 / 2.
#include <memory>
#include <vector>

#include "models/force_registry.h"

namespace springlab {
namespace {

class DragForce final : public ForceTerm {
 public:
  DragForce(double gamma, int dim, int free_particles)
      : gamma_(gamma), free_dofs_(dim * free_particles) {}

  std::string_view name() const override { return "drag"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kDiagonal; }

  void add_force(const Configuration& c, double* f) const override {
    for (int k = 0; k < free_dofs_; ++k) f[k] -= gamma_ * c.v[k];
  }

  // F = -dW/dv with W = gamma |v|^2 / 2.
  bool derives_from_potentials() const override { return true; }
  double velocity_potential(const Configuration& c) const override {
    double sum = 0.0;
    for (int k = 0; k < free_dofs_; ++k) sum += c.v[k] * c.v[k];
    return 0.5 * gamma_ * sum;
  }

  void bind_jacobian(const SparseMatrix& pattern) override { diagonal_ = diagonal_slots(pattern); }

  void add_jacobians(const Configuration&, double*, double* dfdv) const override {
    if (dfdv == nullptr) return;
    for (int slot : diagonal_) dfdv[slot] -= gamma_;
  }

 private:
  double gamma_;
  int free_dofs_;
  std::vector<int> diagonal_;
};

}  // namespace

std::unique_ptr<ForceTerm> make_drag_force(const Scene& scene, const ParticleOrder& order) {
  if (scene.drag == 0.0) return nullptr;
  return std::make_unique<DragForce>(scene.drag, order.dim, order.free_particles);
}

}  // namespace springlab
