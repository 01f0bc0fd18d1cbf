// The adaptive SUNDIALS methods, each suite instantiated over every adaptive
// integrator in the registry: error proportional to tolerance, the analytic
// Jacobian really used, linear solvers agreeing, failures as results.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>

#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "integrators/sundials/reduced_newton_solver.h"
#include "integrators/sundials/sundials_integrator.h"
#include "integrators/sundials/sundials_support.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"
#include "registry_suite.h"
#include "scenes_for_tests.h"

namespace springlab::test_sundials {
namespace {

bool is_adaptive(const IntegratorInfo& i) { return i.adaptive; }
bool is_adaptive_implicit(const IntegratorInfo& i) { return i.adaptive && i.implicit; }

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
  const Model model(scene);
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
    const Model model(c.scene);
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
  const Model model(small_cloth());
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
  const Model model(testing::swinging_spring());
  RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 1.0);
  s.options.stald = true;
  const RunResult r = simulate(model, s);
  if (GetParam() == "cvode-bdf") {
    EXPECT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  } else {
    ASSERT_EQ(r.status, RunStatus::kFailed);
    EXPECT_NE(r.failure.find(GetParam() + ": --stald: stability limit detection is cvode-bdf's, " +
                             GetParam() + " has none"),
              std::string::npos)
        << r.failure;
  }
}

