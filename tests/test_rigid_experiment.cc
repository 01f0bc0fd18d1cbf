// The rigid experiment (experiments/kinds/rigid_experiment.cc) and its reference,
// the torque-free rigid body (experiments/analysis/rigid_reference.h), against closed
// forms: the axisymmetric body's body-frame precession at
// Omega = (I_3 - I_1) / I_1 w_3 and its world motion
// R(t) = exp(t [L / I_1]) R_0 exp(-t Omega [e_3]); the asymmetric body's
// flip interval 2 K(k) / lambda (Jacobi's sn solution of Euler's
// equations); energy and |L| conserved to 1e-10. Then the experiment's
// rows: the flip period of the affine box under rk4 at a small step within
// 5 % of the reference's, the error against kappa falling as kappa grows,
// and the explicit step limit beside 2 / w_kappa.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>

#include "experiment_tasks.h"
#include "experiments/analysis/rigid_reference.h"

namespace springlab::test_rigid_experiment {
namespace {

using Json = nlohmann::json;
using testing::parse_definition;
using testing::task_rows;

Eigen::Matrix3d rotation_about(const Eigen::Vector3d& axis_times_angle) {
  const double angle = axis_times_angle.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, axis_times_angle / angle).toRotationMatrix();
}

TEST(RigidReference, AxisymmetricBodyPrecessesAtTheClosedFormRate) {
  const Eigen::Vector3d I(0.3, 0.3, 0.5);
  const Eigen::Vector3d w0(1.2, -0.7, 4.0);
  const Eigen::Matrix3d R0 = rotation_about(Eigen::Vector3d(0.3, -0.5, 0.8));
  RigidReference ref(I, w0, R0, 1e-3, 0);
  const double Omega = (I[2] - I[0]) / I[0] * w0[2];
  const Eigen::Vector3d L = R0 * I.cwiseProduct(w0);
  for (double t : {0.5, 3.0, 10.0}) {
    ref.advance_to(t);
    // Body frame: w_3 constant, (w_1, w_2) turned by Omega t.
    const Eigen::Vector3d w = ref.omega();
    const double c = std::cos(Omega * t), s = std::sin(Omega * t);
    EXPECT_NEAR(w[0], c * w0[0] - s * w0[1], 1e-10) << t;
    EXPECT_NEAR(w[1], s * w0[0] + c * w0[1], 1e-10) << t;
    EXPECT_NEAR(w[2], w0[2], 1e-10) << t;
    // World frame: R' = [L / I_1] R - Omega R [e_3].
    const Eigen::Matrix3d R = rotation_about(t * L / I[0]) * R0 *
                              rotation_about(Eigen::Vector3d(0.0, 0.0, -Omega * t));
    EXPECT_LT((ref.rotation() - R).norm(), 1e-10) << t;
  }
}

// The tumbling box's moments (0.3 x 0.2 x 0.1 m, 1000 kg/m^3) spun as the
// built-in scene spins it: the reversals of w_2 come every 2 K(k) / lambda
// (w_2 ~ sn(lambda t, k); L^2 > 2 E I_2 here), and E, |L| stay put.
TEST(RigidReference, FlipIntervalIsJacobisAndFirstIntegralsAreKept) {
  const double m = 6.0;
  const Eigen::Vector3d J(m * 0.09 / 12.0, m * 0.04 / 12.0, m * 0.01 / 12.0);
  const Eigen::Vector3d I = Eigen::Vector3d::Constant(J.sum()) - J;
  const Eigen::Vector3d w0 = 2.0 * std::numbers::pi * Eigen::Vector3d(0.01, 1.0, 0.01);
  ASSERT_EQ(middle_axis(I), 1);
  RigidReference ref(I, w0, Eigen::Matrix3d::Identity(), 1e-4, 1);
  const double E0 = ref.energy();
  const Eigen::Vector3d L0 = ref.angular_momentum();
  ref.advance_to(11.0);
  EXPECT_LT(std::abs(ref.energy() - E0) / E0, 1e-10);
  EXPECT_LT((ref.angular_momentum() - L0).norm() / L0.norm(), 1e-10);
  const double L2 = I.cwiseProduct(w0).squaredNorm(), E2 = 2.0 * E0;
  ASSERT_GT(L2, E2 * I[1]);
  const double lambda = std::sqrt((I[2] - I[1]) * (L2 - E2 * I[0]) / I.prod());
  const double k2 = (I[1] - I[0]) * (E2 * I[2] - L2) / ((I[2] - I[1]) * (L2 - E2 * I[0]));
  const double interval = 2.0 * std::comp_ellint_1(std::sqrt(k2)) / lambda;
  ASSERT_EQ(ref.reversals().size(), 3u);
  for (double dt : reversal_intervals(ref.reversals())) {
    EXPECT_LT(std::abs(dt - interval) / interval, 1e-6) << dt << " vs " << interval;
  }
  RecordProperty("flip_interval_seconds", std::to_string(interval));
}

Json small_definition() {
  return {{"experiment", "rigid"}, {"name", "rigid"}, {"scene", "tumbling-box"},
          {"integrators", {"rk4"}}, {"dt", 5e-4}, {"t_end", 7.0}, {"every", 100},
          {"reference_step", 1e-4}, {"kappa", {1e4, 1e6}}, {"kappa_dt", 2e-4},
          {"kappa_t_end", 7.0}, {"limit_integrators", {"verlet"}}};
}

TEST(RigidExperiment, Rk4FlipsWithTheReferencesPeriod) {
  const LoadedExperiment e = parse_definition(small_definition());
  ASSERT_EQ(e.experiment->task_count(), 1u + 2u + 2u);
  const auto tables = task_rows(e, 0);
  ASSERT_EQ(tables[1].size(), 1u);
  const auto& run = tables[1][0];
  EXPECT_EQ(run.at("status"), "completed");
  EXPECT_EQ(run.at("reversals"), "2");
  const double period = std::stod(run.at("flip_period"));
  const double reference = std::stod(run.at("reference_flip_period"));
  EXPECT_LT(std::abs(period - reference) / reference, 0.05) << period << " vs " << reference;
  EXPECT_NEAR(std::stod(run.at("period_error")), (period - reference) / reference, 1e-9);
  EXPECT_NEAR(reference, 4.0665, 1e-3);
  EXPECT_LT(std::stod(run.at("momentum_drift_max")), 1e-6);
  // Rows every 100 steps and at t_end; the axis starts along L.
  EXPECT_EQ(tables[0].size(), 14000u / 100u + 1u);
  EXPECT_NEAR(std::stod(tables[0][0].at("axis")), 1.0, 1e-3);
  EXPECT_EQ(tables[0].back().at("t"), "7");
  RecordProperty("rk4_period_error", run.at("period_error"));
}

TEST(RigidExperiment, ErrorFallsAsKappaGrowsAndTheStepLimitFollowsTheRigidityMode) {
  const LoadedExperiment e = parse_definition(small_definition());
  double previous = 0.0;
  for (std::size_t k = 0; k < 2; ++k) {
    const auto rows = task_rows(e, 1 + k)[2];
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0].at("status"), "completed");
    const double error = std::stod(rows[0].at("orientation_error_max"));
    if (k > 0) {
      EXPECT_LT(error, 0.1 * previous);  // kappa 100 x larger
    }
    previous = error;
  }
  const auto limit = task_rows(e, 4)[3];  // kappa 1e6, verlet
  ASSERT_EQ(limit.size(), 1u);
  EXPECT_EQ(limit[0].at("outcome"), "bracketed");
  const double w_formula = std::stod(limit[0].at("w_formula"));
  EXPECT_LT(std::abs(std::stod(limit[0].at("w_max")) - w_formula) / w_formula, 1e-8);
  const double measured = std::stod(limit[0].at("dt_max_stable"));
  EXPECT_GT(measured, 0.95 * 2.0 / w_formula);
  EXPECT_LT(measured, 1.3 * 2.0 / w_formula);
}

