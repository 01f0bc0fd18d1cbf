// The suites instantiated over the registries (integrators, materials,
// element kinds), checked in one place against the registries. A suite whose
// tests apply to some entries only is instantiated over the entries its
// condition selects (tests/registry_suite.h, conditional_suites), so nothing
// is registered that could only be skipped; these tests make sure that no
// entry falls out of a suite that applies to it:
//   - a conditional suite has exactly the entries its condition selects, and
//     at least one;
//   - every other suite over a registry has every entry;
//   - every method has its accuracy and its declared stability checked by a
//     run, whichever of the conditional suites that takes.
// Each prints how many entries every suite has (run with --gtest_filter to
// see the table).
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "integrators/registry/registry.h"
#include "models/core/element_kind.h"
#include "models/materials/material.h"
#include "registry_suite.h"
#include "models/model/element_registry.h"

namespace springlab::test_registry_coverage {
namespace {

// What gtest instantiated, suite by suite ("Registry/EveryIntegrator"): the
// instance names of its tests (the part after the last '/' of
// "Test/instance") and the printed values of their parameters.
struct Instances {
  std::set<std::string> names, values;
  int tests = 0;
};

std::map<std::string, Instances> instantiated() {
  std::map<std::string, Instances> suites;
  const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
  for (int s = 0; s < unit.total_test_suite_count(); ++s) {
    const ::testing::TestSuite& suite = *unit.GetTestSuite(s);
    for (int t = 0; t < suite.total_test_count(); ++t) {
      const ::testing::TestInfo& test = *suite.GetTestInfo(t);
      if (test.value_param() == nullptr) continue;
      const std::string name = test.name();
      Instances& in = suites[suite.name()];
      in.names.insert(name.substr(name.rfind('/') + 1));
      in.values.insert(test.value_param());
      ++in.tests;
    }
  }
  return suites;
}

std::string underscored(std::string_view name) {
  std::string out(name);
  std::replace(out.begin(), out.end(), '-', '_');
  return out;
}

std::set<std::string> recorded(const std::string& suite) {
  const std::vector<std::string>& names = testing::conditional_suites().at(suite);
  return {names.begin(), names.end()};
}

// The suites of `suites` named `family`*, against `every` (the instance
// names of every entry): a conditional one has its recorded entries, any
// other has every entry. Prints one line per suite; returns how many
// suites each instance is in.
std::map<std::string, int> check_family(const std::map<std::string, Instances>& suites,
                                        const std::vector<std::string>& family,
                                        const std::set<std::string>& every, const char* what) {
  std::map<std::string, int> suites_of;
  for (const std::string& name : every) suites_of[name] = 0;
  for (const auto& [suite, in] : suites) {
    if (std::find(family.begin(), family.end(), suite) == family.end()) continue;
    const bool conditional = testing::conditional_suites().count(suite) > 0;
    if (conditional) {
      EXPECT_EQ(in.names, recorded(suite)) << suite;
    } else {
      EXPECT_EQ(in.names, every)
          << suite << " applies to every entry of the registry: instantiate it over them all, "
          << "or over the entries its condition selects (tests/registry_suite.h)";
    }
    for (const std::string& name : in.names) ++suites_of[name];
    std::cout << "  " << suite << ": " << in.names.size() << " of " << every.size() << " " << what
              << (conditional ? " (its condition)" : "") << ", " << in.tests << " tests\n";
  }
  return suites_of;
}

// Every conditional suite exists, has exactly the entries its condition
// selected (no second instantiation adds others) and at least one.
TEST(RegistryCoverage, ConditionalSuitesHaveTheEntriesTheirConditionSelects) {
  const std::map<std::string, Instances> suites = instantiated();
  ASSERT_FALSE(testing::conditional_suites().empty());
  for (const auto& [suite, names] : testing::conditional_suites()) {
    const auto it = suites.find(suite);
    ASSERT_NE(it, suites.end()) << suite << ": recorded, but gtest has no such suite";
    EXPECT_EQ(it->second.names, std::set<std::string>(names.begin(), names.end())) << suite;
    EXPECT_FALSE(names.empty()) << suite << ": its condition selects no entry";
    std::cout << "  " << suite << ": " << names.size() << " entries\n";
  }
}

TEST(RegistryCoverage, EveryIntegratorIsInEverySuiteThatAppliesToIt) {
  const std::map<std::string, Instances> suites = instantiated();
  std::set<std::string> every, values;
  for (const std::string& name : integrator_names()) {
    every.insert(testing::registry_test_name({name, 0}));
    values.insert(::testing::PrintToString(name));
  }
  // The suites over the integrators: their parameters are registered names.
  std::vector<std::string> family;
  for (const auto& [suite, in] : suites) {
    if (std::includes(values.begin(), values.end(), in.values.begin(), in.values.end())) {
      family.push_back(suite);
    }
  }
  std::cout << integrator_names().size() << " integrators in " << family.size() << " suites:\n";
  const std::map<std::string, int> suites_of = check_family(suites, family, every, "integrators");
  // The suites for every method are among them, unconditional.
  for (const std::string suite : {"Registry/EveryIntegrator", "Registry/DeclaredStability"}) {
    ASSERT_NE(std::find(family.begin(), family.end(), suite), family.end()) << suite;
    EXPECT_EQ(testing::conditional_suites().count(suite), 0u) << suite;
  }
  // What every method must have checked, by one of the suites whose
  // conditions split the methods.
  const std::vector<std::pair<std::string, std::vector<std::string>>> every_method_has = {
      {"its accuracy (order or tolerance)",
       {"Registry/EveryFixedStepIntegrator", "Registry/AdaptiveIntegrator"}},
      {"its declared stability by a run",
       {"Registry/DeclaredStabilityOnTheAxis", "Registry/DeclaredStabilityFixedStepDecay",
        "Registry/DeclaredStabilityAdaptiveDecay"}}};
  for (const auto& [what, alternatives] : every_method_has) {
    for (const std::string& name : every) {
      int in = 0;
      for (const std::string& suite : alternatives) {
        const auto it = suites.find(suite);
        ASSERT_NE(it, suites.end()) << suite;
        in += static_cast<int>(it->second.names.count(name));
      }
      EXPECT_GE(in, 1) << name << " has nothing checking " << what;
    }
  }
  std::cout << "suites per integrator:";
  for (const auto& [name, count] : suites_of) std::cout << " " << name << " " << count;
  std::cout << "\n";
}

TEST(RegistryCoverage, EveryMaterialAndKindIsInEverySuiteThatAppliesToIt) {
  const std::map<std::string, Instances> suites = instantiated();
  // Materials: every model on 2 x 2 and 3 x 3 F, and 3 x 2 where it has membranes.
  std::set<std::string> materials;
  for (const MaterialModel* m : material_models()) {
    materials.insert(underscored(m->name) + "_2x2");
    materials.insert(underscored(m->name) + "_3x3");
    if (m->membranes) materials.insert(underscored(m->name) + "_3x2");
  }
  // Element kinds: every kind in 2-D and 3-D, and all of them at once.
  std::set<std::string> kinds = {"all_2D", "all_3D"};
  for (const ElementKind* kind : element_kinds()) {
    kinds.insert(underscored(kind->name) + "_2D");
    kinds.insert(underscored(kind->name) + "_3D");
  }
  for (const auto& [prefix, every, what] :
       {std::tuple{"Registry/EveryMaterial", materials, "materials x shapes"},
        std::tuple{"Registry/EveryKind", kinds, "kinds x dimensions"}}) {
    std::vector<std::string> family;
    for (const auto& [suite, in] : suites) {
      if (suite.rfind(prefix, 0) == 0) family.push_back(suite);
    }
    ASSERT_NE(std::find(family.begin(), family.end(), prefix), family.end()) << prefix;
    EXPECT_EQ(testing::conditional_suites().count(prefix), 0u) << prefix;
    std::cout << every.size() << " " << what << " in " << family.size() << " suites:\n";
    const std::map<std::string, int> suites_of = check_family(suites, family, every, what);
    for (const auto& [name, count] : suites_of) EXPECT_GE(count, 1) << name;
  }
}

}  // namespace
}  // namespace springlab::test_registry_coverage
