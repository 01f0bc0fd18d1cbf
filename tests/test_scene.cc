// Scene files (docs/physics.md "Scene files"): every refusal gives its exact one-line message, the
// defaults are the documented ones, and scene_to_json round-trips exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "models/springs/drag.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"
#include "scene_equality.h"
#include "models/model/scene_file.h"

namespace springlab::test_scene {
namespace {

// Two particles, one spring: the smallest valid scene, edited by the cases.
std::string two_particles(const std::string& particle1 = R"({"x": [0, -1]})",
                          const std::string& springs = R"([{"i": 0, "j": 1, "k": 100}])",
                          const std::string& extra = "") {
  return R"({"dimension": 2, )" + extra + R"("particles": [{"x": [0, 0], "fixed": true}, )" +
         particle1 + R"(], "springs": )" + springs + "}";
}

// A hanging chain of n particles, as a file would write it.
std::string chain_text(int n, const std::string& last_spring) {
  std::string text = R"({"dimension": 2, "particles": [)";
  for (int p = 0; p < n; ++p) {
    text += (p ? ", " : "") + std::string(R"({"x": [0, )") + std::to_string(-p) + "]" +
            (p == 0 ? R"(, "fixed": true})" : "}");
  }
  text += R"(], "springs": [)";
  for (int p = 0; p + 1 < n; ++p) {
    text +=
        R"({"i": )" + std::to_string(p) + R"(, "j": )" + std::to_string(p + 1) + R"(, "k": 1}, )";
  }
  return text + last_spring + "]}";
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string parse_error(const std::string& text) {
  return error_of([&] { parse_scene(text, "scene.json"); });
}

using testing::expect_same_scene;

struct BadScene {
  std::string name;
  std::string text;
  std::string message;
};

void PrintTo(const BadScene& c, std::ostream* os) { *os << c.name; }

std::vector<BadScene> bad_scenes() {
  const std::string p = R"({"x": [0, -1]})";
  const std::string s = R"([{"i": 0, "j": 1, "k": 100}])";
  return {
      // Syntax.
      {"EmptyText", "",
       "scene.json: malformed JSON: parse error at line 1, column 1: syntax error while parsing "
       "value - "
       "unexpected end of input; expected '[', '{', or a literal"},
      {"Truncated", R"({"dimension": 2,)",
       "scene.json: malformed JSON: parse error at line 1, column 17: syntax error while parsing "
       "object key - "
       "unexpected end of input; expected string literal"},
      {"TrailingComma", R"({"dimension": 2,})",
       "scene.json: malformed JSON: parse error at line 1, column 17: syntax error while parsing "
       "object key - "
       "unexpected '}'; expected string literal"},
      {"DuplicateKey", two_particles(R"({"x": [0, -1], "x": [0, -2]})"),
       "scene.json: particles[1]: duplicate key 'x'"},
      {"DuplicateTopLevelKey", two_particles(p, s, R"("drag": 1, "drag": 2, )"),
       "scene.json: duplicate key 'drag'"},
      // Structure.
      {"TopLevelArray", "[]", "scene.json: top level: expected an object, got array"},
      {"MissingDimension", R"({"particles": [], "springs": []})",
       "scene.json: missing required key 'dimension'"},
      {"MissingParticles", R"({"dimension": 2, "springs": []})",
       "scene.json: missing required key 'particles'"},
      {"MissingSprings", R"({"dimension": 2, "particles": [{"x": [0, 0]}]})",
       "scene.json: missing required key 'springs'"},
      {"UnknownTopLevelKey", two_particles(p, s, R"("gravty": [0, -9.81], )"),
       "scene.json: unknown key 'gravty' (did you mean 'gravity'?) (allowed keys: name, "
       "dimension, gravity, drag, wind, materials, contact, planes, particles, springs, "
       "triangles, tetrahedra, bodies, fluids)"},
      {"UnknownKeyIsEscaped", two_particles(p, s, R"("a\nb": 1, )"),
       "scene.json: unknown key 'a\\nb' (allowed keys: name, dimension, gravity, drag, wind, "
       "materials, contact, planes, particles, springs, triangles, tetrahedra, bodies, fluids)"},
      {"UnknownParticleKey", two_particles(R"({"x": [0, -1], "vel": [0, 0]})"),
       "scene.json: particles[1]: unknown key 'vel' (allowed keys: x, X, v, mass, fixed)"},
      {"UnknownSpringKey", two_particles(p, R"([{"i": 0, "j": 1, "k": 1, "length": 1}])"),
       "scene.json: springs[0]: unknown key 'length' (allowed keys: i, j, k, rest, damping)"},
      {"UnknownWindKey", two_particles(p, s, R"("wind": {"velocity": [1, 0], "speed": 2}, )"),
       "scene.json: wind: unknown key 'speed' (allowed keys: velocity, coefficient, gust, "
       "frequency)"},
      {"WindWithoutVelocity", two_particles(p, s, R"("wind": {"coefficient": 1}, )"),
       "scene.json: wind: missing required key 'velocity'"},
      {"WindNotObject", two_particles(p, s, R"("wind": [1, 0], )"),
       "scene.json: wind: expected an object, got array"},
      {"ParticleWithoutX", two_particles(R"({"mass": 2})"),
       "scene.json: particles[1]: missing required key 'x'"},
      {"SpringWithoutK", two_particles(p, R"([{"i": 0, "j": 1}])"),
       "scene.json: springs[0]: missing required key 'k'"},
      {"ParticlesNotArray", R"({"dimension": 2, "particles": {"x": [0, 0]}, "springs": []})",
       "scene.json: particles: expected an array, got object"},
      {"SpringsNotArray", two_particles(p, "{}"),
       "scene.json: springs: expected an array, got object"},
      {"ParticleNotObject", two_particles("[0, -1]"),
       "scene.json: particles[1]: expected an object, got array"},
      // Types.
      {"DimensionFour", two_particles(p, s).replace(14, 1, "4"),
       "scene.json: dimension: must be 2 or 3 (got 4)"},
      {"DimensionFractional", two_particles(p, s).replace(14, 1, "2.5"),
       "scene.json: dimension: must be 2 or 3 (got 2.5)"},
      {"DimensionString", two_particles(p, s).replace(14, 1, "\"2\""),
       "scene.json: dimension: expected a number, got string"},
      {"NameNotString", two_particles(p, s, R"("name": 7, )"),
       "scene.json: name: expected a string, got number"},
      {"MassString", two_particles(R"({"x": [0, -1], "mass": "1"})"),
       "scene.json: particles[1].mass: expected a number, got string"},
      {"FixedNumber", two_particles(R"({"x": [0, -1], "fixed": 1})"),
       "scene.json: particles[1].fixed: expected true or false, got number"},
      {"ComponentNull", two_particles(R"({"x": [0, null]})"),
       "scene.json: particles[1].x[1]: expected a number, got null"},
      {"IndexString", two_particles(p, R"([{"i": 0, "j": "1", "k": 1}])"),
       "scene.json: springs[0].j: expected a number, got string"},
      {"VectorNotArray", two_particles(R"({"x": 5})"),
       "scene.json: particles[1].x: expected an array of 2 numbers, got number"},
      // Vector lengths.
      {"XTooLong", two_particles(R"({"x": [0, -1, 0]})"),
       "scene.json: particles[1].x: expected 2 numbers (dimension is 2), got 3"},
      {"VTooShort", two_particles(R"({"x": [0, -1], "v": [1]})"),
       "scene.json: particles[1].v: expected 2 numbers (dimension is 2), got 1"},
      {"RestPositionTooLong", two_particles(R"({"x": [0, -1], "X": [0, -1, 0]})"),
       "scene.json: particles[1].X: expected 2 numbers (dimension is 2), got 3"},
      {"GravityTooLong", two_particles(p, s, R"("gravity": [0, -9.81, 0], )"),
       "scene.json: gravity: expected 2 numbers (dimension is 2), got 3"},
      {"WindVelocityTooLong", two_particles(p, s, R"("wind": {"velocity": [1, 0, 0]}, )"),
       "scene.json: wind.velocity: expected 2 numbers (dimension is 2), got 3"},
      // Non-finite numbers (JSON has no inf, but 1e999 overflows a double).
      {"PositionOverflow", two_particles(R"({"x": [1e999, -1]})"),
       "scene.json: particles[1].x[0]: must be a finite number"},
      {"RestPositionString", two_particles(R"({"x": [0, -1], "X": [0, "-1"]})"),
       "scene.json: particles[1].X[1]: expected a number, got string"},
      {"RestPositionsTooFarApart",
       R"({"dimension": 2, "particles": [{"x": [0, 0], "X": [-1e308, 0], "fixed": true},
                                         {"x": [0, -1], "X": [1e308, 0]}],
           "springs": [{"i": 0, "j": 1, "k": 1}]})",
       "scene.json: springs[0]: particles 0 and 1 are too far apart to take their distance as "
       "rest length"},
      // Coinciding ends at x have no direction, whatever their rest positions.
      {"CoincideWithRestPositionsApart",
       two_particles(R"({"x": [0, 0], "X": [0, -1]})", R"([{"i": 0, "j": 1, "k": 1}])"),
       "scene.json: springs[0]: particles 0 and 1 coincide and no rest length is given"},
      {"StiffnessOverflow", two_particles(p, R"([{"i": 0, "j": 1, "k": 1e999}])"),
       "scene.json: springs[0].k: must be a finite number"},
      {"GravityOverflow", two_particles(p, s, R"("gravity": [0, -1e999], )"),
       "scene.json: gravity[1]: must be a finite number"},
      // Ranges.
      {"NegativeMass", two_particles(R"({"x": [0, -1], "mass": -1})"),
       "scene.json: particles[1].mass: must be > 0 (got -1)"},
      {"ZeroMass", two_particles(R"({"x": [0, -1], "mass": 0})"),
       "scene.json: particles[1].mass: must be > 0 (got 0)"},
      {"NegativeStiffness", two_particles(p, R"([{"i": 0, "j": 1, "k": -5}])"),
       "scene.json: springs[0].k: must be >= 0 (got -5)"},
      {"NegativeRest", two_particles(p, R"([{"i": 0, "j": 1, "k": 1, "rest": -1}])"),
       "scene.json: springs[0].rest: must be >= 0 (got -1)"},
      {"NegativeDamping", two_particles(p, R"([{"i": 0, "j": 1, "k": 1, "damping": -0.25}])"),
       "scene.json: springs[0].damping: must be >= 0 (got -0.25)"},
      {"NegativeDrag", two_particles(p, s, R"("drag": -0.5, )"),
       "scene.json: drag: must be >= 0 (got -0.5)"},
      {"NegativeWindCoefficient",
       two_particles(p, s, R"("wind": {"velocity": [1, 0], "coefficient": -1}, )"),
       "scene.json: wind.coefficient: must be >= 0 (got -1)"},
      {"NegativeGust", two_particles(p, s, R"("wind": {"velocity": [1, 0], "gust": -2}, )"),
       "scene.json: wind.gust: must be >= 0 (got -2)"},
      {"NegativeFrequency",
       two_particles(p, s, R"("wind": {"velocity": [1, 0], "frequency": -3}, )"),
       "scene.json: wind.frequency: must be >= 0 (got -3)"},
      // Indices and spring geometry.
      {"FractionalIndex", two_particles(p, R"([{"i": 1.5, "j": 0, "k": 1}])"),
       "scene.json: springs[0].i: must be a whole number (got 1.5)"},
      {"NegativeIndex", two_particles(p, R"([{"i": -1, "j": 1, "k": 1}])"),
       "scene.json: springs[0]: particle -1 does not exist (scene has 2 particles)"},
      {"IndexPastEnd", chain_text(12, R"({"i": 4, "j": 17, "k": 1})"),
       "scene.json: springs[11]: particle 17 does not exist (scene has 12 particles)"},
      {"SelfSpring", two_particles(p, R"([{"i": 1, "j": 1, "k": 1}])"),
       "scene.json: springs[0]: joins particle 1 to itself"},
      {"CoincideWithPositiveRest",
       two_particles(R"({"x": [0, 0]})", R"([{"i": 0, "j": 1, "k": 1, "rest": 1}])"),
       "scene.json: springs[0]: particles 0 and 1 coincide but the rest length is positive"},
      {"CoincideWithoutRest", two_particles(R"({"x": [0, 0]})", R"([{"i": 0, "j": 1, "k": 1}])"),
       "scene.json: springs[0]: particles 0 and 1 coincide and no rest length is given"},
      {"DuplicateSpringReversed", chain_text(5, R"({"i": 3, "j": 2, "k": 1})"),
       "scene.json: springs[4]: duplicates springs[2] (both join particles 2 and 3)"},
      {"NoFreeParticle", two_particles(R"({"x": [0, -1], "fixed": true})"),
       "scene.json: particles: scene has no free particle"},
      {"NoParticles", R"({"dimension": 2, "particles": [], "springs": []})",
       "scene.json: particles: scene has no free particle"},
      // The first problem in the file wins.
      {"FirstParticleFirst",
       R"({"dimension": 2, "particles": [{"x": [0, 0], "mass": -1}, {"x": [0, -1, 0]}], "springs": []})",
       "scene.json: particles[0].mass: must be > 0 (got -1)"},
      {"DuplicateBeforeLaterSpringError",
       two_particles(
           p, R"([{"i": 0, "j": 1, "k": 1}, {"i": 1, "j": 0, "k": 1}, {"i": 0, "j": 1, "k": -1}])"),
       "scene.json: springs[1]: duplicates springs[0] (both join particles 0 and 1)"},
  };
}

