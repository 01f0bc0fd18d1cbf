// Rigid bodies as affine bodies (docs/physics.md "Rigid bodies (affine
// bodies)"), against closed forms: polyhedral mass properties of a box and
// a cylinder mesh, the principal frame of a rotated box, the rigidity's
// force and Jacobians against central differences at strained states, free
// fall, the torque-free axisymmetric body's precession, angular momentum
// conservation, symplectic Euler's bounded energy, the Dzhanibekov flip,
// the box on a slope (stick and slide), the bodies' JSON momenta, the
// refusals of bad bodies, and every integrator running or refusing them.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "experiments/io/body_output.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/bodies/bodies.h"
#include "models/scenes/builtin_scenes.h"
#include "models/contact/contact.h"
#include "models/model/model.h"
#include "models/springs/gravity.h"
#include "models/bodies/mass_properties.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"
#include "registry_suite.h"
#include "run_process.h"
#include "models/model/scene_file.h"

namespace springlab::test_rigid_bodies {
namespace {

double relative(double a, double b) { return std::abs(a - b) / std::abs(b); }

// ---- Mass properties. ----

// A box a x b x c of density rho: V = abc, m = rho V, J_i = m s_i^2 / 12;
// far from the origin, so the centre's cancellation would show.
TEST(MassProperties, BoxMatchesTheClosedForm) {
  const Eigen::Vector3d size(0.3, 0.2, 0.1), offset(5.0, -3.0, 2.0);
  const double rho = 700.0;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<SurfaceTriangle> triangles;
  box_surface(size, vertices, triangles);
  for (Eigen::Vector3d& v : vertices) v += offset;
  const MassProperties mp = mass_properties(vertices, triangles, rho);
  const double V = size.prod(), m = rho * V;
  EXPECT_LT(relative(mp.volume, V), 1e-12);
  EXPECT_LT(relative(mp.mass, m), 1e-12);
  EXPECT_LT((mp.centre - offset).norm() / offset.norm(), 1e-12);
  EXPECT_LT((mp.frame - Eigen::Matrix3d::Identity()).norm(), 1e-12);  // axis-aligned: R = I
  for (int i = 0; i < 3; ++i) EXPECT_LT(relative(mp.J[i], m * size[i] * size[i] / 12.0), 1e-12);
}

// The cylinder mesh is a prism over the regular N-gon of circumradius r:
// area A = N r^2 sin(t) / 2 (t = 2 pi / N), polar second moment of the
// N-gon N r^4 sin(t) (2 + cos t) / 12, isotropic in the plane; so
// J_x = J_y = rho h N r^4 sin(t) (2 + cos t) / 24 and J_z = m h^2 / 12.
// They tend to the cylinder's m r^2 / 4 as N grows (checked at N = 4096).
TEST(MassProperties, CylinderMeshMatchesThePrismsClosedForm) {
  const double r = 0.1, h = 0.4, rho = 1000.0;
  for (int N : {3, 7, 32, 4096}) {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<SurfaceTriangle> triangles;
    cylinder_surface(r, h, N, vertices, triangles);
    const MassProperties mp = mass_properties(vertices, triangles, rho);
    const double t = 2.0 * std::numbers::pi / N;
    const double V = 0.5 * N * r * r * std::sin(t) * h, m = rho * V;
    const double J_plane = rho * h * N * std::pow(r, 4) * std::sin(t) * (2.0 + std::cos(t)) / 24.0;
    EXPECT_LT(relative(mp.volume, V), 1e-12) << N;
    EXPECT_LT(mp.centre.norm(), 1e-12 * r) << N;
    EXPECT_LT(relative(mp.J[0], J_plane), 1e-12) << N;
    EXPECT_LT(relative(mp.J[1], J_plane), 1e-12) << N;
    EXPECT_LT(relative(mp.J[2], m * h * h / 12.0), 1e-12) << N;
    if (N == 4096) {
      const double cylinder = rho * std::numbers::pi * r * r * h;
      EXPECT_LT(relative(mp.mass, cylinder), 1e-5);
      EXPECT_LT(relative(mp.J[0], cylinder * r * r / 4.0), 1e-5);
    }
  }
}

// A box turned by Q and moved: its principal axes are Q's columns (up to
// sign and order) and the J are the unturned box's.
TEST(MassProperties, PrincipalFrameOfARotatedBoxIsRecovered) {
  const Eigen::Vector3d size(0.5, 0.3, 0.2);
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(0.83, Eigen::Vector3d(0.3, -0.8, 0.5).normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3d> vertices;
  std::vector<SurfaceTriangle> triangles;
  box_surface(size, vertices, triangles);
  for (Eigen::Vector3d& v : vertices) v = Q * v + Eigen::Vector3d(1.0, 2.0, -0.5);
  const MassProperties mp = mass_properties(vertices, triangles, 1000.0);
  EXPECT_NEAR(mp.frame.determinant(), 1.0, 1e-12);
  const double m = 1000.0 * size.prod();
  const Eigen::Matrix3d P = mp.frame.transpose() * Q;  // a signed permutation
  for (int i = 0; i < 3; ++i) {
    int k = 0;
    P.row(i).cwiseAbs().maxCoeff(&k);
    EXPECT_NEAR(std::abs(P(i, k)), 1.0, 1e-12);
    EXPECT_LT(relative(mp.J[i], m * size[k] * size[k] / 12.0), 1e-12);
  }
  EXPECT_LT((mp.centre - Eigen::Vector3d(1.0, 2.0, -0.5)).norm(), 1e-12);
}

// ---- The rigidity: force and Jacobians against central differences at
// strained states (the shared kind tests check them at the random instance).

Scene one_body(const Body& b, double g = 0.0) {
  Scene s;
  s.name = "body";
  s.dimension = 3;
  s.block<Springs>();
  s.block<Gravity>().acceleration = {0.0, -g, 0.0};
  s.block<Bodies>().push_back(b);
  return s;
}

Body box(const Eigen::Vector3d& size, double rigidity = 1e6) {
  Body b;
  b.shape = Body::Shape::kBox;
  b.size = size;
  b.rigidity = rigidity;
  b.position = Eigen::Vector3d::Zero();
  return b;
}

TEST(Rigidity, ForceAndJacobiansMatchCentralDifferences) {
  const Model model(one_body(box({0.3, 0.2, 0.1}, 50.0)));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Vector x = model.initial_positions();
    const Vector v = model.initial_velocities();
    for (Eigen::Index k = 3; k < 12; ++k) x[k] += 0.4 * u(rng);  // A far from a rotation
    Vector f;
    model.force(0.0, x, v, f);
    SparseMatrix dfdx, dfdv, definite, unused;
    model.jacobians(0.0, x, v, &dfdx, &dfdv);
    model.definite_jacobians(0.0, x, v, &definite, &unused);
    const Eigen::MatrixXd K(dfdx);
    const double eps = 1e-6;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector xp = x, xm = x, fp, fm;
      xp[k] += eps;
      xm[k] -= eps;
      const double dV = (model.position_potential(0.0, xp) - model.position_potential(0.0, xm)) / (2 * eps);
      EXPECT_NEAR(f[k], -dV, 1e-7 * (1.0 + std::abs(f[k]))) << "trial " << trial << ", " << k;
      model.force(0.0, xp, v, fp);
      model.force(0.0, xm, v, fm);
      const Vector column = (fp - fm) / (2 * eps);
      EXPECT_LT((K.col(k) - column).norm(), 1e-7 * (1.0 + column.norm())) << "trial " << trial;
    }
    EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
    // The definite part: -K+ semidefinite.
    const Eigen::MatrixXd Kd = -Eigen::MatrixXd(definite);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Kd).eigenvalues()[0], -1e-10 * Kd.norm());
  }
}

