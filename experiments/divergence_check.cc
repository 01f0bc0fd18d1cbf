#include "experiments/divergence_check.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "models/springs.h"

namespace springlab {

DivergenceCheck::DivergenceCheck(const ElasticModel& model, double bound)
    : model_(model), bound_(bound), mass_(model.mass()), energies_(model.energies(
                                                            model.initial_positions(),
                                                            model.initial_velocities())) {
  // The certificate bounds the spring energy only: with other potentials
  // that count with it (elements, contact) every state is checked exactly.
  const EnergyLayout& layout = model.energy_layout();
  const std::size_t spring = layout.find("spring");
  certifies_ = layout.counts_with_spring.size() == 1 && layout.counts_with_spring[0] == spring;
  x_ref_ = model.initial_positions();  // (read by the pass even when it certifies nothing)
  if (!certifies_) return;
  std::vector<double> kappa(static_cast<std::size_t>(model.particle_count()), 0.0);
  if (const Springs* springs = model.scene().find<Springs>()) {
    for (const Spring& s : *springs) {
      kappa[static_cast<std::size_t>(s.i)] += s.k;
      kappa[static_cast<std::size_t>(s.j)] += s.k;
    }
  }
  for (double k : kappa) two_kappa_ = std::max(two_kappa_, 2.0 * k);
  x_ref_ = model.initial_positions();
  u_ref_ = energies_["spring"];
}

bool DivergenceCheck::diverged(const Vector& x, const Vector& v, Vector& x_copy, Vector& v_copy) {
  const Eigen::Index n = x.size();
  x_copy.resize(n);
  v_copy.resize(n);
  if (!(bound_ > 0.0)) {
    x_copy = x;
    v_copy = v;
    return !x.allFinite() || !v.allFinite();
  }
  const double* px = x.data();
  const double* pv = v.data();
  const double* pr = x_ref_.data();
  const double* pm = mass_.data();
  double* cx = x_copy.data();
  double* cv = v_copy.data();
  double momentum2 = 0.0, drift2 = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double xi = px[i], vi = pv[i];
    cx[i] = xi;
    cv[i] = vi;
    momentum2 += pm[i] * vi * vi;
    const double d = xi - pr[i];
    drift2 += d * d;
  }
  // (Finite, as the rule asks of the state, also when the bound is not.)
  if (certifies_) {
    const double certificate = 0.5 * momentum2 + 2.0 * u_ref_ + two_kappa_ * drift2;
    if (std::isfinite(certificate) && certificate <= bound_) return false;
  }
  if (!x.allFinite() || !v.allFinite()) return true;
  model_.energies(x, v, energies_);
  if (energies_.kinetic_and_spring() > bound_ || !std::isfinite(energies_.total())) return true;
  if (certifies_) {
    x_ref_ = x;
    u_ref_ = energies_["spring"];
  }
  return false;
}

}  // namespace springlab
