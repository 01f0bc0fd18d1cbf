// The run driver (experiments/driver/simulation.h) and the stability search
// (experiments/analysis/stability.h) in-process: the output time grid of
// docs/command-line.md "The command line", the observer protocol, the divergence rule (the E_s
// threshold) and the bisection on dt, each checked against a value worked out by hand.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/driver/divergence_check.h"
#include "experiments/driver/simulation.h"
#include "experiments/analysis/stability.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/springs/drag.h"
#include "models/model/model.h"
#include "models/springs/gravity.h"
#include "models/model/modal_analysis.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"

namespace springlab::test_simulation {
namespace {

// One zero-rest-length spring along x from a fixed anchor at the origin, no
// gravity: F = -k x in every direction, so the linear analysis is exact.
// w = sqrt(k / m), E(0) = k amplitude^2 / 2 = E_s.
Scene linear_oscillator(double k = 100.0, double mass = 1.0, double amplitude = 0.1) {
  Scene s;
  s.name = "linear-oscillator";
  s.dimension = 2;
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(amplitude, 0, 0), Eigen::Vector3d::Zero(), mass, false}};
  s.block<Springs>() = {{0, 1, k, 0.0, 0.0}};
  return s;
}

RunSettings settings(const std::string& integrator, double dt, double t_end) {
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  return s;
}

class RecordingObserver final : public Observer {
 public:
  void observe(double t, const Vector& x, const Vector& v) override {
    times.push_back(t);
    xs.push_back(x);
    vs.push_back(v);
  }
  std::vector<double> times;
  std::vector<Vector> xs, vs;
};

// ---------------------------------------------------------------- time_grid

TEST(SimulationTimeGrid, WholeNumberOfStepsEvenWhenTOverDtIsInexact) {
  // 1 / 0.1 is not exactly 10 in binary; the grid still has 10 points.
  const std::vector<double> grid = time_grid(0.1, 1.0);
  ASSERT_EQ(grid.size(), 10u);
  for (std::size_t k = 0; k + 1 < grid.size(); ++k) {
    EXPECT_EQ(grid[k], static_cast<double>(k + 1) / 10.0) << "k = " << k + 1;  // k x 0.1 in decimal
  }
  EXPECT_EQ(grid.back(), 1.0);

  // 0.3 / 0.1 = 2.9999999999999996 and (3 * 0.1) / 0.1 = 3.0000000000000004.
  const std::vector<double> below = time_grid(0.1, 0.3);
  ASSERT_EQ(below.size(), 3u);
  EXPECT_EQ(below[0], 0.1);
  EXPECT_EQ(below[1], 2 * 0.1);
  EXPECT_EQ(below[2], 0.3);
  const std::vector<double> above = time_grid(0.1, 3 * 0.1);
  ASSERT_EQ(above.size(), 3u);
  EXPECT_EQ(above[2], 3 * 0.1);

  EXPECT_EQ(time_grid(0.01, 5.0).size(), 500u);
  EXPECT_EQ(time_grid(0.25, 1.0), (std::vector<double>{0.25, 0.5, 0.75, 1.0}));
}

TEST(SimulationTimeGrid, LastStepShortenedToEndExactlyAtT) {
  const std::vector<double> grid = time_grid(0.3, 1.0);
  ASSERT_EQ(grid.size(), 4u);
  EXPECT_EQ(grid[0], 0.3);
  EXPECT_EQ(grid[1], 0.6);
  EXPECT_EQ(grid[2], 0.9);  // the double nearest 0.9, not 3 * 0.3 = 0.8999999999999999
  EXPECT_EQ(grid[3], 1.0);

  EXPECT_EQ(time_grid(1.0, 3.5), (std::vector<double>{1.0, 2.0, 3.0, 3.5}));
  // 1e-6 past a whole number is far outside the 1e-9 rounding window.
  EXPECT_EQ(time_grid(1.0, 3.0 + 1e-6), (std::vector<double>{1.0, 2.0, 3.0, 3.0 + 1e-6}));
}