// Two states of one body far apart, for the discrete-gradient tests: x
// its rest state with A strained by up to 0.4, y that turned by up to 1 rad
// about a random axis and strained by up to 0.1 more.
void two_far_states(const Model& model, std::mt19937& rng,
                    std::uniform_real_distribution<double>& u, Vector& x, Vector& y) {
  x = model.initial_positions();
  for (Eigen::Index k = 3; k < 12; ++k) x[k] += 0.4 * u(rng);
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
          .toRotationMatrix();
  y = x;
  for (int i = 0; i < 4; ++i) y.segment<3>(3 * i) = Q * x.segment<3>(3 * i);
  for (Eigen::Index k = 3; k < 12; ++k) y[k] += 0.1 * u(rng);
}

// The rigidity's own discrete gradient g(x, y) = 4 kappa V A_m G_avg
// (bodies.cc), seen through the model as the discrete-gradient method sees
// it: F(x_m) + d, d = add_own_discrete_gradient_difference, is -g. Between
// two states far apart (A strained by up to 0.4 and turned by up to 1 rad)
// it is exact, -(F(x_m) + d) . (y - x) = V(y) - V(x) to round-off (1e-12
// relative), which the midpoint force alone misses by more than 1e-4
// (the least of the five trials: 5.0e-4); it exerts no torque, sum over
// the pseudo-particles of q_m x (F(x_m) + d) = 0 (1e-12 of sum |q_m| |F|),
// which Gonzalez's generic correction c D does (more than 1e-4 of it; the
// least: 7.7e-4); and at y = x it is the gradient (d = 0).
TEST(Rigidity, OwnDiscreteGradientIsExactAndTorqueFree) {
  const Model model(one_body(box({0.3, 0.2, 0.1}, 50.0)));
  ASSERT_TRUE(model.has_own_discrete_gradients());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vector v = model.initial_velocities();
  auto torque = [](const Vector& q, const Vector& f, double& scale) {
    Eigen::Vector3d tau = Eigen::Vector3d::Zero();
    scale = 0.0;
    for (Eigen::Index k = 0; k < q.size() / 3; ++k) {
      tau += q.segment<3>(3 * k).cross(f.segment<3>(3 * k));
      scale += q.segment<3>(3 * k).norm() * f.segment<3>(3 * k).norm();
    }
    return tau;
  };
  for (int trial = 0; trial < 5; ++trial) {
    Vector x, y;
    two_far_states(model, rng, u, x, y);
    const Vector xm = 0.5 * (x + y), D = y - x;
    Vector f, d = Vector::Zero(x.size());
    model.force(0.0, xm, v, f);
    model.add_own_discrete_gradient_difference(0.0, x, xm, y, d);
    const Vector g = -(f + d);
    const double dV = model.position_potential(0.0, y) - model.position_potential(0.0, x);
    const double scale = std::abs(model.position_potential(0.0, y)) +
                         std::abs(model.position_potential(0.0, x));
    EXPECT_LT(std::abs(g.dot(D) - dV), 1e-12 * scale) << "trial " << trial;
    EXPECT_GT(std::abs(-f.dot(D) - dV), 1e-4 * scale) << "trial " << trial;
    double s = 0.0;
    const double own_torque = torque(xm, f + d, s).norm();
    EXPECT_LT(own_torque, 1e-12 * s) << "trial " << trial;
    // Gonzalez's generic discrete gradient of the same energy.
    const Vector generic = -f + (dV + f.dot(D)) / D.squaredNorm() * D;
    const double generic_torque = torque(xm, -generic, s).norm();
    EXPECT_GT(generic_torque, 1e-4 * s) << "trial " << trial;
    Vector same = Vector::Zero(x.size());
    model.add_own_discrete_gradient_difference(0.0, x, x, x, same);
    Vector fx;
    model.force(0.0, x, v, fx);
    EXPECT_LT(same.norm(), 1e-13 * fx.norm()) << "trial " << trial;
  }
}