// With the analytic Jacobian, a Jacobian costs no force evaluations: the
// evaluations per Jacobian are the nonlinear iterations it serves (a few
// hundred at most), far below the 2n a difference-quotient Jacobian costs.
TEST_P(AdaptiveImplicitIntegrator, AnalyticJacobianCostsNoForceEvaluations) {
  const Model model(make_builtin_scene("chain", {{"n", "600"}, {"horizontal", "1"}}));
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
  const Model model(small_cloth());
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
  const Model model(make_builtin_scene("cloth", {{"n", "6"}, {"drag", "0.01"}}));
  Vector first;
  for (const char* solver : {"dense", "klu", "gmres", "reduced"}) {
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

TEST_P(AdaptiveImplicitIntegrator, KluAndReducedRefuseDifferenceQuotients) {
  const Model model(testing::swinging_spring());
  for (const char* solver : {"klu", "reduced"}) {
    RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 1.0);
    s.options.linear_solver = solver;
    s.options.dq_jacobian = true;
    const RunResult r = simulate(model, s);
    ASSERT_EQ(r.status, RunStatus::kFailed) << solver;
    EXPECT_NE(r.failure.find("--dq-jacobian: SUNDIALS forms difference-quotient Jacobians only as "
                             "dense matrices: add --linear-solver dense or gmres"),
              std::string::npos)
        << r.failure;
  }
}

// The reduced solver (reduced_newton_solver.h) is an exact rewriting of the
// first-order Newton system: its answer equals a dense LU solve of the full
// 2n x 2n matrix to round-off, for CVODE's I - gamma J (after SUNDIALS'
// own scaling, SUNMatScaleAddI) and IDA's G(cj), on a cloth with drag
// (a nonzero dF/dv) and with compressed springs (K indefinite).
TEST(ReducedNewtonSolver, EqualsTheFullFirstOrderSolve) {
  const Model model(make_builtin_scene("cloth", {{"n", "4"}, {"drag", "0.3"}}));
  const Eigen::Index n = model.dofs();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vector x = model.initial_positions(), v = model.initial_velocities();
  for (Eigen::Index i = 0; i < n; ++i) {
    x[i] += 0.02 * u(rng);  // some springs compressed
    v[i] += u(rng);
  }
  SparseMatrix dfdx, dfdv;
  model.jacobians(0.0, x, v, &dfdx, &dfdv);
  ASSERT_GT(dfdv.norm(), 0.0);
  sundials::FirstOrderJacobian jacobian(model);
  sundials::ContextPtr context;
  {
    SUNContext c = nullptr;
    ASSERT_EQ(SUNContext_Create(nullptr, &c), 0);
    context.reset(c);
  }
  const sundials::ReducedSystem system{&model, &dfdx, &dfdv, &jacobian};
  sundials::MatrixPtr A(sundials::make_reduced_matrix(system, context.get()));
  sundials::LinearSolverPtr solver(sundials::make_reduced_solver(system, context.get()));
  sundials::MatrixPtr dense(SUNDenseMatrix(2 * n, 2 * n, context.get()));
  sundials::VectorPtr b = sundials::make_vector(2 * n, context.get());
  sundials::VectorPtr out = sundials::make_vector(2 * n, context.get());
  sundials::VectorPtr back = sundials::make_vector(2 * n, context.get());
  Eigen::Map<Vector>(N_VGetArrayPointer(b.get()), 2 * n) = Vector::NullaryExpr(2 * n, [&] { return u(rng); });
  for (const bool dae : {false, true}) {
    SCOPED_TRACE(dae ? "IDA's G(cj)" : "CVODE's I - gamma J");
    const double gamma = 0.01, cj = 1.0 / gamma;
    Eigen::MatrixXd full;
    if (dae) {
      sundials::set_dae_jacobian(A.get(), cj);
      jacobian.fill_dae(dfdx, dfdv, cj, dense.get());
    } else {
      sundials::set_ode_jacobian(A.get());
      ASSERT_EQ(SUNMatScaleAddI(-gamma, A.get()), 0);  // as CVODE's setup does
      jacobian.fill_ode(dfdx, dfdv, dense.get());
      ASSERT_EQ(SUNMatScaleAddI(-gamma, dense.get()), 0);
    }
    full = Eigen::Map<Eigen::MatrixXd>(SUNDenseMatrix_Data(dense.get()), 2 * n, 2 * n);
    ASSERT_EQ(SUNLinSolSetup(solver.get(), A.get()), 0);
    ASSERT_EQ(SUNLinSolSolve(solver.get(), A.get(), out.get(), b.get(), 0.0), 0);
    const Eigen::Map<const Vector> rhs(N_VGetArrayPointer(b.get()), 2 * n);
    const Eigen::Map<const Vector> reduced(N_VGetArrayPointer(out.get()), 2 * n);
    const Vector exact = full.partialPivLu().solve(rhs);
    EXPECT_LT((reduced - exact).norm(), 1e-10 * exact.norm());
    // The placeholder's product is the full matrix's.
    ASSERT_EQ(SUNMatMatvec(A.get(), out.get(), back.get()), 0);
    const Eigen::Map<const Vector> product(N_VGetArrayPointer(back.get()), 2 * n);
    EXPECT_LT((product - full * reduced).norm(), 1e-12 * (full * reduced).norm());
  }
}

// --max-order is checked against the method before any run (issue 17,
// class 4): the orders a method takes are the ones its package has
// (SUNDIALS 6.4: CVODE BDF 1-5, Adams 1-12, IDA 1-5; ARKODE's default ERK
// tables 2-6 and 8, DIRK 2-5, IMEX 3-5 -- ARKODE would silently swap any
// other for a default). Each accepted order runs; each refused one is a
// message naming the accepted ones, and a failed run through simulate().
TEST_P(AdaptiveIntegrator, MaxOrderIsCheckedAgainstTheMethod) {
  const std::map<std::string, std::set<int>> orders = {
      {"cvode-bdf", {1, 2, 3, 4, 5}},        {"cvode-adams", {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}},
      {"ida", {1, 2, 3, 4, 5}},              {"arkode-erk", {2, 3, 4, 5, 6, 8}},
      {"arkode-dirk", {2, 3, 4, 5}},         {"arkode-imex", {3, 4, 5}}};
  ASSERT_TRUE(orders.count(GetParam())) << "a new adaptive method: add its orders here";
  const auto integrator = make_integrator(GetParam());
  const Model model(testing::swinging_spring());
  std::set<int> accepted;
  for (int q = 1; q <= 14; ++q) {
    IntegratorOptions o;
    o.max_order = q;
    const std::string why = integrator->check_options(o, model.dofs());
    if (why.empty()) {
      accepted.insert(q);
      RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 0.5);
      s.options.max_order = q;
      const RunResult r = simulate(model, s);
      EXPECT_EQ(r.status, RunStatus::kCompleted) << "order " << q << ": " << r.failure;
    } else {
      EXPECT_EQ(why.rfind("--max-order " + std::to_string(q) + ": " + GetParam() + " takes ", 0), 0u) << why;
      RunSettings s = adaptive(GetParam(), 1e-6, 0.1, 0.5);
      s.options.max_order = q;
      const RunResult r = simulate(model, s);
      EXPECT_EQ(r.status, RunStatus::kFailed);
      EXPECT_EQ(r.failure, GetParam() + ": " + why);
    }
  }
  EXPECT_EQ(accepted, orders.at(GetParam()));
}