// t_k is k times dt as written: the double nearest (k d) x 10^e for dt's
// shortest decimal d x 10^e, checked against strtod of that decimal, so its
// shortest text is the decimal a reader expects ("0.9", not
// "0.8999999999999999"). A dt with 17 digits (1/60) keeps k dt.
TEST(SimulationTimeGrid, GridTimesAreTheDecimalsAReaderExpects) {
  struct Case {
    double dt;
    long long d;
    int e;
  };
  for (const Case c : {Case{0.1, 1, -1}, Case{0.3, 3, -1}, Case{0.01, 1, -2}, Case{0.05, 5, -2},
                       Case{0.0166667, 166667, -7}, Case{2.5e-7, 25, -8}, Case{0.007, 7, -3},
                       Case{1.5, 15, -1}, Case{40.0, 4, 1}}) {
    SCOPED_TRACE(c.dt);
    const std::vector<double> grid = time_grid(c.dt, 1000 * c.dt);
    ASSERT_EQ(grid.size(), 1000u);
    for (std::size_t k = 1; k < grid.size(); ++k) {
      const std::string decimal = std::to_string(static_cast<long long>(k) * c.d) + "e" + std::to_string(c.e);
      EXPECT_EQ(grid[k - 1], std::strtod(decimal.c_str(), nullptr)) << "k = " << k;
      EXPECT_LT(grid[k - 1], grid[k]);
    }
  }
  EXPECT_EQ(time_grid(0.3, 0.9)[1], 0.6);
  // 3 * 0.3 and 3 * 0.1 as doubles are not 0.9 and 0.3; the grid's are.
  ASSERT_NE(3 * 0.3, 0.9);
  EXPECT_EQ(time_grid(0.3, 3.0)[2], 0.9);
  ASSERT_NE(3 * 0.1, 0.3);
  EXPECT_EQ(time_grid(0.1, 1.0)[2], 0.3);
  // 1/60 has a 17-digit shortest decimal: k d passes 2^53 at once.
  const double sixtieth = 1.0 / 60.0;
  const std::vector<double> frames = time_grid(sixtieth, 1.0);
  ASSERT_EQ(frames.size(), 60u);
  for (std::size_t k = 1; k < frames.size(); ++k) EXPECT_EQ(frames[k - 1], static_cast<double>(k) * sixtieth);
}

TEST(SimulationTimeGrid, StepLongerThanTGivesOnePointAtT) {
  EXPECT_EQ(time_grid(2.0, 1.0), (std::vector<double>{1.0}));
  EXPECT_EQ(time_grid(1.0, 1.0), (std::vector<double>{1.0}));
  EXPECT_EQ(time_grid(1e3, 1e-3), (std::vector<double>{1e-3}));
}

TEST(SimulationTimeGrid, WithinOneBillionthOfWholeRounds) {
  // T / dt = 10 + 5e-11 (and 10 - 5e-11): 10 steps, the last ending at T.
  for (const double t_end : {1.0 + 5e-12, 1.0 - 5e-12}) {
    SCOPED_TRACE(t_end);
    const std::vector<double> grid = time_grid(0.1, t_end);
    ASSERT_EQ(grid.size(), 10u);
    EXPECT_EQ(grid[8], 9 * 0.1);
    EXPECT_EQ(grid.back(), t_end);
  }
  // 3 + 1e-10 whole steps of 1.
  EXPECT_EQ(time_grid(1.0, 3.0 + 1e-10), (std::vector<double>{1.0, 2.0, 3.0 + 1e-10}));
}

TEST(SimulationTimeGrid, BadStepOrEndTimeThrows) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const double dt : {0.0, -0.0, -0.1, nan, inf, -inf}) {
    SCOPED_TRACE(dt);
    EXPECT_THROW(time_grid(dt, 1.0), std::invalid_argument);
  }
  for (const double t_end : {0.0, -0.0, -1.0, nan, inf, -inf}) {
    SCOPED_TRACE(t_end);
    EXPECT_THROW(time_grid(0.1, t_end), std::invalid_argument);
  }
}