// The own discrete gradient's Jacobian for Newton's matrix (bodies.cc
// add_discrete_gradient_jacobian, through the model's
// add_own_discrete_gradient_jacobian_difference): with dF/dx at the
// midpoint, the difference turns the rigidity's part into -2 dg/dy, which
// must match central differences of -g(x, 2 m - x) in m (1e-7 relative);
// it is not symmetric (its skew part above 1e-2 of it here; the least of
// the five trials: 1.9e-2). The difference itself is the closed form
// -4 kappa V [dA D^T D / 4 + A_m (dA^T D + D^T dA) / 2] on random
// directions (1e-10 relative); it vanishes at y = x; the definite variant
// is symmetric and negative semidefinite.
TEST(Rigidity, OwnDiscreteGradientJacobianMatchesCentralDifferences) {
  const Body body = box({0.3, 0.2, 0.1}, 50.0);
  const Model model(one_body(body));
  const double kappa_v = body.rigidity * rigid_body(body).mass.volume;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vector v = model.initial_velocities();
  auto affine = [](const Vector& q) {
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i) A.col(i) = q.segment<3>(3 + 3 * i);
    return A;
  };
  for (int trial = 0; trial < 5; ++trial) {
    Vector x, y;
    two_far_states(model, rng, u, x, y);
    const Vector xm = 0.5 * (x + y);
    // -g(x, 2 m - x) as the model gives it.
    auto minus_g = [&](const Vector& m) {
      Vector f, d = Vector::Zero(x.size());
      model.force(0.0, m, v, f);
      model.add_own_discrete_gradient_difference(0.0, x, m, 2.0 * m - x, d);
      return Vector(f + d);
    };
    SparseMatrix dfdx, dfdv, replaced, unused;
    model.jacobians(0.0, xm, v, &dfdx, &dfdv);
    replaced = dfdx;
    model.add_own_discrete_gradient_jacobian_difference(0.0, x, xm, y, false, 1.0, replaced);
    const Eigen::MatrixXd K(replaced), K_mid(dfdx);
    Eigen::MatrixXd fd(x.size(), x.size());
    const double eps = 1e-6;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector mp = xm, mm = xm;
      mp[k] += eps;
      mm[k] -= eps;
      fd.col(k) = (minus_g(mp) - minus_g(mm)) / (2 * eps);
    }
    EXPECT_LT((K - fd).norm(), 1e-7 * fd.norm()) << "trial " << trial;
    const double skew = 0.5 * (K - K.transpose()).norm() / K.norm();
    EXPECT_GT(skew, 1e-2) << "trial " << trial;
    RecordProperty("skew_" + std::to_string(trial), std::to_string(skew));
    // The difference against the midpoint Hessian in closed form.
    const Eigen::Matrix3d Am = 0.5 * (affine(x) + affine(y)), D = affine(y) - affine(x);
    const Eigen::MatrixXd diff = K - K_mid;
    for (int probe = 0; probe < 3; ++probe) {
      Vector a = Vector::Zero(x.size());
      for (Eigen::Index k = 3; k < 12; ++k) a[k] = u(rng);
      auto closed = [&](const Vector& q) {  // -4 kappa V [...] applied to dA = q's columns
        const Eigen::Matrix3d dA = affine(q);
        const Eigen::Matrix3d M =
            -4.0 * kappa_v *
            (dA * D.transpose() * D / 4.0 + Am * (dA.transpose() * D + D.transpose() * dA) / 2.0);
        Vector out = Vector::Zero(q.size());
        for (int i = 0; i < 3; ++i) out.segment<3>(3 + 3 * i) = M.col(i);
        return out;
      };
      EXPECT_LT((diff * a - closed(a)).norm(), 1e-10 * closed(a).norm()) << "trial " << trial;
    }
    // At y = x the difference vanishes.
    SparseMatrix at_x, unused_x;
    model.jacobians(0.0, x, v, &at_x, &unused_x);
    const Eigen::MatrixXd K_x(at_x);
    model.add_own_discrete_gradient_jacobian_difference(0.0, x, x, x, false, 1.0, at_x);
    EXPECT_LT((Eigen::MatrixXd(at_x) - K_x).norm(), 1e-14 * K_x.norm()) << "trial " << trial;
    // The definite variant: -K semidefinite.
    SparseMatrix definite;
    model.definite_jacobians(0.0, xm, v, &definite, &unused);
    model.add_own_discrete_gradient_jacobian_difference(0.0, x, xm, y, true, 1.0, definite);
    const Eigen::MatrixXd Kd = -Eigen::MatrixXd(definite);
    EXPECT_LT((Kd - Kd.transpose()).norm(), 1e-12 * Kd.norm()) << "trial " << trial;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Kd).eigenvalues()[0],
              -1e-10 * Kd.norm())
        << "trial " << trial;
  }
}

