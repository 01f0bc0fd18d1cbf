// Contact with planes (docs/physics.md "Contact with planes"), checked against closed forms: the
// penalty's resting gap, the explicit methods' stability limit with the contact
// stiffness, energy through a bounce, the barrier's positive gaps, and
// Coulomb friction on the `slope` scene under every integrator (stick,
// slide, stopping distance, the work it dissipates).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/contact/contact_potential.h"
#include "models/scenes/builtin_scenes.h"
#include "random_scenes.h"
#include "registry_suite.h"
#include "experiments/analysis/stability.h"
#include "models/contact/contact.h"
#include "models/model/model.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"
#include "models/model/scene_file.h"

namespace springlab::test_contact {
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
  const Model model(drop(m, 0.0, g, ContactModel::kPenalty, k));
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
// Verlet's oscillate by a factor up to 1 / (1 - (w h / 2)^2) (docs/command-line.md,
// "Divergence": a stable symplectic method near its limit) and would be flagged by so small a
// factor.
TEST(Contact, ExplicitStabilityLimitIsTheContactFrequency) {
  const double m = 1.0, k = 1e4, depth = 1e-3;
  Scene s = drop(m, 0.5 * depth, 0.0, ContactModel::kPenalty, k);
  s.block<Planes>()[0].point = {0.0, depth, 0.0};  // normal +y: penetrated below y = depth
  Plane top;
  top.point = {0.0, -depth, 0.0};
  top.normal = {0.0, -1.0, 0.0};  // penetrated above y = -depth
  s.block<Planes>().push_back(top);
  const Model model(s);
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
  const Model model(drop(1.0, 0.1, 9.81, ContactModel::kPenalty, 1e5));
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

// IPC's step cap: with the barrier, the fraction of a step dx at which the
// first gap closes is d / (-n.dx) of the particle that approaches fastest
// relative to its gap; moving away, or with the penalty (no forbidden
// states), nothing closes.
TEST(Contact, AdmissibleFractionIsWhereTheFirstGapCloses) {
  Scene s = drop(1.0, 0.2, 9.81, ContactModel::kBarrier, 1e3, 0.01);
  Particle second;
  second.x = {1.0, 0.05, 0.0};
  s.particles.push_back(second);
  const Model barrier(s);
  const Vector x = barrier.initial_positions();
  Vector dx(4);
  dx << 0.0, -0.4, 0.0, -0.2;  // gaps 0.2 and 0.05: closed at 0.5 and 0.25
  EXPECT_DOUBLE_EQ(barrier.admissible_fraction(x, dx), 0.25);
  dx << 0.3, -0.4, 0.0, 0.2;  // the second moves away
  EXPECT_DOUBLE_EQ(barrier.admissible_fraction(x, dx), 0.5);
  dx << 0.0, 0.1, 0.0, 0.2;
  EXPECT_EQ(barrier.admissible_fraction(x, dx), std::numeric_limits<double>::infinity());
  s.block<Contact>().model = ContactModel::kPenalty;
  const Model penalty(s);
  dx << 0.0, -0.4, 0.0, -0.2;
  EXPECT_EQ(penalty.admissible_fraction(x, dx), std::numeric_limits<double>::infinity());
}

// The normal damping law (contact_potential.h): -alpha f_n v_n while slow
// (g -> alpha as v_n -> 0), never more than the normal force itself (|g v_n|
// <= 1: the total normal force f_n (1 - g v_n) of a separating contact is
// never a pull), exactly f_n from |v_n| = 2 / alpha on; its slope is
// d(g v_n)/dv_n and its potential's derivative g v_n (central differences);
// alpha = 0 is no damping at all.
TEST(Contact, NormalDampingIsHuntCrossleyWhenSlowAndNeverMoreThanTheNormalForce) {
  const double eps = 1e-7;
  for (double alpha : {0.5, 2.0, 5.0}) {
    SCOPED_TRACE(alpha);
    EXPECT_NEAR(normal_damping(alpha, 1e-9).g, alpha, 1e-6 * alpha);
    for (double vn = -3.0; vn <= 3.0; vn += 0.0625) {
      const NormalDamping d = normal_damping(alpha, vn);
      EXPECT_LE(std::abs(d.g * vn), 1.0 + 1e-15) << vn;
      if (std::abs(vn) >= 2.0 / alpha) EXPECT_NEAR(std::abs(d.g * vn), 1.0, 1e-15) << vn;
      const double force = d.g * vn;
      const double fp = normal_damping(alpha, vn + eps).g * (vn + eps);
      const double fm = normal_damping(alpha, vn - eps).g * (vn - eps);
      EXPECT_NEAR(d.slope, (fp - fm) / (2 * eps), 1e-6 * (1.0 + alpha)) << vn;
      const double Wp = normal_damping(alpha, vn + eps).potential;
      const double Wm = normal_damping(alpha, vn - eps).potential;
      EXPECT_NEAR(force, (Wp - Wm) / (2 * eps), 1e-6) << vn;
    }
  }
  const NormalDamping none = normal_damping(0.0, 0.7);
  EXPECT_EQ(none.g, 0.0);
  EXPECT_EQ(none.slope, 0.0);
  EXPECT_EQ(none.potential, 0.0);
}

// Lagged friction (the hand-written implicit methods, during a step): with
// f_n taken from x_lag, friction is -dW/dv of its dissipation potential W(v),
// dF/dv is symmetric and matches central differences of F, and the model
// says so; cleared, it is live again (no potential, dF/dx not symmetric).
// At random states of each friction kind's own random instance (planes,
// penalty or barrier): particles in 2-D and 3-D, and the rigid bodies'
// friction and normal damping (contact_potential.h's normal_damping) with
// the planes and between bodies.
TEST(Contact, LaggedFrictionIsTheGradientOfItsDissipationPotential) {
  const std::vector<std::pair<std::string, int>> cases = {
      {"friction", 2}, {"friction", 3}, {"body-friction", 3}, {"body-body-friction", 3}};
  for (const auto& [kind, dim] : cases) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      SCOPED_TRACE(kind + ", seed " + std::to_string(seed));
      const Model model(testing::random_scene({&testing::kind_named(kind)}, dim, seed));
      ASSERT_FALSE(model.derives_from_potentials());
      ASSERT_FALSE(model.jacobian_symmetric());
      const Vector x = model.initial_positions(), v = model.initial_velocities();
      Vector f_live;
      model.force(0.0, x, v, f_live);
      model.lag_normal_forces(&x, &v, 0.01);
      EXPECT_TRUE(model.derives_from_potentials());
      EXPECT_TRUE(model.jacobian_symmetric());
      Vector f;
      model.force(0.0, x, v, f);
      EXPECT_LT((f - f_live).norm(), 1e-12 * (1.0 + f.norm()));  // at x_lag itself: the same
      EXPECT_GT(std::abs(model.velocity_potential(0.0, v)), 0.0);
      SparseMatrix dfdv;
      model.jacobians(0.0, x, v, nullptr, &dfdv);
      const Eigen::MatrixXd K(dfdv);
      EXPECT_LT((K - K.transpose()).norm(), 1e-12 * (1.0 + K.norm()));
      const double eps = 1e-6;
      for (Eigen::Index k = 0; k < v.size(); ++k) {
        Vector vp = v, vm = v;
        vp[k] += eps;
        vm[k] -= eps;
        Vector fp, fm;
        model.force(0.0, x, vp, fp);
        model.force(0.0, x, vm, fm);
        EXPECT_LT((K.col(k) - (fp - fm) / (2 * eps)).norm(), 1e-6 * (1.0 + K.col(k).norm()))
            << "dF/dv, column " << k;
        const double dW =
            (model.velocity_potential(0.0, vp) - model.velocity_potential(0.0, vm)) / (2 * eps);
        const double dV =
            (model.position_potential(0.0, x + eps * Vector::Unit(x.size(), k)) -
             model.position_potential(0.0, x - eps * Vector::Unit(x.size(), k))) / (2 * eps);
        EXPECT_NEAR(f[k], -dV - dW, 1e-6 * (1.0 + std::abs(f[k])))
            << dim << "-D, coordinate " << k;
      }
      model.lag_normal_forces(nullptr, nullptr, 0.0);
      EXPECT_FALSE(model.derives_from_potentials());
      EXPECT_FALSE(model.jacobian_symmetric());
    }
  }
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
  const Model model(drop(1.0, 0.2, 9.81, ContactModel::kBarrier, 1e3, 0.01));
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
  const RunResult r = simulate(model, s);
  EXPECT_EQ(r.status, RunStatus::kDiverged);
  // The divergence names the particle and the plane it stepped through.
  EXPECT_NE(r.failure.find("particle 0 stepped through plane 0"), std::string::npos) << r.failure;
}

