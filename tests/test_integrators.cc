// Shared suites, instantiated once per registered integrator: a new method
// gets every test that applies to it (read off its IntegratorInfo: order,
// stability function, symplecticity) by one registry line.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include <Eigen/Eigenvalues>

#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"
#include "registry_suite.h"
#include "scenes_for_tests.h"

namespace springlab::test_integrators {
namespace {

using testing::damped_windy_chain;
using testing::oscillator;
using testing::swinging_spring;

// The tests for every method; each suite after it applies to the methods
// whose IntegratorInfo meets its condition, and is instantiated over those
// only (tests/test_registry_coverage.cc checks that each method is in every
// suite that applies to it).
class EveryIntegrator : public testing::RegistryTest {};
// Fixed step, one step the scalar map R(z) on y' = lambda y.
class EveryIntegratorWithR : public testing::RegistryTest {};
bool fixed_step_with_r(const IntegratorInfo& i) { return i.stability_function && !i.adaptive; }
// Fixed step (an adaptive method's accuracy follows its tolerance:
// AdaptiveIntegrator.ErrorFallsWithTolerance, tests/test_sundials.cc).
class EveryFixedStepIntegrator : public testing::RegistryTest {};
bool fixed_step(const IntegratorInfo& i) { return !i.adaptive; }
class EverySymplecticIntegrator : public testing::RegistryTest {};
bool symplectic(const IntegratorInfo& i) { return i.symplectic; }
// Iterates Newton to --newton-tol.
class EveryNewtonIntegrator : public testing::RegistryTest {};
bool iterates_newton(const IntegratorInfo& i) { return i.iterates_to_tolerance; }

double mechanical_energy(const Model& m, const Vector& x, const Vector& v) {
  return m.energies(x, v).total();
}

// On the undamped oscillator one step multiplies the energy by |R(i w h)|^2
// exactly, for any method whose step is the scalar map R on y' = lambda y.
TEST_P(EveryIntegratorWithR, OscillatorEnergyFactorPerStepIsExact) {
  const IntegratorInfo i = info();
  const Model model(oscillator(100.0, 1.0));
  const double w = 10.0;
  for (double wh : {0.1, 0.7, 2.5}) {
    auto integrator = make_integrator(GetParam());
    IntegratorOptions options;
    options.newton_tol = 1e-14;
    ASSERT_TRUE(integrator->initialize(model, 0.0, model.initial_positions(),
                                       model.initial_velocities(), options).ok);
    const double factor = std::norm(i.stability_function(std::complex<double>(0.0, wh)));
    double energy = mechanical_energy(model, integrator->x(), integrator->v());
    for (int step = 1; step <= 5; ++step) {
      ASSERT_TRUE(integrator->advance_to(step * wh / w).ok);
      const double next = mechanical_energy(model, integrator->x(), integrator->v());
      EXPECT_NEAR(next / energy, factor, 1e-9 * factor) << "w h = " << wh << ", step " << step;
      energy = next;
    }
  }
}

// Final-state error e(h) = |x - x*| + |v - v*| / w against the exact
// solution (oscillator) or a tight RK4 reference (nonlinear scenes); the
// observed order log2(e(h) / e(h/2)) must be within 0.2 of the declared one.
double observed_order(const std::string& name, int order, const Scene& scene, double t_end,
                      const Vector& x_ref, const Vector& v_ref, double w) {
  const Model model(scene);
  const double h = order == 1 ? 1e-3 : (order == 2 ? 1e-2 : 1e-2);
  double error[2];
  for (int k = 0; k < 2; ++k) {
    RunSettings s;
    s.integrator = name;
    s.dt = h / (1 << k);
    s.t_end = t_end;
    s.options.newton_tol = 1e-14;
    const RunResult r = simulate(model, s);
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    error[k] = (r.x_final - x_ref).norm() + (r.v_final - v_ref).norm() / w;
  }
  return std::log2(error[0] / error[1]);
}

TEST_P(EveryFixedStepIntegrator, ConvergenceOrderOnOscillatorMatchesTheory) {
  const IntegratorInfo i = info();
  const double k = 100.0, w = 10.0, rest = 0.0, amplitude = 0.1, t_end = 1.0;
  Vector x_exact(2), v_exact(2);
  x_exact << rest + amplitude * std::cos(w * t_end), 0.0;
  v_exact << -amplitude * w * std::sin(w * t_end), 0.0;
  const double p = observed_order(GetParam(), i.order, oscillator(k, 1.0, rest, amplitude), t_end,
                                  x_exact, v_exact, w);
  EXPECT_NEAR(p, i.order, 0.2);
}

RunResult reference_run(const Scene& scene, double t_end) {
  const Model model(scene);
  RunSettings s;
  s.integrator = "rk4";
  s.dt = 2.5e-5;
  s.t_end = t_end;
  return simulate(model, s);
}

TEST_P(EveryFixedStepIntegrator, ConvergenceOrderOnNonlinearScenesMatchesTheory) {
  const IntegratorInfo i = info();
  for (const Scene& scene : {swinging_spring(), damped_windy_chain()}) {
    const RunResult ref = reference_run(scene, 0.5);
    ASSERT_EQ(ref.status, RunStatus::kCompleted);
    const double p = observed_order(GetParam(), i.order, scene, 0.5, ref.x_final, ref.v_final, 7.0);
    EXPECT_NEAR(p, i.order, 0.2) << scene.name;
  }
}

// Symplectic methods: the energy error oscillates without drift.
TEST_P(EverySymplecticIntegrator, SymplecticEnergyStaysBoundedOver10000Steps) {
  for (const Scene& scene : {oscillator(), swinging_spring()}) {
    const Model model(scene);
    auto integrator = make_integrator(GetParam());
    ASSERT_TRUE(integrator->initialize(model, 0.0, model.initial_positions(),
                                       model.initial_velocities(), IntegratorOptions{}).ok);
    const double h = 0.01, e0 = model.energies(model.initial_positions(),
                                               model.initial_velocities()).total();
    double early = 0.0, late = 0.0;
    for (int step = 1; step <= 10000; ++step) {
      ASSERT_TRUE(integrator->advance_to(step * h).ok);
      const double dev = std::abs(mechanical_energy(model, integrator->x(), integrator->v()) - e0);
      if (step <= 2000) early = std::max(early, dev);
      if (step > 8000) late = std::max(late, dev);
    }
    // Bounded: the w h = 0.1 (oscillator) deviation is O(h) of the energy...
    EXPECT_LT(late, 0.1 * std::abs(e0)) << scene.name;
    // ...and does not grow: the last 2000 steps stay within the first 2000's band.
    EXPECT_LT(late, 1.05 * early + 1e-12 * std::abs(e0)) << scene.name;
  }
}

// The declared stability property (limits, A- and L-stability) is measured
// in tests/test_stability_property.cc.

// A hanging mass at its equilibrium stays there, whatever the method.
TEST_P(EveryIntegrator, EquilibriumIsAFixedPoint) {
  // Rest length 1, placed where the spring balances the weight m g / k.
  Scene s = oscillator(100.0, 2.0, 1.0, 0.0);
  // Pulls along -x, toward the anchor.
  s.block<Gravity>().acceleration = Eigen::Vector3d(-9.81, 0, 0);
  s.particles[1].x.x() = 1.0 - 2.0 * 9.81 / 100.0;
  s.block<Drag>().gamma = 0.5;
  const Model model(s);
  const RunResult r = simulate(model, settings(0.01, 1.0));
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_LT((r.x_final - model.initial_positions()).norm(), 1e-12);
  EXPECT_LT(r.v_final.norm(), 1e-12);
}

// Compressed springs: Newton's matrix is indefinite, Newton must still
// converge (the line search keeps it on course), never crash. (A single
// linearized step, Baraff-Witkin's, has no such guarantee: it diverges here.)
TEST_P(EveryNewtonIntegrator, NewtonConvergesThroughAnIndefiniteMatrix) {
  const IntegratorInfo i = info();
  const Model model(testing::compressed_chain());
  const double h = 0.2;
  SparseMatrix dfdx;
  model.jacobians(0.0, model.initial_positions(), model.initial_velocities(), &dfdx, nullptr);
  Eigen::MatrixXd newton = -h * h * Eigen::MatrixXd(dfdx);
  newton.diagonal() += model.mass();
  const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(newton).eigenvalues()[0];
  ASSERT_LT(lowest, 0.0) << "the scene must make M - h^2 dF/dx indefinite";
  RunSettings s = settings(h, 4.0);
  s.options.newton_tol = 1e-10;
  const RunResult r = simulate(model, s);
  // A conditionally stable implicit method (linear-acceleration,
  // fox-goodwin: w h up to 4 here) may diverge, but its Newton must not fail.
  if (i.stability == StabilityKind::kConditional) {
    EXPECT_NE(r.status, RunStatus::kFailed) << r.failure;
  } else {
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  }
  // Adaptive methods may retry a step after a failed Newton solve (that is
  // their step control); a fixed-step method has no retry, so none may fail
  // -- but hht-alpha's third step here: its first Newton stalls at the
  // potential's round-off (||dv|| 8e-9, above the 1e-10 asked for, along
  // definite updates the line search cannot lengthen) and the second
  // attempt, definite matrices from the step's start, solves it. Measured,
  // kept visible: docs/integrators.md "How the hand-written implicit
  // methods solve".
  if (!i.adaptive) {
    EXPECT_LE(r.stats.nonlinear_failures, i.name == "hht-alpha" ? 1 : 0);
  }
  EXPECT_TRUE(r.x_final.allFinite());
}

// Large steps on a falling cloth compress and fold it: Newton's path crosses
// regions where J is indefinite and ||r|| has local minima (the line search
// on ||r|| alone fails the first step here, 20 iterations without
// convergence); minimizing the incremental potential with definite matrices
// where needed converges at every step.
TEST(ImplicitEuler, ConvergesOnAFoldingClothAtLargeSteps) {
  const Model model(make_builtin_scene("cloth", {{"n", "16"}}));
  ASSERT_TRUE(model.derives_from_potentials());
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 0.1;
  s.t_end = 1.0;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_EQ(r.stats.steps, 10);
  EXPECT_EQ(r.stats.nonlinear_failures, 0);
  // Backward Euler only removes energy from this undamped cloth (the true
  // motion keeps it): the total must end below the start's.
  const Energies e0 = model.energies(model.initial_positions(), model.initial_velocities());
  const Energies e1 = model.energies(r.x_final, r.v_final);
  EXPECT_LT(e1.total(), e0.total());
}

// Linear-implicit Euler's one linear step with the exact stiffness amplifies
// the compressed chain's buckling (its matrix M - h^2 dF/dx is indefinite
// here) until the run blows up; with the definite stiffness (Choi and Ko
// 2002: each compressed spring's negative transverse stiffness dropped) the
// matrix stays above M and the energy of this undamped chain only falls.
TEST(LinearImplicitEuler, DefiniteStiffnessKeepsTheCompressedChainCalm) {
  const Model model(testing::compressed_chain());
  RunSettings s;
  s.integrator = "linear-implicit-euler";
  s.dt = 0.2;
  s.t_end = 4.0;
  s.options.stiffness = Stiffness::kExact;
  const RunResult exact = simulate(model, s);
  EXPECT_EQ(exact.status, RunStatus::kDiverged);
  s.options.stiffness = Stiffness::kDefinite;
  const RunResult definite = simulate(model, s);
  ASSERT_EQ(definite.status, RunStatus::kCompleted) << definite.failure;
  EXPECT_LT(definite.energy_final, definite.energy_initial);
}

// The discrete gradient conserves T + V exactly for forces that derive from
// V, whatever the step, up to how well Newton solves the step: on the cloth
// at a frame step and on the swinging chain, the energy stays within
// 1e-6 E_s at the default tolerance and within 1e-9 E_s at 1e-8 m/s (in the
// measurements: 2e-9 and 3e-13 E_s on the cloth, 4e-9 and 1.3e-12 on the
// chain). The implicit midpoint rule, the same step without Gonzalez's
// correction, drifts by 0.6% and 1.1% of E_s on the same runs.
TEST(DiscreteGradient, ConservesEnergyToTheNewtonTolerance) {
  struct Case {
    Scene scene;
    double dt, t_end;
  };
  const std::vector<Case> cases = {
      {make_builtin_scene("cloth", {{"n", "8"}}), 1.0 / 60.0, 1.0},
      {make_builtin_scene("chain", {{"n", "10"}, {"horizontal", "1"}}), 0.01, 2.0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene.name);
    const Model model(c.scene);
    ASSERT_EQ(model.velocity_dependence(), VelocityDependence::kNone) << "no damping";
    auto drift = [&](const std::string& name, double tol) {
      auto integrator = make_integrator(name);
      IntegratorOptions options;
      options.newton_tol = tol;
      const Vector& x0 = model.initial_positions();
      const Vector& v0 = model.initial_velocities();
      EXPECT_TRUE(integrator->initialize(model, 0.0, x0, v0, options).ok);
      const double e0 = model.energies(x0, v0).total();
      double largest = 0.0;
      for (const double t : time_grid(c.dt, c.t_end)) {
        const StepResult r = integrator->advance_to(t);
        EXPECT_TRUE(r.ok) << r.message;
        if (!r.ok) break;
        largest = std::max(
            largest, std::abs(model.energies(integrator->x(), integrator->v()).total() - e0));
      }
      return largest / model.energy_scale();
    };
    EXPECT_LT(drift("discrete-gradient", IntegratorOptions{}.newton_tol), 1e-6);
    EXPECT_LT(drift("discrete-gradient", 1e-8), 1e-9);
    EXPECT_GT(drift("implicit-midpoint", 1e-8), 1e-3);
  }
}

// The default Newton tolerance leaves a solver error far below the step's
// own error: every tenth step of a frame-step run of the 16 x 16 cloth,
// solved again from the same state with a fresh integrator at the default
// tolerance and at 1/1000 of it, lands within 0.1 mm of the tighter solve
// (measured: 0.5 um on cloth 16, 1.5 um on cloth 64, BM_NewtonAccuracy,
// where one step of h and two of h/2 differ by 0.5-0.9 mm). And the run,
// undamped, never gains energy in a step: backward Euler solved to the
// tolerance only dissipates.
TEST(ImplicitEuler, SolverErrorIsFarBelowTheStepsAndEnergyNeverGrows) {
  const Model model(make_builtin_scene("cloth", {{"n", "16"}}));
  const double h = 1.0 / 60.0, tol = IntegratorOptions{}.newton_tol;
  auto run = make_integrator("implicit-euler");
  ASSERT_TRUE(run->initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                              IntegratorOptions{}).ok);
  auto one_step = [&](double t, const Vector& x, const Vector& v, double newton_tol) {
    auto fresh = make_integrator("implicit-euler");
    IntegratorOptions options;
    options.newton_tol = newton_tol;
    EXPECT_TRUE(fresh->initialize(model, t, x, v, options).ok);
    const StepResult r = fresh->advance_to(t + h);
    EXPECT_TRUE(r.ok) << r.message;
    return Vector(fresh->x());
  };
  double energy = model.energies(run->x(), run->v()).total();
  double largest = 0.0;
  for (int k = 1; k <= 60; ++k) {
    const double t = run->t();
    const Vector x = run->x(), v = run->v();
    const StepResult r = run->advance_to(k * h);
    ASSERT_TRUE(r.ok) << r.message;
    const double next = model.energies(run->x(), run->v()).total();
    EXPECT_LE(next, energy + 1e-12) << "step " << k;
    energy = next;
    if (k % 10 != 0) continue;
    const Vector loose = one_step(t, x, v, tol), tight = one_step(t, x, v, tol / 1000.0);
    largest = std::max(largest, (loose - tight).lpNorm<Eigen::Infinity>());
  }
  EXPECT_LT(largest, 1e-4);
  EXPECT_GT(largest, 0.0) << "the two tolerances must give different steps";
}

// The implicit midpoint rule on the folding cloth at a frame step: its
// energy grows (it is not energy-stable for nonlinear springs at large
// steps) until the energy check stops the run -- a divergence with its time,
// not a Newton failure (Newton solves every step).
TEST(ImplicitMidpoint, EnergyGrowthOnTheFoldingClothIsReportedAsDivergence) {
  const Model model(make_builtin_scene("cloth", {{"n", "16"}}));
  RunSettings s;
  s.integrator = "implicit-midpoint";
  s.dt = 1.0 / 60.0;
  s.t_end = 2.0;
  const RunResult r = simulate(model, s);
  EXPECT_EQ(r.status, RunStatus::kDiverged) << r.failure;
  // The blow-up's message says what the rule saw and what to try.
  EXPECT_EQ(r.failure.find("kinetic + spring energy "), 0u) << r.failure;
  EXPECT_NE(r.failure.find(" J exceeded --blowup 1000 x E_s = "), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("try a smaller --dt"), std::string::npos) << r.failure;
  EXPECT_EQ(r.stats.nonlinear_failures, 0);
  ASSERT_TRUE(r.diverged_at.has_value());
  EXPECT_GT(*r.diverged_at, 1.0);
  // The last good state already holds far more energy than the start's 0.
  EXPECT_GT(r.energy_final, 100.0 * model.energy_scale());
}

// A Newton that cannot converge is a result naming the reason, not a crash.
TEST(ImplicitEuler, NewtonFailureIsReportedInTheResult) {
  const Model model(testing::compressed_chain());
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 0.2;
  s.t_end = 1.0;
  s.options.max_newton = 1;
  s.options.newton_tol = 1e-14;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kFailed);
  EXPECT_NE(r.failure.find("implicit-euler: Newton failed at t = 0"), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("no convergence in 1 iterations"), std::string::npos) << r.failure;
  // Two solves failed: Newton's, then the step's second attempt with the
  // definite matrix only.
  EXPECT_EQ(r.stats.nonlinear_failures, 2);
  EXPECT_DOUBLE_EQ(*r.diverged_at, 0.2);
}