TEST(SimulationTimeGrid, SimulateRefusesBadSettings) {
  const Model model(linear_oscillator());
  EXPECT_THROW(simulate(model, settings("rk4", 0.0, 1.0)), std::invalid_argument);
  EXPECT_THROW(simulate(model, settings("rk4", -0.1, 1.0)), std::invalid_argument);
  EXPECT_THROW(simulate(model, settings("rk4", 0.1, 0.0)), std::invalid_argument);
  RunSettings every = settings("rk4", 0.1, 1.0);
  every.every = 0;
  EXPECT_THROW(simulate(model, every), std::invalid_argument);
}

// ----------------------------------------------------------------- observer

TEST(SimulationObserver, SeesInitialStateFirstAndEndTimeLast) {
  const Model model(linear_oscillator());
  RecordingObserver a, b;
  const RunResult r = simulate(model, settings("verlet", 0.1, 1.0), {&a, &b});
  EXPECT_FALSE(r.diverged());
  EXPECT_EQ(r.status, RunStatus::kCompleted);
  EXPECT_FALSE(r.diverged_at.has_value());
  EXPECT_EQ(r.t_final, 1.0);
  EXPECT_EQ(r.stats.steps, 10);

  ASSERT_EQ(a.times.size(), 11u);
  EXPECT_EQ(a.times, b.times);  // every observer sees every output time
  EXPECT_EQ(a.times.front(), 0.0);
  for (std::size_t k = 1; k + 1 < a.times.size(); ++k) EXPECT_EQ(a.times[k], static_cast<double>(k) / 10.0);
  EXPECT_EQ(a.times.back(), 1.0);

  // The first observation is the initial state, the last the final one.
  EXPECT_EQ(a.xs.front(), model.initial_positions());
  EXPECT_EQ(a.vs.front(), model.initial_velocities());
  EXPECT_EQ(a.xs.back(), r.x_final);
  EXPECT_EQ(a.vs.back(), r.v_final);
  ASSERT_EQ(a.xs.back().size(), 2);  // only the free particle is a state
}

TEST(SimulationObserver, EveryKthGridTimeAndAlwaysTheLast) {
  const Model model(linear_oscillator());
  {
    RecordingObserver o;
    RunSettings s = settings("rk4", 0.1, 1.0);
    s.every = 3;
    simulate(model, s, {&o});
    EXPECT_EQ(o.times, (std::vector<double>{0.0, 0.3, 0.6, 0.9, 1.0}));
  }
  {
    RecordingObserver o;  // 10 steps, every 5: the last is also a 5th
    RunSettings s = settings("rk4", 0.1, 1.0);
    s.every = 5;
    simulate(model, s, {&o});
    EXPECT_EQ(o.times, (std::vector<double>{0.0, 5 * 0.1, 1.0}));
  }
  {
    RecordingObserver o;  // every larger than the step count
    RunSettings s = settings("rk4", 0.1, 1.0);
    s.every = 1000;
    simulate(model, s, {&o});
    EXPECT_EQ(o.times, (std::vector<double>{0.0, 1.0}));
  }
  {
    RecordingObserver o;  // shortened last step (w h = 0.3: stable)
    RunSettings s = settings("symplectic-euler", 0.3, 1.0);
    s.every = 2;
    const RunResult r = simulate(Model(linear_oscillator(1.0)), s, {&o});
    EXPECT_FALSE(r.diverged());
    EXPECT_EQ(o.times, (std::vector<double>{0.0, 2 * 0.3, 1.0}));
  }
}

TEST(SimulationObserver, NotCalledForTheDivergedStep) {
  const Model model(linear_oscillator());
  RecordingObserver o;
  const RunResult r = simulate(model, settings("explicit-euler", 0.05, 10.0), {&o});
  ASSERT_TRUE(r.diverged());
  ASSERT_TRUE(r.diverged_at.has_value());
  ASSERT_FALSE(o.times.empty());
  EXPECT_EQ(o.times.back(), r.t_final);
  EXPECT_LT(o.times.back(), *r.diverged_at);
  for (const Vector& x : o.xs) EXPECT_TRUE(x.allFinite());
}

// --------------------------------------------------------- divergence rule

