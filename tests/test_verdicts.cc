// Verdicts per kind of matter (docs/command-line.md "Divergence", issue 46
// items 1-4): the driver's plain rule (experiments/driver/divergence.h) against its
// fast check, the fluids' and bodies' rules on the issue's commands, E_s
// from the scene's extent of motion, the Newmark-alpha overshoot, the run's
// warnings, and the stability answer's wording (issue 52). Each case runs
// in well under a second.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "experiments/driver/divergence.h"
#include "experiments/driver/divergence_check.h"
#include "experiments/driver/run_warnings.h"
#include "experiments/driver/simulation.h"
#include "experiments/analysis/stability.h"
#include "integrators/methods/newmark_family.h"
#include "integrators/registry/registry.h"
#include "models/bodies/bodies.h"
#include "models/scenes/builtin_scenes.h"
#include "models/contact/contact.h"
#include "models/fluids/fluids.h"
#include "models/model/model.h"
#include "models/springs/gravity.h"
#include "models/core/scene_io.h"
#include "models/model/scene_file.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"
#include "random_scenes.h"
#include "run_process.h"

namespace springlab::test_verdicts {
namespace {

RunSettings settings(const std::string& integrator, double dt, double t_end,
                     double blowup = 1000.0) {
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  s.blowup = blowup;
  return s;
}

Scene builtin(const std::string& name, std::vector<std::pair<std::string, std::string>> p = {}) {
  return make_builtin_scene(name, p);
}

// ------------------------------------------------ the plain rule and the fast check

// DivergenceCheck (the certificate and the kinds' rules, with the method's
// overshoot allowance) gives divergence()'s verdict at every step: the same
// step, the same rule, the same particle or body.
void expect_same_verdicts(const Model& model, const std::string& integrator, double dt,
                          long steps, double blowup, const IntegratorOptions& options = {}) {
  auto method = make_integrator(integrator);
  ASSERT_TRUE(method->initialize(model, 0.0, model.initial_positions(),
                                 model.initial_velocities(), options).ok);
  const double bound = blowup * model.energy_scale();
  const int k_overshoot = method->overshoot_steps();
  DivergenceCheck check(model, bound,
                        model.energies(model.initial_positions(), model.initial_velocities()),
                        k_overshoot);
  OvershootWindow window(k_overshoot);
  for (long k = 1; k <= steps; ++k) {
    const double t = static_cast<double>(k) * dt;
    if (!method->advance_to(t).ok) return;  // a failed step: no verdict to compare
    const std::optional<Verdict> fast = check.judge(method->x(), method->v(), t);
    const std::optional<Verdict> plain =
        divergence(model, bound, method->x(), method->v(), window, k, t);
    ASSERT_EQ(fast.has_value(), plain.has_value()) << "step " << k;
    if (!plain) continue;
    EXPECT_EQ(fast->rule, plain->rule) << "step " << k;
    EXPECT_EQ(fast->where, plain->where) << "step " << k;
    return;
  }
}

TEST(Verdicts, TheFastCheckDecidesAsThePlainRuleOnRealRuns) {
  struct Case {
    Scene scene;
    std::string integrator;
    double dt;
    long steps;
    double blowup;
  };
  const std::vector<Case> cases = {
      {builtin("chain", {{"n", "12"}, {"horizontal", "1"}}), "symplectic-euler", 0.0105, 2000, 1000},
      {builtin("chain", {{"n", "12"}, {"horizontal", "1"}}), "explicit-euler", 0.001, 20000, 50},
      {builtin("cloth", {{"n", "6"}}), "rk4", 0.02, 500, 100},
      {builtin("cloth", {{"n", "5"}, {"ground", "0.3"}, {"contact", "1"}}), "symplectic-euler",
       0.02, 100, 1000},
      {builtin("dam-break", {{"spacing", "0.02"}}), "symplectic-euler", 0.004, 100, 1000},
      {builtin("dam-break", {{"spacing", "0.02"}}), "explicit-euler", 0.002, 200, 1000},
      {builtin("tank", {{"spacing", "0.05"}}), "rk4", 0.02, 50, 1000},
      {builtin("tumbling-box"), "newmark", 0.25, 20, 1000},
      {builtin("box-chain", {{"n", "2"}}), "symplectic-euler", 0.002, 200, 1000},
      {builtin("box-pile", {{"n", "2"}}), "verlet", 0.004, 100, 1000},
      {builtin("oscillator"), "hht-alpha", 100.0, 12, 100},
      {builtin("oscillator"), "generalized-alpha", 1000.0, 12, 100},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene.name + " " + c.integrator);
    const Model model(c.scene);
    expect_same_verdicts(model, c.integrator, c.dt, c.steps, c.blowup);
  }
}

// Random scenes of every kind (fluids and bodies among them) on random
// walks of growing stride, the energy bound low enough that some states
// break it: the same verdict, state after state.
TEST(Verdicts, TheFastCheckDecidesAsThePlainRuleOnRandomStates) {
  int verdicts = 0;
  for (int dim : {2, 3}) {
    for (unsigned seed = 1; seed <= 12; ++seed) {
      SCOPED_TRACE(std::to_string(dim) + "-D seed " + std::to_string(seed));
      const Model model(testing::random_scene(dim, seed));
      const double bound = 3.0 * model.energy_scale();
      DivergenceCheck check(model, bound,
                            model.energies(model.initial_positions(), model.initial_velocities()));
      OvershootWindow window;
      std::mt19937 rng(seed);
      std::normal_distribution<double> g(0.0, 1.0);
      Vector x = model.initial_positions(), v = model.initial_velocities();
      for (long k = 1; k <= 60; ++k) {
        const double stride = 1e-3 * std::pow(1.15, static_cast<double>(k));
        for (Eigen::Index i = 0; i < x.size(); ++i) {
          x[i] += stride * g(rng);
          v[i] += stride * g(rng);
        }
        const std::optional<Verdict> fast = check.judge(x, v, 0.01 * k);
        const std::optional<Verdict> plain = divergence(model, bound, x, v, window, k, 0.01 * k);
        ASSERT_EQ(fast.has_value(), plain.has_value()) << "step " << k;
        if (plain) {
          EXPECT_EQ(fast->rule, plain->rule);
          ++verdicts;
          break;
        }
      }
    }
  }
  EXPECT_GE(verdicts, 12) << "the walks must reach the bounds";
}

// ------------------------------------------------ fluids (issue 46 item 1)

// The issue's commands, each a run that "completed" over a blow-up on main
// (energy x300-x4300, particles tens of metres out of the tank): each now
// ends at a fluid's rule. And a run that is fine completes.
TEST(Verdicts, TheIssuesFluidBlowUpsDiverge) {
  struct Case {
    std::string scene;
    std::vector<std::pair<std::string, std::string>> p;
    std::string integrator;
    double dt, t_end;
    int substeps = 0;
  };
  const std::vector<Case> cases = {
      {"dam-break", {{"spacing", "0.01"}}, "explicit-euler", 0.002, 0.5},
      {"dam-break", {{"spacing", "0.01"}}, "symplectic-euler", 0.002, 0.5},
      {"dam-break", {{"spacing", "0.01"}}, "verlet", 0.002, 0.5},
      {"dam-break", {{"spacing", "0.01"}}, "central-difference", 0.002, 0.5},
      {"dam-break", {{"spacing", "0.01"}}, "yoshida4", 0.002, 0.5},
      {"tank", {{"spacing", "0.025"}}, "rk4", 0.02, 1.0},
      {"sloshing", {{"spacing", "0.025"}}, "symplectic-euler", 0.02, 1.0},
      {"dam-break", {{"spacing", "0.01"}, {"sound", "1000"}}, "xpbd", 0.0166667, 1.0, 8},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene + " " + c.integrator);
    const Model model(builtin(c.scene, c.p));
    RunSettings s = settings(c.integrator, c.dt, c.t_end);
    s.options.substeps = c.substeps;
    const RunResult r = simulate(model, s);
    ASSERT_EQ(r.status, RunStatus::kDiverged);
    ASSERT_TRUE(r.verdict.has_value());
    EXPECT_TRUE(r.verdict->rule == VerdictRule::kFluidOutside ||
                r.verdict->rule == VerdictRule::kFluidDensity)
        << to_string(r.verdict->rule);
    EXPECT_GT(r.verdict->value, r.verdict->bound);
    // The message names the particle and says what to try.
    EXPECT_NE(r.failure.find("water particle " + std::to_string(r.verdict->where)),
              std::string::npos)
        << r.failure;
    EXPECT_NE(r.failure.find(c.integrator == "xpbd" ? "more --substeps" : "a smaller --dt"),
              std::string::npos)
        << r.failure;
    // Outside the walls' box: which side, and the three ways out.
    if (r.verdict->rule == VerdictRule::kFluidOutside && r.verdict->plane < 0) {
      const std::string side = std::string(r.verdict->side % 2 == 1 ? "+" : "-") +
                               "xyz"[r.verdict->side / 2] + " side";
      EXPECT_NE(r.failure.find("(beyond its " + side + ")"), std::string::npos) << r.failure;
      EXPECT_NE(r.failure.find("left the tank: flung out by a blow-up, through a wall, or "
                               "thrown over one"),
                std::string::npos)
          << r.failure;
    }
  }
  // Below the CFL step the dam break completes, its energy falling.
  const Model dam(builtin("dam-break", {{"spacing", "0.02"}}));
  const RunResult fine = simulate(dam, settings("symplectic-euler", 0.0005, 0.3));
  EXPECT_EQ(fine.status, RunStatus::kCompleted) << fine.failure;
  EXPECT_LT(fine.energy_final, fine.energy_initial);
}

