// The Newton loop (integrators/newton/newton_loop.h) on problems that are not a
// time step: a plain residual with a non-symmetric Jacobian, and the
// gradient of a convex potential from far away, through the same pieces
// the implicit methods give it (policy, line search, linear solver).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "integrators/newton/newton_loop.h"

namespace springlab::test_newton_loop {
namespace {

// A problem of n unknowns with a dense-pattern J assembled from a callback.
class SmallProblem : public NewtonProblem, public DefiniteMatrixSource {
 public:
  explicit SmallProblem(Vector start) : start_(std::move(start)) {}
  const Vector& start() const override { return start_; }
  bool fallback_start(Vector&) const override { return false; }
  void matrix(const Vector& v, bool /*definite*/, NewtonLinearSolver& linear) override {
    v_ = v;
    assemble_definite(linear.matrix(false, symmetric(), *this));
  }
  void assemble_definite(SparseMatrix& out) override {
    const Eigen::MatrixXd j = jacobian(v_);
    // Every entry stored, zero or not: the pattern stays fixed.
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index c = 0; c < j.cols(); ++c) {
      for (Eigen::Index r = 0; r < j.rows(); ++r) entries.emplace_back(r, c, j(r, c));
    }
    out.resize(j.rows(), j.cols());
    out.setFromTriplets(entries.begin(), entries.end());
  }
  virtual bool symmetric() const = 0;
  virtual Eigen::MatrixXd jacobian(const Vector& v) const = 0;

 private:
  Vector start_, v_;
};

// r(v) = (v0^2 + v1 - 3, v0 v1^2 - 4): a simple root at (1, 2) (J there
// [2, 1; 4, 4], det 4), J = [2 v0, 1; v1^2, 2 v0 v1] not symmetric, no
// potential: the search is on ||r||.
class PlainResidual final : public SmallProblem {
 public:
  PlainResidual() : SmallProblem(Vector::Constant(2, 1.5)) {}
  void residual(const Vector& v, Vector& r) override {
    r.resize(2);
    r << v[0] * v[0] + v[1] - 3.0, v[0] * v[1] * v[1] - 4.0;
  }
  bool has_potential() const override { return false; }
  double potential(const Vector&, double& magnitude) override { return magnitude = 0.0; }
  bool symmetric() const override { return false; }
  Eigen::MatrixXd jacobian(const Vector& v) const override {
    Eigen::MatrixXd j(2, 2);
    j << 2.0 * v[0], 1.0, v[1] * v[1], 2.0 * v[0] * v[1];
    return j;
  }
};

// Phi(v) = sum_i exp(v_i) - c_i v_i, minimized at v_i = ln c_i: J is
// symmetric positive definite (CG with the kept factor), the merit is Phi.
class ConvexPotential final : public SmallProblem {
 public:
  ConvexPotential() : SmallProblem(Vector::Constant(3, 6.0)) { c_ << 1.0, 2.0, 5.0; }
  void residual(const Vector& v, Vector& r) override {
    r = v.array().exp().matrix() - c_;
  }
  bool has_potential() const override { return true; }
  double potential(const Vector& v, double& magnitude) override {
    magnitude = v.array().exp().sum() + c_.cwiseProduct(v).cwiseAbs().sum();
    return v.array().exp().sum() - c_.dot(v);
  }
  bool symmetric() const override { return true; }
  Eigen::MatrixXd jacobian(const Vector& v) const override {
    return v.array().exp().matrix().asDiagonal();
  }
  const Vector& c() const { return c_; }

 private:
  Vector c_ = Vector(3);
};

StepResult solve(SmallProblem& problem, IntegratorStats& stats, Vector& v) {
  NewtonLinearSolver linear;
  linear.reset(stats);
  NewtonPolicy policy(NewtonPolicy::Matrices::kAlternating, problem.symmetric());
  LineSearch search;
  NewtonLoop loop;
  return loop.solve(problem, {policy, linear, search}, {.tol = 1e-13, .max_iterations = 50},
                    {.t = 0.0, .h = 1.0}, stats, v);
}

TEST(NewtonLoop, SolvesAPlainResidualWithANonSymmetricJacobian) {
  PlainResidual problem;
  IntegratorStats stats;
  Vector v;
  const StepResult result = solve(problem, stats, v);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_NEAR(v[0], 1.0, 1e-13);
  EXPECT_NEAR(v[1], 2.0, 1e-13);
  // Quadratic convergence from (1.5, 1.5): a handful of iterations, each
  // one LU factorization of the non-symmetric J.
  EXPECT_LE(stats.newton_iterations, 8);  // measured: 7
  EXPECT_EQ(stats.factorizations, stats.linear_solves);
}

TEST(NewtonLoop, MinimizesAConvexPotentialFromFarAway) {
  ConvexPotential problem;
  IntegratorStats stats;
  Vector v;
  const StepResult result = solve(problem, stats, v);
  ASSERT_TRUE(result.ok) << result.message;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(v[i], std::log(problem.c()[i]), 1e-12) << i;
  // Each Newton update moves v_i by c_i e^-v_i - 1 > -1: from 6 to ln 1 = 0
  // at least 6 iterations, then quadratic convergence.
  EXPECT_GE(stats.newton_iterations, 6);
  EXPECT_LE(stats.newton_iterations, 15);  // measured: 12
}

TEST(NewtonLoop, ReportsTheIterationCapWithTheLastUpdate) {
  ConvexPotential problem;
  IntegratorStats stats;
  NewtonLinearSolver linear;
  linear.reset(stats);
  NewtonPolicy policy(NewtonPolicy::Matrices::kAlternating, true);
  LineSearch search;
  NewtonLoop loop;
  Vector v;
  const StepResult result =
      loop.solve(problem, {policy, linear, search}, {.tol = 1e-13, .max_iterations = 3},
                 {.t = 0.5, .h = 0.25}, stats, v);
  ASSERT_FALSE(result.ok);
  // The loop does not know the method: the method puts its name in front.
  EXPECT_EQ(result.message.rfind("Newton failed at t = 0.5 (h = 0.25): no convergence in 3 "
                                 "iterations (last update ",
                                 0),
            0u)
      << result.message;
  EXPECT_NE(result.message.find("try a larger --max-newton or a smaller --dt"), std::string::npos);
}

}  // namespace
}  // namespace springlab::test_newton_loop