// Issue #38: linear-implicit-euler (implicit, but one linear solve per step)
// stepping through the barrier was told to "use an implicit method", and
// rk4, whose stage inside the plane makes the state non-finite, diverged
// with no message at all. Both now name what keeps gaps open.
TEST(Contact, BarrierDivergenceSaysToUseImplicitEulerAndWhy) {
  const Model drop_model(drop(1.0, 0.2, 9.81, ContactModel::kBarrier, 1e3, 0.01));
  // (On the drop linear-implicit-euler's linear solve fails first; the
  // block, dropped on the ground, it steps through.)
  const Model block(make_builtin_scene("block", {{"n", "2"}, {"contact", "1"}}));
  for (const char* name : {"explicit-euler", "linear-implicit-euler", "rk4"}) {
    const Model& model =
        std::string(name) == "linear-implicit-euler" ? block : drop_model;
    RunSettings s;
    s.integrator = name;
    s.dt = 1.0 / 30.0;
    s.t_end = 1.0;
    const RunResult r = simulate(model, s);
    EXPECT_EQ(r.status, RunStatus::kDiverged) << name;
    EXPECT_NE(r.failure.find("; use implicit-euler (its Newton iteration keeps every gap open) "
                             "or a smaller --dt"),
              std::string::npos)
        << name << ": " << r.failure;
    EXPECT_EQ(r.failure.find("an implicit method"), std::string::npos) << r.failure;
  }
}