// The walls' box: a water particle placed 1.2 L outside it (L the fluid's
// size) breaks the rule, at 0.8 L it does not; a water particle pressed onto
// another by a fifth of a spacing ... its density error is measured.
TEST(Verdicts, TheFluidsRuleMeasuresTheWallsBoxAndTheDensity) {
  const Scene scene = builtin("tank", {{"spacing", "0.05"}});
  const Model model(scene);
  std::vector<Verdict> measured;
  const Vector x0 = model.initial_positions(), v0 = model.initial_velocities();
  model.measure_divergence(x0, v0, 0.0, measured);
  ASSERT_EQ(measured.size(), 2u);
  EXPECT_EQ(measured[0].rule, VerdictRule::kFluidOutside);
  EXPECT_EQ(measured[0].value, 0.0);  // every water particle in the box
  const double L = measured[0].bound;
  // The tank's particles span its walls: width 0.5 + 6 spacings.
  EXPECT_NEAR(L, 0.5 + 5 * 0.05, 1e-12);
  EXPECT_EQ(measured[1].rule, VerdictRule::kFluidDensity);
  EXPECT_LT(std::abs(measured[1].value), 0.05);  // the lattice at rest: near rho0
  EXPECT_FALSE(measured[1].exceeded());
  // Water particle 0 (free) lifted above the walls' top by 0.8 L, then 1.2 L.
  double top = -INFINITY;
  for (const Particle& p : scene.particles) {
    if (p.fixed) top = std::max(top, p.x.y());
  }
  for (const double f : {0.8, 1.2}) {
    Vector x = x0;
    x[1] = top + f * L;
    model.measure_divergence(x, v0, 0.0, measured);
    EXPECT_NEAR(measured[0].value, f * L, 1e-12);
    EXPECT_EQ(measured[0].where, 0);
    EXPECT_EQ(measured[0].exceeded(), f > 1.0);
    EXPECT_EQ(measured[0].side, 3);  // the +y side
  }
  // Beyond the -x wall by 1.2 L: the side the message names.
  double left = INFINITY;
  for (const Particle& p : scene.particles) {
    if (p.fixed) left = std::min(left, p.x.x());
  }
  Vector x = x0;
  x[0] = left - 1.2 * L;
  model.measure_divergence(x, v0, 0.0, measured);
  EXPECT_NEAR(measured[0].value, 1.2 * L, 1e-12);
  EXPECT_EQ(measured[0].side, 0);  // the -x side
}