// Below double precision's unit roundoff no solver can meet a tolerance:
// refused up front instead of SUNDIALS' "too much accuracy" at t = 0.
TEST_P(AdaptiveIntegrator, ToleranceBelowRoundoffIsRefused) {
  const auto integrator = make_integrator(GetParam());
  IntegratorOptions o;
  for (const double rtol : {1e-300, 1e-16, 2.2e-16}) {
    o.rtol = rtol;
    EXPECT_NE(integrator->check_options(o, 3).find("below double precision's unit roundoff"),
              std::string::npos)
        << rtol;
  }
  o.rtol = 2.3e-16;
  EXPECT_EQ(integrator->check_options(o, 3), "");
}

// The steps per output interval scale with the system (5e6 / unknowns,
// within [500, 100000]) unless --max-steps is given: a hopeless run on a
// large scene fails after a few thousand steps, not 100000.
TEST(SundialsWorkLimit, ScalesWithTheSystem) {
  IntegratorOptions o;
  EXPECT_EQ(sundials_step_limit(o, 2), kMaxStepLimit);
  EXPECT_EQ(sundials_step_limit(o, 1524), 3280);  // the 16 x 16 cloth
  EXPECT_EQ(sundials_step_limit(o, 2'000'000), kMinStepLimit);
  o.max_steps = 7;
  EXPECT_EQ(sundials_step_limit(o, 1524), 7);
}

// A stiff cloth asked for one output at t = 1000 s: explicit arkode-erk
// needs ~10^6 steps; it stops at the scaled limit with what to try.
TEST(SundialsWorkLimit, HopelessRunFailsAtTheScaledLimit) {
  const Model model(make_builtin_scene("cloth", {{"n", "8"}, {"k", "1e5"}}));
  const double unknowns = 2.0 * static_cast<double>(model.dofs());
  const long limit = static_cast<long>(kStepBudget / unknowns);
  RunSettings s = adaptive("arkode-erk", 1e-6, 1000.0, 1000.0);
  const RunResult r = simulate(model, s);
  ASSERT_EQ(r.status, RunStatus::kFailed);
  EXPECT_EQ(r.stats.steps, limit);
  EXPECT_NE(r.failure.find(std::to_string(limit) + " internal steps did not reach the next output "
                           "time (the default limit, 5e6 / unknowns)"),
            std::string::npos)
      << r.failure;
  EXPECT_NE(r.failure.find("too stiff for an explicit method, try an implicit one"), std::string::npos)
      << r.failure;
}

// --linear-solver dense is refused above kMaxDenseUnknowns first-order
// unknowns, --dq-jacobian where auto picks the reduced solver (above 100
// unknowns).
TEST(SundialsOptions, DenseSizeCapAndDifferenceQuotientsWithAuto) {
  const auto bdf = make_integrator("cvode-bdf");
  IntegratorOptions o;
  o.linear_solver = "dense";
  EXPECT_EQ(bdf->check_options(o, kMaxDenseUnknowns / 2), "");
  EXPECT_EQ(bdf->check_options(o, kMaxDenseUnknowns / 2 + 1),
            "--linear-solver dense: a 1002 x 1002 Newton matrix, over the cap of 1000 unknowns "
            "for a dense one (each factorization would take seconds): use --linear-solver "
            "reduced, klu or gmres");
  o.linear_solver = "auto";
  o.dq_jacobian = true;
  EXPECT_EQ(bdf->check_options(o, 50), "");  // 100 unknowns: dense
  EXPECT_EQ(bdf->check_options(o, 51),
            "--dq-jacobian: SUNDIALS forms difference-quotient Jacobians only as dense matrices "
            "(--linear-solver auto picks reduced above 100 unknowns; this system has 102): add "
            "--linear-solver dense or gmres");
  o.linear_solver = "gmres";
  EXPECT_EQ(bdf->check_options(o, 5000), "");
  // Methods without a Newton matrix neither use nor refuse these.
  for (const char* name : {"cvode-adams", "arkode-erk"}) {
    o.linear_solver = "dense";
    EXPECT_EQ(make_integrator(name)->check_options(o, 5000), "") << name;
    const std::vector<std::string> read = make_integrator(name)->options_read();
    EXPECT_EQ(std::count(read.begin(), read.end(), "linear-solver"), 0) << name;
  }
}