// Forward Euler on x'' = -w^2 x multiplies E = (m v^2 + k x^2) / 2 by exactly
// 1 + w^2 h^2 per step. Here E(0) = E_s, so with blowup B the run diverges at
// the first step n with (1 + w^2 h^2)^n > B.
TEST(SimulationDivergence, ExplicitEulerDivergesAtThePredictedStep) {
  const Model model(linear_oscillator(100.0, 1.0, 0.1));
  ASSERT_DOUBLE_EQ(model.energy_scale(), 0.5);
  const double h = 0.05, w = 10.0;
  const double growth = 1.0 + w * w * h * h;  // 1.25
  for (const double blowup : {10.0, 1000.0}) {
    SCOPED_TRACE(blowup);
    const double n = std::ceil(std::log(blowup) / std::log(growth));  // 11, 31
    RunSettings s = settings("explicit-euler", h, 10.0);
    s.blowup = blowup;
    const RunResult r = simulate(model, s);
    EXPECT_EQ(r.status, RunStatus::kDiverged);
    EXPECT_TRUE(r.diverged());
    ASSERT_TRUE(r.diverged_at.has_value());
    EXPECT_EQ(*r.diverged_at, n * h);
    EXPECT_EQ(r.t_final, (n - 1) * h);
    // The result keeps the last good state: finite, below the threshold.
    EXPECT_TRUE(r.x_final.allFinite());
    EXPECT_TRUE(r.v_final.allFinite());
    EXPECT_NEAR(r.energy_final, 0.5 * std::pow(growth, n - 1), 1e-9 * r.energy_final);
    EXPECT_LE(r.energy_final, blowup * model.energy_scale());
    EXPECT_DOUBLE_EQ(r.energy_initial, 0.5);
  }
}

// The driver proves most states good from one pass over x and v (an upper
// bound of the spring energy from a reference state; simulation.cc) and
// evaluates the energy only when that bound cannot: the decision must be the
// rule's at every step. Against a loop that evaluates the rule itself after
// every step, on runs that diverge slowly (many steps under the bound, the
// reference moving) and fast, in 2-D and 3-D, with several blow-up factors,
// with equal masses (the pass reads no masses) and unequal ones.
TEST(SimulationDivergence, CheapCertificateDecidesAsTheEnergyRuleAtEveryStep) {
  struct Case {
    Scene scene;
    std::string integrator;
    double dt, t_end, blowup;
  };
  Scene chain = make_builtin_scene("chain", {{"n", "12"}, {"horizontal", "1"}});
  Scene cloth = make_builtin_scene("cloth", {{"n", "6"}});
  Scene unequal_chain = chain, unequal_cloth = cloth;  // masses m, 2 m, 3 m, m, ...
  for (Scene* s : {&unequal_chain, &unequal_cloth}) {
    for (std::size_t i = 0; i < s->particles.size(); ++i) s->particles[i].mass *= 1.0 + i % 3;
  }
  const std::vector<Case> cases = {
      {linear_oscillator(), "explicit-euler", 0.05, 10.0, 1000.0},
      {linear_oscillator(), "explicit-euler", 0.002, 200.0, 3.0},
      {chain, "symplectic-euler", 0.0105, 20.0, 1000.0},   // just above 2 / w_max
      {chain, "explicit-euler", 0.001, 20.0, 50.0},
      {cloth, "explicit-euler", 0.002, 10.0, 1000.0},
      {cloth, "rk4", 0.02, 10.0, 100.0},
      {unequal_chain, "explicit-euler", 0.001, 20.0, 50.0},
      {unequal_cloth, "explicit-euler", 0.002, 10.0, 1000.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene.name + " " + c.integrator + " dt " + std::to_string(c.dt));
    const Model model(c.scene);
    RunSettings s = settings(c.integrator, c.dt, c.t_end);
    s.blowup = c.blowup;
    const RunResult r = simulate(model, s);
    // The rule, evaluated after every step.
    auto integrator = make_integrator(c.integrator);
    ASSERT_TRUE(integrator->initialize(model, 0.0, model.initial_positions(),
                                       model.initial_velocities(), s.options).ok);
    const TimeGrid grid = make_time_grid(c.dt, c.t_end);
    std::optional<double> diverged_at;
    Vector x_good = model.initial_positions(), v_good = model.initial_velocities();
    for (long k = 1; k <= grid.steps; ++k) {
      ASSERT_TRUE(integrator->advance_to(grid.at(k)).ok);
      const Vector& x = integrator->x();
      const Vector& v = integrator->v();
      bool blown = !x.allFinite() || !v.allFinite();
      if (!blown) {
        const Energies e = model.energies(x, v);
        blown = e.kinetic_and_spring() > c.blowup * model.energy_scale() ||
                !std::isfinite(e.total());
      }
      if (blown) {
        diverged_at = grid.at(k);
        break;
      }
      x_good = x;
      v_good = v;
    }
    ASSERT_TRUE(diverged_at.has_value()) << "each case must diverge";
    EXPECT_EQ(r.status, RunStatus::kDiverged);
    ASSERT_TRUE(r.diverged_at.has_value());
    EXPECT_EQ(*r.diverged_at, *diverged_at);
    EXPECT_EQ(r.x_final, x_good);
    EXPECT_EQ(r.v_final, v_good);
  }
}

