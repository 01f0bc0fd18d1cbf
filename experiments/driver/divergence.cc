#include "experiments/driver/divergence.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "models/core/element_kind.h"
#include "models/model/element_registry.h"
#include "models/fluids/fluids.h"

namespace springlab {

std::optional<Verdict> divergence(const Model& model, double bound, const Vector& x,
                                  const Vector& v, OvershootWindow& window, long k, double t) {
  // 1. A state that is not finite.
  if (!x.allFinite() || !v.allFinite()) return Verdict{.rule = VerdictRule::kNonFinite};
  if (!(bound > 0.0) && !model.has_divergence_rules()) return std::nullopt;
  const Energies e = model.energies(x, v);
  if (bound > 0.0) {
    // 2. Infinite energy: a barrier's gap closed (or a sum that overflowed).
    if (!std::isfinite(e.total())) {
      return Verdict{.rule = model.has_forbidden_states() ? VerdictRule::kForbidden
                                                          : VerdictRule::kEnergy,
                     .value = e.kinetic_and_spring(), .bound = bound};
    }
    // 3. Kinetic + elastic energy above blowup x E_s.
    const Verdict energy{.rule = VerdictRule::kEnergy, .value = e.kinetic_and_spring(),
                         .bound = bound};
    if (window.breaks(energy, k, t)) return energy;
  }
  // 4. The kinds' own rules (fluids, bodies).
  std::vector<Verdict> measured;
  model.measure_divergence(x, v, e.total(), measured);
  for (const Verdict& m : measured) {
    if (m.rule == VerdictRule::kBodyEnergy ? window.breaks(m, k, t) : m.exceeded()) return m;
  }
  return std::nullopt;
}

std::optional<Verdict> divergence(const Model& model, double bound, const Vector& x,
                                  const Vector& v) {
  OvershootWindow none;
  return divergence(model, bound, x, v, none, 0, 0.0);
}

std::vector<std::string> divergence_sentences() {
  std::vector<std::string> sentences = {
      "every scene: a state that is not finite, or infinite energy (a barrier's gap closed)",
      "springs and elements (every scene): the kinetic + elastic energy above --blowup x E_s, "
      "E_s = T(0) + U_elastic(0) + sum_free m (|g| d + |w_max|^2 / 2), d the scene's extent of "
      "motion"};
  for (const ElementKind* kind : element_kinds()) {
    if (!kind->divergence_sentence.empty()) sentences.emplace_back(kind->divergence_sentence);
  }
  return sentences;
}

bool OvershootWindow::breaks(const Verdict& v, long k, double t) {
  Excursion& e = excursion_[v.rule == VerdictRule::kBodyEnergy ? 1 : 0];
  if (!v.exceeded()) {
    if (e.on) done_.push_back(e.seen);
    e.on = false;
    return false;
  }
  if (steps_ == 0) return true;
  const double ratio = v.value / v.bound;
  if (!e.on) {
    e = {.on = true, .start = k, .seen = {.rule = v.rule, .peak_ratio = ratio, .t_peak = t}};
  } else if (ratio > e.seen.peak_ratio) {
    // A new high: an overshoot's rise lasts at most K steps.
    if (k - e.start >= steps_) return true;
    e.seen.peak_ratio = ratio;
    e.seen.t_peak = t;
  }
  ++e.seen.steps;
  return false;
}

std::vector<OvershootWindow::Overshoot> OvershootWindow::overshoots() const {
  std::vector<Overshoot> all = done_;
  for (const Excursion& e : excursion_) {
    if (e.on) all.push_back(e.seen);
  }
  return all;
}

namespace {

// "; <method> is unstable or inaccurate at this step: try ..." of a blow-up.
constexpr const char* kTryStability =
    " is unstable or inaccurate at this step: try a smaller --dt (`springlab stability` finds "
    "the largest stable one) or a method with a larger stability limit";

// The fluid a scene particle belongs to (nullptr: none).
const Fluid* fluid_of(const Model& model, int particle) {
  for (const Fluid& f : model.scene().get<Fluids>()) {
    if (particle >= f.first && particle < f.first + f.count) return &f;
  }
  return nullptr;
}

// What to try for a fluid: the step of Monaghan's CFL condition,
// dt <= 0.4 h / c (Monaghan 1992, sec. 10; h the smoothing length, c the
// speed of sound; the flow's speed adds to c where it is not small).
void fluid_advice(std::ostream& text, const Model& model, const VerdictContext& context,
                  int particle) {
  text << "; " << context.integrator << " is unstable or inaccurate at this step: try ";
  if (context.integrator == "xpbd") {
    // Position-based fluids project densities: no speed of sound limits them.
    text << "more --substeps or a smaller --dt";
    return;
  }
  text << "a smaller --dt";
  if (const Fluid* f = fluid_of(model, particle)) {
    text << " (explicit methods need about dt <= 0.4 h / c = "
         << 0.4 * kSmoothingPerSpacing * f->spacing / f->speed_of_sound
         << " s for this fluid: h its smoothing length, c its speed of sound)";
  }
  text << " or xpbd";
}

// The overshoot's part of an energy verdict's message (Integrator::
// overshoot_steps > 0: the Newmark-alpha family).
void overshoot_advice(std::ostream& text, const VerdictContext& context) {
  text << " and kept rising more than " << context.overshoot_steps
       << " steps after it passed the bound, longer than " << context.integrator
       << "'s overshoot lasts (Hilber and Hughes 1978: at large w h a stiff mode's energy "
          "rises for up to "
       << context.overshoot_steps
       << " steps before the method damps it, and a run that then decays goes on); "
       << context.integrator
       << " is unstable or inaccurate at this step: try a smaller --dt, or a method that does "
          "not overshoot (implicit-euler, bdf2)";
}

}  // namespace

std::string verdict_text(const Verdict& verdict, const Model& model,
                         const VerdictContext& context, const Vector& x,
                         [[maybe_unused]] const Vector& v) {
  std::ostringstream text;
  switch (verdict.rule) {
    case VerdictRule::kNonFinite:
      if (model.has_forbidden_states() && x.allFinite()) {
        const std::string where = model.forbidden_state(x);
        if (!where.empty()) {
          return where + "; use implicit-euler (its Newton iteration keeps every gap open) or a "
                         "smaller --dt";
        }
      } else if (model.has_forbidden_states()) {
        // A stage of a multi-stage step (rk4) inside a plane, where the
        // barrier has no force, makes the step's end non-finite.
        return "the state turned non-finite (with barrier contact: a stage of the step inside a "
               "plane, where the barrier has no force); use implicit-euler (its Newton iteration "
               "keeps every gap open) or a smaller --dt";
      }
      text << "the state turned non-finite; " << context.integrator << kTryStability;
      return text.str();
    case VerdictRule::kForbidden:
    case VerdictRule::kEnergy: {
      // A finite state of infinite energy (a barrier's gap closed): say where.
      // (Not "an implicit method": linear-implicit-euler's one linear solve
      // steps through a plane too; implicit-euler's Newton keeps gaps open.)
      if (model.has_forbidden_states()) {
        const std::string where = model.forbidden_state(x);
        if (!where.empty()) {
          return where + "; use implicit-euler (its Newton iteration keeps every gap open) or a "
                         "smaller --dt";
        }
      }
      text << "kinetic + spring energy " << verdict.value << " J exceeded --blowup "
           << context.blowup << " x E_s = " << verdict.bound << " J";
      if (context.overshoot_steps > 0) {
        overshoot_advice(text, context);
      } else {
        text << "; " << context.integrator << kTryStability;
      }
      return text.str();
    }
    case VerdictRule::kFluidOutside:
      text << "water particle " << verdict.where << " is " << verdict.value << " m ";
      if (verdict.plane >= 0) {
        text << "behind plane " << verdict.plane;
      } else {
        text << "outside its walls' box";
        if (verdict.side >= 0) {
          text << " (beyond its " << (verdict.side % 2 == 1 ? "+" : "-") << "xyz"[verdict.side / 2]
               << " side)";
        }
      }
      text << ", further than the fluid's size " << verdict.bound << " m: ";
      // The state cannot tell over from through: a stable run's jets can
      // outgrow open walls too (bdf2 on the dam break at 1/60 s with
      // -p lid=0: water particle 199 lands 0.54 m beyond the -x side).
      text << (verdict.plane >= 0 ? "the fluid blew up or leaked through the plane"
                                  : "the water left the tank: flung out by a blow-up, through "
                                    "a wall, or thrown over one (a splash higher than open "
                                    "walls: the dam-break's -p lid=1 closes its box)");
      fluid_advice(text, model, context, verdict.where);
      return text.str();
    case VerdictRule::kFluidDensity:
      text << "water particle " << verdict.where << "'s density is " << 1.0 + verdict.value
           << " x the rest density, more than " << 1.0 + verdict.bound
           << " x: the fluid is crushed";
      fluid_advice(text, model, context, verdict.where);
      return text.str();
    case VerdictRule::kBodyStrain:
      text << "body " << verdict.where << "'s rigidity strain |A^T A - I|_F reached "
           << verdict.value << ", more than " << verdict.bound
           << " (0.1 above its start): the rigid body is no longer rigid; " << context.integrator
           << " is unstable or inaccurate on the rigidity's stiff modes at this step: try a "
              "smaller --dt (`springlab stability` finds the largest stable one) or an L-stable "
              "method (implicit-euler, bdf2)";
      return text.str();
    case VerdictRule::kBodyEnergy: {
      const double e0 = model.energies(model.initial_positions(), model.initial_velocities()).total();
      text << "the energy rose to " << e0 + verdict.value << " J from " << e0
           << " J at t = 0, more than E_s = " << verdict.bound
           << " J above its start, in a scene where nothing feeds energy in (bodies, no wind)";
      if (context.overshoot_steps > 0) {
        overshoot_advice(text, context);
      } else {
        text << "; " << context.integrator
             << " made energy up at this step: try a smaller --dt, or a method that cannot gain "
                "energy (discrete-gradient, implicit-euler)";
      }
      return text.str();
    }
  }
  return "diverged";
}

}  // namespace springlab
