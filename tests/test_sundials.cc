// The adaptive SUNDIALS methods, each suite instantiated over every adaptive
// integrator in the registry: error proportional to tolerance, the analytic
// Jacobian really used, linear solvers agreeing, failures as results.
#include <gtest/gtest.h>

#include <cmath>

#include "experiments/simulation.h"
#include "integrators/registry.h"
#include "models/builtin_scenes.h"
#include "models/mass_spring_model.h"
#include "scenes_for_tests.h"

namespace springlab {
namespace {

std::vector<std::string> adaptive_names(bool implicit_only) {
  std::vector<std::string> names;
  for (const std::string& name : integrator_names()) {
    const IntegratorInfo i = make_integrator(name)->info();
    if (i.adaptive && (!implicit_only || i.implicit)) names.push_back(name);
  }
  return names;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& p) {
  std::string name = p.param;
  for (char& c : name) {
    if (c == '-') c = '_';
  }
  return name;
}

RunSettings adaptive(const std::string& name, double rtol, double dt, double t_end) {
  RunSettings s;
  s.integrator = name;
  s.dt = dt;
  s.t_end = t_end;
  s.options.rtol = rtol;
  s.options.atol = rtol * 1e-2;
  return s;
}

Scene small_cloth() { return make_builtin_scene("cloth", {{"n", "4"}, {"wind", "2"}}); }

// The reference: rk4 at a step far below its stability limit and error scale.
Vector reference_positions(const Scene& scene, double t_end, double dt) {
  const MassSpringModel model(scene);
  RunSettings s;
  s.integrator = "rk4";
  s.dt = dt;
  s.t_end = t_end;
  const RunResult r = simulate(model, s);
  EXPECT_EQ(r.status, RunStatus::kCompleted);
  return r.x_final;
}

class AdaptiveIntegrator : public ::testing::TestWithParam<std::string> {};
class AdaptiveImplicitIntegrator : public ::testing::TestWithParam<std::string> {};

// Error control works: 10^4 times tighter tolerance, at least 100x smaller error.
TEST_P(AdaptiveIntegrator, ErrorFallsWithTolerance) {
  struct Case {
    Scene scene;
    double t_end, reference_dt;
  };
  for (const Case& c : {Case{testing::swinging_spring(), 1.0, 1e-5},
                        Case{small_cloth(), 0.5, 2e-6}}) {
    const Vector reference = reference_positions(c.scene, c.t_end, c.reference_dt);
    const MassSpringModel model(c.scene);
    double error[2];
    int k = 0;
    for (double rtol : {1e-4, 1e-8}) {
      const RunResult r = simulate(model, adaptive(GetParam(), rtol, 0.05, c.t_end));
      ASSERT_EQ(r.status, RunStatus::kCompleted) << c.scene.name << ": " << r.failure;
      error[k++] = (r.x_final - reference).lpNorm<Eigen::Infinity>();
    }
    EXPECT_LT(error[1], error[0] / 100.0)
        << c.scene.name << ": error " << error[0] << " at rtol 1e-4, " << error[1] << " at 1e-8";
  }
}

// A run that cannot finish (--max-steps too small) is a result naming the call.
TEST_P(AdaptiveIntegrator, TooMuchWorkIsReportedAsAResult) {
  const MassSpringModel model(small_cloth());
  RunSettings s = adaptive(GetParam(), 1e-8, 1.0, 2.0);
  s.options.max_steps = 10;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kFailed);
  EXPECT_TRUE(r.diverged());
  EXPECT_NE(r.failure.find(GetParam() + ": "), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("failed at t = "), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("mxstep"), std::string::npos) << r.failure;
  EXPECT_TRUE(r.x_final.allFinite());
  EXPECT_EQ(r.t_final, 0.0);  // the last good output time
}

TEST_P(AdaptiveIntegrator, StabilityLimitDetectionIsCvodeBdfOnly) {
  const MassSpringModel model(testing::swinging_spring());
  RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 1.0);
  s.options.stald = true;
  const RunResult r = simulate(model, s);
  if (GetParam() == "cvode-bdf") {
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  } else {
    ASSERT_EQ(r.status, RunStatus::kFailed);
    EXPECT_NE(r.failure.find("--stald applies to cvode-bdf only"), std::string::npos)
        << r.failure;
  }
}