class BadSceneTest : public ::testing::TestWithParam<BadScene> {};

TEST_P(BadSceneTest, RefusedWithExactMessage) {
  SCOPED_TRACE(GetParam().text);
  EXPECT_EQ(parse_error(GetParam().text), GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(Scene, BadSceneTest, ::testing::ValuesIn(bad_scenes()),
                         [](const auto& info) { return info.param.name; });

TEST(SceneTest, HelpersBuildValidScenes) {
  // The bad cases are edits of these; they must be valid to begin with.
  EXPECT_NO_THROW(parse_scene(two_particles(), "scene.json"));
  EXPECT_NO_THROW(parse_scene(chain_text(12, R"({"i": 0, "j": 11, "k": 1})"), "scene.json"));
  // The "Dimension*" cases replace the character at offset 14.
  EXPECT_EQ(two_particles().substr(0, 16), R"({"dimension": 2,)");
}

TEST(SceneTest, DefaultsAreTheDocumentedOnes) {
  const Scene scene = parse_scene(
      R"({"dimension": 2, "particles": [{"x": [0, 0], "fixed": true}, {"x": [3, 4]}],
          "springs": [{"i": 0, "j": 1, "k": 10}]})",
      "scene.json");
  EXPECT_EQ(scene.name, "");
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d::Zero());
  EXPECT_EQ(scene.get<Drag>().gamma, 0.0);
  EXPECT_FALSE(scene.has<Wind>());
  ASSERT_EQ(scene.particles.size(), 2u);
  EXPECT_TRUE(scene.particles[0].fixed);
  EXPECT_FALSE(scene.particles[1].fixed);
  EXPECT_EQ(scene.particles[1].mass, 1.0);
  EXPECT_EQ(scene.particles[1].v, Eigen::Vector3d::Zero());
  ASSERT_EQ(scene.get<Springs>().size(), 1u);
  EXPECT_EQ(scene.get<Springs>()[0].rest, 5.0);  // the initial distance of (0,0)-(3,4)
  EXPECT_EQ(scene.get<Springs>()[0].damping, 0.0);
}

