// Second-order family details of issue 46. The stability search's theory follows the Newmark member the options pick
// (issue 46: `stability oscillator --integrator newmark --beta 0` printed
// "none: A-stable (average acceleration, the default beta 1/4 ...)" beside
// a measured 2 / w). Closed form (Hughes 9.1.2, undamped): the member
// (beta, gamma), gamma >= 1/2, is stable for every step when 2 beta >= gamma,
// otherwise for w h <= 1 / sqrt(gamma/2 - beta).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "experiments/analysis/stability.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/model/model.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab::test_newmark_members {
namespace {

TheoryLimit newmark_theory(double beta, double gamma, double w) {
  IntegratorOptions o;
  o.beta = beta;
  o.gamma = gamma;
  return theoretical_max_dt(make_integrator("newmark")->info_for(o), w, 1.0, 1000.0);
}

TEST(NewmarkMembers, TheoryIsTheMembersClosedForm) {
  const double w = 10.0;
  EXPECT_FALSE(newmark_theory(0.25, 0.5, w).dt.has_value());  // average acceleration
  EXPECT_FALSE(newmark_theory(0.3, 0.6, w).dt.has_value());   // 2 beta >= gamma
  ASSERT_TRUE(newmark_theory(0.0, 0.5, w).dt.has_value());
  EXPECT_NEAR(*newmark_theory(0.0, 0.5, w).dt, 2.0 / w, 1e-12);  // central difference
  EXPECT_NEAR(*newmark_theory(1.0 / 6.0, 0.5, w).dt, std::sqrt(12.0) / w, 1e-12);  // linear acceleration
  EXPECT_NEAR(*newmark_theory(0.1, 0.6, w).dt, 1.0 / std::sqrt(0.2) / w, 1e-12);
  // The default's declared properties are untouched.
  IntegratorOptions defaults;
  EXPECT_EQ(make_integrator("newmark")->info_for(defaults).stability, StabilityKind::kA);
}

// The search on the oscillator (w = 10 rad/s) finds the member's limit.
TEST(NewmarkMembers, SearchMeetsTheMembersLimit) {
  const Model model(make_builtin_scene("oscillator"));
  for (const double beta : {0.0, 0.1}) {
    SCOPED_TRACE("beta " + std::to_string(beta));
    StabilitySettings s;
    s.run.integrator = "newmark";
    s.run.t_end = 10.0;
    s.run.options.beta = beta;
    const StabilityResult r = find_max_stable_dt(model, s);
    ASSERT_TRUE(r.theory.dt.has_value()) << r.theory.rule;
    EXPECT_NEAR(*r.theory.dt, 1.0 / std::sqrt(0.25 - beta) / 10.0, 1e-12);
    EXPECT_NEAR(r.max_stable_dt / *r.theory.dt, 1.0, 0.01);
  }
}

// The compositions of Verlet steps fail under their own name (issue 46:
// yoshida4's failures said "verlet: ..."): box-pile's contact friction makes
// the closing half-kick nonlinear, and one Newton iteration at a tolerance
// no update meets cannot converge.
TEST(VerletFamily, FailuresNameTheMethodThatRan) {
  const Model model(make_builtin_scene("box-pile"));
  for (const char* name : {"verlet", "yoshida4", "yoshida6"}) {
    SCOPED_TRACE(name);
    RunSettings s;
    s.integrator = name;
    s.dt = 0.01;
    s.t_end = 0.05;
    s.options.max_newton = 1;
    s.options.newton_tol = 1e-300;
    const RunResult r = simulate(model, s);
    ASSERT_EQ(r.status, RunStatus::kFailed) << to_string(r.status);
    EXPECT_EQ(r.failure.rfind(std::string(name) + ": the closing half-kick's Newton did not converge in 1 "
                              "iterations",
                              0),
              0u)
        << r.failure;
  }
}

}  // namespace
}  // namespace springlab::test_newmark_members
