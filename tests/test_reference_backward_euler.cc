// implicit-euler's step (newton_loop.h: inexact CG with a kept Cholesky
// factor, line search, definite matrices, negative curvature) against the
// textbook reference (integrators/methods/reference_backward_euler.h: full Newton
// updates, a dense LU): both solve the same equations, so on small scenes,
// each solved to 1e-12 m/s, they must land on the same states.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "integrators/methods/reference_backward_euler.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"

namespace springlab::test_reference_backward_euler {
namespace {

constexpr double kTol = 1e-12;  // m/s, both solvers

struct Case {
  std::string scene;
  std::vector<std::pair<std::string, std::string>> parameters;
  double h;
  int steps;
};

struct Difference {
  double x = 0.0, v = 0.0;   // the largest over the steps, max norm
  int reference_iterations = 0;
};

Difference compare(const Case& c) {
  const Model model(make_builtin_scene(c.scene, c.parameters));
  std::unique_ptr<Integrator> fast = make_integrator("implicit-euler");
  IntegratorOptions options;
  options.newton_tol = kTol;
  Vector x = model.initial_positions(), v = model.initial_velocities();
  EXPECT_TRUE(fast->initialize(model, 0.0, x, v, options).ok);
  Difference d;
  double t = 0.0;
  for (int k = 1; k <= c.steps; ++k) {
    const double t_next = k * c.h;
    const StepResult step = fast->advance_to(t_next);
    EXPECT_TRUE(step.ok) << c.scene << " step " << k << ": " << step.message;
    const ReferenceStepResult reference =
        reference_backward_euler_step(model, t, t_next - t, kTol, 50, x, v);
    EXPECT_TRUE(reference.ok) << c.scene << " step " << k << ": " << reference.message;
    if (!step.ok || !reference.ok) break;
    d.x = std::max(d.x, (fast->x() - x).lpNorm<Eigen::Infinity>());
    d.v = std::max(d.v, (fast->v() - v).lpNorm<Eigen::Infinity>());
    d.reference_iterations += reference.iterations;
    t = t_next;
  }
  return d;
}

// One step on the linear oscillator (rest length 0: linear in every
// direction) against the closed form of backward Euler:
//   v1 = (v0 - h w^2 (x0 - 0)) / (1 + h^2 w^2),  x1 = x0 + h v1,  w^2 = k/m.
TEST(ReferenceBackwardEuler, OneStepOnTheOscillatorIsTheClosedForm) {
  const Model model(make_builtin_scene("oscillator", {{"k", "100"}, {"mass", "2"}}));
  Vector x = model.initial_positions(), v = model.initial_velocities();
  const Vector x0 = x, v0 = v;
  const double h = 0.05, w2 = 100.0 / 2.0;
  const ReferenceStepResult r = reference_backward_euler_step(model, 0.0, h, 1e-14, 10, x, v);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_LE(r.iterations, 2);  // linear: one update, and one to see it is 0
  // The fixed end of the spring sits at the origin: x0 is the stretch.
  const Vector v1 = (v0 - h * w2 * x0) / (1.0 + h * h * w2);
  EXPECT_LT((v - v1).lpNorm<Eigen::Infinity>(), 1e-14);
  EXPECT_LT((x - (x0 + h * v1)).lpNorm<Eigen::Infinity>(), 1e-14);
}

// The fast step and the reference, step by step from the same states on
// small scenes: the hanging spring with drag, a swinging chain, the 4 x 4
// cloth (compressed springs: an indefinite matrix) and a block of 2^3
// cubes of neo-Hookean tetrahedra falling onto the ground.
TEST(ReferenceBackwardEuler, ImplicitEulerLandsOnTheReferenceSolution) {
  const std::vector<Case> cases = {
      {"spring", {}, 0.01, 50},
      {"chain", {{"n", "6"}, {"horizontal", "1"}}, 0.01, 50},
      {"cloth", {{"n", "4"}}, 1.0 / 60.0, 30},
      {"block", {{"n", "2"}, {"height", "0.05"}}, 0.005, 30},
  };
  for (const Case& c : cases) {
    const Difference d = compare(c);
    // Measured: at most 5e-15 m and 1.6e-13 m/s (the chain); each solve
    // leaves up to the tolerance, 1e-12 m/s, a step.
    EXPECT_LT(d.x, 1e-12) << c.scene;
    EXPECT_LT(d.v, 1e-11) << c.scene;
    // The reference iterated to its tolerance: an update, and one that
    // saw the last below it, at least.
    EXPECT_GE(d.reference_iterations, 2 * c.steps) << c.scene;
    std::printf("%s: max |x - x_ref| %.3g m, |v - v_ref| %.3g m/s, %d reference iterations\n",
                c.scene.c_str(), d.x, d.v, d.reference_iterations);
  }
}

}  // namespace
}  // namespace springlab::test_reference_backward_euler
