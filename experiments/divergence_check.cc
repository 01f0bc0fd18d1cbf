#include "experiments/divergence_check.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "models/materials/lanes.h"
#include "models/springs.h"

namespace springlab {
namespace {

// The certificate's two sums, sum_i m_i v_i^2 and sum_i (x_i - r_i)^2, in
// kLanes running sums (entry i adds to sum i mod kLanes), added up at the
// end: with one running sum every entry waits on the addition before it;
// in lanes one instruction adds eight entries (models/materials/lanes.h;
// four SSE2 instructions on the default target). Another order of
// summation bounds the same energy: where the certificate proves nothing,
// the exact rule decides, so no decision depends on the order.
SPRINGLAB_LANES_INLINE void load(const double* p, Lanes& a) { std::memcpy(&a, p, sizeof a); }

SPRINGLAB_LANES_INLINE double lane_sum(const Lanes& a) {
  double sum = 0.0;
  for (int l = 0; l < kLanes; ++l) sum += a[l];
  return sum;
}

SPRINGLAB_LANES_INLINE void store(const Lanes& a, double* p) { std::memcpy(p, &a, sizeof a); }

// One pass over the state: (x, v) copied to (x_copy, v_copy), and the two
// sums (each vector read once: as separate passes, the copies and the sums
// ran slower, BM_RunPair's ratio_min 1.23-1.29 against 1.18-1.19).
SPRINGLAB_LANES_CLONES void copy_and_sum(const double* x, const double* v, const double* m,
                                         const double* r, double* x_copy, double* v_copy,
                                         Eigen::Index n, double& momentum2, double& drift2) {
  Lanes momentum = {}, drift = {};
  const Eigen::Index whole = n - n % kLanes;
  for (Eigen::Index i = 0; i < whole; i += kLanes) {
    Lanes xi, vi, mi, ri;
    load(x + i, xi);
    load(v + i, vi);
    load(m + i, mi);
    load(r + i, ri);
    store(xi, x_copy + i);
    store(vi, v_copy + i);
    momentum += mi * vi * vi;
    const Lanes d = xi - ri;
    drift += d * d;
  }
  momentum2 = lane_sum(momentum);
  drift2 = lane_sum(drift);
  for (Eigen::Index i = whole; i < n; ++i) {
    x_copy[i] = x[i];
    v_copy[i] = v[i];
    momentum2 += m[i] * v[i] * v[i];
    drift2 += (x[i] - r[i]) * (x[i] - r[i]);
  }
}

}  // namespace

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
  // The last good state's copy and the certificate's sums in one pass, in
  // lanes: the scalar loop took about 11 instructions per entry and waited
  // on its sums, a quarter of a symplectic Euler step on the 1000-particle
  // chain (benchmarks/README.md, issue 37).
  double momentum2 = 0.0, drift2 = 0.0;
  copy_and_sum(x.data(), v.data(), mass_.data(), x_ref_.data(), x_copy.data(), v_copy.data(), n,
               momentum2, drift2);
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
