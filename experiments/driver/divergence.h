// The driver's divergence rule (docs/command-line.md "Divergence"), stated
// plainly. A state after a step has diverged when
//   1. it is not finite, or
//   2. its energy is infinite (a barrier's gap closed), or
//   3. its kinetic + elastic energy (spring, elements, contact, rigidity,
//      pressure: the potentials that count with the spring energy, each by
//      its magnitude) exceeds blowup x E_s, or
//   4. a kind of matter's own rule says so (models/core/verdict.h: a fluid's
//      particle out of its walls' box or its density error; a body's
//      rigidity strain, or its energy above its start when unforced),
// checked in that order; the first rule broken is the verdict, as data.
// divergence() below is that rule and nothing else: the reference the fast
// check (divergence_check.h, which the run driver uses) is tested against.
//
// One allowance, for the methods whose steps overshoot (Integrator::
// overshoot_steps: the Newmark-alpha family, whose stiff modes' energy rises
// for a few steps before the method damps it; Hilber and Hughes 1978): an
// energy verdict (rule 3, or a body's energy) is forgiven while the energy
// that passed the bound has not set a new high more than K steps after it
// first did (OvershootWindow). A run that overshoots and then decays goes
// on, with a warning; one that keeps rising is diverged, and its message
// says overshoot.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "models/model/model.h"
#include "models/core/verdict.h"

namespace springlab {

// The overshoot allowance above, for a method that declares K > 0 steps
// (K = 0: no allowance, every energy verdict stands).
class OvershootWindow {
 public:
  explicit OvershootWindow(int steps = 0) : steps_(steps) {}
  // Whether energy verdict `v` (kEnergy or kBodyEnergy: value, bound) of
  // step k, at time t, breaks its rule: it exceeds the bound, and either
  // K = 0 or the energy has set a new high more than K steps after it
  // first passed the bound. Call it at every step the rule is measured,
  // in order (a value within the bound ends an excursion).
  bool breaks(const Verdict& v, long k, double t);
  // The excursions above the bound that ended below it (overshoots
  // forgiven), for the run's warnings.
  struct Overshoot {
    VerdictRule rule = VerdictRule::kEnergy;
    double peak_ratio = 0.0;  // the highest value / bound
    double t_peak = 0.0;
    long steps = 0;           // steps above the bound
  };
  // Those that ended, and the one under way (if any) at the run's end.
  std::vector<Overshoot> overshoots() const;
  int steps() const { return steps_; }

 private:
  struct Excursion {
    bool on = false;
    long start = 0;
    Overshoot seen;
  };
  int steps_;
  std::array<Excursion, 2> excursion_;  // kEnergy, kBodyEnergy
  std::vector<Overshoot> done_;
};

// The verdict on the state (x, v) after step k (time t): the first rule it
// breaks, or nullopt. bound = blowup x E_s (0: rule 3 is off, as for a
// scene with E_s = 0). window: the method's overshoot allowance.
std::optional<Verdict> divergence(const Model& model, double bound, const Vector& x,
                                  const Vector& v, OvershootWindow& window, long k, double t);
// The same without an allowance (K = 0), for one state.
std::optional<Verdict> divergence(const Model& model, double bound, const Vector& x,
                                  const Vector& v);

// The rules in one sentence each (`springlab list`, docs/command-line.md
// "Divergence"): the driver's own for every scene ("springs and elements:
// ..."), then each registered kind's that has one (fluids, bodies).
std::vector<std::string> divergence_sentences();

// What the run needs to say why a verdict ended it.
struct VerdictContext {
  std::string integrator;
  double blowup = 0.0;
  int overshoot_steps = 0;  // the method's K (0: it does not overshoot)
};

// The failure message of a run the verdict ended, from the verdict's data
// (x, v: the state it is of): what the rule saw and what to try.
std::string verdict_text(const Verdict& verdict, const Model& model,
                         const VerdictContext& context, const Vector& x, const Vector& v);

}  // namespace springlab
