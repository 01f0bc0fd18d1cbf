#include "experiments/driver/divergence_check.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <stdexcept>

#include "models/materials/kernels/lanes.h"
#include "models/springs/springs.h"
#include "models/model/energy_layout.h"

namespace springlab {
namespace {

// The certificate is compared as certificate <= (1 - kRoundingMargin) x
// bound: its sums (and the energy's) are rounded, each by far less than
// 1e-9 of itself, so a certificate that passes proves the rule's own
// computed energy within the bound too.
constexpr double kRoundingMargin = 1e-9;

// The certificate's two sums, sum_i v_i^2 (or sum_i m_i v_i^2) and
// sum_i (x_i - c_i)^2 (c: the copy's old contents), in kLanes running sums
// (entry i adds to sum i mod kLanes), added up at the end: with one running
// sum every entry waits on the addition before it; in lanes one instruction
// adds eight entries (models/materials/kernels/lanes.h; four SSE2 instructions on
// the default target). Another order of summation bounds the same energy:
// where the certificate proves nothing, the exact rule decides, so no
// decision depends on the order.
SPRINGLAB_LANES_INLINE void load(const double* p, Lanes& a) { std::memcpy(&a, p, sizeof a); }

SPRINGLAB_LANES_INLINE double lane_sum(const Lanes& a) {
  double sum = 0.0;
  for (int l = 0; l < kLanes; ++l) sum += a[l];
  return sum;
}

SPRINGLAB_LANES_INLINE void store(const Lanes& a, double* p) { std::memcpy(p, &a, sizeof a); }

// One pass over the state: (x, v) copied over (x_copy, v_copy), whose old
// contents x_copy are read just before (the store brings their cache lines
// in anyway), and the two sums. It reads x and v once and the masses only
// when they differ (kWeighted): as separate passes, the copies and the
// sums ran slower (BM_RunPair's ratio_min 1.23-1.29 against 1.18-1.19), and
// reading the masses and a reference state as well cost 0.15 us more per
// step of the chain (run - kernel 0.98-1.04 us against 0.84-0.88;
// benchmarks/README.md, issue 37).
template <bool kWeighted>
SPRINGLAB_LANES_INLINE void copy_and_sum(const double* x, const double* v, const double* m,
                                         double* x_copy, double* v_copy, Eigen::Index n,
                                         double& velocity2, double& step2) {
  // Backwards: the step just wrote x and v front to back, so their last
  // entries are the ones still in the first-level cache.
  double velocity_tail = 0.0, step_tail = 0.0;
  const Eigen::Index whole = n - n % kLanes;
  for (Eigen::Index i = n - 1; i >= whole; --i) {
    const double d = x[i] - x_copy[i];
    x_copy[i] = x[i];
    v_copy[i] = v[i];
    velocity_tail += (kWeighted ? m[i] : 1.0) * v[i] * v[i];
    step_tail += d * d;
  }
  Lanes velocity = {}, step = {};
  for (Eigen::Index i = whole - kLanes; i >= 0; i -= kLanes) {
    Lanes xi, vi, ci;
    load(x + i, xi);
    load(v + i, vi);
    load(x_copy + i, ci);
    store(xi, x_copy + i);
    store(vi, v_copy + i);
    if constexpr (kWeighted) {
      Lanes mi;
      load(m + i, mi);
      velocity += mi * vi * vi;
    } else {
      velocity += vi * vi;
    }
    const Lanes d = xi - ci;
    step += d * d;
  }
  velocity2 = lane_sum(velocity) + velocity_tail;
  step2 = lane_sum(step) + step_tail;
}

SPRINGLAB_LANES_CLONES void copy_and_sum_equal_masses(const double* x, const double* v,
                                                      double* x_copy, double* v_copy,
                                                      Eigen::Index n, double& velocity2,
                                                      double& step2) {
  copy_and_sum<false>(x, v, nullptr, x_copy, v_copy, n, velocity2, step2);
}

SPRINGLAB_LANES_CLONES void copy_and_sum_weighted(const double* x, const double* v,
                                                  const double* m, double* x_copy, double* v_copy,
                                                  Eigen::Index n, double& velocity2,
                                                  double& step2) {
  copy_and_sum<true>(x, v, m, x_copy, v_copy, n, velocity2, step2);
}

}  // namespace

DivergenceCheck::DivergenceCheck(const Model& model, double bound,
                                 const Energies& initial, int overshoot_steps)
    : model_(model), bound_(bound), energies_(initial), window_(overshoot_steps) {
  // Both copies start as the initial state, the first reference (drift 0).
  n_ = model.initial_positions().size();
  auto line_aligned = [this] {
    return Buffer(static_cast<double*>(
        ::operator new[](sizeof(double) * static_cast<std::size_t>(n_), std::align_val_t{64})));
  };
  for (int c = 0; c < 2; ++c) {
    x_[c] = line_aligned();
    v_[c] = line_aligned();
    Eigen::Map<Vector>(x_[c].get(), n_) = model.initial_positions();
    Eigen::Map<Vector>(v_[c].get(), n_) = model.initial_velocities();
  }
  const Vector& mass = model.mass();
  if (mass.size() > 0 && mass.minCoeff() == mass.maxCoeff()) equal_mass_ = mass[0];
  // The certificate bounds the spring energy only: with other potentials
  // that count with it (elements, contact) every state is checked exactly.
  const EnergyLayout& layout = model.energy_layout();
  const std::size_t spring = layout.find("spring");
  certifies_ = layout.counts_with_spring.size() == 1 && layout.counts_with_spring[0] == spring &&
               !model.has_divergence_rules();
  if (!certifies_) return;
  std::vector<double> kappa(static_cast<std::size_t>(model.particle_count()), 0.0);
  if (const Springs* springs = model.scene().find<Springs>()) {
    for (const Spring& s : *springs) {
      kappa[static_cast<std::size_t>(s.i)] += s.k;
      kappa[static_cast<std::size_t>(s.j)] += s.k;
    }
  }
  double kappa_max = 0.0;
  for (double k : kappa) kappa_max = std::max(kappa_max, k);
  sqrt_kappa_ = std::sqrt(kappa_max);
  sqrt_u_ref_ = std::sqrt(energies_["spring"]);
}

std::optional<Verdict> DivergenceCheck::judge(const Vector& x, const Vector& v, double t) {
  ++step_;
  const Eigen::Index n = n_;
  if (x.size() != n || v.size() != n) {
    throw std::invalid_argument("DivergenceCheck: the state's size is not the model's");
  }
  const int next = 1 - good_;
  Eigen::Map<Vector> x_copy(x_[next].get(), n);
  Eigen::Map<Vector> v_copy(v_[next].get(), n);
  // The kinds' rules (fluids, bodies), given the energies of (x, v).
  auto kinds = [&]() -> std::optional<Verdict> {
    model_.measure_divergence(x, v, energies_.total(), measured_);
    for (const Verdict& m : measured_) {
      if (m.rule == VerdictRule::kBodyEnergy ? window_.breaks(m, step_, t) : m.exceeded()) {
        return m;
      }
    }
    good_ = next;
    return std::nullopt;
  };
  if (!(bound_ > 0.0)) {
    x_copy = x;
    v_copy = v;
    if (!x.allFinite() || !v.allFinite()) return Verdict{.rule = VerdictRule::kNonFinite};
    if (model_.has_divergence_rules()) {
      model_.energies(x, v, energies_);
      return kinds();
    }
    good_ = next;
    return std::nullopt;
  }
  // The last good state's copy and the certificate's sums in one pass, in
  // lanes: the scalar loop took about 11 instructions per entry and waited
  // on its sums, a quarter of a symplectic Euler step on the 1000-particle
  // chain (benchmarks/README.md, issue 37).
  double velocity2 = 0.0, step2 = 0.0;
  if (equal_mass_ > 0.0) {
    copy_and_sum_equal_masses(x.data(), v.data(), x_copy.data(), v_copy.data(), n, velocity2,
                              step2);
    velocity2 *= equal_mass_;
  } else {
    copy_and_sum_weighted(x.data(), v.data(), model_.mass().data(), x_copy.data(),
                          v_copy.data(), n, velocity2, step2);
  }
  // D_k = |x_k - x_{k-2}| + D_{k-2} >= |x_k - x_ref| (not finite when the
  // state is not: then no certificate, and the exact rule below).
  drift_[next] += std::sqrt(step2);
  if (certifies_) {
    const double spring = sqrt_u_ref_ + sqrt_kappa_ * drift_[next];
    const double certificate = 0.5 * velocity2 + spring * spring;
    if (std::isfinite(certificate) && certificate <= (1.0 - kRoundingMargin) * bound_) {
      // Within the bound (an excursion above it, if one was under way, ends;
      // without an allowance there is none).
      if (window_.steps() > 0) {
        window_.breaks({.rule = VerdictRule::kEnergy, .value = certificate, .bound = bound_},
                       step_, t);
      }
      good_ = next;
      return std::nullopt;
    }
  }
  // (Finite, as the rule asks of the state, also when the bound is not.)
  if (!x.allFinite() || !v.allFinite()) return Verdict{.rule = VerdictRule::kNonFinite};
  ++exact_evaluations_;
  model_.energies(x, v, energies_);
  const double energy = energies_.kinetic_and_spring();
  if (!std::isfinite(energies_.total())) {
    return Verdict{.rule = model_.has_forbidden_states() ? VerdictRule::kForbidden
                                                         : VerdictRule::kEnergy,
                   .value = energy, .bound = bound_};
  }
  if (certifies_) {
    // x_k the new reference: its copy's drift is 0, the other copy's (the
    // state before) |x_{k-1} - x_k|.
    sqrt_u_ref_ = std::sqrt(energies_["spring"]);
    drift_[next] = 0.0;
    drift_[good_] = (x_good() - x_copy).norm();
  }
  const Verdict verdict{.rule = VerdictRule::kEnergy, .value = energy, .bound = bound_};
  if (window_.breaks(verdict, step_, t)) return verdict;
  return kinds();
}

}  // namespace springlab
