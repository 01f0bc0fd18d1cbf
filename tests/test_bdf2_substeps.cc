// bdf2's step solved again in substeps (integrators/methods/bdf2.h): where
// Newton cannot solve a whole step, n = 2, 4 or 8 steps of h/n of the
// variable-step formula (the ratio 1/n, then 1) from the same history take
// its place, and the step after it is of the ratio 1 again, from
// (x_n, x_n+1).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include "integrators/newton/velocity_implicit_method.h"
#include "integrators/registry/registry.h"
#include "models/model/model.h"
#include "models/scenes/builtin_scenes.h"
#include "scenes_for_tests.h"

namespace springlab::test_bdf2_substeps {
namespace {

long substep_fallbacks(const Integrator& integrator) {
  long steps = 0;
  for (const FallbackCount& f : integrator.fallbacks()) {
    if (f.fallback == Fallback::kSubsteps) steps += f.steps;
  }
  return steps;
}

// The hanging chain at 1/60 s with --max-newton 3: some of its steps need
// more Newton iterations and are solved in substeps, each of which needs
// fewer. At the first such step k, the run with the default 200 iterations
// steps the same h up to k - 1 (its Newton stops at the same iterates) and
// then n steps of h/n: for one of n = 2, 4, 8 that is the same state
// within what Newton's tolerance leaves (h tol: the iterates of its inexact
// solves differ by the factors kept, which the failed attempts changed).
// Measured: step 3, in 4 substeps (the split in 2 failed), 1.8e-7 m apart
// against h tol = 1.7e-6 m, the split in 2 3.7e-5 m. At a step solved in
// substeps whose next step is solved whole (step 4, in 2), that next step
// is of the ratio 1: x_k+1 = x_k + (1/3) (x_k - x_k-1) + (2/3) h v_k+1
// holds to round-off; with the history left on the substeps' grid
// (x(t_k - h/n) before x_k, the ratio n: c0 = n^2 / (1 + 2 n),
// b = (1 + n) / (1 + 2 n)) it would be 5.7e-5 m off.
TEST(Bdf2Substeps, AStepNewtonCannotSolveIsSolvedInSubstepsAndTheNextIsOfRatioOne) {
  const Model model(make_builtin_scene("chain", {}));
  const double h = 1.0 / 60.0;
  const Vector& x0 = model.initial_positions();
  const Vector& v0 = model.initial_velocities();
  IntegratorOptions few;
  few.max_newton = 3;
  const IntegratorOptions plenty;
  const double tolerance = h * few.newton_tol;
  auto run = [&](const IntegratorOptions& options) {
    auto integrator = make_integrator("bdf2");
    EXPECT_TRUE(integrator->initialize(model, 0.0, x0, v0, options).ok);
    return integrator;
  };
  auto limited = run(few);
  std::vector<Vector> x{x0}, v{v0};
  std::vector<long> fallbacks{0};
  for (int k = 1; k <= 60; ++k) {
    ASSERT_TRUE(limited->advance_to(k * h).ok) << "step " << k;
    x.push_back(limited->x());
    v.push_back(limited->v());
    fallbacks.push_back(substep_fallbacks(*limited));
  }
  // The split n of step k that `options` replays to its state (0: none),
  // and the state one substep before its end.
  auto split = [&](std::size_t k, const IntegratorOptions& options, Vector& before_end) {
    const int steps = static_cast<int>(k);
    for (int n : {2, 4, 8}) {
      auto replay = run(options);
      for (int j = 1; j < steps; ++j) EXPECT_TRUE(replay->advance_to(j * h).ok);
      EXPECT_EQ(replay->x(), x[k - 1]) << "the replay of step " << k;
      const long own = substep_fallbacks(*replay);
      bool solved = true;
      for (int i = 1; i <= n && solved; ++i) {
        if (i == n) before_end = replay->x();
        solved = replay->advance_to((steps - 1 + double(i) / n) * h).ok &&
                 substep_fallbacks(*replay) == own;
      }
      const double apart = (replay->x() - x[k]).lpNorm<Eigen::Infinity>();
      std::cout << "step " << steps << " in " << n
                << " substeps: " << (solved ? "" : "not solved whole, ") << apart << " m apart\n";
      if (solved && apart <= tolerance) return n;
    }
    return 0;
  };
  std::size_t first = 1;
  while (first <= 60 && fallbacks[first] == 0) ++first;
  ASSERT_LE(first, 60u) << "no step needed more than 3 Newton iterations";
  Vector before_end;
  EXPECT_GT(split(first, plenty, before_end), 0)
      << "step " << first << " is no split of 2, 4 or 8 steps of bdf2";
  std::size_t k = first;
  while (k < 60 && !(fallbacks[k] > fallbacks[k - 1] && fallbacks[k + 1] == fallbacks[k])) ++k;
  ASSERT_LT(k, 60u) << "no step in substeps was followed by one solved whole";
  const int n = split(k, few, before_end);
  ASSERT_GT(n, 0) << "step " << k << " is no split of 2, 4 or 8 steps of bdf2";
  auto mismatch = [&](const Vector& x_before, double c0, double b) {
    return (x[k + 1] - x[k] - c0 * (x[k] - x_before) - b * h * v[k + 1]).lpNorm<Eigen::Infinity>();
  };
  const double of_ratio_1 = mismatch(x[k - 1], 1.0 / 3.0, 2.0 / 3.0);
  const double of_ratio_n =
      mismatch(before_end, n * n / (1.0 + 2.0 * n), (1.0 + n) / (1.0 + 2.0 * n));
  std::cout << "step " << k + 1 << "'s formula, of the ratio 1: " << of_ratio_1
            << " m off; of the ratio " << n << " from the substeps' grid: " << of_ratio_n << " m\n";
  EXPECT_LT(of_ratio_1, 1e-12 * x[k].lpNorm<Eigen::Infinity>());
  EXPECT_GT(of_ratio_n, 10.0 * tolerance);
}

// retry_in_substeps' restart hook, on a method whose substeps only count:
// each adds 1 to x and to its own history. The split in 2 fails at its
// second substep (after its first had moved x and the history on), the
// split in 4 works. The hook runs before each split, so the split in 4
// starts from the history as it was; x is put back by retry_in_substeps
// itself; the step counts once as solved in substeps.
class Splitter final : public VelocityImplicitMethod {
 public:
  Splitter() : VelocityImplicitMethod({.name = "splitter", .implicit = true}) {}
  int restarts = 0;
  double history = 0.0;
  std::vector<double> history_at_split_start;