// docs/physics.md "Finite elements": a particle's rest position X defaults to x; a spring without
// "rest" takes the distance of its ends' rest positions.
TEST(SceneTest, RestPositionsDefaultToXAndGiveTheSpringsRestLength) {
  const Scene scene = parse_scene(
      R"({"dimension": 2, "particles": [{"x": [0, 0], "fixed": true},
                                        {"x": [0, -1], "X": [0, -2.5]}, {"x": [3, 4]}],
          "springs": [{"i": 0, "j": 1, "k": 10}, {"i": 0, "j": 2, "k": 10},
                      {"i": 1, "j": 2, "k": 10, "rest": 0.5}]})",
      "scene.json");
  EXPECT_FALSE(scene.particles[0].X.has_value());
  EXPECT_EQ(scene.particles[0].rest_position(), scene.particles[0].x);
  ASSERT_TRUE(scene.particles[1].X.has_value());
  EXPECT_EQ(*scene.particles[1].X, Eigen::Vector3d(0, -2.5, 0));
  EXPECT_EQ(scene.particles[1].rest_position(), Eigen::Vector3d(0, -2.5, 0));
  EXPECT_EQ(scene.particles[1].x, Eigen::Vector3d(0, -1, 0));
  const Springs& springs = scene.get<Springs>();
  EXPECT_EQ(springs[0].rest, 2.5);  // |X_1 - X_0|, not |x_1 - x_0| = 1
  EXPECT_EQ(springs[1].rest, 5.0);  // no X: |x_2 - x_0|
  EXPECT_EQ(springs[2].rest, 0.5);  // given
  // Rest positions that coincide give a zero rest length (ends apart at x).
  const Scene zero = parse_scene(
      two_particles(R"({"x": [0, -1], "X": [0, 0]})", R"([{"i": 0, "j": 1, "k": 1}])"),
      "scene.json");
  EXPECT_EQ(zero.get<Springs>()[0].rest, 0.0);
}