// The certificate spares the energy evaluation on all but a few steps of a
// run far from the bound (DivergenceCheck::exact_evaluations), as on
// BM_RunPair's scenes: symplectic Euler from rest at dt = 0.5 / w_max, the
// default blow-up factor. The falling chain moves its reference every 30 or
// so steps (its drift bound grows with the path of the whole state; 32
// times in 1024 steps, where the earlier certificate, 2 U_spring(x_ref) +
// 2 kappa |x - x_ref|^2 with the exact drift, took 40), the cloth never in
// 256 steps. Every step is good, and the check's copy is the state.
TEST(SimulationDivergence, CertificateLeavesFewStepsToTheEnergy) {
  struct Case {
    Scene scene;
    long steps, most_exact;
  };
  const std::vector<Case> cases = {
      {make_builtin_scene("chain", {{"n", "200"}}), 1024, 36},
      {make_builtin_scene("cloth", {{"n", "16"}}), 256, 0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene.name);
    const Model model(c.scene);
    const double dt = 0.5 / max_angular_frequency(model);
    auto integrator = make_integrator("symplectic-euler");
    ASSERT_TRUE(integrator->initialize(model, 0.0, model.initial_positions(),
                                       model.initial_velocities(), {}).ok);
    DivergenceCheck check(model, RunSettings{}.blowup * model.energy_scale(),
                          model.energies(model.initial_positions(), model.initial_velocities()));
    for (long k = 1; k <= c.steps; ++k) {
      ASSERT_TRUE(integrator->advance_to(static_cast<double>(k) * dt).ok);
      ASSERT_FALSE(check.diverged(integrator->x(), integrator->v())) << "step " << k;
      ASSERT_EQ(Vector(check.x_good()), integrator->x());
      ASSERT_EQ(Vector(check.v_good()), integrator->v());
    }
    EXPECT_LE(check.exact_evaluations(), c.most_exact);
  }
}

// The threshold is on kinetic + spring energy, not on the total: a particle
// falling freely keeps its mechanical energy, yet its kinetic energy grows
// past B E_s. E_s = m |g| d = 1 * 10 * 1 (d: the fixed particle 1 m away).
TEST(SimulationDivergence, ThresholdIsOnKineticPlusSpringEnergy) {
  Scene s;
  s.name = "free-fall";
  s.dimension = 2;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -10, 0);
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), 1.0, false}};
  const Model model(s);
  ASSERT_DOUBLE_EQ(model.energy_scale(), 10.0);
  // v_n = -10 n h: kinetic 50 (n h)^2 > 1e4 first at n h = 14.2 (h = 0.1).
  const RunResult r = simulate(model, settings("explicit-euler", 0.1, 20.0));
  ASSERT_TRUE(r.diverged());
  ASSERT_TRUE(r.diverged_at.has_value());
  EXPECT_DOUBLE_EQ(*r.diverged_at, 142 * 0.1);
  // ... while the mechanical energy is still what it was, up to Euler's drift.
  EXPECT_NEAR(r.energy_initial, 0.0, 1e-12);
}

