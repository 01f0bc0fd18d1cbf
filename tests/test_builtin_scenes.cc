// Built-in scenes (docs/scenes.md "Built-in scenes"): each builds a valid scene that round-trips as
// a file, its parameters do what they say, and bad -p values are refused with
// an exact message.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

#include "models/scenes/builtin_scenes.h"
#include "scene_equality.h"
#include "models/model/scene_file.h"
#include "models/fem/fem.h"
#include "models/materials/material.h"

namespace springlab::test_builtin_scenes {
namespace {

using Overrides = std::vector<std::pair<std::string, std::string>>;

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string build_error(const std::string& name, const Overrides& overrides) {
  return error_of([&] { make_builtin_scene(name, overrides); });
}

std::vector<std::string> names_of(const std::vector<BuiltinScene>& scenes) {
  std::vector<std::string> names;
  for (const BuiltinScene& s : scenes) names.push_back(s.name);
  return names;
}

using testing::expect_same_scene;

double distance(const Scene& scene, const Spring& s) {
  return (scene.particles[s.i].x - scene.particles[s.j].x).norm();
}

// ---- Every built-in. ----

class EveryBuiltin : public ::testing::TestWithParam<BuiltinScene> {};

TEST_P(EveryBuiltin, DefaultsBuildAValidSceneNamedAfterIt) {
  const Scene scene = make_builtin_scene(GetParam().name);
  EXPECT_EQ(scene.name, GetParam().name);
  EXPECT_NO_THROW(validate_scene(scene, "check"));
  EXPECT_TRUE(is_builtin_scene(GetParam().name));
  if (scene.dimension == 2) {
    for (const Particle& p : scene.particles) EXPECT_EQ(p.x.z(), 0.0);
  }
}

TEST_P(EveryBuiltin, RoundTripsThroughASceneFile) {
  const Scene scene = make_builtin_scene(GetParam().name);
  expect_same_scene(parse_scene(scene_to_json(scene), "printed"), scene);
}

TEST_P(EveryBuiltin, ParametersAreDocumentedAndTheirDefaultsAreTheDefaults) {
  ASSERT_FALSE(GetParam().parameters.empty());
  EXPECT_FALSE(GetParam().description.empty());
  Overrides overrides;
  for (const SceneParameter& p : GetParam().parameters) {
    EXPECT_FALSE(p.meaning.empty()) << p.name;
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", p.default_value);
    overrides.emplace_back(p.name, text);
  }
  // Giving every default explicitly changes nothing.
  expect_same_scene(make_builtin_scene(GetParam().name, overrides),
                    make_builtin_scene(GetParam().name));
}

TEST_P(EveryBuiltin, RefusesUnknownAndNonNumericParameters) {
  const std::string name = GetParam().name;
  std::string list;
  for (const SceneParameter& p : GetParam().parameters) list += (list.empty() ? "" : ", ") + p.name;
  EXPECT_EQ(build_error(name, {{"foo", "1"}}),
            "scene '" + name + "': unknown parameter 'foo' (parameters: " + list + ")");
  const std::string first = GetParam().parameters.front().name;
  for (const std::string bad :
       {"", "1x", "nan", "inf", "-inf", "1e999", " 1", "1 ", "0x10", "1,5", "+-1"}) {
    EXPECT_EQ(build_error(name, {{first, bad}}), "scene '" + name + "': parameter '" + first +
                                                     "' must be a finite number (got '" + bad +
                                                     "')");
  }
}

INSTANTIATE_TEST_SUITE_P(Builtin, EveryBuiltin, ::testing::ValuesIn(builtin_scenes()),
                         [](const auto& info) {
                           std::string name = info.param.name;  // "box-pile" -> "box_pile"
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// ---- The registry and its messages. ----

TEST(BuiltinScenesTest, AreTheSpecsSortedByName) {
  EXPECT_EQ(names_of(builtin_scenes()),
            (std::vector<std::string>{"beam", "block", "box-chain", "box-drop", "box-on-slope",
                                      "box-pile", "box-tower", "chain", "cloth", "dam-break",
                                      "dam-break-obstacle",
                                      "membrane", "oscillator", "slope", "sloshing", "spring",
                                      "tank", "tumbling-box"}));
  EXPECT_FALSE(is_builtin_scene("xyz"));
  EXPECT_FALSE(is_builtin_scene("Chain"));
}

TEST(BuiltinScenesTest, ParameterListsMatchTheSpec) {
  auto parameter_names = [](const std::string& scene) {
    for (const BuiltinScene& s : builtin_scenes()) {
      if (s.name != scene) continue;
      std::vector<std::string> names;
      for (const SceneParameter& p : s.parameters) names.push_back(p.name);
      return names;
    }
    return std::vector<std::string>{};
  };
  using Names = std::vector<std::string>;
  EXPECT_EQ(parameter_names("spring"), (Names{"k", "mass", "rest", "drag", "g"}));
  EXPECT_EQ(parameter_names("oscillator"), (Names{"k", "mass", "rest", "amplitude"}));
  EXPECT_EQ(parameter_names("chain"),
            (Names{"n", "k", "mass", "length", "drag", "g", "horizontal", "stretch"}));
  // The spec's parameters first, then the ground's (docs/scenes.md "Built-in scenes").
  EXPECT_EQ(parameter_names("cloth"),
            (Names{"n", "k", "k_shear", "k_bend", "mass", "size", "drag", "wind", "ground",
                   "friction", "contact", "contact_stiffness"}));
  EXPECT_EQ(parameter_names("slope"), (Names{"angle", "friction", "speed", "mass", "length", "g",
                                             "contact_stiffness", "smoothing"}));
}

TEST(BuiltinScenesTest, ExactMessages) {
  EXPECT_EQ(build_error("xyz", {}),
            "unknown built-in scene 'xyz' (built-in scenes: beam, block, box-chain, box-drop, "
            "box-on-slope, box-pile, box-tower, chain, cloth, dam-break, dam-break-obstacle, "
            "membrane, oscillator, slope, sloshing, spring, tank, tumbling-box)");
  EXPECT_EQ(build_error("chain", {{"foo", "1"}}),
            "scene 'chain': unknown parameter 'foo' (parameters: n, k, mass, length, drag, g, "
            "horizontal, stretch)");
  EXPECT_EQ(build_error("chain", {{"k", "1x"}}),
            "scene 'chain': parameter 'k' must be a finite number (got '1x')");
  EXPECT_EQ(build_error("chain", {{"n", "2.5"}}),
            "scene 'chain': parameter 'n' must be a whole number in [2, 10000000] (got 2.5)");
  EXPECT_EQ(build_error("chain", {{"n", "1"}}),
            "scene 'chain': parameter 'n' must be a whole number in [2, 10000000] (got 1)");
  EXPECT_EQ(build_error("chain", {{"n", "10000001"}}),
            "scene 'chain': parameter 'n' must be a whole number in [2, 10000000] (got 10000001)");
  EXPECT_EQ(build_error("chain", {{"k", "-1"}}),
            "scene 'chain': parameter 'k' must be >= 0 (got -1)");
  EXPECT_EQ(build_error("chain", {{"length", "0"}}),
            "scene 'chain': parameter 'length' must be > 0 (got 0)");
  EXPECT_EQ(build_error("chain", {{"horizontal", "0.5"}}),
            "scene 'chain': parameter 'horizontal' must be 0 or 1 (got 0.5)");
  EXPECT_EQ(build_error("cloth", {{"n", "2049"}}),
            "scene 'cloth': parameter 'n' must be a whole number in [2, 2048] (got 2049)");
  EXPECT_EQ(build_error("cloth", {{"mass", "-2"}}),
            "scene 'cloth': parameter 'mass' must be > 0 (got -2)");
  EXPECT_EQ(build_error("cloth", {{"k_bend", "-0.5"}}),
            "scene 'cloth': parameter 'k_bend' must be >= 0 (got -0.5)");
  EXPECT_EQ(build_error("spring", {{"mass", "0"}}),
            "scene 'spring': parameter 'mass' must be > 0 (got 0)");
  EXPECT_EQ(build_error("spring", {{"rest", "0"}}),
            "scene 'spring': parameter 'rest' must be > 0 (got 0)");
  EXPECT_EQ(build_error("spring", {{"drag", "-1"}}),
            "scene 'spring': parameter 'drag' must be >= 0 (got -1)");
  EXPECT_EQ(build_error("oscillator", {{"k", "0"}}),
            "scene 'oscillator': parameter 'k' must be > 0 (got 0)");
  EXPECT_EQ(build_error("oscillator", {{"rest", "-1"}}),
            "scene 'oscillator': parameter 'rest' must be >= 0 (got -1)");
  EXPECT_EQ(build_error("oscillator", {{"rest", "1"}, {"amplitude", "-1"}}),
            "scene 'oscillator': parameter 'amplitude' must satisfy rest + amplitude > 0 (got rest "
            "1, amplitude -1)");
  EXPECT_EQ(build_error("chain", {{"stretc", "1"}}),
            "scene 'chain': unknown parameter 'stretc' (did you mean 'stretch'?) (parameters: n, k, "
            "mass, length, drag, g, horizontal, stretch)");
  EXPECT_EQ(build_error("beam", {{"model", "corotatd"}}),
            "scene 'beam': parameter 'model' must be one of linear, corotated, stvk, neo-hookean, "
            "stable-neo-hookean or its number 0 to 4 (got 'corotatd') (did you mean 'corotated'?)");
  EXPECT_EQ(build_error("block", {{"model", "5"}}),
            "scene 'block': parameter 'model' must be one of linear, corotated, stvk, neo-hookean, "
            "stable-neo-hookean or its number 0 to 4 (got '5')");
}

// Every material of the registry is usable in every finite-element scene by
// its name (issue 47: one file and one line add a material, usable here),
// and the name gives exactly the scene its registry number gives.
TEST(BuiltinScenesTest, AMaterialIsChosenByNameOrByItsNumber) {
  int scenes_with_a_model = 0;
  for (const BuiltinScene& s : builtin_scenes()) {
    const auto model = std::find_if(s.parameters.begin(), s.parameters.end(),
                                    [](const SceneParameter& p) { return p.name == "model"; });
    if (model == s.parameters.end()) continue;
    ++scenes_with_a_model;
    const std::vector<const MaterialModel*> materials = material_models();
    ASSERT_EQ(model->choices.size(), materials.size()) << s.name;
    for (std::size_t i = 0; i < materials.size(); ++i) {
      const std::string name(materials[i]->name);
      SCOPED_TRACE(s.name + " " + name);
      EXPECT_EQ(model->choices[i], name);
      const std::string by_name_error = build_error(s.name, {{"model", name}});
      EXPECT_EQ(by_name_error, build_error(s.name, {{"model", std::to_string(i)}}));
      if (by_name_error != "(no error)") continue;  // e.g. a model without a membrane form
      const Scene by_name = make_builtin_scene(s.name, {{"model", name}});
      expect_same_scene(by_name, make_builtin_scene(s.name, {{"model", std::to_string(i)}}));
      ASSERT_EQ(by_name.get<Materials>().size(), 1u);
      EXPECT_EQ(by_name.get<Materials>()[0].model, name);
    }
  }
  EXPECT_EQ(scenes_with_a_model, 3);  // beam, block, membrane
}

TEST(BuiltinScenesTest, AcceptsOrdinaryNumberSpellingsAndTheLastValueWins) {
  EXPECT_EQ(make_builtin_scene("spring", {{"k", "+5"}}).get<Springs>()[0].k, 5.0);
  EXPECT_EQ(make_builtin_scene("spring", {{"k", "1e3"}}).get<Springs>()[0].k, 1000.0);
  EXPECT_EQ(make_builtin_scene("spring", {{"k", ".5"}}).get<Springs>()[0].k, 0.5);
  EXPECT_EQ(make_builtin_scene("chain", {{"n", "5.0"}}).particles.size(), 5u);
  EXPECT_EQ(make_builtin_scene("spring", {{"k", "5"}, {"k", "7"}}).get<Springs>()[0].k, 7.0);
  // Each value is checked as given, even if a later one would replace it.
  EXPECT_EQ(build_error("spring", {{"k", "-5"}, {"k", "7"}}),
            "scene 'spring': parameter 'k' must be >= 0 (got -5)");
}

// ---- Each scene's physics. ----

TEST(BuiltinScenesTest, SpringIsTheCourseExample) {
  const Scene scene = make_builtin_scene("spring");
  EXPECT_EQ(scene.dimension, 2);
  ASSERT_EQ(scene.particles.size(), 2u);
  EXPECT_TRUE(scene.particles[0].fixed);
  EXPECT_FALSE(scene.particles[1].fixed);
  EXPECT_EQ(scene.particles[0].x, Eigen::Vector3d::Zero());
  EXPECT_EQ(scene.particles[1].x,
            Eigen::Vector3d(0, -1, 0));  // undeformed: at rest length below x0
  EXPECT_EQ(scene.particles[1].v, Eigen::Vector3d::Zero());
  ASSERT_EQ(scene.get<Springs>().size(), 1u);
  EXPECT_EQ(scene.get<Springs>()[0].rest, distance(scene, scene.get<Springs>()[0]));
  EXPECT_EQ(scene.get<Springs>()[0].k, 100.0);
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d(0, -9.81, 0));
  EXPECT_GT(scene.get<Drag>().gamma, 0.0);
  EXPECT_FALSE(scene.has<Wind>());

  const Scene custom = make_builtin_scene(
      "spring", {{"k", "40"}, {"mass", "2"}, {"rest", "0.5"}, {"drag", "0"}, {"g", "-1.5"}});
  EXPECT_EQ(custom.get<Springs>()[0].k, 40.0);
  EXPECT_EQ(custom.particles[1].mass, 2.0);
  EXPECT_EQ(custom.particles[1].x, Eigen::Vector3d(0, -0.5, 0));
  EXPECT_EQ(custom.get<Springs>()[0].rest, 0.5);
  EXPECT_EQ(custom.get<Drag>().gamma, 0.0);
  EXPECT_EQ(custom.get<Gravity>().acceleration, Eigen::Vector3d(0, 1.5, 0));
}

TEST(BuiltinScenesTest, OscillatorStartsStretchedByTheAmplitude) {
  const Scene scene = make_builtin_scene(
      "oscillator", {{"k", "4"}, {"mass", "2"}, {"rest", "0.5"}, {"amplitude", "0.25"}});
  ASSERT_EQ(scene.particles.size(), 2u);
  ASSERT_EQ(scene.get<Springs>().size(), 1u);
  EXPECT_TRUE(scene.particles[0].fixed);
  EXPECT_EQ(scene.particles[1].mass, 2.0);
  EXPECT_EQ(scene.get<Springs>()[0].k, 4.0);
  EXPECT_EQ(distance(scene, scene.get<Springs>()[0]) - scene.get<Springs>()[0].rest, 0.25);
  EXPECT_EQ(scene.particles[1].x.y(), 0.0);  // stretched along the spring axis
  EXPECT_EQ(scene.particles[1].v, Eigen::Vector3d::Zero());
  // Undamped and unforced: the exact solution holds.
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d::Zero());
  EXPECT_EQ(scene.get<Drag>().gamma, 0.0);
  EXPECT_EQ(scene.get<Springs>()[0].damping, 0.0);
  EXPECT_FALSE(scene.has<Wind>());
  // A compressed start is allowed while the length stays positive; a zero-rest spring too.
  EXPECT_EQ(make_builtin_scene("oscillator", {{"rest", "1"}, {"amplitude", "-0.5"}}).particles[1].x.x(),
            0.5);
  // The default is the zero-rest (linear in every direction) spring.
  EXPECT_EQ(make_builtin_scene("oscillator").get<Springs>()[0].rest, 0.0);
}

TEST(BuiltinScenesTest, ChainStretchPlacesParticlesBeyondTheRestLength) {
  const Scene scene = make_builtin_scene("chain", {{"n", "5"}, {"stretch", "0.01"}, {"g", "0"}});
  for (const Spring& s : scene.get<Springs>()) {
    EXPECT_DOUBLE_EQ(s.rest, 0.25);
    EXPECT_NEAR(distance(scene, s), 0.25 * 1.01, 1e-15);
  }
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d::Zero());
}

TEST(BuiltinScenesTest, ChainHasNParticlesAndSpringsSummingToItsLength) {
  for (const int n : {2, 3, 10, 1000}) {
    SCOPED_TRACE(n);
    const Scene scene =
        make_builtin_scene("chain", {{"n", std::to_string(n)}, {"length", "2.5"}, {"mass", "0.3"}});
    ASSERT_EQ(scene.particles.size(), static_cast<std::size_t>(n));
    ASSERT_EQ(scene.get<Springs>().size(), static_cast<std::size_t>(n - 1));
    double total_rest = 0;
    for (std::size_t s = 0; s < scene.get<Springs>().size(); ++s) {
      EXPECT_EQ(scene.get<Springs>()[s].i, static_cast<int>(s));
      EXPECT_EQ(scene.get<Springs>()[s].j, static_cast<int>(s) + 1);
      EXPECT_NEAR(distance(scene, scene.get<Springs>()[s]), scene.get<Springs>()[s].rest, 1e-12);
      total_rest += scene.get<Springs>()[s].rest;
    }
    EXPECT_NEAR(total_rest, 2.5, 1e-12);
    EXPECT_TRUE(scene.particles[0].fixed);
    for (std::size_t p = 1; p < scene.particles.size(); ++p) EXPECT_FALSE(scene.particles[p].fixed);
    for (const Particle& p : scene.particles) {
      EXPECT_EQ(p.mass, 0.3);   // per particle
      EXPECT_EQ(p.x.x(), 0.0);  // hanging straight down
    }
    EXPECT_NEAR(scene.particles.back().x.y(), -2.5, 1e-12);
  }
}

TEST(BuiltinScenesTest, ChainParametersChangeTheScene) {
  const Scene scene = make_builtin_scene(
      "chain",
      {{"n", "4"}, {"k", "50"}, {"drag", "0.2"}, {"g", "3"}, {"horizontal", "1"}, {"length", "3"}});
  EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d(0, -3, 0));
  EXPECT_EQ(scene.get<Drag>().gamma, 0.2);
  for (const Spring& s : scene.get<Springs>()) EXPECT_EQ(s.k, 50.0);
  for (std::size_t p = 0; p < scene.particles.size(); ++p) {
    EXPECT_EQ(scene.particles[p].x,
              Eigen::Vector3d(static_cast<double>(p), 0, 0));  // released from horizontal
  }
}

