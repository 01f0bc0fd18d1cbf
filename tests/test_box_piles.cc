// Bodies meeting bodies in the built-in scenes and the scene files of
// experiments/scenes (docs/physics.md "Contact between bodies",
// docs/scenes.md): the box pile of 8 stands under implicit Euler at a frame
// step, with every accepted state apart and the energy never rising, and
// at a millisecond under implicit Euler, BDF2, generalized-alpha and the
// implicit midpoint (the boxes' contact damping takes their bounce out); a
// pile of two lands and stands under generalized-alpha and the implicit
// midpoint at a millisecond; with elastic contact (no damping) n = 8 under
// them passes the steps at t = 0.843 s and 0.088 s where their Newton
// fails, in substeps (docs/physics.md "Limits"); a box dropped on the
// ground bounces back to its height without contact damping and lower with
// it; the tower of 10 equal boxes stands; a box
// comes to rest on a lying cylinder and an icosahedron on a box; boxes
// dropped into a bin in two layers come to rest (the 100 of the default,
// four layers, do too in 5 s: 300 steps, some 50 ms each, too long for a
// test); an explicit method past its step limit ends with a message.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "experiments/driver/simulation.h"
#include "models/bodies/bodies.h"
#include "models/bodies/body_contacts.h"
#include "models/scenes/builtin_scenes.h"
#include "models/contact/contact.h"
#include "models/model/model.h"
#include "models/model/scene_file.h"
#include "models/core/scene.h"

namespace springlab::test_box_piles {
namespace {

std::string scene_file(const std::string& name) {
  return std::string(SPRINGLAB_TEST_DATA) + "/../../experiments/scenes/" + name;
}

// Watches a run of a scene of bodies only: the smallest gap between two
// bodies' surfaces and any interpenetration at every accepted state, and
// the largest rise of the total energy from one state to the next.
class Watch final : public Observer {
 public:
  Watch(const Model& model)
      : model_(model), finder_(model.scene(), body_layout(model.scene(), 0)) {}
  void observe(double, const Vector& x, const Vector& v) override {
    finder_.place(x.data());
    std::vector<BodyContact> contacts;
    finder_.all_contacts(0.01, contacts);
    for (const BodyContact& k : contacts) smallest_gap = std::min(smallest_gap, k.d);
    overlaps += finder_.overlap().found() ? 1 : 0;
    const double E = model_.energies(x, v).total();
    if (states > 0) largest_rise = std::max(largest_rise, E - previous_);
    previous_ = E;
    ++states;
  }
  double smallest_gap = INFINITY, largest_rise = -INFINITY;
  int overlaps = 0;
  long states = 0;

 private:
  const Model& model_;
  BodyContactFinder finder_;
  double previous_ = 0.0;
};

RunResult run(const Model& model, const std::string& integrator, double dt, double t_end,
              std::vector<Observer*> observers = {}) {
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  return simulate(model, s, observers);
}

std::vector<BodyState> states_of(const Model& model, const RunResult& r) {
  const BodyLayout layout = body_layout(model.scene(), 0);
  std::vector<BodyState> out;
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    out.push_back(body_state(layout.bodies[b], layout.first[b], r.x_final.data(), r.v_final.data()));
  }
  return out;
}

// A pile stands: every box above the one below it, its centre within
// `offset` of that one's vertical axis, all still (speeds below `speed`).
void expect_stands(const Model& model, const RunResult& r, double offset, double speed) {
  const std::vector<BodyState> s = states_of(model, r);
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_LT(s[i].dp.norm(), speed) << "box " << i;
    if (i == 0) continue;
    EXPECT_GT(s[i].p.y(), s[i - 1].p.y()) << "box " << i;
    EXPECT_LT(std::hypot(s[i].p.x() - s[i - 1].p.x(), s[i].p.z() - s[i - 1].p.z()), offset)
        << "box " << i;
  }
}