// E_s = 0: both particles start at the same point, at rest, on a zero-rest
// spring (so T(0) = U(0) = 0 and the bounding box has diameter 0), yet
// gravity pulls the free one down. Its energy grows from 0, which must not
// count: only a non-finite state does.
TEST(SimulationDivergence, ZeroEnergyScaleOnlyNonFiniteStateDiverges) {
  Scene s;
  s.name = "zero-energy-scale";
  s.dimension = 2;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -9.81, 0);
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, false}};
  s.block<Springs>() = {{0, 1, 100.0, 0.0, 0.0}};
  const Model model(s);
  ASSERT_EQ(model.energy_scale(), 0.0);

  // Stable integrators: finite motion, never a divergence.
  for (const char* integrator : {"symplectic-euler", "rk4", "implicit-euler"}) {
    SCOPED_TRACE(integrator);
    const RunResult r = simulate(model, settings(integrator, 0.01, 5.0));
    EXPECT_EQ(r.status, RunStatus::kCompleted);
    EXPECT_FALSE(r.diverged_at.has_value());
    EXPECT_GT(model.energies(r.x_final, r.v_final).kinetic_and_spring(), 0.0);
  }
  // Forward Euler grows the energy 1.25-fold per step: 1.25^200 ~ 1e19 times
  // whatever it had, still finite, still not a divergence ...
  const RunResult grown = simulate(model, settings("explicit-euler", 0.05, 10.0));
  EXPECT_EQ(grown.status, RunStatus::kCompleted);
  EXPECT_TRUE(grown.x_final.allFinite());
  EXPECT_GT(grown.x_final.norm(), 1e6);
  // ... until the state overflows (|x| ~ 1.118^n reaches 1e308 near n = 6400).
  const RunResult overflow = simulate(model, settings("explicit-euler", 0.05, 500.0));
  EXPECT_EQ(overflow.status, RunStatus::kDiverged);
  ASSERT_TRUE(overflow.diverged_at.has_value());
  EXPECT_GT(*overflow.diverged_at, 250.0);
  EXPECT_LT(*overflow.diverged_at, 500.0);
  EXPECT_TRUE(overflow.x_final.allFinite());
  EXPECT_TRUE(overflow.v_final.allFinite());
}

// Near its limit a stable symplectic method's energy is bounded but large.
// Symplectic Euler (v+ = v - h w^2 x, x+ = x + h v+) conserves
// Q = v^2 + w^2 x^2 - h w^2 x v, so released from rest its energy peaks at
// E0 / (1 - w h / 2): 1000 E0 at w h = 1.998, 2000 E0 at 1.999. The blow-up
// rule (kinetic + spring > B E_s, E_s = E0 here) therefore calls it diverged
// above w h = 2 (1 - 1/B), 0.1% below the limit for B = 1000 -- inside the
// stability bisection's tolerance -- and a larger --blowup sees closer.
double peak_energy_ratio(const Model& model, const RunSettings& s, RunResult& r) {
  RecordingObserver o;
  r = simulate(model, s, {&o});
  double peak = 0.0;
  for (std::size_t k = 0; k < o.times.size(); ++k) {
    const Energies e = model.energies(o.xs[k], o.vs[k]);
    peak = std::max(peak, e.kinetic_and_spring());
  }
  return peak / r.energy_initial;
}

TEST(SimulationDivergence, SymplecticEulerNearItsLimitPeaksAtOneOverOneMinusHalfWh) {
  const Model model(linear_oscillator(100.0, 1.0, 0.1));
  const double w = 10.0;
  RunResult r;
  for (const double wh : {1.9, 1.99, 1.997}) {
    SCOPED_TRACE(wh);
    // Sampled at steps, the peak is approached to within a few 1e-6.
    const double ratio = peak_energy_ratio(model, settings("symplectic-euler", wh / w, 20000 * wh / w), r);
    EXPECT_EQ(r.status, RunStatus::kCompleted);
    EXPECT_NEAR(ratio, 1.0 / (1.0 - wh / 2.0), 1e-4 / (1.0 - wh / 2.0));
  }
  // At 1.999 (stable) the peak is 2000 E0: over the default blow-up factor.
  RunSettings s = settings("symplectic-euler", 1.999 / w, 20000 * 1.999 / w);
  EXPECT_EQ(simulate(model, s).status, RunStatus::kDiverged);
  s.blowup = 4000.0;
  const double ratio = peak_energy_ratio(model, s, r);
  EXPECT_EQ(r.status, RunStatus::kCompleted);
  EXPECT_NEAR(ratio, 2000.0, 2000.0 * 1e-4);
}