TEST_P(EveryIntegrator, ReportsConsistentStatistics) {
  const IntegratorInfo i = info();
  const Model model(damped_windy_chain());
  const RunResult r = simulate(model, settings(0.001, 0.01));
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const IntegratorStats& s = r.stats;
  EXPECT_GE(s.force_evals, s.steps);
  EXPECT_GE(s.rejected_steps, 0);
  if (i.adaptive) {
    // Error control chooses the steps, and every output time is a stop
    // time, reached by a step (not interpolated): at least one step per
    // output interval.
    EXPECT_GE(s.steps, 10);
  } else {
    EXPECT_EQ(s.steps, 10);
    EXPECT_EQ(s.rejected_steps, 0);
    EXPECT_EQ(s.nonlinear_failures, 0);
  }
  if (i.jacobian_free) {
    // The fast solvers: a fixed number of iterations per step, no Jacobian;
    // projective dynamics factors its constant matrix once per step size.
    EXPECT_EQ(s.jacobian_evals, 0);
    EXPECT_GE(s.newton_iterations, s.steps);
    EXPECT_LE(s.factorizations, 1);
  } else if (i.implicit) {
    EXPECT_GE(s.newton_iterations, s.steps);
    EXPECT_GE(s.linear_solves, s.newton_iterations);
    EXPECT_GE(s.factorizations, 1);
    if (i.adaptive) {
      // SUNDIALS reuses a Jacobian across steps.
      EXPECT_GE(s.jacobian_evals, 1);
      EXPECT_LE(s.jacobian_evals, s.steps);
    } else if (i.iterates_to_tolerance) {
      // A Jacobian at every Newton iteration; a factorization far more
      // rarely (kept as the preconditioner of CG across iterations and
      // steps), each of a matrix assembled from a Jacobian evaluation.
      EXPECT_GE(s.jacobian_evals, s.newton_iterations);
      EXPECT_GE(s.factorizations, 1);
      EXPECT_LE(s.factorizations, s.jacobian_evals + s.linear_solves);
    } else {
      // One linearization per step (plus, with an indefinite stiffness, the
      // definite matrix its preconditioner is made of).
      EXPECT_GE(s.jacobian_evals, s.steps);
      EXPECT_LE(s.jacobian_evals, 2 * s.steps);
    }
  } else if (i.adaptive) {
    // Explicit RK, or Adams with fixed-point iteration: no Jacobian at all.
    EXPECT_EQ(s.jacobian_evals, 0);
    EXPECT_EQ(s.linear_solves, 0);
  } else {
    // Explicit fixed-step methods never iterate (Verlet's closing kick with
    // spring damping is one linear solve, exact because F is affine in v,
    // with the one force evaluation at v = 0 it needs; Yoshida's
    // compositions take three or seven such kicks per step).
    EXPECT_EQ(s.newton_iterations, 0);
    EXPECT_LE(s.linear_solves, s.force_evals);
  }
}