// With the analytic Jacobian, a Jacobian costs no force evaluations: the
// evaluations per Jacobian are the nonlinear iterations it serves (a few
// hundred at most), far below the 2n a difference-quotient Jacobian costs.
TEST_P(AdaptiveImplicitIntegrator, AnalyticJacobianCostsNoForceEvaluations) {
  const MassSpringModel model(make_builtin_scene("chain", {{"n", "600"}, {"horizontal", "1"}}));
  const double unknowns = 2.0 * static_cast<double>(model.dofs());  // 2396
  RunSettings s = adaptive(GetParam(), 1e-6, 0.05, 0.1);
  s.options.linear_solver = "klu";
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  ASSERT_GE(r.stats.jacobian_evals, 1);
  const double per_jacobian =
      static_cast<double>(r.stats.force_evals) / static_cast<double>(r.stats.jacobian_evals);
  EXPECT_LT(per_jacobian, unknowns / 4) << "force evaluations per Jacobian";
}

// --dq-jacobian: SUNDIALS differences the right-hand side instead, paying
// at least one evaluation per unknown per Jacobian, for the same answer.
TEST_P(AdaptiveImplicitIntegrator, DifferenceQuotientJacobianGivesTheSameAnswer) {
  const MassSpringModel model(small_cloth());
  const double unknowns = 2.0 * static_cast<double>(model.dofs());
  RunSettings s = adaptive(GetParam(), 1e-8, 0.05, 0.3);
  s.options.linear_solver = "dense";
  const RunResult analytic = simulate(model, s);
  s.options.dq_jacobian = true;
  const RunResult dq = simulate(model, s);
  ASSERT_EQ(analytic.status, RunStatus::kCompleted) << analytic.failure;
  ASSERT_EQ(dq.status, RunStatus::kCompleted) << dq.failure;
  ASSERT_GE(dq.stats.jacobian_evals, 1);
  EXPECT_GE(static_cast<double>(dq.stats.force_evals),
            unknowns * static_cast<double>(dq.stats.jacobian_evals));
  EXPECT_LT(analytic.stats.force_evals, dq.stats.force_evals);
  // Same answer to the tolerance (positions of order 1 m).
  EXPECT_LT((analytic.x_final - dq.x_final).lpNorm<Eigen::Infinity>(), 1e-5);
}

TEST_P(AdaptiveImplicitIntegrator, LinearSolversAgree) {
  const MassSpringModel model(make_builtin_scene("cloth", {{"n", "6"}, {"drag", "0.01"}}));
  Vector first;
  for (const char* solver : {"dense", "klu", "gmres"}) {
    RunSettings s = adaptive(GetParam(), 1e-8, 0.05, 0.15);
    s.options.linear_solver = solver;
    const RunResult r = simulate(model, s);
    ASSERT_EQ(r.status, RunStatus::kCompleted) << solver << ": " << r.failure;
    if (first.size() == 0) {
      first = r.x_final;
    } else {
      EXPECT_LT((r.x_final - first).lpNorm<Eigen::Infinity>(), 1e-5) << solver;
    }
  }
}

TEST_P(AdaptiveImplicitIntegrator, KluRefusesDifferenceQuotients) {
  const MassSpringModel model(testing::swinging_spring());
  RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 1.0);
  s.options.linear_solver = "klu";
  s.options.dq_jacobian = true;
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kFailed);
  EXPECT_NE(r.failure.find("--dq-jacobian needs --linear-solver dense or gmres"),
            std::string::npos)
      << r.failure;
}

INSTANTIATE_TEST_SUITE_P(Registry, AdaptiveIntegrator, ::testing::ValuesIn(adaptive_names(false)),
                         test_name);
INSTANTIATE_TEST_SUITE_P(Registry, AdaptiveImplicitIntegrator,
                         ::testing::ValuesIn(adaptive_names(true)), test_name);

// Two different solvers on two different formulations (CVODE on y' = f(y),
// IDA on the residual form) and a tiny-step RK4 agree on the chain.
TEST(Sundials, IdaCvodeBdfAndRk4AgreeOnTheChain) {
  const Scene chain = make_builtin_scene("chain", {{"n", "8"}, {"horizontal", "1"}});
  const MassSpringModel model(chain);
  const Vector reference = reference_positions(chain, 0.5, 1e-5);
  for (const char* name : {"cvode-bdf", "ida"}) {
    const RunResult r = simulate(model, adaptive(name, 1e-10, 0.05, 0.5));
    ASSERT_EQ(r.status, RunStatus::kCompleted) << name << ": " << r.failure;
    EXPECT_LT((r.x_final - reference).lpNorm<Eigen::Infinity>(), 1e-6) << name;
  }
}

}  // namespace
}  // namespace springlab