// ------------------------------------------------ bodies (issue 46 items 3, 4)

TEST(Verdicts, TheIssuesBodyBlowUpsDiverge) {
  // Boxes stretched 38 % and 547 E_s in an unforced scene: the strain rule.
  const Model chain(builtin("box-chain"));
  const RunResult a = simulate(chain, settings("generalized-alpha", 0.25, 5.0));
  ASSERT_EQ(a.status, RunStatus::kDiverged);
  ASSERT_TRUE(a.verdict.has_value());
  EXPECT_EQ(a.verdict->rule, VerdictRule::kBodyStrain);
  EXPECT_GT(a.verdict->value, 0.1);
  EXPECT_NE(a.failure.find("no longer rigid"), std::string::npos) << a.failure;
  // 0.987 -> 32.1 J with no force to feed it: the energy rule.
  const Model box(builtin("tumbling-box"));
  const RunResult b = simulate(box, settings("newmark", 0.25, 5.0));
  ASSERT_EQ(b.status, RunStatus::kDiverged);
  ASSERT_TRUE(b.verdict.has_value());
  EXPECT_EQ(b.verdict->rule, VerdictRule::kBodyEnergy);
  EXPECT_GT(b.verdict->value, box.energy_scale());
  EXPECT_NE(b.failure.find("nothing feeds energy in"), std::string::npos) << b.failure;
  // A fine step completes both.
  EXPECT_EQ(simulate(chain, settings("implicit-euler", 0.01, 0.5)).status, RunStatus::kCompleted);
  EXPECT_EQ(simulate(box, settings("implicit-midpoint", 0.01, 1.0)).status, RunStatus::kCompleted);
}

