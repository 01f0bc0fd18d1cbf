// When NewtonLinearSolver refreshes its kept Cholesky factor
// (integrators/newton/newton_linear_solver.h): once the CG iterations the kept
// factor costs beyond a fresh one's, summed since it was made, exceed
// kRefreshCost; for the exact matrix, beyond the count its first solve with
// the factor took (the exact and definite matrices' own difference, which
// no refresh removes); and how many steps start with a fresh factor after
// the kept one failed at a step's start.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "integrators/newton/newton_linear_solver.h"

namespace springlab::test_newton_linear_solver {
namespace {

constexpr int kN = 40;

// The definite matrix a refresh factors: whatever the test last set.
class FixedSource final : public DefiniteMatrixSource {
 public:
  void assemble_definite(SparseMatrix& out) override { out = definite; }
  SparseMatrix definite;
};

// A symmetric tridiagonal matrix, diagonal d_i, off-diagonal `off`: the
// same pattern whatever the values.
SparseMatrix tridiagonal(const std::vector<double>& d, double off) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < kN; ++i) {
    entries.emplace_back(i, i, d[i]);
    if (i + 1 < kN) {
      entries.emplace_back(i, i + 1, off);
      entries.emplace_back(i + 1, i, off);
    }
  }
  SparseMatrix a(kN, kN);
  a.setFromTriplets(entries.begin(), entries.end());
  return a;
}

struct Counts {
  long iterations, factorizations;
};

// One solve of `a` (with `definite`: a is the definite matrix), to a tight
// tolerance; the CG iterations and factorizations it took.
Counts solve(NewtonLinearSolver& linear, FixedSource& source, const SparseMatrix& a, bool definite,
             IntegratorStats& stats) {
  const long iterations = stats.linear_iterations, factorizations = stats.factorizations;
  linear.matrix(definite, true, source) = a;
  const Vector rhs = Vector::LinSpaced(kN, 1.0, 2.0);
  Vector d;
  std::string error;
  const NewtonLinearSolver::Result result =
      linear.solve(rhs, {.rtol = 1e-10, .atol = 0.0, .truncate = true}, d, error);
  EXPECT_TRUE(result.ok && result.converged) << error;
  return {stats.linear_iterations - iterations, stats.factorizations - factorizations};
}

TEST(NewtonLinearSolver, RefreshesTheKeptFactorOnceItsExtraIterationsExceedAFactorization) {
  IntegratorStats stats;
  NewtonLinearSolver linear;
  linear.reset(stats);
  FixedSource source;
  std::vector<double> d0(kN, 4.0), d1(kN);
  for (int i = 0; i < kN; ++i) d1[i] = 4.0 * (1.0 + 0.05 * std::sin(0.7 * i));
  const SparseMatrix a0 = tridiagonal(d0, -1.0), a1 = tridiagonal(d1, -1.0);
  // The first solve factors a0 and solves it in 1 iteration.
  source.definite = a0;
  const Counts first = solve(linear, source, a0, true, stats);
  EXPECT_EQ(first.factorizations, 1);
  EXPECT_EQ(first.iterations, 1);
  // a1 with a0's factor: each solve costs its iterations beyond 1 as rent.
  source.definite = a1;
  long rent = 0;
  int solves = 0;
  while (rent <= NewtonLinearSolver::kRefreshCost) {
    const Counts kept = solve(linear, source, a1, true, stats);
    ASSERT_EQ(kept.factorizations, 0) << "refreshed at a rent of " << rent;
    ASSERT_GE(kept.iterations, 2);  // a0's factor is not a1's
    ASSERT_LT(kept.iterations, NewtonLinearSolver::kCgHardLimit);
    rent += kept.iterations - 1;
    ++solves;
  }
  // Summed over more than one solve (no single solve exceeds the cost).
  EXPECT_GE(solves, 2);
  // The rent now exceeds a factorization: the next solve has a fresh
  // factor of a1, which solves it in 1 iteration.
  const Counts fresh = solve(linear, source, a1, true, stats);
  EXPECT_EQ(fresh.factorizations, 1);
  EXPECT_EQ(fresh.iterations, 1);
}

TEST(NewtonLinearSolver, KeepsTheFactorWhileTheExactMatrixCostsWhatItCostFresh) {
  IntegratorStats stats;
  NewtonLinearSolver linear;
  linear.reset(stats);
  FixedSource source;
  // The definite matrix and an exact matrix far from it (diagonal 2..12
  // against 4): CG with the definite factor needs many iterations however
  // fresh the factor is.
  std::vector<double> definite(kN, 4.0), exact(kN);
  for (int i = 0; i < kN; ++i) exact[i] = 2.0 + 10.0 * i / (kN - 1.0);
  source.definite = tridiagonal(definite, -1.0);
  const SparseMatrix j = tridiagonal(exact, -0.5);
  const Counts first = solve(linear, source, j, false, stats);
  EXPECT_EQ(first.factorizations, 1);
  // More than a factorization's worth of iterations in each solve (the rule
  // it replaced refreshed after every such solve) ...
  ASSERT_GT(first.iterations, NewtonLinearSolver::kRefreshCost);
  ASSERT_LT(first.iterations, NewtonLinearSolver::kCgHardLimit);
  // ... but no more than the fresh factor's: nothing to gain, no refresh.
  for (int k = 0; k < 5; ++k) {
    const Counts again = solve(linear, source, j, false, stats);
    EXPECT_EQ(again.factorizations, 0) << k;
    EXPECT_EQ(again.iterations, first.iterations) << k;
  }
}

TEST(NewtonLinearSolver, BacksOffFromProbingAKeptFactorThatKeepsFailing) {
  IntegratorStats stats;
  NewtonLinearSolver linear;
  linear.reset(stats);
  FixedSource source;
  // Two definite matrices far apart (diagonal 2..12 against 4), one per
  // step in turn: the factor kept from the step before never serves.
  std::vector<double> flat(kN, 4.0), ramp(kN);
  for (int i = 0; i < kN; ++i) ramp[i] = 2.0 + 10.0 * i / (kN - 1.0);
  const SparseMatrix a[2] = {tridiagonal(flat, -1.0), tridiagonal(ramp, -0.5)};
  std::vector<int> probes;  // the steps that tried the kept factor first
  for (int step = 1; step <= 40; ++step) {
    const SparseMatrix& m = a[step % 2];
    source.definite = m;
    linear.start_nonlinear_solve();
    const Counts c = solve(linear, source, m, true, stats);
    ASSERT_EQ(c.factorizations, 1) << step;  // a fresh factor either way
    // A fresh factor of the matrix itself takes 1 iteration; a probe first
    // spends kCgSoftLimit on the kept one.
    if (c.iterations > 1) {
      EXPECT_EQ(c.iterations, NewtonLinearSolver::kCgSoftLimit + 1) << step;
      probes.push_back(step);
    }
  }
  // Step 1 has no factor yet; then a probe, kFreshSteps = 4 fresh steps,
  // a probe, 8, a probe, 16, a probe (the rule it replaced probed every
  // fifth step: 2, 7, 12, 17, ...).
  EXPECT_EQ(probes, (std::vector<int>{2, 7, 16, 33}));
}

}  // namespace
}  // namespace springlab::test_newton_linear_solver