TEST(SceneTest, WindDefaultsToSteadyWithZeroCoefficient) {
  const Scene scene = parse_scene(
      two_particles(R"({"x": [0, -1]})", "[]", R"("wind": {"velocity": [2, 1]}, )"), "scene.json");
  ASSERT_TRUE(scene.has<Wind>());
  EXPECT_EQ(scene.find<Wind>()->velocity, Eigen::Vector3d(2, 1, 0));
  EXPECT_EQ(scene.find<Wind>()->coefficient, 0.0);
  EXPECT_EQ(scene.find<Wind>()->gust, 0.0);
  EXPECT_EQ(scene.find<Wind>()->frequency, 0.0);
}

TEST(SceneTest, TwoDimensionalVectorsHaveZeroZ) {
  const Scene scene =
      parse_scene(two_particles(R"({"x": [1.5, -2.5], "v": [3, 4]})", "[]",
                                R"("gravity": [0.5, -9.81], "wind": {"velocity": [7, 8]}, )"),
                  "scene.json");
  EXPECT_EQ(scene.particles[1].x, Eigen::Vector3d(1.5, -2.5, 0));
  EXPECT_EQ(scene.particles[1].v, Eigen::Vector3d(3, 4, 0));
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d(0.5, -9.81, 0));
  EXPECT_EQ(scene.find<Wind>()->velocity, Eigen::Vector3d(7, 8, 0));
}