TEST(BuiltinScenesTest, ClothCountsMassAndFixedCorners) {
  for (const int n : {2, 3, 4, 16}) {
    SCOPED_TRACE(n);
    const Scene scene =
        make_builtin_scene("cloth", {{"n", std::to_string(n)}, {"mass", "2.5"}, {"size", "3"}});
    EXPECT_EQ(scene.dimension, 3);
    ASSERT_EQ(scene.particles.size(), static_cast<std::size_t>(n * n));
    const std::size_t springs = 2 * n * (n - 1) + 2 * (n - 1) * (n - 1) + 2 * n * (n - 2);
    EXPECT_EQ(scene.get<Springs>().size(), springs);
    std::vector<int> fixed;
    double total_mass = 0;
    for (std::size_t p = 0; p < scene.particles.size(); ++p) {
      if (scene.particles[p].fixed) fixed.push_back(static_cast<int>(p));
      total_mass += scene.particles[p].mass;
      EXPECT_EQ(scene.particles[p].x.y(), 0.0);  // flat in the x-z plane
    }
    EXPECT_EQ(fixed, (std::vector<int>{0, n - 1}));
    EXPECT_NEAR(total_mass, 2.5, 1e-12);
    // Particle (r, c) = r n + c sits at (c s, 0, r s).
    const double s = 3.0 / (n - 1);
    EXPECT_NEAR((scene.particles[n * n - 1].x - Eigen::Vector3d(3, 0, 3)).norm(), 0, 1e-12);
    EXPECT_NEAR((scene.particles[n].x - Eigen::Vector3d(0, 0, s)).norm(), 0, 1e-12);
    // Structural first, then shear, then bend: the rest lengths say which is which.
    const std::size_t structural = 2 * n * (n - 1), shear = 2 * (n - 1) * (n - 1);
    for (std::size_t i = 0; i < scene.get<Springs>().size(); ++i) {
      const double expected = i < structural           ? s
                              : i < structural + shear ? s * std::sqrt(2.0)
                                                       : 2 * s;
      EXPECT_NEAR(scene.get<Springs>()[i].rest, expected, 1e-12) << "spring " << i;
      EXPECT_EQ(scene.get<Springs>()[i].rest, distance(scene, scene.get<Springs>()[i]));
    }
    EXPECT_EQ(scene.get<Gravity>().acceleration, Eigen::Vector3d(0, -9.81, 0));
    EXPECT_FALSE(scene.has<Wind>());
  }
}

