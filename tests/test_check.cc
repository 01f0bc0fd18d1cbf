// `springlab check` (experiments/analysis/claims.h): every built-in method
// passes the claims `list` states for it, and each seeded mistake
// (tests/plugins/seeded_mistakes.cc, loaded by the command line as a
// plug-in) fails the claim it breaks, named in --json; the example plug-ins
// (examples/plugins) pass theirs. Short runs: seconds per method.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>
#include <nlohmann/json.hpp>

#include "experiments/analysis/claims.h"
#include "integrators/registry/registry.h"
#include "registry_suite.h"
#include "run_process.h"

namespace springlab::test_check {
namespace {

using testing::ProcessResult;
using testing::run_springlab;
using testing::write_text;
namespace fs = std::filesystem;

class EveryBuiltinPassesItsClaims : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryBuiltinPassesItsClaims, Check) {
  const std::string name = GetParam();
  const Claims claims = stated_claims(make_integrator(name)->info());
  const CheckReport report =
      check_claims({name, "--integrator " + name, "springlab check " + name}, claims);
  EXPECT_TRUE(report.passed()) << check_report_text(report);
  EXPECT_FALSE(report.results.empty());
  RecordProperty("claims", static_cast<int>(report.results.size()));
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryBuiltinPassesItsClaims,
                         ::testing::ValuesIn(integrator_names()), ::springlab::testing::registry_test_name);

// The claims a built-in states are the ones its IntegratorInfo declares.
TEST(StatedClaims, FollowTheDeclaration) {
  const Claims verlet = stated_claims(make_integrator("verlet")->info());
  ASSERT_TRUE(verlet.order && verlet.stable_limit);
  EXPECT_EQ(*verlet.order, 2);
  EXPECT_DOUBLE_EQ(*verlet.stable_limit, 2.0);
  EXPECT_TRUE(verlet.symplectic);
  EXPECT_FALSE(verlet.a_stable);
  const Claims implicit = stated_claims(make_integrator("implicit-euler")->info());
  EXPECT_TRUE(implicit.a_stable && implicit.dissipative);
  EXPECT_FALSE(implicit.stable_limit.has_value());
  const Claims cvode = stated_claims(make_integrator("cvode-bdf")->info());
  EXPECT_FALSE(cvode.order.has_value());
  EXPECT_TRUE(cvode.deterministic);
}

// A claim a method does not have fails, with its numbers: explicit Euler
// gains energy (not symplectic, not dissipative, not momentum-conserving),
// RK4 is not second order... it is fourth (the claim is "at least").
TEST(Check, WrongClaimsOfBuiltinsFail) {
  Claims claims;
  claims.symplectic = true;
  claims.dissipative = true;
  claims.momentum = true;
  claims.stable_limit = 2.0;
  const CheckReport euler = check_claims(
      {"explicit-euler", "--integrator explicit-euler", "springlab check explicit-euler"}, claims);
  ASSERT_EQ(euler.results.size(), 4u);
  for (const ClaimResult& r : euler.results) {
    EXPECT_FALSE(r.passed) << r.claim << ": " << r.measured;
    EXPECT_FALSE(r.run.empty()) << r.claim;
    if (r.claim == "--dissipative") {
      // It diverges at w h = 1, but the rise at w h = 0.1 is named first:
      // explicit Euler on the oscillator has E_{n+1} = (1 + (w h)^2) E_n
      // exactly, so the largest rise of 200 steps is the last,
      // (w h)^2 (1 + (w h)^2)^199 E_0.
      EXPECT_NEAR(r.figures["largest_rise"]["0.1"].get<double>(), 0.01 * std::pow(1.01, 199), 1e-6)
          << r.measured;
      EXPECT_NE(r.measured.find("the energy rises"), std::string::npos) << r.measured;
    }
  }
  Claims order;
  order.order = 6;
  const CheckReport rk4 = check_claims({"rk4", "--integrator rk4", "springlab check rk4"}, order);
  ASSERT_EQ(rk4.results.size(), 1u);
  EXPECT_FALSE(rk4.results[0].passed) << rk4.results[0].measured;
  const double observed = rk4.results[0].figures["observed_order"].get<double>();
  EXPECT_NEAR(observed, 4.0, 0.3);
}

TEST(Check, MomentumHoldsForVerletNotRk4) {
  Claims claims;
  claims.momentum = true;
  const CheckReport verlet = check_claims({"verlet", "--integrator verlet", "springlab check verlet"}, claims);
  EXPECT_TRUE(verlet.passed()) << check_report_text(verlet);
  const CheckReport euler = check_claims(
      {"explicit-euler", "--integrator explicit-euler", "springlab check explicit-euler"}, claims);
  EXPECT_FALSE(euler.passed()) << check_report_text(euler);
}

TEST(Check, AdaptiveMethodsRefuseStepClaims) {
  Claims claims;
  claims.order = 2;
  EXPECT_THROW(check_claims({"cvode-bdf", "--integrator cvode-bdf", "springlab check cvode-bdf"}, claims),
               std::invalid_argument);
}

// The command line: a seeded mistake fails the claim it breaks, exit 1.
struct Seeded {
  const char* method;
  const char* broken;  // the claim that must FAIL
};

void PrintTo(const Seeded& s, std::ostream* os) { *os << s.method << " breaks " << s.broken; }

class SeededMistake : public ::testing::TestWithParam<Seeded> {};

TEST_P(SeededMistake, FailsNamingTheClaim) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("seeded-" + std::string(GetParam().method));
  fs::create_directories(dir);
  const ProcessResult r = run_springlab(
      {"check", GetParam().method, "--plugin", SPRINGLAB_SEEDED_PLUGIN, "--json"}, dir, dir);
  ASSERT_EQ(r.status, 1) << r.out << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j.at("passed").get<bool>());
  bool named = false;
  for (const nlohmann::json& c : j.at("claims")) {
    if (c.at("claim").get<std::string>() == GetParam().broken) {
      named = true;
      EXPECT_FALSE(c.at("passed").get<bool>()) << c.dump();
      EXPECT_FALSE(c.at("run").get<std::string>().empty());
    }
  }
  EXPECT_TRUE(named) << r.out;
}

