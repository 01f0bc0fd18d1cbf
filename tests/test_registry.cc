// The one registration idiom (models/core/registry.h): every registry keeps
// its entries in its file's order, finds them by name, refuses a name given
// twice, and answers an unknown name with the closest ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/kinds/experiment.h"
#include "integrators/registry/registry.h"
#include "models/core/registry.h"
#include "models/materials/material.h"
#include "models/model/element_registry.h"

namespace springlab::test_registry {
namespace {

TEST(Registry, ClosestNamesForeseeTyposCaseAndSeparators) {
  const std::vector<std::string> names = integrator_names();
  EXPECT_EQ(closest_names("implicit-eulr", names), std::vector<std::string>{"implicit-euler"});
  EXPECT_EQ(closest_names("RK4", names), std::vector<std::string>{"rk4"});
  // Equal but for case: that one only, not every name one letter away.
  EXPECT_EQ(closest_names("N", {"n", "k", "g", "mass"}), std::vector<std::string>{"n"});
  EXPECT_EQ(closest_names("x", {"n", "k"}), (std::vector<std::string>{"n", "k"}));
  EXPECT_EQ(closest_names("symplectic_euler", names),
            std::vector<std::string>{"symplectic-euler"});
  EXPECT_EQ(closest_names("yoshdia4", names).front(), "yoshida4");  // two letters swapped
  EXPECT_TRUE(closest_names("frobnicate", names).empty());
  EXPECT_TRUE(closest_names("", names).empty());
  EXPECT_EQ(did_you_mean("newmrak", names), " (did you mean 'newmark'?)");
}

TEST(Registry, AnUnknownIntegratorNamesTheClosestAndListsAll) {
  try {
    make_integrator("implicit-eulr");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("unknown integrator 'implicit-eulr' (did you mean 'implicit-euler'?) "
                         "(integrators: arkode-dirk, ",
                         0),
              0u)
        << what;
  }
}

struct Named {
  std::string name;
};
const Named& first_named() {
  static const Named n{"first"};
  return n;
}
const Named& second_named() {
  static const Named n{"second"};
  return n;
}

TEST(Registry, KeepsItsOrderFindsByNameAndRefusesANameTwice) {
  Registry<Named> registry = {&second_named, &first_named};
  EXPECT_EQ(registry.names(), (std::vector<std::string>{"second", "first"}));
  EXPECT_EQ(registry.find("first"), &first_named());
  EXPECT_EQ(registry.find("third"), nullptr);
  static const Named third{"third"};
  registry.add(third);
  EXPECT_EQ(registry.find("third"), &third);
  static const Named again{"first"};
  EXPECT_THROW(registry.add(again), std::invalid_argument);
  EXPECT_EQ(registry.unknown("thing", "secnod"),
            "unknown thing 'secnod' (did you mean 'second'?) (things: first, second, third)");
}

// Each of the five registries holds what its file lists, under unique names.
TEST(Registry, EveryRegistryHasUniqueNames) {
  auto unique = [](std::vector<std::string> names) {
    std::sort(names.begin(), names.end());
    return std::adjacent_find(names.begin(), names.end()) == names.end() && !names.empty();
  };
  EXPECT_TRUE(unique(integrator_registry().names()));
  EXPECT_TRUE(unique(element_registry().names()));
  std::vector<std::string> materials, kinds;
  for (const MaterialModel* m : material_models()) materials.emplace_back(m->name);
  for (const ExperimentKind* k : experiment_kinds()) kinds.emplace_back(k->name);
  EXPECT_TRUE(unique(materials));
  EXPECT_TRUE(unique(kinds));
  EXPECT_EQ(materials.front(), "linear");  // built-in scenes' `model` index 0
}

}  // namespace
}  // namespace springlab::test_registry