TEST(SceneTest, AcceptsEdgeCasesTheSpecAllows) {
  // Coinciding ends with an explicit zero rest length: a linear spring.
  const Scene zero_rest = parse_scene(
      two_particles(R"({"x": [0, 0]})", R"([{"i": 0, "j": 1, "k": 1, "rest": 0}])"), "scene.json");
  EXPECT_EQ(zero_rest.get<Springs>()[0].rest, 0.0);
  // Whole numbers written as floats, an empty spring list, k = 0, dimension 3.
  const Scene scene = parse_scene(
      R"({"dimension": 3.0, "particles": [{"x": [0, 0, 0]}, {"x": [1, 2, 2]}],
          "springs": [{"i": 1.0, "j": 0, "k": 0}]})",
      "scene.json");
  EXPECT_EQ(scene.dimension, 3);
  EXPECT_EQ(scene.get<Springs>()[0].i, 1);
  EXPECT_EQ(scene.get<Springs>()[0].rest, 3.0);
  EXPECT_NO_THROW(parse_scene(two_particles(R"({"x": [0, -1]})", "[]"), "scene.json"));
}

Scene awkward_3d_scene() {
  Scene scene;
  scene.name = "a \"quoted\"\nname";
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.1, -9.81, 1.0 / 3.0};
  scene.block<Drag>().gamma = 1e-300;
  scene.block<Wind>() = Wind{{2.0, -0.0, 1e300}, 0.1, 0.5, 0.7};
  Particle fixed;
  fixed.fixed = true;
  fixed.mass = 2.0 / 3.0;
  Particle moving;
  moving.x = {std::nextafter(1.0, 2.0), 4.9e-324, -123456789.123456789};
  moving.v = {0.0, 0.0, -2.5};
  moving.mass = 7;
  scene.particles = {fixed, moving, moving};
  scene.particles[2].x.x() = 17.0;
  scene.particles[2].X = Eigen::Vector3d(16.5, -0.0, 1e-300);
  scene.block<Springs>() = {{0, 1, 100.0, 0.1 + 0.2, 0.0}, {2, 1, 0.0, 0.0, 3.25}};
  return scene;
}

TEST(SceneTest, ThreeDimensionalSceneWithWindRoundTripsExactly) {
  const Scene scene = awkward_3d_scene();
  ASSERT_NO_THROW(validate_scene(scene, "awkward"));
  const std::string text = scene_to_json(scene);
  expect_same_scene(parse_scene(text, "round trip"), scene);
  EXPECT_EQ(scene_to_json(parse_scene(text, "round trip")), text);  // deterministic
}