// Issue #38: a plane normal whose norm overflows ([0, 1e308, 1e308], every
// component finite) was refused as "must be a nonzero vector"; it is the
// normal [0, 1, 1] / sqrt(2).
TEST(Contact, HugeFiniteNormalIsNormalizedWithoutOverflow) {
  const Scene s = parse_scene(
      R"({"dimension": 3, "particles": [{"x": [0, -1, 0]}], "springs": [],
          "planes": [{"point": [0, 0, 0], "normal": [0, 1e308, 1e308]}],
          "contact": {"model": "penalty", "stiffness": 100}})",
      "huge-normal.json");
  const Model model(s);
  const Energies e = model.energies(model.initial_positions(), model.initial_velocities());
  // gap d = n.x = -1/sqrt(2): k/2 d^2 = 25 J.
  EXPECT_NEAR(e["contact"], 25.0, 1e-12);
}

// The smallest height (coordinate 1) of any free particle at any output.
class LowestHeight final : public Observer {
 public:
  explicit LowestHeight(int dim) : dim_(dim) {}
  void observe(double, const Vector& x, const Vector&) override {
    for (Eigen::Index k = 1; k < x.size(); k += dim_) lowest = std::min(lowest, x[k]);
  }
  double lowest = 1e300;

 private:
  int dim_;
};