TEST_P(EveryIntegrator, SameInputsGiveBitIdenticalResults) {
  const Model model(damped_windy_chain());
  const RunResult a = simulate(model, settings(0.002, 0.1));
  const RunResult b = simulate(Model(damped_windy_chain()), settings(0.002, 0.1));
  ASSERT_EQ(a.x_final.size(), b.x_final.size());
  for (Eigen::Index k = 0; k < a.x_final.size(); ++k) {
    EXPECT_EQ(a.x_final[k], b.x_final[k]);
    EXPECT_EQ(a.v_final[k], b.v_final[k]);
  }
  EXPECT_EQ(a.stats.force_evals, b.stats.force_evals);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryIntegrator, ::testing::ValuesIn(integrator_names()),
                         testing::registry_test_name);
SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(EveryIntegratorWithR, fixed_step_with_r);
SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(EveryFixedStepIntegrator, fixed_step);
SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(EverySymplecticIntegrator, symplectic);
SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(EveryNewtonIntegrator, iterates_newton);

}  // namespace
}  // namespace springlab::test_integrators

namespace springlab::test_integrators {
namespace {

// A 2-D chain of 6 particles (the first fixed) whose springs join them in
// `order`: the particles sit on a zig-zag line in that order, so every
// order gives the same counts (6 particles, 5 springs) and another topology,
// hence another Jacobian pattern of the same size.
Scene chain_in_order(const std::vector<int>& order, double rest, double damping) {
  Scene s;
  s.name = "chain-in-order";
  s.dimension = 2;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -9.81, 0);
  s.particles.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    Particle& p = s.particles[static_cast<std::size_t>(order[k])];
    p.x = Eigen::Vector3d(0.3 * static_cast<double>(k), 0.05 * static_cast<double>(k % 2), 0.0);
    p.fixed = order[k] == 0;
  }
  for (std::size_t k = 0; k + 1 < order.size(); ++k) {
    s.block<Springs>().push_back({order[k], order[k + 1], 100.0, rest, damping});
  }
  return s;
}

