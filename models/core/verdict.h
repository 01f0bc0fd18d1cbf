// Verdicts per kind of matter (docs/command-line.md "Divergence"): the
// quantity each kind of matter is judged by after every step, as data. A
// kind that has a rule of its own (fluids, bodies) registers a factory
// (ElementKind::divergence_rule) whose DivergenceRule measures its quantity
// on a state; the run driver (experiments/driver/divergence.h) compares it with
// its bound and prints the message from the Verdict, never from text.
//
// The rules, one sentence each (what `springlab list` and the docs say):
//   - springs and elements: the kinetic + elastic energy above --blowup x
//     E_s (the driver's own rule, for every scene);
//   - fluids: a water particle further outside its walls' box than the
//     box's largest side, or further behind a contact plane than that, or
//     a water particle's density more than 100 % above the rest density;
//   - bodies: a body's rigidity strain |A^T A - I|_F above 0.1, or, in an
//     unforced scene, the energy above its start by more than E_s.
// The model knows nothing of time stepping: a rule measures one state.
#pragma once

#include <string_view>
#include <vector>

#include "models/core/fast_solver_views.h"

namespace springlab {

struct Configuration;

// Which rule a verdict is of.
enum class VerdictRule {
  kNonFinite,      // the state is not finite
  kEnergy,         // kinetic + elastic energy above --blowup x E_s
  kForbidden,      // a barrier's gap closed (a state of infinite energy)
  kFluidOutside,   // a water particle beyond its walls' box (or behind a plane)
  kFluidDensity,   // a water particle's density error above the bound
  kBodyStrain,     // a body's rigidity strain |A^T A - I|_F above the bound
  kBodyEnergy,     // the energy above its start in an unforced scene with bodies
};

// Its name in data (`run --json`'s "verdict": {"rule": ...}).
std::string_view to_string(VerdictRule rule);

// One rule's measurement on one state: its quantity's worst value, the
// bound it may not exceed, and where (the scene index of the particle or
// body the value is of; -1: the scene as a whole). A verdict whose value
// exceeds its bound is a divergence.
struct Verdict {
  VerdictRule rule = VerdictRule::kEnergy;
  double value = 0.0;
  double bound = 0.0;
  int where = -1;
  // kFluidOutside: the index of the plane a particle is behind (-1: the
  // walls' box).
  int plane = -1;
  // kFluidOutside beyond the walls' box: the side it is furthest beyond,
  // 2 r + 1 for the +r side of axis r, 2 r for the -r side; -1: none.
  int side = -1;
  bool exceeded() const { return value > bound; }
};

// What a kind's rule may need of the model (the model gives it): E(0) (the
// total: kinetic + every potential), the energy scale E_s, whether the
// scene is unforced (no kind that feeds energy in: no wind), and the
// contact planes the particles must stay out of (the terms' own
// FastSolverViews::plane_constraints: unit normal n, offset n.point).
struct VerdictScale {
  double energy_initial = 0.0;
  double energy_scale = 0.0;
  bool unforced = true;
  std::vector<PlaneConstraint> planes;
};

// A kind's divergence rule, bound to one model's scene.
class DivergenceRule {
 public:
  virtual ~DivergenceRule() = default;
  // Appends one Verdict per quantity of the kind (its worst value on the
  // state, exceeded or not). c: every particle at the state (the model's
  // internal order, as force terms see it); total: the state's total
  // energy (kinetic + every potential).
  virtual void measure(const Configuration& c, double total, std::vector<Verdict>& out) const = 0;
};

}  // namespace springlab