TEST(SceneTest, TwoDimensionalSceneRoundTripsExactly) {
  const Scene scene = parse_scene(
      R"({"name": "two", "dimension": 2, "gravity": [0, -9.81], "drag": 0.3,
          "particles": [{"x": [0, 0], "fixed": true}, {"x": [0.1, -1], "v": [0.2, 0], "mass": 0.5}],
          "springs": [{"i": 0, "j": 1, "k": 100, "damping": 0.01}]})",
      "scene.json");
  expect_same_scene(parse_scene(scene_to_json(scene), "round trip"), scene);
}

TEST(SceneTest, WrittenFileIsReadableAndOmitsDefaults) {
  const Scene scene = parse_scene(two_particles(), "scene.json");
  const std::string text = scene_to_json(scene);
  EXPECT_EQ(text,
            "{\n"
            "  \"name\": \"\",\n"
            "  \"dimension\": 2,\n"
            "  \"gravity\": [0.0, 0.0],\n"
            "  \"drag\": 0.0,\n"
            "  \"particles\": [\n"
            "    {\"x\": [0.0, 0.0], \"mass\": 1.0, \"fixed\": true},\n"
            "    {\"x\": [0.0, -1.0], \"mass\": 1.0}\n"
            "  ],\n"
            "  \"springs\": [\n"
            "    {\"i\": 0, \"j\": 1, \"k\": 100.0, \"rest\": 1.0}\n"
            "  ]\n"
            "}\n");
}

// validate_scene and parse_scene share their checks: the same defect gives
// the same message whether it comes from a file or from code.
struct Defect {
  std::string name;
  std::function<void(Scene&)> apply;
  std::string message;
};

void PrintTo(const Defect& d, std::ostream* os) { *os << d.name; }

class DefectTest : public ::testing::TestWithParam<Defect> {};