// An integrator serves one system once: a second initialize() is refused and
// leaves the first run untouched, for every method.
TEST(Integrator, SecondInitializeIsRefusedAndChangesNothing) {
  const Model first(testing::swinging_spring());
  const Model second(testing::compressed_chain());
  for (const std::string& name : integrator_names()) {
    auto integrator = make_integrator(name);
    ASSERT_TRUE(integrator->initialize(first, 0.0, first.initial_positions(),
                                       first.initial_velocities(), {}).ok) << name;
    ASSERT_TRUE(integrator->advance_to(0.01).ok) << name;
    const Vector x = integrator->x(), v = integrator->v();
    const long steps = integrator->stats().steps;
    const StepResult again = integrator->initialize(second, 0.0, second.initial_positions(),
                                                    second.initial_velocities(), {});
    EXPECT_FALSE(again.ok) << name;
    EXPECT_EQ(again.message, name + ": already initialized: an integrator runs one system once "
                                    "(its caches belong to that system); make a new one for the "
                                    "next run");
    EXPECT_EQ(integrator->t(), 0.01) << name;
    EXPECT_EQ(integrator->x(), x) << name;
    EXPECT_EQ(integrator->v(), v) << name;
    EXPECT_EQ(integrator->stats().steps, steps) << name;
    EXPECT_TRUE(integrator->advance_to(0.02).ok) << name;  // still runs the first system
  }
}