INSTANTIATE_TEST_SUITE_P(
    Plugins, SeededMistake,
    ::testing::Values(Seeded{"wrong-half-kick-verlet", "--order 2"},
                      Seeded{"explicit-force-implicit-euler", "--a-stable"},
                      Seeded{"wrong-weight-rk4", "--order 4"},
                      Seeded{"not-symplectic-heun", "--symplectic"}),
    [](const ::testing::TestParamInfo<Seeded>& info) {
      std::string name = info.param.method;
      std::replace(name.begin(), name.end(), '-', '_');
      return name;
    });

// The heun plug-in's order claim holds while its symplectic claim fails:
// the text names each, one line per claim, and the command to rerun it.
TEST(CheckCommand, TextNamesEachClaim) {
  const fs::path dir = fs::path(::testing::TempDir()) / "check-text";
  fs::create_directories(dir);
  const ProcessResult r =
      run_springlab({"check", "not-symplectic-heun", "--plugin", SPRINGLAB_SEEDED_PLUGIN}, dir, dir);
  ASSERT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.out.find("PASS  --order 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("FAIL  --symplectic"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("springlab run oscillator -p k=1 -p mass=1 -p amplitude=1 --integrator "
                       "not-symplectic-heun --plugin " SPRINGLAB_SEEDED_PLUGIN),
            std::string::npos)
      << r.out;
}