// ---- Dynamics. ----

// A rigid body's angular velocity in the body frame, from A^T dA/dt = [w_b]x.
Eigen::Vector3d body_rate(const Vector& x, const Vector& v) {
  Eigen::Matrix3d A, dA;
  for (int i = 0; i < 3; ++i) {
    A.col(i) = x.segment<3>(3 + 3 * i);
    dA.col(i) = v.segment<3>(3 + 3 * i);
  }
  const Eigen::Matrix3d W = A.transpose() * dA;
  return 0.5 * Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
}

class Recorder final : public Observer {
 public:
  void observe(double t, const Vector& x, const Vector& v) override {
    times.push_back(t);
    xs.push_back(x);
    vs.push_back(v);
  }
  std::vector<double> times;
  std::vector<Vector> xs, vs;
};

RunResult run(const Scene& scene, const std::string& integrator, double dt, double t_end,
              Recorder* recorder = nullptr, double newton_tol = 1e-12) {
  const Model model(scene);
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  s.options.newton_tol = newton_tol;
  std::vector<Observer*> observers;
  if (recorder != nullptr) observers.push_back(recorder);
  return simulate(model, s, observers);
}

// Gravity alone: p(t) = p0 + v0 t + g t^2 / 2 and A(t) = A0, exactly for
// methods exact on constant acceleration.
TEST(RigidBodies, FreeFallIsExactAndKeepsA) {
  // kappa 1e3 Pa: rk4 and Verlet stay below their step limit on the
  // rigidity mode (w ~ 100 rad/s, w h ~ 1).
  Body b = box({0.3, 0.2, 0.1}, 1e3);
  b.position = Eigen::Vector3d(1.0, 2.0, 3.0);
  b.v = Eigen::Vector3d(0.5, 1.0, -0.2);
  b.orientation = {0.3, -0.2, 0.5};
  const Scene scene = one_body(b, 9.81);
  const Model model(scene);
  const double T = 1.0;
  for (const char* method : {"rk4", "verlet", "implicit-midpoint"}) {
    const RunResult r = run(scene, method, 0.01, T);
    ASSERT_EQ(r.status, RunStatus::kCompleted) << method << ": " << r.failure;
    const Eigen::Vector3d p = *b.position + b.v * T + 0.5 * Eigen::Vector3d(0, -9.81, 0) * T * T;
    EXPECT_LT((r.x_final.head<3>() - p).norm(), 1e-11) << method;
    EXPECT_LT((r.x_final.segment<9>(3) - model.initial_positions().segment<9>(3)).norm(), 1e-12)
        << method;
  }
}