// A state whose energy overflows a double has nothing to integrate: the run
// diverges at t = 0 (it used to complete, with inf energies in every row).
TEST(SimulationDivergence, NonFiniteInitialEnergyIsADivergenceAtTimeZero) {
  Scene s = linear_oscillator(100.0, 1.0, 1e200);  // k x^2 / 2 = 5e401
  const Model model(s);
  ASSERT_FALSE(std::isfinite(model.energies(model.initial_positions(), model.initial_velocities()).total()));
  const RunResult r = simulate(model, settings("rk4", 0.1, 1.0));
  EXPECT_EQ(r.status, RunStatus::kDiverged);
  ASSERT_TRUE(r.diverged_at.has_value());
  EXPECT_EQ(*r.diverged_at, 0.0);
  EXPECT_EQ(r.failure, "the initial energy is not finite");
  EXPECT_EQ(r.stats.steps, 0);
}

// A stop request ends a run at its next step, as an exception the
// experiment runner turns into "not done".
TEST(SimulationStop, StopRequestThrowsAtTheNextStep) {
  const Model model(linear_oscillator());
  std::atomic<bool> stop{true};
  RunSettings s = settings("rk4", 0.01, 1.0);
  s.options.stop = &stop;
  EXPECT_THROW(simulate(model, s), StopRequested);
  stop = false;
  EXPECT_EQ(simulate(model, s).status, RunStatus::kCompleted);
  // The same through a StopScope, for runs whose settings carry none.
  stop = true;
  const StopScope scope(&stop);
  EXPECT_THROW(simulate(model, settings("rk4", 0.01, 1.0)), StopRequested);
  EXPECT_THROW(find_max_stable_dt(model, [] {
                 StabilitySettings st;
                 st.run = settings("rk4", 0.01, 1.0);
                 return st;
               }()),
               StopRequested);
}

// ---------------------------------------------------------------- stability

StabilitySettings stability_settings(const std::string& integrator, double t_end) {
  StabilitySettings s;
  s.run = settings(integrator, 0.01, t_end);
  s.dt_min = 1e-3;  // every search here starts far below the limit
  s.dt_max = 1.0;
  return s;
}

void expect_limit(const StabilityResult& r, double limit, double rel_tol) {
  EXPECT_GE(r.max_stable_dt, 0.97 * limit);
  EXPECT_LE(r.max_stable_dt, (1.0 + rel_tol) * limit);
  EXPECT_EQ(r.lo, r.max_stable_dt);
  EXPECT_LT(r.lo, r.hi);
  EXPECT_LE(r.hi / r.lo, 1.0 + rel_tol + 1e-12);
  EXPECT_GT(r.runs, 2);
}

TEST(SimulationStability, SymplecticMethodsStopAtTwoOverOmega) {
  const Model model(linear_oscillator(100.0, 1.0, 0.1));
  const double w = 10.0;
  for (const char* integrator : {"symplectic-euler", "verlet"}) {
    SCOPED_TRACE(integrator);
    const StabilitySettings s = stability_settings(integrator, 100.0 / w);
    const StabilityResult r = find_max_stable_dt(model, s);
    EXPECT_EQ(r.integrator, integrator);
    expect_limit(r, 2.0 / w, s.rel_tol);
  }
}

// Just past its limit RK4 amplifies by only |R(i w h)| - 1 ~ 2.5 (w h - 2
// sqrt 2) per step, so a long run (~3500 steps) is needed to see it.
TEST(SimulationStability, Rk4StopsAtTwoRootTwoOverOmega) {
  const Model model(linear_oscillator(100.0, 1.0, 0.1));
  const double w = 10.0;
  const StabilitySettings s = stability_settings("rk4", 1e4 / w);
  const StabilityResult r = find_max_stable_dt(model, s);
  expect_limit(r, 2.0 * std::sqrt(2.0) / w, s.rel_tol);
}