// Wind feeds energy in: the bodies' energy rule is off (the strain rule
// stays); without wind it is on.
TEST(Verdicts, TheBodiesEnergyRuleNeedsAnUnforcedScene) {
  Scene scene = builtin("tumbling-box");
  std::vector<Verdict> measured;
  {
    const Model model(scene);
    model.measure_divergence(model.initial_positions(), model.initial_velocities(), 0.0, measured);
    ASSERT_EQ(measured.size(), 2u);
    EXPECT_EQ(measured[1].rule, VerdictRule::kBodyEnergy);
  }
  Particle leaf;  // wind acts on particles: one to carry it
  leaf.x = Eigen::Vector3d(2.0, 0.0, 0.0);
  scene.particles.push_back(leaf);
  scene.block<Wind>() = {.velocity = Eigen::Vector3d(1.0, 0.0, 0.0), .coefficient = 0.1};
  const Model model(scene);
  model.measure_divergence(model.initial_positions(), model.initial_velocities(), 0.0, measured);
  ASSERT_EQ(measured.size(), 1u);
  EXPECT_EQ(measured[0].rule, VerdictRule::kBodyStrain);
}

// Issue 46 item 4: a 1 cm box 20 m above a plane. E_s takes its length from
// the fall (d = 20.005 m, the box's top to its foot on the plane), not from
// the box (1.7 cm): the fall is no longer a "divergence" at t = 1.88 s, and
// an L-stable method lands it and completes.
TEST(Verdicts, TheEnergyScaleTakesTheHeightABodyCanFall) {
  const Scene drop = parse_scene(
      R"({"dimension": 3, "gravity": [0, -9.81, 0], "particles": [], "springs": [],
          "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0]}],
          "bodies": [{"shape": "box", "size": [0.01, 0.01, 0.01], "position": [0, 20, 0]}]})",
      "drop");
  const Model model(drop);
  const double m = 1000.0 * 1e-6;
  const double d = std::sqrt(0.01 * 0.01 * 2 + 20.005 * 20.005);  // the box's x, z; top to foot
  EXPECT_NEAR(model.energy_scale(), m * 9.81 * d, 1e-9 * m * 9.81 * d);
  for (const char* method : {"implicit-euler", "bdf2"}) {
    SCOPED_TRACE(method);
    const RunResult r = simulate(model, settings(method, 1e-3, 2.5));
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    const Vector p = r.x_final.head(3);
    EXPECT_LT(p.y(), 10.0);  // it fell (lands at t = 2.02 s)
  }
  // Without a plane below nothing changes: the initial positions' box.
  Scene no_floor = drop;
  no_floor.block<Planes>().clear();
  const Model floating(no_floor);
  EXPECT_NEAR(floating.energy_scale(), m * 9.81 * std::sqrt(3e-4), 1e-9);
}