// box-pile, n = 8, under the barrier (its default), implicit Euler at
// 1/60 s for 5 s: no accepted state has two surfaces touching or crossing;
// the energy never rises from one step to the next beyond round-off
// (1e-12 of E_s: implicit Euler minimizes the incremental potential of a
// convex contact energy within each step); the pile stands, its boxes still
// and within 2 mm of each other's axes.
TEST(BoxPiles, ThePileOfEightStandsUnderImplicitEulerAtAFrameStep) {
  const Model model(make_builtin_scene("box-pile", {{"n", "8"}}));
  Watch watch(model);
  const RunResult r = run(model, "implicit-euler", 1.0 / 60.0, 5.0, {&watch});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_EQ(watch.states, 301);
  EXPECT_GT(watch.smallest_gap, 0.0);
  EXPECT_EQ(watch.overlaps, 0);
  EXPECT_LT(watch.largest_rise, 1e-12 * model.energy_scale());
  expect_stands(model, r, 2e-3, 1e-3);
  RecordProperty("smallest_gap", std::to_string(watch.smallest_gap));
  RecordProperty("largest_rise", std::to_string(watch.largest_rise));
}

// The same pile at 1 ms for 5 s under implicit Euler, BDF2,
// generalized-alpha and the implicit midpoint. The last two damp little:
// with elastic contact (contact_damping 0) their boxes bounce and the pile
// topples (the top box ends on the ground under generalized-alpha; the
// midpoint diverges at t = 1.5 s); the boxes' default contact damping
// (2 s/m) takes the bounce out and it stands.
TEST(BoxPiles, ThePileOfEightStandsAtAMillisecond) {
  const Model model(make_builtin_scene("box-pile", {{"n", "8"}}));
  for (const char* method : {"implicit-euler", "bdf2", "generalized-alpha", "implicit-midpoint"}) {
    SCOPED_TRACE(method);
    Watch watch(model);
    const RunResult r = run(model, method, 1e-3, 5.0, {&watch});
    ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    EXPECT_GT(watch.smallest_gap, 0.0);
    EXPECT_EQ(watch.overlaps, 0);
    expect_stands(model, r, 1e-2, 1e-2);
  }
}

// Generalized-alpha and the implicit midpoint evaluate the forces short of
// the step's end (at x_n + (x_{n+1} - x_n) (1 - alpha_f), at the
// midpoint): when the second box lands (t = 0.054 s) Newton's start v_n
// has its forces' state before the barrier's gap and its end past it, a
// start every trial near which is refused. From a start between the
// accepted state and v_n (NewtonLoop::allowed_start) the pile of two
// lands and stands with elastic contact (contact_damping 0): the top box at 1 s within 0.5 mm (measured: 9 and 56 um) of the
// height it has on the bottom one under implicit Euler, its centre within
// 1 cm of the bottom one's axis, every state apart.
TEST(BoxPiles, APileOfTwoLandsUnderGeneralizedAlphaAndTheMidpointAtAMillisecond) {
  const Model model(make_builtin_scene("box-pile", {{"n", "2"}, {"contact_damping", "0"}}));
  const RunResult rest = run(model, "implicit-euler", 1e-3, 1.0);
  ASSERT_EQ(rest.status, RunStatus::kCompleted) << rest.failure;
  const double top = states_of(model, rest)[1].p.y();
  for (const char* method : {"generalized-alpha", "implicit-midpoint"}) {
    SCOPED_TRACE(method);
    Watch watch(model);
    const RunResult r = run(model, method, 1e-3, 1.0, {&watch});
    ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    EXPECT_GT(watch.smallest_gap, 0.0);
    EXPECT_EQ(watch.overlaps, 0);
    const std::vector<BodyState> s = states_of(model, r);
    EXPECT_NEAR(s[1].p.y(), top, 5e-4);
    expect_stands(model, r, 1e-2, 0.1);
    RecordProperty(std::string(method) + "_top_height_error", std::to_string(s[1].p.y() - top));
  }
}

