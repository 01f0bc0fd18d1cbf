// The "drag" element kind: the scene key "drag" (docs/physics.md "Scene files") and the course's
// F^dp = -gamma v on every free particle (docs/physics.md "The physics").
// dF/dv = -gamma I (diagonal), dF/dx = 0. Dissipates power gamma |v|^2.
// Derives from the dissipation potential W(v) = gamma |v|^2 / 2.
#include <memory>
#include <random>
#include <vector>

#include "models/springs/drag.h"
#include "models/core/element_kind.h"

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

  // The particles' diagonal only (rigid bodies' unknowns follow them).
  void bind_jacobian(const SparseMatrix& pattern) override {
    diagonal_ = diagonal_slots(pattern);
    diagonal_.resize(static_cast<std::size_t>(free_dofs_));
  }

  // Vertex block descent (models/vertex_blocks.h): F_p = -gamma v_p,
  // dF_p/dv_p = -gamma I.
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool,
                         const VertexBlocks& out) const override {
    const int d = c.dim;
    for (int n = 0; n < count; ++n) {
      for (int r = 0; r < d; ++r) {
        out.f[n * d + r] -= gamma_ * c.v[particles[n] * d + r];
        if (out.dfdv != nullptr) out.dfdv[n * d * d + r * d + r] -= gamma_;
      }
    }
  }

  void add_jacobians(const Configuration&, double*, double* dfdv) const override {
    if (dfdv == nullptr) return;
    for (int slot : diagonal_) dfdv[slot] -= gamma_;
  }

 private:
  double gamma_;
  int free_dofs_;
  std::vector<int> diagonal_;
};

std::unique_ptr<ForceTerm> make_drag_force(const Scene& scene, const ParticleOrder& order) {
  const double gamma = scene.get<Drag>().gamma;
  if (gamma == 0.0) return nullptr;
  return std::make_unique<DragForce>(gamma, order.dim, order.free_particles);
}

void read_drag(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("drag")) return;
  const double gamma = read_number(r, "drag", document.at("drag"));
  check_nonnegative(r, "drag", gamma);
  scene.block<Drag>().gamma = gamma;
}

void validate_drag(const Scene& scene, const Reporter& r) {
  check_nonnegative(r, "drag", scene.get<Drag>().gamma);
}

// Always written (0 when absent), so a scene file shows that it has none.
void write_drag(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  entries.emplace_back("drag", json_number(scene.get<Drag>().gamma));
}

void add_random_drag(Scene& scene, std::mt19937& rng, RandomStates) {
  scene.block<Drag>().gamma = std::uniform_real_distribution<double>(0.1, 0.6)(rng);
}

}  // namespace

const ElementKind& drag_kind() {
  static const ElementKind kind = {
      .name = "drag",
      .keys = {{.name = "drag"}},
      .read = read_drag,
      .validate = validate_drag,
      .write = write_drag,
      .make = make_drag_force,
      .add_random = add_random_drag,
  };
  return kind;
}

}  // namespace springlab