// The barrier on the built-in scenes at dt = 1/30: the tetrahedral block
// dropped on the ground (y = 0) and the cloth swinging onto a ground 0.6 m
// below its corners (with friction 0.3). Every accepted state of every
// implicit method (the hand-written ones and SUNDIALS'; the fast solvers
// refuse the barrier) keeps every gap positive; a method that cannot continue
// stops with a result (failed, or diverged for the one linearized step),
// never with a closed gap.
TEST(Contact, BarrierKeepsTheBlockAndTheClothAboveTheGround) {
  struct Case {
    const char* scene;
    std::vector<std::pair<std::string, std::string>> parameters;
    double ground;
    std::vector<const char*> integrators;
  };
  const std::vector<Case> cases = {
      {"block", {{"n", "2"}, {"contact", "1"}}, 0.0,
       {"implicit-euler", "implicit-midpoint", "discrete-gradient", "linear-implicit-euler",
        "cvode-bdf", "ida", "arkode-dirk", "arkode-imex"}},
      {"cloth", {{"n", "5"}, {"ground", "0.6"}, {"contact", "1"}}, -0.6,
       {"implicit-euler", "implicit-midpoint", "discrete-gradient", "linear-implicit-euler",
        "cvode-bdf", "ida", "arkode-dirk", "arkode-imex"}},
  };
  for (const Case& c : cases) {
    const Model model(make_builtin_scene(c.scene, c.parameters));
    for (const char* name : c.integrators) {
      RunSettings s;
      s.integrator = name;
      s.dt = 1.0 / 30.0;
      s.t_end = 1.0;  // the block lands at 0.32 s, the cloth at about 0.35 s
      LowestHeight height(model.dimension());
      const RunResult r = simulate(model, s, {&height});
      EXPECT_GT(height.lowest, c.ground) << c.scene << ", " << name;
      if (std::string(name) == "implicit-euler") {
        EXPECT_EQ(r.status, RunStatus::kCompleted) << c.scene << ": " << r.failure;
        EXPECT_LT(height.lowest, c.ground + 0.01) << c.scene << ": it reached the barrier";
      }
    }
  }
}

// Coulomb friction on the built-in `slope` (one particle on a plane inclined
// at theta, g = 9.81, friction mu, smoothing eps_v = 1e-3 m/s), under every
// registered integrator at a step of 1e-4 s.
class Friction : public testing::RegistryTest {
 protected:
  static constexpr double kG = 9.81, kEps = 1e-3;
  // Runs slope with `parameters`; false when the run did not complete.
  bool run(const std::vector<std::pair<std::string, std::string>>& parameters, double t_end,
           RunResult& r, Observer* observer = nullptr) {
    const Model model(make_builtin_scene("slope", parameters));
    RunSettings s = settings(1e-4, t_end);
    s.options.newton_tol = 1e-10;
    std::vector<Observer*> observers;
    if (observer != nullptr) observers.push_back(observer);
    r = simulate(model, s, observers);
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    return r.status == RunStatus::kCompleted;
  }
  static double radians(double degrees) { return degrees * std::numbers::pi / 180.0; }
};

// Records the particle's speed at two times.
class SpeedAt final : public Observer {
 public:
  SpeedAt(double t1, double t2) : t1_(t1), t2_(t2) {}
  void observe(double t, const Vector&, const Vector& v) override {
    if (std::abs(t - t1_) < 1e-9) v1 = v.head(2).norm();
    if (std::abs(t - t2_) < 1e-9) v2 = v.head(2).norm();
  }
  double v1 = -1.0, v2 = -1.0;

 private:
  double t1_, t2_;
};

// tan(theta) < mu: the particle sticks. Smoothed friction balances the
// weight's slope component m g sin(theta) = mu m g cos(theta) f1(y) at the
// creep speed y with f1(y) = tan(theta) / mu, so
//   y = eps_v (1 - sqrt(1 - tan(theta) / mu)) < eps_v:
// it creeps at most eps_v t (docs/physics.md "Contact with planes"), and at this
// speed within 1 %.
TEST_P(Friction, SticksWhenTheSlopeIsBelowTheFrictionAngle) {
  const double theta = radians(20.0), mu = 0.5, t = 2.0;
  RunResult r;
  const Model start(make_builtin_scene("slope", {{"angle", "20"}, {"friction", "0.5"}}));
  if (!run({{"angle", "20"}, {"friction", "0.5"}}, t, r)) GTEST_SKIP() << r.failure;
  const double creep = (r.x_final - start.initial_positions()).head(2).norm();
  EXPECT_LE(creep, kEps * t);
  if (GetParam() == "xpbd" || GetParam() == "projective-dynamics") {
    // The fast solvers' friction is Coulomb's without the smoothing (xpbd.h,
    // projective_dynamics.h): they do not creep at all.
    EXPECT_LT(creep, 1e-12);
    return;
  }
  const double y = kEps * (1.0 - std::sqrt(1.0 - std::tan(theta) / mu));
  EXPECT_NEAR(creep / t, y, 0.01 * y);
}