// ------------------------------------------------ discrete-gradient (issue 46 item 2)

// At dt = 0.05 Newton fails on the tumbling box's steps with the rigidity's
// own discrete gradient; its definite fallback solved Gonzalez's generic one
// and |L| fell from 0.3142 to 0.0044. Now the step is solved as substeps
// with the own gradient: |L| and E kept to Newton's tolerance, and no step
// fell back to the generic gradient (the one warning is the substeps').
TEST(Verdicts, DiscreteGradientKeepsTheAngularMomentumWhenNewtonFails) {
  const Model model(builtin("tumbling-box"));
  const RunResult r = simulate(model, settings("discrete-gradient", 0.05, 2.0));
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_GT(r.stats.nonlinear_failures, 0) << "the case must exercise the fallback";
  const BodyLayout layout = body_layout(model.scene(), model.particle_order());
  const BodyState s0 = body_state(layout.bodies[0], layout.first[0], model.initial_positions().data(),
                                  model.initial_velocities().data());
  const BodyState s = body_state(layout.bodies[0], layout.first[0], r.x_final.data(),
                                 r.v_final.data());
  EXPECT_NEAR(s.angular_momentum.norm() / s0.angular_momentum.norm(), 1.0, 1e-6);
  EXPECT_NEAR(r.energy_final / r.energy_initial, 1.0, 1e-6);
  // The failed steps were solved in substeps (a warning says how many), none
  // with the generic gradient.
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0].fallback, Fallback::kSubsteps);
  EXPECT_GE(r.warnings[0].steps, 1);
}

TEST(Verdicts, AFallbackIsAWarningThatSaysWhatAndHowOften) {
  const RunWarning w{.code = WarningCode::kFallback,
                     .fallback = Fallback::kGenericDiscreteGradient, .steps = 2};
  const std::string text = warning_text(w, "discrete-gradient");
  EXPECT_EQ(text.rfind("discrete-gradient: 2 steps fell back to Gonzalez's generic", 0), 0u) << text;
  EXPECT_NE(text.find("angular momentum"), std::string::npos);
}

// ------------------------------------------------ the Newmark-alpha overshoot (item 4)