// The pile part (issue 49): box-pile with two boxes under implicit Euler at
// 1/60 s and BDF2 at 5 ms for 1 s. Each case is one task after the rigid
// ones; its rows sample the top box's height and the energy every 0.05 s
// (and at t_end), its summary says the run completed with the bodies apart
// (smallest gap > 0, within the barrier's 1 mm) and the top box resting on
// the bottom one (its centre between 0.13 and 0.15 m: 0.1 + 0.04, the two
// heights, plus the gaps).
TEST(RigidExperiment, ThePileRowsFollowTheTopBoxAndItsGaps) {
  Json d = small_definition();
  d["pile"] = {{"scene", "box-pile"}, {"parameters", {{"n", 2}}}, {"t_end", 1.0},
               {"sample", 0.05},
               {"cases", {{{"integrator", "implicit-euler"}, {"dt", 1.0 / 60.0}},
                          {{"integrator", "bdf2"}, {"dt", 5e-3}}}}};
  const LoadedExperiment e = parse_definition(d);
  ASSERT_EQ(e.experiment->task_count(), 1u + 2u + 2u + 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto tables = task_rows(e, 5 + k);
    ASSERT_EQ(tables[5].size(), 1u);
    const auto& run = tables[5][0];
    EXPECT_EQ(run.at("status"), "completed") << run.at("failure");
    const double gap = std::stod(run.at("smallest_gap"));
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap, 1e-3);
    const double top = std::stod(run.at("top_height_final"));
    EXPECT_GT(top, 0.13);
    EXPECT_LT(top, 0.15);
    EXPECT_GE(tables[4].size(), 10u);
    EXPECT_LE(tables[4].size(), 22u);
    EXPECT_EQ(tables[4].back().at("t"), "1");
    EXPECT_NEAR(std::stod(tables[4].back().at("top_height")), top, 1e-12);
  }
}

}  // namespace
}  // namespace springlab::test_rigid_experiment