// The example plug-ins pass the claims they declare, and the symplectic
// Euler is the built-in's trajectory exactly (the sanity line).
TEST(CheckCommand, ExamplePluginsPass) {
  const fs::path dir = fs::path(::testing::TempDir()) / "check-examples";
  fs::create_directories(dir);
  for (const char* method : {"my-symplectic-euler", "my-implicit-euler"}) {
    const ProcessResult r =
        run_springlab({"check", method, "--plugin", SPRINGLAB_EXAMPLE_PLUGIN, "--json"}, dir, dir);
    ASSERT_EQ(r.status, 0) << method << "\n" << r.out << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j.at("passed").get<bool>());
    if (std::string(method) == "my-symplectic-euler") {
      ASSERT_FALSE(j.at("sanity").is_null()) << r.out;
      EXPECT_EQ(j.at("sanity").at("builtin"), "symplectic-euler");
      EXPECT_EQ(j.at("sanity").at("max_difference").get<double>(), 0.0);
    }
  }
}

TEST(CheckCommand, PluginMistakesAreOneLine) {
  const fs::path dir = fs::path(::testing::TempDir()) / "check-refusals";
  fs::create_directories(dir);
  write_text(dir / "not-a-library.so", "text");
  ProcessResult r = run_springlab({"check", "x", "--plugin", "not-a-library.so"}, dir, dir);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("springlab: error: not-a-library.so: cannot load the plug-in: "), std::string::npos) << r.err;
  r = run_springlab({"run", "spring", "--integrator", "x", "--dt", "0.1", "--t-end", "1", "--plugin", "missing.so"}, dir, dir);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("springlab: error: missing.so: no such plug-in file"), std::string::npos) << r.err;
  // The same plug-in named twice is loaded once (its names are not taken twice).
  r = run_springlab({"check", "verlet", "--plugin", SPRINGLAB_EXAMPLE_PLUGIN, "--plugin", SPRINGLAB_EXAMPLE_PLUGIN, "--order", "2"}, dir, dir);
  EXPECT_EQ(r.status, 0) << "loading the same plug-in twice is loading it once: " << r.err;
}

// An experiment definition's "plugins": the plug-in's method runs beside the
// built-in it reimplements (the same energy at every output, to round-off),
// and the settings file lists its facts under "own_integrators" (the report
// draws it in its family); the built-ins are not listed there.
TEST(OwnMethods, DefinitionPluginsRunBesideTheBuiltins) {
  const fs::path dir = fs::path(::testing::TempDir()) / "own-methods-definition";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_text(dir / "d.json",
             std::string(R"({"experiment": "energy", "name": "own", "plugins": [")") +
                 SPRINGLAB_EXAMPLE_PLUGIN +
                 R"("], "integrators": ["symplectic-euler", "my-symplectic-euler"],
                 "cases": [{"scene": "oscillator", "dt": 0.05, "t_end": 2}]})");
  const ProcessResult r = run_springlab({"experiment", "d.json", "--out", "out"}, dir, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream settings_file(dir / "out" / "own.json");
  const nlohmann::json settings = nlohmann::json::parse(settings_file);
  ASSERT_TRUE(settings.contains("own_integrators")) << settings.dump(2);
  const nlohmann::json& own = settings.at("own_integrators");
  ASSERT_EQ(own.size(), 1u) << own.dump();
  EXPECT_EQ(own[0].at("name"), "my-symplectic-euler");
  EXPECT_EQ(own[0].at("family"), "symplectic");
  EXPECT_EQ(own[0].at("stability").at("limit_wh").get<double>(), 2.0);
  std::ifstream table(dir / "out" / "own.csv");
  std::string line;
  std::getline(table, line);  // task,scene,integrator,dt,t,kinetic,spring,gravity,total
  std::map<std::string, std::vector<double>> total;
  while (std::getline(table, line)) {
    std::vector<std::string> cell;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cell.push_back(c);
    ASSERT_EQ(cell.size(), 9u) << line;
    total[cell[2]].push_back(std::stod(cell[8]));
  }
  ASSERT_EQ(total.size(), 2u);
  ASSERT_EQ(total["my-symplectic-euler"].size(), 41u);  // t = 0, 0.05, ..., 2
  ASSERT_EQ(total["symplectic-euler"].size(), 41u);
  for (std::size_t k = 0; k < 41; ++k) {
    EXPECT_NEAR(total["my-symplectic-euler"][k], total["symplectic-euler"][k], 1e-12) << k;
  }
}

}  // namespace
}  // namespace springlab::test_check