 protected:
  StepResult do_step(double h) override {
    int substep = 0;
    return retry_in_substeps(
        h, StepResult::failure("the whole step"),
        [&](double dt) {
          const int n = static_cast<int>(std::lround(h / dt));
          if (substep++ == 0) history_at_split_start.push_back(history);
          if (n == 2 && substep == 2) return StepResult::failure("the second half");
          x_.array() += 1.0;
          history += 1.0;
          if (substep == n) substep = 0;
          return StepResult::success();
        },
        nullptr,
        [&] {
          ++restarts;
          substep = 0;
          history = 0.0;
        });
  }
};

TEST(Bdf2Substeps, TheRestartHookRunsBeforeEachSplit) {
  const Model model(testing::oscillator());
  Splitter method;
  ASSERT_TRUE(method
                  .initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                              IntegratorOptions{})
                  .ok);
  const Vector x0 = method.x();
  ASSERT_TRUE(method.advance_to(0.1).ok);
  EXPECT_EQ(method.restarts, 2);
  EXPECT_EQ(method.history_at_split_start, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(method.history, 4.0);
  EXPECT_EQ(method.x(), (x0.array() + 4.0).matrix());
  ASSERT_EQ(method.fallbacks().size(), 1u);
  EXPECT_EQ(method.fallbacks()[0].fallback, Fallback::kSubsteps);
  EXPECT_EQ(method.fallbacks()[0].steps, 1);
}

}  // namespace
}  // namespace springlab::test_bdf2_substeps