// tan(theta) > mu: it slides with acceleration g (sin(theta) - mu cos(theta))
// (within 1 %, from the speeds at t = 1 s and 2 s).
TEST_P(Friction, SlidesWithTheCoulombAcceleration) {
  const double theta = radians(30.0), mu = 0.3;
  RunResult r;
  SpeedAt speed(1.0, 2.0);
  if (!run({{"angle", "30"}, {"friction", "0.3"}}, 2.0, r, &speed)) GTEST_SKIP() << r.failure;
  const double a = kG * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(speed.v2 - speed.v1, a, 0.01 * a);
}

// Launched at v0 along a level floor, it stops after v0^2 / (2 mu g)
// (within 2 %), and stays stopped.
TEST_P(Friction, StopsAfterTheCoulombDistance) {
  const double mu = 0.4, v0 = 2.0, distance = v0 * v0 / (2.0 * mu * kG);
  RunResult r;
  if (!run({{"angle", "0"}, {"friction", "0.4"}, {"speed", "2"}}, 1.0, r)) {
    GTEST_SKIP() << r.failure;
  }
  EXPECT_NEAR(r.x_final[0], distance, 0.02 * distance);
  EXPECT_LT(std::abs(r.v_final[0]), kEps);
}

// The fast solvers' plane constraint is the penalty (XPBD: compliance
// 1/k_c; projective dynamics: weight k_c): at rest on the plane a particle
// sinks to d = -m g / k_c like implicit Euler's, whatever the substeps and
// iterations.
TEST(Contact, FastSolversRestingGapIsWeightOverStiffness) {
  const double m = 2.0, g = 9.81, k = 5e4;
  const Model model(drop(m, 0.0, g, ContactModel::kPenalty, k));
  for (const char* name : {"xpbd", "projective-dynamics"}) {
    for (int substeps : {1, 10}) {
      for (int iterations : {1, 3}) {
        RunSettings s;
        s.integrator = name;
        s.dt = 0.01;
        s.t_end = 20.0;
        s.options.substeps = std::string(name) == "xpbd" ? substeps : 0;
        s.options.iterations = iterations;
        const RunResult r = simulate(model, s);
        ASSERT_EQ(r.status, RunStatus::kCompleted) << name << ": " << r.failure;
        EXPECT_NEAR(r.x_final[1], -m * g / k, 1e-6 * m * g / k)
            << name << ", " << substeps << " x " << iterations;
      }
    }
  }
  // The barrier is refused by both, with a message that says what to use.
  const Model barrier(drop(m, 0.1, g, ContactModel::kBarrier, 1e3, 0.01));
  for (const char* name : {"xpbd", "projective-dynamics"}) {
    RunSettings s;
    s.integrator = name;
    const RunResult r = simulate(barrier, s);
    EXPECT_EQ(r.status, RunStatus::kFailed) << name;
    EXPECT_NE(r.failure.find("use the penalty contact with"), std::string::npos) << r.failure;
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, Friction, ::testing::ValuesIn(integrator_names()),
                         testing::registry_test_name);

// Friction's work is dissipation, like drag's: the mechanical energy falls
// by the work of the nonconservative forces, integral of F.v (trapezoid
// rule on the output grid; the sliding particle at 1e-4 s, implicit Euler's
// own dissipation being O(h)), within 1 % of the energy lost.
class PowerIntegral final : public Observer {
 public:
  explicit PowerIntegral(const Model& m) : model(m) {}
  void observe(double t, const Vector& x, const Vector& v) override {
    const double p = model.nonconservative_power(t, x, v);
    if (t > 0.0) work += 0.5 * (t - t_last) * (p + p_last);
    t_last = t;
    p_last = p;
  }
  const Model& model;
  double work = 0.0, t_last = 0.0, p_last = 0.0;
};

TEST(Contact, FrictionWorkIsTheEnergyLost) {
  const Model model(make_builtin_scene("slope", {{"angle", "30"}, {"friction", "0.3"}}));
  RunSettings s;
  s.integrator = "rk4";
  s.dt = 1e-4;
  s.t_end = 1.0;
  PowerIntegral power(model);
  const RunResult r = simulate(model, s, {&power});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const double lost = r.energy_final - r.energy_initial;
  ASSERT_LT(power.work, 0.0);
  EXPECT_NEAR(lost, power.work, 0.01 * std::abs(power.work));
}

}  // namespace
}  // namespace springlab::test_contact