// Hilber and Hughes (1978): on the undamped oscillator at w h >> 1 the
// alpha methods' energy rises for a few steps before they damp it. The
// recurrence's peak step per parameter set, and the run reproducing the
// issue's numbers: generalized-alpha x3.9e5 at rho_inf 0.5, w h = 1e4;
// hht-alpha (alpha -0.1) x343 at w h = 1e3, peaking at step 5.
TEST(Verdicts, TheAlphaMethodsOvershootForAFewStepsAndNewmarkDoesNot) {
  EXPECT_EQ(newmark_overshoot_steps(hht_parameters(-0.1)), 5);
  EXPECT_EQ(newmark_overshoot_steps(hht_parameters(-0.05)), 11);  // 10 from rest, 11 at a phase
  EXPECT_EQ(newmark_overshoot_steps(generalized_alpha_parameters(0.9)), 10);
  EXPECT_LE(newmark_overshoot_steps(generalized_alpha_parameters(0.5)), 2);
  EXPECT_GE(newmark_overshoot_steps(generalized_alpha_parameters(0.5)), 1);
  EXPECT_EQ(newmark_overshoot_steps({.beta = 0.25, .gamma = 0.5}), 0);
  EXPECT_EQ(newmark_overshoot_steps({.beta = 0.3, .gamma = 0.6}), 0);
  EXPECT_EQ(newmark_overshoot_steps({.beta = 0.0, .gamma = 0.5}), 0);  // not A-stable
  // The runs (w = 10 rad/s), energies sampled at every step.
  struct Case {
    std::string method;
    double wh, peak_ratio;
    long peak_step;
  };
  for (const Case& c : {Case{"hht-alpha", 1e3, 343.2, 5}, Case{"generalized-alpha", 1e4, 3.906e5, 1}}) {
    SCOPED_TRACE(c.method);
    const Model model(builtin("oscillator"));
    class Peak final : public Observer {
     public:
      explicit Peak(const Model& m) : model_(m) {}
      void observe(double, const Vector& x, const Vector& v) override {
        e.push_back(model_.energies(x, v).total());
      }
      const Model& model_;
      std::vector<double> e;
    } peak(model);
    RunSettings s = settings(c.method, c.wh / 10.0, 12 * c.wh / 10.0, 1e300);
    const RunResult r = simulate(model, s, {&peak});
    ASSERT_EQ(r.status, RunStatus::kCompleted);
    const auto top = std::max_element(peak.e.begin(), peak.e.end());
    EXPECT_NEAR(*top / peak.e.front(), c.peak_ratio, 1e-3 * c.peak_ratio);
    EXPECT_EQ(top - peak.e.begin(), c.peak_step);
    // At --blowup 100 the overshoot passes the bound and decays: the run
    // completes, with a warning that says overshoot.
    const RunResult warned =
        simulate(model, settings(c.method, c.wh / 10.0, 40 * c.wh / 10.0, 100.0));
    EXPECT_EQ(warned.status, RunStatus::kCompleted) << warned.failure;
    ASSERT_EQ(warned.warnings.size(), 1u);
    EXPECT_EQ(warned.warnings[0].code, WarningCode::kOvershoot);
    EXPECT_NE(warning_text(warned.warnings[0], c.method).find("overshoot"), std::string::npos);
  }
}

// The allowance: an energy above the bound that sets new highs for at most
// K steps after it first passed it and then falls is forgiven; one still
// setting new highs after K steps breaks the rule (and its message says
// overshoot and what to try).
TEST(Verdicts, TheOvershootWindowForgivesARiseOfKStepsThatDecays) {
  auto energy = [](double value) {
    return Verdict{.rule = VerdictRule::kEnergy, .value = value, .bound = 1.0};
  };
  OvershootWindow decays(3);
  const std::vector<double> overshoot = {0.5, 2.0, 4.0, 6.0, 5.0, 3.0, 1.5, 0.9, 0.8};
  for (std::size_t k = 0; k < overshoot.size(); ++k) {
    EXPECT_FALSE(decays.breaks(energy(overshoot[k]), static_cast<long>(k), 0.1 * k)) << k;
  }
  ASSERT_EQ(decays.overshoots().size(), 1u);
  EXPECT_EQ(decays.overshoots()[0].peak_ratio, 6.0);
  EXPECT_EQ(decays.overshoots()[0].steps, 6);
  OvershootWindow grows(3);
  long broke = -1;
  for (long k = 0; k < 10 && broke < 0; ++k) {
    if (grows.breaks(energy(std::pow(2.0, static_cast<double>(k))), k, 0.0)) broke = k;
  }
  EXPECT_EQ(broke, 4);  // passed the bound at step 1 (2 > 1); a new high at step 1 + 3
  OvershootWindow none(0);
  EXPECT_TRUE(none.breaks(energy(1.5), 1, 0.0));

  const Model model(builtin("oscillator"));
  const std::string text =
      verdict_text(energy(2.0), model, {"hht-alpha", 1000.0, 5}, model.initial_positions(),
                   model.initial_velocities());
  EXPECT_NE(text.find("overshoot"), std::string::npos) << text;
  EXPECT_NE(text.find("implicit-euler"), std::string::npos) << text;
}

