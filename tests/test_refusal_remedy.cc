// A refused pairing carries its remedy as data (models/core/refusal.h; issue
// 47 item 4): the scene setting that would make it work, which the command
// line turns into `-p field=value` for a built-in scene with that parameter.
// The remedy is checked here as fields, and each fix is checked to work:
// the scene with the remedy applied is no longer refused.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "experiments/driver/simulation.h"
#include "models/model/model.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab::test_refusal_remedy {
namespace {

using Overrides = std::vector<std::pair<std::string, std::string>>;

// The remedy of the refusal of `integrator` on the scene, or nullopt-like
// empty field with "(accepted)" when the pairing is not refused.
SceneRemedy remedy_of(const std::string& scene, const Overrides& p, const std::string& integrator) {
  const Model model(make_builtin_scene(scene, p));
  RunSettings settings;
  settings.integrator = integrator;
  try {
    prepare_integrator(model, settings);
  } catch (const RunRefused& e) {
    // The line names the method once; the reason is the same sentence
    // without the name (the command line's "--integrator xpbd: <reason>").
    EXPECT_EQ(std::string(e.what()), integrator + ": " + e.reason());
    EXPECT_EQ(e.reason().find(integrator + ":"), std::string::npos) << e.reason();
    return e.remedy();
  }
  return {"(accepted)", "", ""};
}

struct Case {
  const char* scene;
  Overrides parameters;
  const char* field;
  const char* value;
};

TEST(RefusalRemedy, IsTheSettingThatMakesThePairingWork) {
  const std::vector<Case> cases = {
      {"block", {{"n", "1"}}, "model", "corotated"},
      {"beam", {{"nx", "2"}, {"ny", "1"}, {"model", "stvk"}}, "model", "corotated"},
      {"membrane", {{"n", "3"}, {"model", "neo-hookean"}}, "model", "corotated"},
      {"cloth", {{"n", "3"}, {"ground", "1"}, {"contact", "1"}}, "contact", "0"},
  };
  for (const char* method : {"xpbd", "projective-dynamics"}) {
    for (const Case& c : cases) {
      SCOPED_TRACE(std::string(method) + " on " + c.scene);
      const SceneRemedy remedy = remedy_of(c.scene, c.parameters, method);
      EXPECT_EQ(remedy.field, c.field);
      EXPECT_EQ(remedy.value, c.value);
      // The remedy applied (a later -p wins): accepted.
      Overrides fixed = c.parameters;
      fixed.emplace_back(remedy.field, remedy.value);
      EXPECT_EQ(remedy_of(c.scene, fixed, method).field, "(accepted)");
    }
  }
}

// A refusal no scene setting mends has no remedy (a fluid for projective
// dynamics: no material or contact choice makes SPH projective).
TEST(RefusalRemedy, EmptyWhereNoSettingHelps) {
  EXPECT_TRUE(remedy_of("tank", {{"spacing", "0.1"}}, "projective-dynamics").empty());
}

}  // namespace
}  // namespace springlab::test_refusal_remedy