// box-pile n = 8 at 1 ms with elastic contact (contact_damping 0):
// generalized-alpha's Newton fails on the step at
// t = 0.843 s, the midpoint's at t = 0.088 s (the barrier acts short of the
// step's end and cannot stop a box within the step: docs/physics.md
// "Limits"). Those steps are solved again in substeps
// (VelocityImplicitMethod::retry_in_substeps), so both runs pass them, no
// accepted state has two surfaces touching or crossing, and the run says
// how many steps were split (at least one; the rest as one step each).
TEST(BoxPiles, AStepTheBarrierCannotCloseIsSolvedInSubsteps) {
  const Model model(make_builtin_scene("box-pile", {{"n", "8"}, {"contact_damping", "0"}}));
  for (const auto& [method, t_end] : {std::pair{"generalized-alpha", 0.9},
                                      std::pair{"implicit-midpoint", 0.15}}) {
    SCOPED_TRACE(method);
    Watch watch(model);
    const RunResult r = run(model, method, 1e-3, t_end, {&watch});
    ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    EXPECT_EQ(r.stats.steps, std::lround(t_end / 1e-3));
    EXPECT_GT(watch.smallest_gap, 0.0);
    EXPECT_EQ(watch.overlaps, 0);
    const auto split = std::find_if(r.warnings.begin(), r.warnings.end(), [](const RunWarning& w) {
      return w.code == WarningCode::kFallback && w.fallback == Fallback::kSubsteps;
    });
    ASSERT_NE(split, r.warnings.end());
    EXPECT_GE(split->steps, 1);
    EXPECT_LT(split->steps, r.stats.steps / 20);
    RecordProperty(std::string(method) + "_split_steps", std::to_string(split->steps));
  }
}

// One box (box-pile n = 1) dropped flat from 1 cm onto the ground, under
// the implicit midpoint at 0.1 ms for 0.4 s (it keeps the energy of
// elastic contact: no numerical damping to speak of). Without contact
// damping its lowest point bounces back to the height it fell from (within
// 1 %) and the energy stays; with the default damping (2 s/m: -alpha f_n v_n
// while slow, at most f_n) the first bounce is lower (measured 6.0 of the
// 10 mm: a restitution of 0.77 at 0.44 m/s) but still a bounce (the damping
// never pulls: no glue), and the energy falls with each bounce.
TEST(BoxPiles, ContactDampingLowersTheBounce) {
  for (const char* alpha : {"0", "2"}) {
    SCOPED_TRACE(std::string("contact_damping ") + alpha);
    const Model model(make_builtin_scene("box-pile", {{"n", "1"}, {"contact_damping", alpha}}));
    const double dhat = model.scene().get<Contact>().distance_or_default();
    const BodyLayout layout = body_layout(model.scene(), 0);
    struct Lowest final : Observer {
      const BodyLayout* layout;
      double start = NAN, after = -INFINITY;  // the first gap; the highest once within dhat
      double dhat = 0.0;
      bool landed = false;
      void observe(double, const Vector& x, const Vector&) override {
        const RigidBody& b = layout->bodies[0];
        const BodyState s = body_state(b, layout->first[0], x.data(), x.data());
        double lowest = INFINITY;
        for (const Eigen::Vector3d& X : b.X) lowest = std::min(lowest, (s.p + s.A * X).y());
        if (std::isnan(start)) start = lowest;
        landed = landed || lowest < dhat;
        if (landed) after = std::max(after, lowest);
      }
    } watch;
    watch.layout = &layout;
    watch.dhat = dhat;
    const RunResult r = run(model, "implicit-midpoint", 1e-4, 0.4, {&watch});
    ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    ASSERT_TRUE(watch.landed);
    EXPECT_NEAR(watch.start, 0.01, 1e-9);
    const double m_g_drop = layout.bodies[0].mass.mass * 9.81 * watch.start;
    const double lost = r.energy_initial - r.energy_final;
    if (std::string(alpha) == "0") {
      EXPECT_NEAR(watch.after, watch.start, 0.01 * watch.start);
      EXPECT_LT(std::abs(lost), 1e-3 * m_g_drop);
    } else {
      EXPECT_LT(watch.after, 0.8 * watch.start);
      EXPECT_GT(watch.after, 2.0 * dhat);
      EXPECT_GT(lost, 0.5 * m_g_drop);
    }
    RecordProperty(std::string("rebound_") + alpha, std::to_string(watch.after));
    RecordProperty(std::string("lost_over_mgh_") + alpha, std::to_string(lost / m_g_drop));
  }
}

