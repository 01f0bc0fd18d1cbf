// The run options declared once (integrators/core/integrator_options.h, issue
// 32.4): every option a method reads is declared; the command line offers
// and checks exactly the declared ones; an experiment definition reads and
// checks them through the same declaration.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/kinds/definition.h"
#include "experiments/kinds/experiment_support.h"
#include "integrators/core/integrator_options.h"
#include "integrators/registry/registry.h"
#include "run_process.h"

namespace springlab::test_integrator_options {
namespace {

TEST(IntegratorOptions, EveryOptionAMethodReadsIsDeclared) {
  for (const std::string& name : integrator_names()) {
    SCOPED_TRACE(name);
    for (const std::string& option : make_integrator(name)->options_read()) {
      EXPECT_NE(find_integrator_option(option), nullptr) << "--" << option << " is not declared";
    }
  }
}

TEST(IntegratorOptions, TheCommandLineOffersEveryDeclaredOptionWithItsDefault) {
  testing::TempDir temp("integrator-options");
  std::filesystem::create_directories(temp.path() / "io");
  for (const char* command : {"run", "stability"}) {
    const testing::ProcessResult help =
        testing::run_springlab({command, "--help"}, temp.path(), temp.path() / "io");
    ASSERT_TRUE(help.exited && help.status == 0) << help.err;
    for (const OptionSpec& spec : integrator_options()) {
      const std::string option = "--" + std::string(spec.name);
      const auto at = help.out.find(option + " ");
      ASSERT_NE(at, std::string::npos) << command << ": " << option;
      if (*spec.default_text != '\0') {
        const std::string shown = help.out.substr(at, help.out.find('\n', at) - at);
        EXPECT_NE(shown.find(std::string("=") + spec.default_text), std::string::npos) << shown;
      }
      if (!spec.choices.empty() && std::string(command) == "run") {
        // A name that is not a choice is refused, naming the choices.
        const testing::ProcessResult r = testing::run_springlab(
            {command, "spring", "--integrator", "implicit-euler", "--t-end", "0.1", "--dt", "0.01",
             option, "bogus"},
            temp.path(), temp.path() / "io");
        EXPECT_EQ(r.status, 1);
        std::string list;
        for (std::string_view c : spec.choices) list += (list.empty() ? "" : ", ") + std::string(c);
        EXPECT_NE(r.err.find(option + ": unknown 'bogus' (" + list + ")"), std::string::npos)
            << r.err;
      }
    }
  }
}

TEST(IntegratorOptions, RangesAreCheckedFromTheDeclaration) {
  IntegratorOptions o;
  const OptionSpec& newton_tol = *find_integrator_option("newton-tol");
  EXPECT_EQ(check_option_range(newton_tol, o, false), "");
  o.newton_tol = -1.0;
  EXPECT_EQ(check_option_range(newton_tol, o, true), "must be a positive number (got -1)");
  const OptionSpec& substeps = *find_integrator_option("substeps");
  EXPECT_EQ(check_option_range(substeps, o, false), "") << "0: the method's own";
  o.substeps = kMaxInnerCount + 1;
  EXPECT_EQ(check_option_range(substeps, o, true),
            "must be between 1 and 100000 (got 100001)");
  const OptionSpec& chebyshev = *find_integrator_option("chebyshev");
  o.chebyshev = 1.0;
  EXPECT_EQ(check_option_range(chebyshev, o, true), "must be in [0, 1) (0: off)");
}

TEST(IntegratorOptions, DefinitionsReadTheDeclaredNamesWithUnderscores) {
  const nlohmann::json good = {{"rtol", 1e-8}, {"newton_tol", 1e-7}, {"max_newton", 7},
                               {"stiffness", "definite"}, {"stald", true}};
  const IntegratorOptions o = definition_options(DefinitionObject(good, "d.json", ""));
  EXPECT_EQ(o.rtol, 1e-8);
  EXPECT_EQ(o.newton_tol, 1e-7);
  EXPECT_EQ(o.max_newton, 7);
  EXPECT_EQ(o.stiffness, Stiffness::kDefinite);
  EXPECT_TRUE(o.stald);
  auto refusal = [](const nlohmann::json& j) {
    try {
      definition_options(DefinitionObject(j, "d.json", ""));
    } catch (const DefinitionError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal({{"newton_tol", -1}}).find("newton_tol: must be a positive number (got -1)"),
            std::string::npos);
  EXPECT_NE(refusal({{"max_newton", 0}}).find("max_newton: must be >= 1"), std::string::npos);
  EXPECT_NE(refusal({{"solver", "bfgs"}}).find("solver: unknown 'bfgs' (newton, quasi-newton)"),
            std::string::npos);
}

}  // namespace
}  // namespace springlab::test_integrator_options