TEST(BuiltinScenesTest, ClothStiffnessesGoToTheirSpringFamilies) {
  const int n = 5;
  const Scene scene =
      make_builtin_scene("cloth", {{"n", "5"}, {"k", "11"}, {"k_shear", "22"}, {"k_bend", "33"}});
  const std::size_t structural = 2 * n * (n - 1), shear = 2 * (n - 1) * (n - 1);
  for (std::size_t i = 0; i < scene.get<Springs>().size(); ++i) {
    const double expected = i < structural ? 11 : i < structural + shear ? 22 : 33;
    EXPECT_EQ(scene.get<Springs>()[i].k, expected) << "spring " << i;
  }
}

TEST(BuiltinScenesTest, ClothWindBlowsAlongZWithAOneSecondRelaxation) {
  const Scene scene =
      make_builtin_scene("cloth", {{"n", "4"}, {"mass", "3.2"}, {"wind", "-2"}, {"drag", "0.1"}});
  ASSERT_TRUE(scene.has<Wind>());
  EXPECT_EQ(scene.find<Wind>()->velocity, Eigen::Vector3d(0, 0, -2));
  EXPECT_EQ(scene.find<Wind>()->coefficient, 3.2 / 16);  // = particle mass
  EXPECT_EQ(scene.find<Wind>()->coefficient, scene.particles[5].mass);
  EXPECT_EQ(scene.find<Wind>()->gust, 0.5);
  EXPECT_EQ(scene.find<Wind>()->frequency, 0.5);
  EXPECT_EQ(scene.get<Drag>().gamma, 0.1);
}

}  // namespace
}  // namespace springlab::test_builtin_scenes