// box-drop with a second layer (30 boxes: 25, then 5 on top of them),
// implicit Euler at 1/60 s for 3 s. The contacts a step keeps are found at
// its start; when the upper boxes land, an edge slides along an edge below
// and other points of it than the kept ones reach the box below, so that
// the surfaces cross where no kept gap closes (the run ended at
// t = 0.2 s). Found again where the line search had to shorten Newton's
// update (MechanicalSystem::follow_lagged_contacts), they hold: the boxes
// come to rest (every speed below 3 mm/s; measured 1 um/s with the default
// contact damping, 0.3 mm/s without), every state apart.
TEST(BoxPiles, BoxesDroppedInTwoLayersComeToRest) {
  const Model model(make_builtin_scene("box-drop", {{"n", "30"}}));
  Watch watch(model);
  const RunResult r = run(model, "implicit-euler", 1.0 / 60.0, 3.0, {&watch});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_GT(watch.smallest_gap, 0.0);
  EXPECT_EQ(watch.overlaps, 0);
  double fastest = 0.0;
  for (const BodyState& b : states_of(model, r)) fastest = std::max(fastest, b.dp.norm());
  EXPECT_LT(fastest, 3e-3);
  RecordProperty("fastest", std::to_string(fastest));
}

// box-tower: 10 equal boxes, implicit Euler at 1/60 s for 5 s.
TEST(BoxPiles, TheTowerOfTenStandsUnderImplicitEulerAtAFrameStep) {
  const Model model(make_builtin_scene("box-tower", {}));
  ASSERT_EQ(model.scene().get<Bodies>().size(), 10u);
  Watch watch(model);
  const RunResult r = run(model, "implicit-euler", 1.0 / 60.0, 5.0, {&watch});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  EXPECT_GT(watch.smallest_gap, 0.0);
  EXPECT_EQ(watch.overlaps, 0);
  expect_stands(model, r, 2e-3, 1e-3);
  // Ten boxes 0.1 m high, each resting within the barrier's 1 mm.
  const std::vector<BodyState> s = states_of(model, r);
  EXPECT_NEAR(s.back().p.y(), 0.95, 10 * 1e-3);
}

// A box resting on a lying cylinder (a 32-sided prism on one of its faces)
// and an icosahedron (a closed mesh) landing on a box, implicit Euler at
// 1/60 s for 3 s: they come to rest on top, apart.
TEST(BoxPiles, ABoxRestsOnALyingCylinderAndAnIcosahedronOnABox) {
  for (const char* name : {"box-on-cylinder.json", "icosahedron-on-box.json"}) {
    SCOPED_TRACE(name);
    const Model model(load_scene_file(scene_file(name)));
    Watch watch(model);
    const RunResult r = run(model, "implicit-euler", 1.0 / 60.0, 3.0, {&watch});
    ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
    EXPECT_GT(watch.smallest_gap, 0.0);
    EXPECT_LT(watch.smallest_gap, 1e-3);  // touching within the barrier's distance
    EXPECT_EQ(watch.overlaps, 0);
    const std::vector<BodyState> s = states_of(model, r);
    EXPECT_LT(s[1].dp.norm(), 1e-3);
    EXPECT_GT(s[1].p.y(), s[0].p.y());
  }
}

// Past its step limit (the rigidity's 2 / w_kappa: 0.65 ms for the bottom
// box, 0.41 ms for the top one of three) symplectic Euler ends the pile
// diverged, with a message that says what happened and what to try.
TEST(BoxPiles, AnExplicitMethodPastItsLimitSaysSo) {
  const Model model(make_builtin_scene("box-pile", {{"n", "3"}}));
  for (double dt : {1e-3, 5e-4}) {
    const RunResult r = run(model, "symplectic-euler", dt, 1.0);
    EXPECT_EQ(r.status, RunStatus::kDiverged) << dt;
    EXPECT_NE(r.failure.find("smaller --dt"), std::string::npos) << r.failure;
  }
}

}  // namespace
}  // namespace springlab::test_box_piles
