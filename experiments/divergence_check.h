// The divergence rule of docs/command-line.md ("Divergence"): a run
// diverges when its state is not finite or its kinetic + spring energy
// (+ every potential that counts with it) exceeds blowup x E_s. simulate()
// (simulation.h) checks it after every step; the lab page (web/) checks its
// panels' steps with the same object.
#pragma once

#include <vector>

#include "models/elastic_model.h"

namespace springlab {

// docs/command-line.md "The command line"'s divergence rule, checked after every step at the cost
// of one pass over the state instead of an energy evaluation (a pass over every
// spring with a square root each, as much as the force).
//
// The certificate. For a spring of stiffness k and rest length L between
// particles i and j, with d = x_i - x_j, l = |d|, and any reference state
// (d_ref, l_ref): |l - L| <= |l - l_ref| + |l_ref - L| <= |d - d_ref| +
// |l_ref - L| (triangle inequality), so with (a + b)^2 <= 2 a^2 + 2 b^2
//   k (l - L)^2 / 2 <= k |d - d_ref|^2 + k (l_ref - L)^2,
// and |d - d_ref|^2 <= 2 |dx_i|^2 + 2 |dx_j|^2 (dx = x - x_ref). Summed over
// the springs,
//   U_spring(x) <= 2 U_spring(x_ref) + 2 kappa |x - x_ref|^2,
// kappa the largest sum of the stiffnesses of one particle's springs. So
//   T(v) + 2 U_spring(x_ref) + 2 kappa |x - x_ref|^2 <= blowup E_s
// proves kinetic + spring energy within the bound; the left side takes one
// pass over x and v, and it is not finite whenever the state is not (a
// non-finite value fails the comparison). Only when it cannot prove the
// state good is the energy evaluated (the exact rule, as before), and a good
// state becomes the new reference. The decision is exactly the rule's at
// every step (the certificate only ever says "good" when the rule does);
// what changes is the cost: the reference moves every so many steps (after
// a motion of about sqrt(blowup E_s / (4 kappa)) in the whole state), not
// every step.
class DivergenceCheck {
 public:
  // bound = blowup x model.energy_scale() (0: only a non-finite state
  // diverges).
  DivergenceCheck(const ElasticModel& model, double bound);

  // True when (x, v) is not finite or its kinetic + spring energy exceeds
  // the bound (with a bound of 0: only when it is not finite). The same pass
  // copies (x, v) to (x_copy, v_copy): the driver's last good state.
  bool diverged(const Vector& x, const Vector& v, Vector& x_copy, Vector& v_copy);

 private:
  const ElasticModel& model_;
  double bound_;
  const Vector& mass_;
  Energies energies_;
  bool certifies_ = false;
  double two_kappa_ = 0.0;
  Vector x_ref_;
  double u_ref_ = 0.0;
};

}  // namespace springlab
