#include "experiments/cli/integrator_table.h"

#include "experiments/driver/divergence.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

#include "experiments/kinds/integrator_facts.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab {
namespace {

// One line per method. Hues follow the families (warm: explicit; green/blue:
// symplectic; purple/pink: implicit; dark tones: adaptive) and no two methods
// share a colour or a marker, so lines stay apart even where they coincide.
const std::map<std::string, IntegratorStyle>& style_table() {
  static const std::map<std::string, IntegratorStyle> table = {
      {"explicit-euler", {"#d62728", "o"}},
      {"rk4", {"#ff7f0e", "s"}},
      {"symplectic-euler", {"#2ca02c", "^"}},
      {"verlet", {"#17becf", "v"}},
      {"implicit-midpoint", {"#1f77b4", "D"}},
      {"implicit-euler", {"#9467bd", "P"}},
      {"linear-implicit-euler", {"#e377c2", "X"}},
      {"discrete-gradient", {"#8c564b", "h"}},
      {"projective-dynamics", {"#bcbd22", "8"}},
      {"xpbd", {"#6b6ecf", "1"}},
      {"vbd", {"#c51b7d", "$V$"}},
      {"cvode-bdf", {"#000000", "<"}},
      {"cvode-adams", {"#e6ab02", ">"}},
      {"ida", {"#7f7f7f", "p"}},
      {"arkode-erk", {"#843c39", "*"}},
      {"arkode-dirk", {"#393b79", "d"}},
      {"arkode-imex", {"#637939", "H"}},
      {"central-difference", {"#98df8a", "+"}},
      {"yoshida4", {"#1b9e77", "$4$"}},
      {"yoshida6", {"#0b5345", "$6$"}},
      {"newmark", {"#c5b0d5", "x"}},
      {"linear-acceleration", {"#f7b6d2", "2"}},
      {"fox-goodwin", {"#ad494a", "3"}},
      {"hht-alpha", {"#7b4173", "4"}},
      {"generalized-alpha", {"#ce6dbd", "$\\alpha$"}},
      {"bdf2", {"#5254a3", "$2$"}},
      {"tr-bdf2", {"#a55194", "$T$"}},
  };
  return table;
}

// FNV-1a: a hash that is the same on every machine and run.
std::uint32_t stable_hash(const std::string& text) {
  std::uint32_t h = 2166136261u;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 16777619u;
  }
  return h;
}

}  // namespace

IntegratorStyle integrator_style(const std::string& name) {
  const auto& table = style_table();
  const auto it = table.find(name);
  if (it != table.end()) return it->second;
  static const char* const kReserveColours[] = {"#3182bd", "#31a354", "#756bb1", "#e6550d",
                                               "#636363", "#d6616b", "#17a589"};
  static const char* const kReserveMarkers[] = {"8", "1", "2", "3", "4", "+"};
  const std::uint32_t h = stable_hash(name);
  return {kReserveColours[h % 7], kReserveMarkers[(h / 7) % 6]};
}

nlohmann::ordered_json integrator_table_json() {
  using Json = nlohmann::ordered_json;
  Json integrators = Json::array();
  for (const std::string& name : integrator_names()) {
    const IntegratorInfo info = make_integrator(name)->info();
    const IntegratorStyle style = integrator_style(name);
    Json entry = integrator_facts_json(name, info);
    entry["colour"] = style.colour;
    entry["marker"] = style.marker;
    integrators.push_back(entry);
  }
  Json scenes = Json::array();
  for (const BuiltinScene& s : builtin_scenes()) {
    Json parameters = Json::array();
    for (const SceneParameter& p : s.parameters) {
      Json parameter = {{"name", p.name}, {"default", p.default_value}, {"meaning", p.meaning}};
      if (!p.choices.empty()) parameter["choices"] = p.choices;  // the default: their index
      parameters.push_back(parameter);
    }
    scenes.push_back({{"name", s.name}, {"description", s.description}, {"parameters", parameters}});
  }
  // docs/command-line.md "Divergence": the rule for each kind of matter.
  return {{"integrators", integrators}, {"scenes", scenes}, {"divergence", divergence_sentences()}};
}

}  // namespace springlab
