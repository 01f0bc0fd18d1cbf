// The divergence rule of docs/command-line.md ("Divergence";
// divergence.h states it plainly: divergence() is the reference), decided
// fast. simulate() (simulation.h) checks it after every step; the lab page
// (web/) checks its panels' steps with the same object, which also keeps the
// last good state. Its verdicts equal divergence()'s at every step
// (tests/test_verdicts.cc compares them on random and real runs).
#pragma once

#include <memory>
#include <new>
#include <optional>
#include <vector>

#include "experiments/driver/divergence.h"
#include "models/model/model.h"

namespace springlab {

// The rule, checked after every step at the cost of one pass over the state
// instead of an energy evaluation (a pass over every spring with a square
// root each, as much as the force) where it can be: a scene of springs
// alone, judged by the energy rule only (the kinds with rules of their own,
// fluids and bodies, have potentials that count with the spring energy, so
// their states are judged exactly, as divergence() does).
//
// The certificate. For a spring of stiffness k and rest length L between
// particles i and j, with d = x_i - x_j, l = |d|, and any reference state
// (d_ref, l_ref): |l - L| <= |l - l_ref| + |l_ref - L| <= |d - d_ref| +
// |l_ref - L| (triangle inequality). Summed over the springs with weights
// k, Minkowski's inequality (the triangle inequality of the weighted
// 2-norm) gives
//   sqrt(2 U_spring(x)) <= sqrt(sum k |d - d_ref|^2) + sqrt(2 U_spring(x_ref)),
// and |d - d_ref|^2 <= 2 |dx_i|^2 + 2 |dx_j|^2 (dx = x - x_ref), so
// sum k |d - d_ref|^2 <= 2 kappa |x - x_ref|^2, kappa the largest sum of
// the stiffnesses of one particle's springs:
//   U_spring(x) <= (sqrt(U_spring(x_ref)) + sqrt(kappa) |x - x_ref|)^2
// (at most 2 U_spring(x_ref) + 2 kappa |x - x_ref|^2, the bound the check
// used before, by (a + b)^2 <= 2 a^2 + 2 b^2). The kinetic energy
// T = 1/2 sum_i m_i v_i^2 = 1/2 m sum_i v_i^2 when the masses are all m
// (the pass then reads no masses; with unequal masses it sums m_i v_i^2).
// The drift |x - x_ref| is bounded without reading x_ref: the pass that
// writes step k's state over the copy of step k - 2's (the two copies
// alternate: one holds the last good state) reads that copy first, and by
// the triangle inequality
//   |x_k - x_ref| <= |x_k - x_{k-2}| + |x_{k-2} - x_ref| <= |x_k - x_{k-2}| + D_{k-2} =: D_k,
// a running bound per copy (D of a copy equal to x_ref is 0; when the
// reference moves to x_k, the other copy's D is |x_{k-1} - x_k|, computed
// then). So
//   T + (sqrt(U_spring(x_ref)) + sqrt(kappa) D_k)^2 <= blowup E_s
// proves kinetic + spring energy within the bound; the left side takes
// the one pass over x and v that copies them, and it is not finite
// whenever the state is not (a non-finite value fails the comparison).
// Only when it cannot prove the state good is the energy evaluated (the
// exact rule, as before), and a good state becomes the new reference. The
// decision is exactly the rule's at every step (the certificate only ever
// says "good" when the rule does; it is compared with a margin of 1e-9 of
// the bound so that rounding in its sums cannot matter); what changes is
// the cost: the reference moves every so many steps (after a path of about
// sqrt(blowup E_s / kappa) in the whole state), not every step
// (exact_evaluations() counts them: 2 in the 256 steps of BM_RunPair's
// chain, none on its cloths).
class DivergenceCheck {
 public:
  // bound = blowup x model.energy_scale() (0: the energy rule is off);
  // initial = model.energies() of the model's initial state, which also
  // starts as the last good state; overshoot_steps: the method's overshoot
  // allowance K (divergence.h; 0: none).
  DivergenceCheck(const Model& model, double bound, const Energies& initial,
                  int overshoot_steps = 0);

  // divergence()'s verdict on the state after the next step (x, v at time
  // t; the calls count the steps). The same pass copies (x, v); when it
  // returns nullopt that copy is the last good state.
  std::optional<Verdict> judge(const Vector& x, const Vector& v, double t);
  // Whether judge() returns a verdict.
  bool diverged(const Vector& x, const Vector& v) { return judge(x, v, 0.0).has_value(); }

  // The overshoot allowance and the overshoots it forgave.
  const OvershootWindow& window() const { return window_; }

  // The last good state: the initial one, or the last (x, v) for which
  // diverged() returned false (a view of the check's copy, valid until the
  // next diverged()).
  Eigen::Map<const Vector> x_good() const { return {x_[good_].get(), n_}; }
  Eigen::Map<const Vector> v_good() const { return {v_[good_].get(), n_}; }

  // How many times the energy was evaluated (the certificate could not
  // prove the state good).
  long exact_evaluations() const { return exact_evaluations_; }

 private:
  const Model& model_;
  double bound_;
  Energies energies_;
  OvershootWindow window_;
  long step_ = 0;
  std::vector<Verdict> measured_;  // the kinds' rules' measurements (scratch)
  bool certifies_ = false;
  double sqrt_kappa_ = 0.0;
  // m_max when the masses are all equal (the pass then reads no masses),
  // else 0 (the pass sums m_i v_i^2).
  double equal_mass_ = 0.0;
  double sqrt_u_ref_ = 0.0;  // sqrt(U_spring(x_ref))
  // The two copies: x_[good_], v_[good_] the last good state, the other
  // pair the state before it (overwritten by the next pass); drift_[c] >=
  // |x_[c] - x_ref|. Each starts on a cache line (64 bytes), so that the
  // pass's 64-byte stores never straddle two lines (Eigen's vectors are
  // aligned to 16 bytes on the default target): BM_RunPair's run - kernel
  // on the chain 0.63-0.67 us per step against 0.68-0.83 with Vector copies.
  struct Free {
    void operator()(double* p) const { ::operator delete[](p, std::align_val_t{64}); }
  };
  using Buffer = std::unique_ptr<double[], Free>;
  Eigen::Index n_ = 0;
  Buffer x_[2], v_[2];
  double drift_[2] = {0.0, 0.0};
  int good_ = 0;
  long exact_evaluations_ = 0;
};

}  // namespace springlab