// Runs `name` on `b` for 100 steps of 0.01 s after the same object has run
// `a`: if the method accepted a second initialize(), with the object that
// ran `a` (its caches built for a's pattern), else with a new one, as every
// caller now does. Returns the final positions.
Vector run_after_another_system(const std::string& name, const MechanicalSystem& a,
                                const Model& b, const Vector& xa, const Vector& va) {
  IntegratorOptions options;
  options.newton_tol = 1e-13;
  auto integrator = make_integrator(name);
  EXPECT_TRUE(integrator->initialize(a, 0.0, xa, va, options).ok);
  for (int k = 1; k <= 10; ++k) EXPECT_TRUE(integrator->advance_to(0.01 * k).ok) << name;
  const StepResult again =
      integrator->initialize(b, 0.0, b.initial_positions(), b.initial_velocities(), options);
  EXPECT_FALSE(again.ok) << name << " accepted a second system";
  if (!again.ok) {
    integrator = make_integrator(name);
    EXPECT_TRUE(
        integrator->initialize(b, 0.0, b.initial_positions(), b.initial_velocities(), options).ok);
  }
  for (int k = 1; k <= 100; ++k) EXPECT_TRUE(integrator->advance_to(0.01 * k).ok) << name;
  return integrator->x();
}

// Issue 12's first example: linear-implicit-euler re-initialized on a scene
// with the same counts and another topology kept the first pattern's
// symbolic factorization and ended 0.25 m off here. On zero-rest-length
// springs (linear forces) its one Newton step is exact, so it must agree
// with implicit Euler solved to 1e-13.
TEST(Integrator, LinearImplicitEulerOnSameCountsOtherTopologyIsRight) {
  const Model a(chain_in_order({0, 1, 2, 3, 4, 5}, 0.0, 0.0));
  const Model b(chain_in_order({0, 3, 5, 1, 4, 2}, 0.0, 0.0));
  ASSERT_EQ(a.jacobian_pattern().nonZeros(), b.jacobian_pattern().nonZeros());
  const Vector x = run_after_another_system("linear-implicit-euler", a, b, a.initial_positions(),
                                            a.initial_velocities());
  RunSettings reference;
  reference.integrator = "implicit-euler";
  reference.dt = 0.01;
  reference.t_end = 1.0;
  reference.options.newton_tol = 1e-13;
  const RunResult r = simulate(b, reference);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_LT((x - r.x_final).lpNorm<Eigen::Infinity>(), 1e-9);
}