// A stop request (Ctrl-C in a sweep) reaches a solver deep inside one long
// output interval: simulate throws StopRequested within a fraction of a
// second, through the right-hand side (ODE packages) or residual (IDA).
TEST(SundialsStop, StopRequestEndsALongIntervalAtOnce) {
  // w = 1000 rad/s for 10^4 s: ~10^6 periods to resolve.
  const Model model(make_builtin_scene("oscillator", {{"k", "1e6"}}));
  for (const char* name : {"arkode-erk", "ida"}) {
    SCOPED_TRACE(name);
    std::atomic<bool> stop{false};
    RunSettings s = adaptive(name, 1e-8, 1e4, 1e4);
    s.options.max_steps = 1'000'000'000;  // minutes of work in one interval
    s.options.stop = &stop;
    std::thread requester([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      stop.store(true);
    });
    const auto start = std::chrono::steady_clock::now();
    EXPECT_THROW(simulate(model, s), StopRequested);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    requester.join();
    EXPECT_LT(seconds, 2.0);
  }
}

// A solver that gives up inside an output interval failed where it stopped,
// not at the interval's end: with a 1 s output interval and 50 internal
// steps allowed, CVODE's Adams method on a 1000 rad/s oscillator gets to
// t ~ 1e-3, and that is the failure time the result (and every table) gives.
TEST(SundialsFailure, FailureTimeIsWhereTheSolverStopped) {
  const Model model(make_builtin_scene("oscillator", {{"k", "1e6"}}));
  for (const char* name : {"cvode-adams", "arkode-erk", "cvode-bdf"}) {
    SCOPED_TRACE(name);
    RunSettings s = adaptive(name, 1e-8, 1.0, 2.0);
    s.options.max_steps = 50;
    const RunResult r = simulate(model, s);
    ASSERT_EQ(r.status, RunStatus::kFailed);
    ASSERT_TRUE(r.diverged_at.has_value());
    EXPECT_GT(*r.diverged_at, 0.0);
    EXPECT_LT(*r.diverged_at, 0.5);
    // The message's "failed at t = ..." is the same time.
    const auto at = r.failure.find("failed at t = ");
    ASSERT_NE(at, std::string::npos) << r.failure;
    EXPECT_NEAR(std::stod(r.failure.substr(at + 14)), *r.diverged_at, 1e-5 * *r.diverged_at);
  }
}

SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(AdaptiveIntegrator, is_adaptive);
SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(AdaptiveImplicitIntegrator, is_adaptive_implicit);

// Two different solvers on two different formulations (CVODE on y' = f(y),
// IDA on the residual form) and a tiny-step RK4 agree on the chain.
TEST(Sundials, IdaCvodeBdfAndRk4AgreeOnTheChain) {
  const Scene chain = make_builtin_scene("chain", {{"n", "8"}, {"horizontal", "1"}});
  const Model model(chain);
  const Vector reference = reference_positions(chain, 0.5, 1e-5);
  for (const char* name : {"cvode-bdf", "ida"}) {
    const RunResult r = simulate(model, adaptive(name, 1e-10, 0.05, 0.5));
    ASSERT_EQ(r.status, RunStatus::kCompleted) << name << ": " << r.failure;
    EXPECT_LT((r.x_final - reference).lpNorm<Eigen::Infinity>(), 1e-6) << name;
  }
}

}  // namespace
}  // namespace springlab::test_sundials