TEST_P(DefectTest, ValidateAndParseAgree) {
  Scene scene = awkward_3d_scene();
  GetParam().apply(scene);
  EXPECT_EQ(error_of([&] { validate_scene(scene, "s.json"); }), GetParam().message);
  EXPECT_EQ(error_of([&] { parse_scene(scene_to_json(scene), "s.json"); }), GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Scene, DefectTest,
    ::testing::Values(
        Defect{"Mass", [](Scene& s) { s.particles[1].mass = -2; },
               "s.json: particles[1].mass: must be > 0 (got -2)"},
        Defect{"Dimension", [](Scene& s) { s.dimension = 4; },
               "s.json: dimension: must be 2 or 3 (got 4)"},
        Defect{"Stiffness", [](Scene& s) { s.block<Springs>()[1].k = -1; },
               "s.json: springs[1].k: must be >= 0 (got -1)"},
        Defect{"Rest", [](Scene& s) { s.block<Springs>()[0].rest = -0.5; },
               "s.json: springs[0].rest: must be >= 0 (got -0.5)"},
        Defect{"Drag", [](Scene& s) { s.block<Drag>().gamma = -1; },
               "s.json: drag: must be >= 0 (got -1)"},
        Defect{"Gust", [](Scene& s) { s.block<Wind>().gust = -1; },
               "s.json: wind.gust: must be >= 0 (got -1)"},
        Defect{"Index", [](Scene& s) { s.block<Springs>()[1].j = 3; },
               "s.json: springs[1]: particle 3 does not exist (scene has 3 particles)"},
        Defect{"Self", [](Scene& s) { s.block<Springs>()[1].i = 1; },
               "s.json: springs[1]: joins particle 1 to itself"},
        Defect{"Coincide",
               [](Scene& s) {
                 s.particles[2].x = s.particles[1].x;
                 s.block<Springs>()[1].rest = 1;
               },
               "s.json: springs[1]: particles 2 and 1 coincide but the rest length is positive"},
        Defect{"Duplicate",
               [](Scene& s) {
                 s.block<Springs>().push_back({1, 0, 1.0, 1.0, 0.0});
               },
               "s.json: springs[2]: duplicates springs[0] (both join particles 0 and 1)"},
        Defect{"NoFree",
               [](Scene& s) {
                 for (Particle& p : s.particles) p.fixed = true;
               },
               "s.json: particles: scene has no free particle"}),
    [](const auto& info) { return info.param.name; });

TEST(SceneTest, CoincideCheckUsesTheResolvedRest) {
  // In a built scene the rest length is always explicit: 0 at coinciding ends is fine.
  Scene scene = awkward_3d_scene();
  scene.particles[2].x = scene.particles[1].x;
  scene.block<Springs>()[1].rest = 0;
  EXPECT_NO_THROW(validate_scene(scene, "s.json"));
}

TEST(SceneTest, ValidateRefusesNonFiniteAndStrayZComponents) {
  Scene scene = awkward_3d_scene();
  scene.particles[1].v.z() = std::nan("");
  EXPECT_EQ(error_of([&] { validate_scene(scene, "s"); }),
            "s: particles[1].v[2]: must be a finite number");
  Scene flat = parse_scene(two_particles(), "scene.json");
  flat.particles[1].x.z() = 1;
  EXPECT_EQ(error_of([&] { validate_scene(flat, "s"); }),
            "s: particles[1].x[2]: must be 0 in a 2-D scene");
  flat.particles[1].x.z() = 0;
  flat.particles[1].X = Eigen::Vector3d(0, -1, 2);
  EXPECT_EQ(error_of([&] { validate_scene(flat, "s"); }),
            "s: particles[1].X[2]: must be 0 in a 2-D scene");
  flat.particles[1].X = Eigen::Vector3d(0, INFINITY, 0);
  EXPECT_EQ(error_of([&] { validate_scene(flat, "s"); }),
            "s: particles[1].X[1]: must be a finite number");
}

TEST(SceneTest, DuplicateCheckScalesToLargeScenes) {
  // A long chain plus one duplicate at the end: found, with the right indices.
  Scene scene;
  const int n = 200000;
  for (int p = 0; p < n; ++p) {
    Particle particle;
    particle.x = {0.0, -p * 0.01, 0.0};
    particle.fixed = p == 0;
    scene.particles.push_back(particle);
    if (p > 0) scene.block<Springs>().push_back({p - 1, p, 1.0, 0.01, 0.0});
  }
  EXPECT_NO_THROW(validate_scene(scene, "big"));
  scene.block<Springs>().push_back({n - 1, n - 2, 1.0, 0.01, 0.0});
  EXPECT_EQ(
      error_of([&] { validate_scene(scene, "big"); }),
      "big: springs[199999]: duplicates springs[199998] (both join particles 199998 and 199999)");
}

TEST(SceneTest, LoadsAFileAndNamesItInMessages) {
  const std::string path = ::testing::TempDir() + "springlab_test_scene.json";
  {
    std::ofstream out(path);
    out << two_particles(R"({"x": [0, -1], "mass": -3})");
  }
  EXPECT_EQ(error_of([&] { load_scene_file(path); }),
            path + ": particles[1].mass: must be > 0 (got -3)");
  {
    std::ofstream out(path);
    out << two_particles();
  }
  EXPECT_EQ(load_scene_file(path).get<Springs>().at(0).rest, 1.0);
  std::remove(path.c_str());
  EXPECT_EQ(error_of([&] { load_scene_file(path); }), path + ": cannot open file");
  EXPECT_EQ(error_of([&] { load_scene_file(::testing::TempDir()); }),
            ::testing::TempDir() + ": cannot open file");
}

#ifdef SPRINGLAB_TEST_DATA
TEST(SceneTest, SpecExampleFileLoads) {
  // The small example docs/physics.md "Scene files" points to, stored verbatim.
  const Scene scene =
      load_scene_file(std::string(SPRINGLAB_TEST_DATA) + "/scenes/spec_example.json");
  EXPECT_EQ(scene.name, "single-spring");
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d(0, -9.81, 0));
  ASSERT_TRUE(scene.has<Wind>());
  EXPECT_EQ(scene.find<Wind>()->velocity, Eigen::Vector3d(2, 0, 0));
  EXPECT_EQ(scene.find<Wind>()->coefficient, 0.1);
  ASSERT_EQ(scene.particles.size(), 2u);
  EXPECT_TRUE(scene.particles[0].fixed);
  ASSERT_EQ(scene.get<Springs>().size(), 1u);
  EXPECT_EQ(scene.get<Springs>()[0].k, 100.0);
  EXPECT_EQ(scene.get<Springs>()[0].rest, 1.0);
}
#endif

}  // namespace
}  // namespace springlab::test_scene
