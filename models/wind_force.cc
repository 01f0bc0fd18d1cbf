// Wind with gusts (SPEC §2): F_i = c_w (w(t) - v_i) on every free particle,
//   w(t) = w0 (1 + gust sin(2 pi f t)).
// It depends on t (so integrators must evaluate it at their stage times) and
// relaxes each particle's velocity toward the wind: dF/dv = -c_w I, dF/dx = 0.
#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "models/force_registry.h"

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

  void bind_jacobian(const SparseMatrix& pattern) override { diagonal_ = diagonal_slots(pattern); }

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

}  // namespace

std::unique_ptr<ForceTerm> make_wind_force(const Scene& scene, const ParticleOrder& order) {
  if (!scene.wind || scene.wind->coefficient == 0.0) return nullptr;
  return std::make_unique<WindForce>(*scene.wind, order.dim, order.free_particles);
}

}  // namespace springlab