// ------------------------------------------------ smaller items of issues 46 and 52

// A body that starts inside a barrier plane is refused at load, naming the
// plane, the body and its vertex (it was "the initial energy is not finite").
TEST(Verdicts, ABodyInsideABarrierPlaneIsRefusedByName) {
  try {
    parse_scene(
        R"({"dimension": 3, "particles": [], "springs": [], "contact": {"model": "barrier"},
            "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0]}],
            "bodies": [{"shape": "box", "size": [1, 1, 1], "position": [0, 0.2, 0]}]})",
        "sunk");
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("planes[0]"), std::string::npos) << what;
    EXPECT_NE(what.find("body 0 starts inside the plane"), std::string::npos) << what;
  }
}

// newmark --beta 0 is the central difference: theory 2 / w_max, as measured.
TEST(Verdicts, StabilityTheoryFollowsNewmarksBetaAndGamma) {
  const Model model(builtin("oscillator"));
  StabilitySettings s;
  s.run.integrator = "newmark";
  s.run.t_end = 5.0;
  s.run.options.beta = 0.0;
  const StabilityResult r = find_max_stable_dt(model, s);
  ASSERT_TRUE(r.theory.dt.has_value()) << r.theory.rule;
  EXPECT_NEAR(*r.theory.dt, 2.0 / 10.0, 1e-12);
  EXPECT_NEAR(r.max_stable_dt / *r.theory.dt, 1.0, 0.01);
  const IntegratorInfo fox = make_integrator("newmark")->info_for({.beta = 1.0 / 12.0});
  EXPECT_NEAR(fox.stability_limit, std::sqrt(6.0), 1e-12);
  EXPECT_EQ(make_integrator("newmark")->info_for({}).stability, StabilityKind::kA);
}

// Explicit Euler undamped has no stable step: the search says so instead of
// "largest stable dt"; on the damped spring, the step it reads above theory
// is one whose fastest mode still grows (|R|^2 > 1).
TEST(Verdicts, TheStabilityAnswerSaysWhenNoStepIsStable) {
  StabilitySettings s;
  s.run.integrator = "explicit-euler";
  s.run.t_end = 1.0;
  const StabilityResult undamped = find_max_stable_dt(Model(builtin("cloth", {{"n", "4"}})), s);
  EXPECT_TRUE(undamped.no_stable_step);
  const StabilityResult damped = find_max_stable_dt(Model(builtin("spring")), s);
  EXPECT_FALSE(damped.no_stable_step);
  ASSERT_TRUE(damped.theory.dt.has_value());
  if (damped.max_stable_dt > 1.01 * *damped.theory.dt) {
    EXPECT_GT(damped.growth_at_lo, 1.0);
  }
}