// Torque-free axisymmetric body (a cylinder, symmetry axis z, I_1 = I_2):
// in the body frame the angular velocity precesses about the axis at
// Omega = (I_3 - I_1) / I_1 w_3 (Euler's equations; e.g. Goldstein,
// Classical Mechanics, sec. 5.6). Measured over about one period, within 1 %.
TEST(RigidBodies, AxisymmetricBodyPrecessesAtTheClosedFormRate) {
  Body b;
  b.shape = Body::Shape::kCylinder;
  b.radius = 0.1;
  b.height = 0.1;
  b.rigidity = 1e6;
  b.position = Eigen::Vector3d::Zero();
  const double w3 = 10.0, w_perp = 1.0;
  b.omega = Eigen::Vector3d(w_perp, 0.0, w3);  // R = I: world = body frame at t = 0
  const Scene scene = one_body(b);
  const RigidBody rb = rigid_body(b);
  ASSERT_LT((rb.mass.frame - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  const Eigen::Vector3d& J = rb.mass.J;
  const double I1 = J[1] + J[2], I3 = J[0] + J[1];
  const double omega = (I3 - I1) / I1 * w3;
  for (auto [method, dt] : {std::pair{"implicit-midpoint", 1e-3}, std::pair{"rk4", 2e-4}}) {
    Recorder rec;
    const double T = 2.0 * std::numbers::pi / std::abs(omega);
    const RunResult r = run(scene, method, dt, T, &rec);
    ASSERT_EQ(r.status, RunStatus::kCompleted) << method << ": " << r.failure;
    double angle = 0.0, previous = 0.0;
    for (std::size_t k = 0; k < rec.times.size(); ++k) {
      const Eigen::Vector3d w = body_rate(rec.xs[k], rec.vs[k]);
      const double a = std::atan2(w.y(), w.x());
      if (k > 0) {
        double d = a - previous;
        while (d > std::numbers::pi) d -= 2 * std::numbers::pi;
        while (d < -std::numbers::pi) d += 2 * std::numbers::pi;
        angle += d;
      }
      previous = a;
    }
    const double rate = angle / rec.times.back();
    EXPECT_LT(relative(std::abs(rate), std::abs(omega)), 0.01)
        << method << ": measured " << rate << " rad/s, closed form " << omega;
  }
}

// The tumbling box's angular momentum L = m p x dp/dt + sum J_i a_i x da_i/dt
// (bodies.h) is a quadratic first integral, which the implicit midpoint rule
// conserves exactly (up to its Newton tolerance and round-off): 1e-10 over
// 10^3 steps. So does the discrete gradient, with the rigidity's own
// discrete gradient 4 kappa V A_m G_avg (bodies.cc: A_m times a symmetric
// matrix, no torque); with Gonzalez's generic one its correction c D
// exerted the torque h sum_k x_mid,k x c D_k and L drifted by 7.2e-6
// relative over the same steps. The discrete gradient also keeps the
// energy to its Newton tolerance (1e-10 relative).
Eigen::Vector3d momentum(const Model& model, const Vector& x, const Vector& v) {
  const BodyLayout layout = body_layout(model.scene(), model.particle_order());
  return body_state(layout.bodies[0], layout.first[0], x.data(), v.data()).angular_momentum;
}

TEST(RigidBodies, ImplicitMidpointAndDiscreteGradientConserveAngularMomentum) {
  const Scene scene = make_builtin_scene("tumbling-box");
  const Model model(scene);
  const Eigen::Vector3d L0 = momentum(model, model.initial_positions(), model.initial_velocities());
  const double E0 = model.energies(model.initial_positions(), model.initial_velocities()).total();
  for (const std::string method : {"implicit-midpoint", "discrete-gradient"}) {
    const RunResult r = run(scene, method, 1e-3, 1.0, nullptr, 1e-14);
    ASSERT_EQ(r.status, RunStatus::kCompleted) << method << ": " << r.failure;
    ASSERT_EQ(r.stats.steps, 1000) << method;
    const Eigen::Vector3d L = momentum(model, r.x_final, r.v_final);
    EXPECT_LT((L - L0).norm() / L0.norm(), 1e-10) << method;
    std::ostringstream drift;
    drift << (L - L0).norm() / L0.norm();
    RecordProperty(method + "_L_drift", drift.str());
    RecordProperty(method + "_newton_per_step",
                   std::to_string(static_cast<double>(r.stats.newton_iterations) /
                                  static_cast<double>(r.stats.steps)));
    if (method == "discrete-gradient") {
      EXPECT_LT(std::abs(model.energies(r.x_final, r.v_final).total() - E0) / E0, 1e-10);
    }
  }
}

// Symplectic Euler, stable below w h = 2 for the rigidity's fastest mode,
// keeps the energy within a bounded band (no drift) over 10^4 steps.
TEST(RigidBodies, SymplecticEulerEnergyStaysBounded) {
  const Scene scene = make_builtin_scene("tumbling-box");
  const Model model(scene);
  const double E0 = model.energies(model.initial_positions(), model.initial_velocities()).total();
  Recorder rec;
  const RunResult r = run(scene, "symplectic-euler", 2e-4, 2.0, &rec);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  double worst = 0.0, late = 0.0;
  for (std::size_t k = 0; k < rec.times.size(); ++k) {
    const double e = std::abs(model.energies(rec.xs[k], rec.vs[k]).total() - E0) / E0;
    worst = std::max(worst, e);
    if (rec.times[k] > 1.0) late = std::max(late, e);
  }
  EXPECT_LT(worst, 1e-2);
  EXPECT_LT(late, 1e-2);
}

// Explicit Euler's energy grows: on an undamped mode of frequency w its step
// is the matrix [[1, h], [-w^2 h, 1]], which in the energy norm (w x, v) is
// sqrt(1 + (w h)^2) times a rotation, so the mode's energy grows by exactly
// |1 + i w h|^2 = 1 + (w h)^2 per step (docs/integrators.md). The tumbling
// box (as built in, spinning) starts with a_3, the axis of least J, stretched
// by e = 1e-3: the rigidity's fastest mode, w^2 = 8 kappa V / J_3
// (docs/physics.md "The rigidity's fastest mode"; 3098 rad/s here). At
// w h = 0.1, 200 steps multiply the energy above the spin's kinetic energy
// by (1.01)^200 = 7.32; measured 7.27, within 2 % (the mode's amplitude grows to
// 2.7e-3, whose nonlinearity shifts w by O(e); the spin at w_s h = 2e-4
// adds 200 (w_s h)^2 = 8e-6 of its 0.99 J).
TEST(RigidBodies, ExplicitEulersEnergyGrowsByOnePlusWHSquaredPerStep) {
  Scene scene = make_builtin_scene("tumbling-box");
  Body& box = scene.block<Bodies>()[0];
  const double e = 1e-3;
  box.affine = Eigen::Vector3d(1.0, 1.0, 1.0 + e).asDiagonal();
  const RigidBody rb = rigid_body(box);
  const double w = std::sqrt(8.0 * box.rigidity * rb.mass.volume / rb.mass.J.minCoeff());
  const double h = 0.1 / w;
  const int steps = 200;
  const Model model(scene);
  const Energies start = model.energies(model.initial_positions(), model.initial_velocities());
  const double spin = start.kinetic();
  Recorder rec;
  const RunResult r = run(scene, "explicit-euler", h, steps * h, &rec);
  ASSERT_NE(r.status, RunStatus::kFailed) << r.failure;
  ASSERT_EQ(rec.xs.size(), static_cast<std::size_t>(steps + 1));
  double previous = start.total() - spin;
  for (std::size_t k = 1; k < rec.xs.size(); ++k) {  // strictly growing, step by step
    const double excess = model.energies(rec.xs[k], rec.vs[k]).total() - spin;
    EXPECT_GT(excess, previous) << "step " << k;
    previous = excess;
  }
  const double growth = previous / (start.total() - spin);
  const double theory = std::pow(1.0 + (w * h) * (w * h), steps);
  EXPECT_NEAR(growth / theory, 1.0, 0.02) << "measured " << growth << ", theory " << theory;
  RecordProperty("explicit_euler_growth", std::to_string(growth));
  RecordProperty("explicit_euler_growth_theory", std::to_string(theory));
}

// The Dzhanibekov flip: spun about its middle axis (y), the box turns over:
// its y axis a_2 points against the spin (a_2 . y < -0.9) within 4 s.
TEST(RigidBodies, TumblingBoxFlipsUnderRk4) {
  const Scene scene = make_builtin_scene("tumbling-box");
  Recorder rec;
  const RunResult r = run(scene, "rk4", 5e-4, 4.0, &rec);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  double lowest = 1.0, first_flip = -1.0;
  for (std::size_t k = 0; k < rec.times.size(); ++k) {
    const Eigen::Vector3d a2 = rec.xs[k].segment<3>(6);
    const double c = a2.y() / a2.norm();
    lowest = std::min(lowest, c);
    if (c < -0.9 && first_flip < 0.0) first_flip = rec.times[k];
  }
  EXPECT_LT(lowest, -0.9);
  RecordProperty("first_flip_seconds", std::to_string(first_flip));
}

// ---- The box on a slope (implicit Euler, the penalty and smoothed Coulomb
// friction at the cube's corners). ----

Eigen::Vector3d down_slope(double degrees) {
  const double t = degrees * std::numbers::pi / 180.0;
  return {std::cos(t), -std::sin(t), 0.0};
}

TEST(RigidBodies, BoxOnSlopeSticksBelowTheFrictionAngle) {
  const Scene scene = make_builtin_scene("box-on-slope", {{"angle", "20"}, {"friction", "0.5"}});
  const Model model(scene);
  // Newton to 1e-6 m/s (far below the creep bound): at 1e-8 the line search
  // stalls on round-off of the incremental potential once the box creeps.
  const RunResult r = run(scene, "implicit-euler", 1e-3, 1.0, nullptr, 1e-6);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const double creep = (r.x_final.head<3>() - model.initial_positions().head<3>()).dot(down_slope(20));
  EXPECT_LT(std::abs(creep), 2e-3);
  RecordProperty("creep_m", std::to_string(creep));
}

TEST(RigidBodies, BoxOnSlopeSlidesWithTheCoulombAcceleration) {
  const double theta = 30.0, mu = 0.3, g = 9.81;
  const Scene scene = make_builtin_scene("box-on-slope", {{"angle", "30"}, {"friction", "0.3"}});
  Recorder rec;
  const RunResult r = run(scene, "implicit-euler", 1e-3, 1.0, &rec, 1e-6);
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const Eigen::Vector3d s = down_slope(theta);
  // dv/dt from the speed at t = 0.5 and t = 1 (implicit Euler's velocity is
  // exact for a constant acceleration).
  const std::size_t half = rec.times.size() / 2;
  ASSERT_NEAR(rec.times[half], 0.5, 1e-9);
  const double a = (rec.vs.back().head<3>().dot(s) - rec.vs[half].head<3>().dot(s)) / 0.5;
  const double t = theta * std::numbers::pi / 180.0;
  const double expected = g * (std::sin(t) - mu * std::cos(t));
  EXPECT_LT(relative(a, expected), 0.01) << "measured " << a << ", closed form " << expected;
}

// ---- Output and refusals. ----

// The JSON's angular momentum about the centre is I w for the rigid box at
// t = 0 (principal frame = world axes: I = diag(J_2 + J_3, J_1 + J_3, J_1 + J_2)).
TEST(RigidBodies, JsonMomentaAreTheRigidBodys) {
  const Scene scene = make_builtin_scene("tumbling-box");
  const Model model(scene);
  const auto j = bodies_json(model, model.initial_positions(), model.initial_velocities());
  ASSERT_EQ(j.size(), 1u);
  const RigidBody rb = rigid_body(scene.get<Bodies>()[0]);
  const Eigen::Vector3d& J = rb.mass.J;
  const Eigen::Vector3d I(J[1] + J[2], J[0] + J[2], J[0] + J[1]);
  const Eigen::Vector3d w = scene.get<Bodies>()[0].omega;
  for (int i = 0; i < 3; ++i) {
    const double L = j[0]["angular_momentum_about_centre"][static_cast<std::size_t>(i)].get<double>();
    EXPECT_NEAR(L, I[i] * w[i], 1e-12 * I.cwiseProduct(w).norm()) << i;
  }
}

std::string refusal(const std::string& body_json) {
  const std::string text = R"({"dimension": 3, "particles": [], "springs": [], "bodies": [)" +
                           body_json + "]}";
  try {
    parse_scene(text, "bad.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(RigidBodies, BadBodiesAreRefusedWithOneLine) {
  const std::string tetra = R"("vertices": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], )";
  struct Case {
    std::string body, expected;
  };
  const std::vector<Case> cases = {
      {"{" + tetra + R"("triangles": [[0,2,1],[0,1,3],[0,3,2],[1,2,3]], "density": -1})",
       "bad.json: bodies[0].density: must be > 0 (got -1)"},
      {"{" + tetra + R"("triangles": [[0,2,1],[0,1,3],[0,3,2]]})",
       "bad.json: bodies[0]: a closed surface needs at least 4 triangles (got 3)"},
      {"{" + tetra + R"("triangles": [[0,2,1],[0,1,3],[0,3,2],[0,1,2]]})",
       "bad.json: bodies[0]: edge (0, 1) is used twice in the same direction (triangles[3]): "
       "the surface is not manifold or not consistently oriented"},
      {"{" + tetra + R"("triangles": [[0,1,2],[0,3,1],[0,2,3],[1,3,2]]})",
       "bad.json: bodies[0]: negative volume"},
      {R"({"vertices": [[0,0,0],[1,0,0],[0,1,0],[1,1,0]], "triangles": [[0,2,1],[0,1,3],[0,3,2],[1,2,3]]})",
       "bad.json: bodies[0]: zero volume"},
      {R"({"vertices": [[0,0,0],[1,0,0],[2,0,0],[0,0,1]], "triangles": [[0,2,1],[0,1,3],[1,2,3],[0,3,2]]})",
       "bad.json: bodies[0]: triangles[0]: degenerate (zero area)"},
      {"{" + tetra + R"("triangles": [[0,2,1],[0,1,3],[0,3,2],[1,2,4]]})",
       "bad.json: bodies[0]: triangles[3]: vertex 4 does not exist (body has 4 vertices)"},
      {R"({"shape": "sphere"})", R"(bad.json: bodies[0].shape: unknown shape "sphere")"},
      {R"({"shape": "box", "size": [1, 0, 1]})", "bad.json: bodies[0].size[1]: must be > 0"},
      {R"({"shape": "box", "radius": 1})", "bad.json: bodies[0].radius: belongs to a cylinder"},
      {R"({"shape": "box", "orientation": [0, 0, 0, 0]})",
       "bad.json: bodies[0].orientation: a quaternion must be nonzero"},
      {R"({"shape": "box", "fixed": true})",
       "bad.json: bodies: scene has no free particle and no free body"},
  };
  for (const Case& c : cases) {
    const std::string message = refusal(c.body);
    EXPECT_EQ(message.rfind(c.expected, 0), 0u) << "expected: " << c.expected << "\ngot: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  // A 2-D scene has no bodies.
  try {
    parse_scene(R"({"dimension": 2, "particles": [{"x": [0, 0]}], "springs": [], "bodies": [{"shape": "box"}]})",
                "flat.json");
    ADD_FAILURE() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "flat.json: bodies: rigid bodies need a 3-D scene (dimension 3)");
  }
}

TEST(RigidBodies, CommandLineRefusesABadBodyWithOneLineAndExitOne) {
  testing::TempDir temp("rigid-cli");
  std::filesystem::create_directories(temp.path() / "io");
  {
    std::ofstream f(temp.path() / "open.json");
    f << R"({"dimension": 3, "particles": [], "springs": [], "bodies": [{"vertices": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "triangles": [[0,2,1],[0,1,3],[0,3,2],[1,3,4]]}]})";
  }
  const testing::ProcessResult r = testing::run_springlab(
      {"run", "open.json", "--integrator", "rk4", "--dt", "0.01", "--t-end", "0.1"}, temp.path(),
      temp.path() / "io");
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err,
            "springlab: error: open.json: bodies[0]: triangles[3]: vertex 4 does not exist (body "
            "has 4 vertices)\n");
}

// Written and read back, a scene with bodies is the same scene.
TEST(RigidBodies, BuiltinBodyScenesRoundTrip) {
  for (const char* name : {"tumbling-box", "box-on-slope", "box-pile"}) {
    const Scene s = make_builtin_scene(name);
    const std::string text = scene_to_json(s);
    EXPECT_EQ(scene_to_json(parse_scene(text, "again.json")), text) << name;
  }
}

// ---- Every integrator runs the bodies or refuses in one line. ----

class EveryIntegratorOnBodies : public testing::RegistryTest {};

TEST_P(EveryIntegratorOnBodies, RunsTheTumblingBoxOrRefuses) {
  const Scene scene = make_builtin_scene("tumbling-box");
  const Model model(scene);
  RunSettings s = settings(2e-4, 0.02);
  s.options.newton_tol = 1e-10;
  const RunResult r = simulate(model, s);
  if (r.status == RunStatus::kFailed) {
    EXPECT_EQ(r.failure.find('\n'), std::string::npos);
    EXPECT_NE(r.failure.find("rigid bod"), std::string::npos) << r.failure;
    return;
  }
  // Forward Euler is unstable at every step on the undamped rigidity mode
  // (|1 + i w h| > 1): diverging is its result, not a failure.
  if (GetParam() == "explicit-euler" && r.status == RunStatus::kDiverged) return;
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const Eigen::Vector3d L0 = momentum(model, model.initial_positions(), model.initial_velocities());
  const Eigen::Vector3d L = momentum(model, r.x_final, r.v_final);
  EXPECT_LT((L - L0).norm() / L0.norm(), 1e-2);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryIntegratorOnBodies,
                         ::testing::ValuesIn(integrator_names()), testing::registry_test_name);

}  // namespace
}  // namespace springlab::test_rigid_bodies