// Issue 12's second example: verlet reused on a second spring-damped scene
// kept the first one's closing-kick factorization: here the factorization
// of the new matrix with the old symbolic analysis corrupted the heap
// (glibc: "malloc(): unaligned tcache chunk detected"). It must end exactly
// where a new verlet on that scene ends.
TEST(Integrator, VerletOnASecondSpringDampedSceneIsRight) {
  const Model a(testing::damped_windy_chain());
  const Model b(chain_in_order({0, 3, 5, 1, 4, 2}, 0.25, 0.5));
  ASSERT_EQ(b.velocity_dependence(), VelocityDependence::kCoupled);
  const Vector x =
      run_after_another_system("verlet", a, b, a.initial_positions(), a.initial_velocities());
  auto fresh = make_integrator("verlet");
  ASSERT_TRUE(fresh->initialize(b, 0.0, b.initial_positions(), b.initial_velocities(), {}).ok);
  for (int k = 1; k <= 100; ++k) ASSERT_TRUE(fresh->advance_to(0.01 * k).ok);
  EXPECT_EQ(x, fresh->x());
}

}  // namespace
}  // namespace springlab::test_integrators

namespace springlab::test_integrators {
namespace {

// Issue #38: Newton's "no convergence" quoted a last update below the
// tolerance (8.97e-05 < 1e-4) without saying why that did not end it. On
// cloth 32 at 1/60 with --newton-tol 6e-4 and --max-newton 6 the last
// update, 5.0e-4 m/s, is below the tolerance, but Newton converges linearly
// there, at the rate 0.58, and the error left after it (q/(1-q) of it) is
// 7.0e-4 m/s: the message says so. (Before the kept factor's refresh rule
// of issue 37 the same happened at --newton-tol 1e-3: 7.5e-4 m/s, rate
// 0.59, 1.08e-3 m/s left; the iterates now differ within the tolerance.)
TEST(ImplicitEuler, NoConvergenceSaysWhyAnUpdateBelowTheToleranceDidNotEndIt) {
  const Model model(make_builtin_scene("cloth", {{"n", "32"}}));
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 0.0166667;
  s.t_end = 1.0;
  s.options.newton_tol = 6e-4;
  s.options.max_newton = 6;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kFailed);
  EXPECT_EQ(r.failure,
            "implicit-euler: Newton failed at t = 0.183334 (h = 0.0166667): no convergence in 6 "
            "iterations (last update 0.000504689 m/s, tolerance 0.0006 m/s; converging linearly "
            "at the rate 0.582305, it leaves an error of about 0.000703583 m/s); try a larger "
            "--max-newton or a smaller --dt");
}

}  // namespace
}  // namespace springlab::test_integrators