// The bisection ends in floating point: with a tolerance no ratio of two
// doubles can meet (1e-16, or 0 + the smallest positive) it stops when the
// bracket's ends are neighbours, after about 60 runs.
TEST(SimulationStability, BisectionEndsWhateverTheTolerance) {
  const Model model(linear_oscillator(100.0, 1.0, 0.1));
  for (const double rel_tol : {1e-16, 4.9e-324}) {
    SCOPED_TRACE(rel_tol);
    StabilitySettings s = stability_settings("symplectic-euler", 10.0);
    s.rel_tol = rel_tol;
    const StabilityResult r = find_max_stable_dt(model, s);
    EXPECT_LT(r.lo, r.hi);
    EXPECT_LE(r.hi, r.lo * (1.0 + 4 * std::numeric_limits<double>::epsilon()));
    EXPECT_LE(r.runs, 70);
    EXPECT_EQ(r.outcome, StabilityOutcome::kBracketed);
  }
}

// A range with no valid grid is refused before the first run.
TEST(SimulationStability, ImpossibleRangeIsRefusedBeforeAnyRun) {
  const Model model(linear_oscillator());
  StabilitySettings s = stability_settings("rk4", 1000.0);
  s.dt_min = 1e-12;
  try {
    find_max_stable_dt(model, s);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "--dt-min 1e-12 with --t-end 1000: t_end / dt exceeds 1e9 steps");
  }
}

TEST(SimulationStability, UnconditionallyStableGivesDtMax) {
  const Model model(linear_oscillator());
  const StabilityResult r = find_max_stable_dt(model, stability_settings("implicit-euler", 10.0));
  EXPECT_EQ(r.max_stable_dt, 1.0);
  EXPECT_EQ(r.runs, 1);
}

// Forward Euler is never stable on an undamped oscillator, but over a finite
// run (n = T / h steps, energy factor (1 + w^2 h^2)^n) it stays under the
// blowup factor for small enough h: the search finds that finite-time limit,
// near h with (T / h) ln(1 + w^2 h^2) = ln(1000), i.e. h ~ ln(1000) / (T w^2).
// (T = 20 s: at least the 20 periods of w = 10 every trial runs, so no
// trial is extended past T.)
TEST(SimulationStability, ExplicitEulerFiniteTimeLimitIsConsistent) {
  const Model model(linear_oscillator());
  const StabilitySettings s = stability_settings("explicit-euler", 20.0);
  const StabilityResult r = find_max_stable_dt(model, s);
  ASSERT_GT(r.lo, 0.0);
  EXPECT_LT(r.lo, r.hi);
  EXPECT_LE(r.hi / r.lo, 1.0 + s.rel_tol + 1e-12);
  EXPECT_EQ(r.max_stable_dt, r.lo);
  RunSettings run = s.run;
  run.dt = r.lo;
  EXPECT_FALSE(simulate(model, run).diverged());
  run.dt = r.hi;
  EXPECT_TRUE(simulate(model, run).diverged());
  const double estimate = std::log(1000.0) / (20.0 * 100.0);
  EXPECT_NEAR(r.max_stable_dt, estimate, 0.03 * estimate);
}

TEST(SimulationStability, EvenDtMinDivergingGivesZero) {
  const Model model(linear_oscillator());
  StabilitySettings s = stability_settings("explicit-euler", 10.0);
  s.dt_min = 0.1;
  const StabilityResult r = find_max_stable_dt(model, s);
  EXPECT_EQ(r.max_stable_dt, 0.0);
  EXPECT_EQ(r.hi, 0.1);
}

TEST(SimulationStability, BadRangeThrows) {
  const Model model(linear_oscillator());
  StabilitySettings s = stability_settings("rk4", 1.0);
  s.dt_min = 0.0;
  EXPECT_THROW(find_max_stable_dt(model, s), std::invalid_argument);
  s.dt_min = 0.5;
  s.dt_max = 0.5;
  EXPECT_THROW(find_max_stable_dt(model, s), std::invalid_argument);
}

}  // namespace
}  // namespace springlab::test_simulation
