// bdf2's step solved again in substeps (integrators/methods/bdf2.h): where
// Newton cannot solve a whole step, n = 2, 4 or 8 steps of h/n of the
// variable-step formula (the ratio 1/n, then 1) from the same history take
// its place, and the step after it is of the ratio 1 again, from
// (x_n, x_n+1).
#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <vector>

#include "integrators/registry/registry.h"
#include "models/model/model.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab::test_bdf2_substeps {
namespace {

long substep_fallbacks(const Integrator &integrator) {
  long steps = 0;
  for (const FallbackCount &f : integrator.fallbacks()) {
    if (f.fallback == Fallback::kSubsteps) steps += f.steps;
  }
  return steps;
}

// The hanging chain at 1/60 s with --max-newton 3: some of its steps need
// more Newton iterations and are solved in substeps, each of which needs
// fewer. At such a step k (one whose next step is solved whole), the same
// run replayed to k - 1 and then stepped n times by h/n gives the same
// state, for one of n = 2, 4, 8, within what Newton's tolerance leaves
// (h tol: the iterates of its inexact solves differ by the factors kept,
// which the failed attempts changed; measured 7.7e-8 m for the n that
// worked, against h tol = 1.7e-6 m, and 5.7e-5 m and more for the others). And
// the step after it is of the ratio 1: x_k+1 = x_k + (1/3) (x_k - x_k-1) +
// (2/3) h v_k+1 holds to round-off; with the history left on the grid of h/n
// (the ratio n: c0 = n^2 / (1 + 2 n), b = (1 + n) / (1 + 2 n)) it would not.
TEST(Bdf2Substeps, AStepNewtonCannotSolveIsSolvedInSubstepsAndTheNextIsOfRatioOne) {
  const Model model(make_builtin_scene("chain", {}));
  const double h = 1.0 / 60.0;
  const Vector &x0 = model.initial_positions();
  const Vector &v0 = model.initial_velocities();
  IntegratorOptions few;
  few.max_newton = 3;
  auto run = [&] {
    auto integrator = make_integrator("bdf2");
    EXPECT_TRUE(integrator->initialize(model, 0.0, x0, v0, few).ok);
    return integrator;
  };
  auto limited = run();
  std::vector<Vector> x{x0}, v{v0};
  std::vector<long> fallbacks{0};
  for (int k = 1; k <= 60; ++k) {
    ASSERT_TRUE(limited->advance_to(k * h).ok) << "step " << k;
    x.push_back(limited->x());
    v.push_back(limited->v());
    fallbacks.push_back(substep_fallbacks(*limited));
  }
  std::size_t k = 1;
  while (k < 60 && !(fallbacks[k] > fallbacks[k - 1] && fallbacks[k + 1] == fallbacks[k])) ++k;
  ASSERT_LT(k, 60u) << "no step solved in substeps with the next solved whole";
  const int steps = static_cast<int>(k);
  const double scale = x[k].lpNorm<Eigen::Infinity>();
  const double tolerance = h * few.newton_tol;
  int matched = 0;
  for (int n : {2, 4, 8}) {
    auto replay = run();
    for (int j = 1; j < steps; ++j) ASSERT_TRUE(replay->advance_to(j * h).ok);
    ASSERT_EQ(replay->x(), x[k - 1]);
    bool solved = true;
    for (int i = 1; i <= n && solved; ++i) {
      solved = replay->advance_to((steps - 1 + double(i) / n) * h).ok;
    }
    const double apart = (replay->x() - x[k]).lpNorm<Eigen::Infinity>();
    std::cout << "step " << steps << " of 60 in " << n
              << " substeps: " << (solved ? "" : "not solved, ") << apart << " m apart\n";
    if (solved && apart <= tolerance && matched == 0) matched = n;
  }
  EXPECT_GT(matched, 0) << "step " << steps << " is no split of 2, 4 or 8 steps of bdf2";
  auto mismatch = [&](double c0, double b) {
    return (x[k + 1] - x[k] - c0 * (x[k] - x[k - 1]) - b * h * v[k + 1]).lpNorm<Eigen::Infinity>();
  };
  EXPECT_LT(mismatch(1.0 / 3.0, 2.0 / 3.0), 1e-12 * scale);
  const double n = matched;
  const double of_ratio_n = mismatch(n * n / (1.0 + 2.0 * n), (1.0 + n) / (1.0 + 2.0 * n));
  std::cout << "the next step's formula, of the ratio 1: " << mismatch(1.0 / 3.0, 2.0 / 3.0)
            << " m off; of the ratio " << matched << ": " << of_ratio_n << " m\n";
  EXPECT_GT(of_ratio_n, 1e3 * tolerance);
}

}  // namespace
}  // namespace springlab::test_bdf2_substeps