// The command line: `list` states each kind's rule in one sentence; `run
// --json` has "warnings" (empty when none) and, for a diverged run,
// "verdict"; the text form prints each warning; a yoshida4 failure names
// yoshida4 (it said "verlet: ...").
TEST(Verdicts, TheCommandLineStatesTheRulesAndPrintsWarningsAndVerdicts) {
  using Json = nlohmann::json;
  testing::TempDir temp("verdicts-cli");
  std::filesystem::create_directories(temp.path() / "io");
  auto run = [&](const std::vector<std::string>& args) {
    const testing::ProcessResult p = testing::run_springlab(args, temp.path(), temp.path() / "io");
    EXPECT_TRUE(p.exited && p.status == 0) << p.err;
    return p;
  };
  const std::string list = run({"list"}).out;
  for (const char* rule : {"springs and elements (every scene): the kinetic + elastic energy",
                           "fluids: a water particle further outside its walls' box",
                           "bodies: a body's rigidity strain |A^T A - I|_F more than 0.1"}) {
    EXPECT_NE(list.find(rule), std::string::npos) << rule;
  }
  EXPECT_EQ(Json::parse(run({"list", "--json"}).out)["divergence"].size(), 4u);

  const Json fine = Json::parse(
      run({"run", "spring", "--integrator", "rk4", "--dt", "0.01", "--t-end", "0.1", "--json"}).out);
  EXPECT_EQ(fine["warnings"], Json::array());
  EXPECT_FALSE(fine.contains("verdict"));
  const Json blown = Json::parse(run({"run", "dam-break", "-p", "spacing=0.02", "--integrator",
                                      "explicit-euler", "--dt", "0.004", "--t-end", "0.5",
                                      "--json"}).out);
  ASSERT_EQ(blown["status"], "diverged") << blown.dump();
  const std::string rule = blown["verdict"]["rule"];
  EXPECT_TRUE(rule == "fluid-outside" || rule == "fluid-density") << rule;
  EXPECT_GT(blown["verdict"]["value"].get<double>(), blown["verdict"]["bound"].get<double>());
  EXPECT_TRUE(blown["verdict"]["where"].is_number_integer());

  const std::string text = run({"run", "oscillator", "--integrator", "generalized-alpha", "--dt",
                                "100", "--t-end", "2000", "--blowup", "100"}).out;
  EXPECT_NE(text.find("status completed"), std::string::npos) << text;
  EXPECT_NE(text.find("warning: generalized-alpha: the kinetic + spring energy passed"),
            std::string::npos)
      << text;

  const std::string yoshida = run({"run", "slope", "-p", "speed=1", "--integrator", "yoshida4",
                                   "--dt", "0.1", "--t-end", "1", "--max-newton", "1"}).out;
  EXPECT_NE(yoshida.find("status failed at t = 0.1: yoshida4: the closing half-kick"),
            std::string::npos)
      << yoshida;
}

// The report's fluid experiment's stability search now runs at `run`'s
// rule (experiments/fluid.json lost its `blowup 2`): the fluids' rule ends
// an unstable trial where 2 E_s did, so the bracket is the same.
TEST(Verdicts, TheFluidStabilitySearchReadsTheSameLimitAtTheRunsRule) {
  Scene scene = builtin("dam-break", {{"a", "0.1"}, {"spacing", "0.02"}, {"sound", "10"}});
  scene.block<Fluids>().front().density *= 1.0 - 1e-9;  // as the experiment does
  const Model model(scene);
  const Fluid& fluid = scene.get<Fluids>().front();
  const double h = 1.3 * fluid.spacing;
  StabilitySettings s;
  s.run.integrator = "symplectic-euler";
  s.run.t_end = 0.05;
  s.rel_tol = 0.01;
  s.dt_min = 1e-3 * h / fluid.speed_of_sound;
  s.dt_max = 4.0 * h / fluid.speed_of_sound;
  s.min_periods = 20.0;
  s.run.blowup = 1000.0;
  const StabilityResult rule = find_max_stable_dt(model, s);
  s.run.blowup = 2.0;
  const StabilityResult old = find_max_stable_dt(model, s);
  EXPECT_EQ(rule.outcome, StabilityOutcome::kBracketed);
  EXPECT_EQ(rule.max_stable_dt, old.max_stable_dt);
  // 1.24 x the acoustic mode's 2 / w_max (the experiment's table).
  EXPECT_NEAR(rule.max_stable_dt * rule.mode.w / 2.0, 1.24, 0.02);
}

}  // namespace
}  // namespace springlab::test_verdicts
