// Contact with planes (README "Contact with planes"), checked against closed forms: the penalty's
// resting gap, the explicit methods' stability limit with the contact
// stiffness, energy through a bounce, and the barrier's positive gaps.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "experiments/simulation.h"
#include "experiments/stability.h"
#include "models/contact.h"
#include "models/elastic_model.h"
#include "models/gravity.h"
#include "models/scene.h"
#include "models/springs.h"

namespace springlab {
namespace {

// One particle of mass m at height y0 above the plane y = 0, under gravity g.
Scene drop(double m, double y0, double g, ContactModel model, double stiffness,
           double distance = 0.0) {
  Scene s;
  s.name = "drop";
  s.dimension = 2;
  s.block<Gravity>().acceleration = {0.0, -g, 0.0};
  s.block<Springs>();
  Particle p;
  p.x = {0.0, y0, 0.0};
  p.mass = m;
  s.particles.push_back(p);
  Plane plane;
  plane.point = {0.0, 0.0, 0.0};
  plane.normal = {0.0, 2.0, 0.0};  // normalized by the force
  s.block<Planes>().push_back(plane);
  Contact c;
  c.model = model;
  c.stiffness = stiffness;
  c.distance = distance;
  s.block<Contact>() = c;
  return s;
}

// Penalty: at rest, k_c (-d) = m g, so the particle sinks to d = -m g / k_c.
// Implicit Euler at a step of 10 s is a static solve (inertia negligible).
TEST(Contact, PenaltyRestingGapIsWeightOverStiffness) {
  const double m = 2.0, g = 9.81, k = 5e4;
  const ElasticModel model(drop(m, 0.0, g, ContactModel::kPenalty, k));
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 10.0;
  s.t_end = 100.0;
  s.options.newton_tol = 1e-14;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_NEAR(r.x_final[1], -m * g / k, 1e-6 * m * g / k);
}

// The contact stiffness is one more spring: a particle squeezed between two
// facing planes (no gravity), both penetrated, is an oscillator of
// stiffness 2 k_c while it stays inside both, so RK4 (stable for
// w h <= 2 sqrt 2 on an oscillator, decaying below, growing fast above) is
// stable up to h = 2 sqrt(2) / sqrt(2 k_c / m). Within 5 %.
//
// Why RK4 and a blow-up factor of 1.2: the static contact energy k_c depth^2
// dominates E_s, and the motion is linear only while the particle stays
// inside both planes, so a divergence must be recognized after a small
// growth; RK4's energy falls below its limit, where symplectic Euler's and
// Verlet's oscillate by a factor up to 1 / (1 - (w h / 2)^2) (README,
// "symplectic near the limit") and would be flagged by so small a factor.
TEST(Contact, ExplicitStabilityLimitIsTheContactFrequency) {
  const double m = 1.0, k = 1e4, depth = 1e-3;
  Scene s = drop(m, 0.5 * depth, 0.0, ContactModel::kPenalty, k);
  s.block<Planes>()[0].point = {0.0, depth, 0.0};  // normal +y: penetrated below y = depth
  Plane top;
  top.point = {0.0, -depth, 0.0};
  top.normal = {0.0, -1.0, 0.0};  // penetrated above y = -depth
  s.block<Planes>().push_back(top);
  const ElasticModel model(s);
  const double w = std::sqrt(2.0 * k / m), limit = 2.0 * std::sqrt(2.0) / w;
  StabilitySettings settings;
  settings.run.integrator = "rk4";
  settings.run.t_end = 2.0;
  settings.run.blowup = 1.2;
  settings.dt_min = 1e-5;
  settings.dt_max = 0.1;
  const StabilityResult r = find_max_stable_dt(model, settings);
  ASSERT_EQ(r.outcome, StabilityOutcome::kBracketed);
  EXPECT_NEAR(r.max_stable_dt, limit, 0.05 * limit);
}

// Without friction or drag a bounce stores and returns the energy: the
// implicit midpoint rule keeps the total within 1 % over several bounces.
TEST(Contact, BounceUnderImplicitMidpointKeepsTheEnergy) {
  const ElasticModel model(drop(1.0, 0.1, 9.81, ContactModel::kPenalty, 1e5));
  RunSettings s;
  s.integrator = "implicit-midpoint";
  s.dt = 5e-4;
  s.t_end = 1.0;
  s.options.newton_tol = 1e-12;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_LT(r.x_final[1], 0.1);  // it moved (and came back up: bounces)
  EXPECT_NEAR(r.energy_final, r.energy_initial, 0.01 * std::abs(r.energy_initial));
}

// Records the smallest gap seen at any output time.
class LowestGap final : public Observer {
 public:
  void observe(double, const Vector& x, const Vector&) override {
    lowest = std::min(lowest, x[1]);
  }
  double lowest = 1e300;
};

// The barrier: implicit solvers minimize an incremental potential that is
// +infinity at d <= 0, so no accepted state closes a gap, at steps up to
// 1/30 s. Implicit Euler (forces at the step's end) completes; the midpoint
// methods evaluate the barrier at the midpoint and refuse a solution whose
// end would close a gap, so they complete or stop with a failure that says
// to take a smaller step, never with a closed gap. Explicit Euler steps
// through the plane and ends diverged.
TEST(Contact, BarrierKeepsEveryGapPositiveForImplicitMethods) {
  const ElasticModel model(drop(1.0, 0.2, 9.81, ContactModel::kBarrier, 1e3, 0.01));
  for (const char* name : {"implicit-euler", "implicit-midpoint", "discrete-gradient"}) {
    for (double dt : {1.0 / 30.0, 1.0 / 120.0}) {
      RunSettings s;
      s.integrator = name;
      s.dt = dt;
      s.t_end = 1.0;
      LowestGap gap;
      const RunResult r = simulate(model, s, {&gap});
      if (std::string(name) == "implicit-euler") {
        EXPECT_EQ(r.status, RunStatus::kCompleted) << name << " dt " << dt << ": " << r.failure;
        EXPECT_LT(gap.lowest, 0.01) << "dt " << dt << ": it reached the barrier's distance";
      } else if (r.status == RunStatus::kFailed) {
        EXPECT_NE(r.failure.find("try a smaller --dt"), std::string::npos) << r.failure;
      }
      EXPECT_NE(r.status, RunStatus::kDiverged) << name << " dt " << dt;
      EXPECT_GT(gap.lowest, 0.0) << name << " dt " << dt;
    }
  }
  RunSettings s;
  s.integrator = "explicit-euler";
  s.dt = 1.0 / 30.0;
  s.t_end = 1.0;
  EXPECT_EQ(simulate(model, s).status, RunStatus::kDiverged);
}

}  // namespace
}  // namespace springlab
