// The round-off scales Newton's stop and the incremental potential check
// use (issue 46.15: results that must not hang on how a BLAS kernel rounds):
// VelocityStep::position_resolution and VelocityStep::stored_magnitude,
// against their closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "integrators/core/integrator.h"
#include "integrators/newton/newton_matrix.h"
#include "integrators/newton/velocity_step.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"

namespace springlab::test_roundoff_scales {
namespace {

// A cantilever under gravity, centred on y = 0 (the beam scene): the
// potential -sum m g.x sums terms of both signs.
struct Fixture {
  Fixture()
      : model(make_builtin_scene("beam", {{"nx", "8"}, {"ny", "2"}})), counted(model, stats) {
    matrix.bind(counted);
    step.bind(counted, matrix);
    x = model.initial_positions();
    x.array() += 1e-3;  // moved off its fixed end: the elements push too
    v = Vector::Constant(x.size(), 0.25);
  }
  Model model;
  IntegratorStats stats;
  CountedModel counted;
  NewtonMatrix matrix;
  VelocityStep step;
  Vector x, v;
};

// (|x_n|_inf + |x_o|_inf) / (h w |b|): the velocity whose step moves the
// stage by the positions' own scale.
TEST(RoundoffScales, PositionResolutionIsThePositionsOverTheStagesStep) {
  Fixture f;
  const double h = 0.01;
  const VelocityImplicitScheme midpoint{.t_eval_offset = 0.5, .a = 0.25, .b = 0.25, .c = 0.5,
                                        .weight = 2.0};
  f.step.begin(0.0, f.x, f.v, h, midpoint);
  EXPECT_DOUBLE_EQ(f.step.position_resolution(), f.x.lpNorm<Eigen::Infinity>() / (h * 2.0 * 0.25));
  Vector offset = Vector::Constant(f.x.size(), -3.0);
  VelocityImplicitScheme shifted = midpoint;
  shifted.x_offset = &offset;
  f.step.begin(0.0, f.x, f.v, h, shifted);
  EXPECT_DOUBLE_EQ(f.step.position_resolution(),
                   (f.x.lpNorm<Eigen::Infinity>() + 3.0) / (h * 2.0 * 0.25));
}

// On a scene whose only non-stiff force is gravity (linear in x), the
// non-stiff part of stored_magnitude is the sum of the magnitudes of the
// potential's terms |m g_r x_r|, which its sum hides where they cancel; the
// stiff part (the elements) adds |F_elements| . |x*|.
TEST(RoundoffScales, StoredMagnitudeSumsTheMagnitudesOfTheTermsThatCancel) {
  Fixture f;
  const double h = 0.01;
  const VelocityImplicitScheme euler{.t_eval_offset = 1.0, .a = 0.0, .b = 1.0, .c = 1.0};
  f.step.begin(0.0, f.x, f.v, h, euler);
  const Vector v = Vector::Zero(f.x.size());
  f.step.stage(v);  // x* = x_n
  Vector gravity, elements;
  f.model.force(ForcePart::kNonstiff, 0.0, f.x, v, gravity);
  f.model.force(ForcePart::kStiff, 0.0, f.x, v, elements);
  double terms = 0.0;
  for (Eigen::Index k = 0; k < f.x.size(); ++k) terms += std::abs(gravity[k] * f.x[k]);
  const double expected = terms + elements.cwiseAbs().dot(f.x.cwiseAbs());
  EXPECT_NEAR(f.step.stored_magnitude(), expected, 1e-12 * expected);
  // The terms' magnitudes are far above their sum: the potential's own
  // magnitude would understate its round-off.
  EXPECT_GT(terms, 10.0 * std::abs(gravity.dot(f.x)));
}

}  // namespace
}  // namespace springlab::test_roundoff_scales
