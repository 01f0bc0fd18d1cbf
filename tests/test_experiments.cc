// The experiment framework (experiments/*.cc) in-process:
//   - ExperimentDefinition: the exact one-line messages parse_experiment
//     gives for broken definitions;
//   - ExperimentKinds: energy, stability, damping-budget and cloth-showcase
//     tasks run directly, their CSV rows read back and checked against what
//     the mathematics says they must contain (explicit Euler's exact energy
//     growth on the oscillator, stability limits against theory, the damping
//     budget of an accurate method, the last good state of a diverged cloth);
//   - ExperimentRunner: run_experiment writing files (shards and merge,
//     thread count, the settings file, nothing left behind on errors).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "experiments/analysis/stability.h"
#include "experiments/kinds/definition.h"
#include "csv_fields.h"
#include "experiment_tasks.h"
#include "run_process.h"
#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_runner.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"
#include "models/springs/springs.h"

namespace springlab::test_experiments {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using testing::definition_error;
using testing::Record;

// ---------------------------------------------------------------- helpers --

std::vector<std::string> split(const std::string& line) { return csv_fields::split_fields(line); }
double number(const std::string& field) { return csv_fields::field_number(field); }

bool close(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b));
}

LoadedExperiment parse(const Json& definition) { return testing::parse_definition(definition); }
std::vector<std::vector<Record>> run_task(const LoadedExperiment& loaded, std::size_t task) {
  return testing::task_rows(loaded, task);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> directory_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

// A fresh temporary directory (removed afterwards) to write definitions into.
class ScratchDir : public testing::TempDir {
 public:
  explicit ScratchDir(const std::string& tag) : TempDir("test-experiments-" + tag) {}
  // Writes a definition file into the directory; returns its path.
  std::string write(const std::string& file, const Json& definition) const {
    const fs::path p = path() / file;
    std::ofstream(p) << definition.dump(2) << "\n";
    return p.string();
  }
};

ExperimentRunOptions quiet(const fs::path& out, int jobs = 1) {
  ExperimentRunOptions o;
  o.out_dir = out.string();
  o.jobs = jobs;
  o.progress = false;
  return o;
}

// ------------------------------------------------------ ExperimentDefinition --

const Json kEnergy = {{"experiment", "energy"},
                      {"integrators", {"symplectic-euler"}},
                      {"cases", {{{"scene", "oscillator"}, {"dt", 0.05}, {"t_end", 1}}}}};

TEST(ExperimentDefinition, AValidDefinitionParses) {
  const LoadedExperiment loaded = parse(kEnergy);
  EXPECT_EQ(loaded.name, "energy");  // the kind when no name is given
  EXPECT_EQ(loaded.experiment->task_count(), 1u);
  EXPECT_EQ(loaded.definition, kEnergy);
}

TEST(ExperimentDefinition, MalformedJson) {
  const std::string message = definition_error(std::string(R"({"experiment": "energy",)"));
  EXPECT_EQ(message,
            "def.json: malformed JSON: parse error at line 1, column 25: syntax error while "
            "parsing object key - unexpected end of input; expected string literal");
  EXPECT_EQ(message.rfind("def.json: malformed JSON: ", 0), 0u) << message;
}

TEST(ExperimentDefinition, TopLevelMustBeAnObjectWithAKind) {
  EXPECT_EQ(definition_error(std::string("[1, 2]")), "def.json: top level: expected an object");
  EXPECT_EQ(definition_error(Json{{"name", "x"}}), "def.json: experiment: missing");
  EXPECT_EQ(definition_error(Json{{"experiment", 3}}),
            "def.json: experiment: expected a string, got number");
}

TEST(ExperimentDefinition, UnknownKindListsTheKinds) {
  EXPECT_EQ(definition_error(Json{{"experiment", "energi"}}),
            "def.json: experiment: unknown kind 'energi' (did you mean 'energy'?) (kinds: energy, "
            "convergence, "
            "work-precision, stability, damping-budget, cloth-showcase, stability-region, step-energy, "
            "motion, contact, mode, rotation, solver-error, spectral, rigid, fluid)");
  // Nothing close: no guess.
  EXPECT_EQ(definition_error(Json{{"experiment", "frobnicate"}}).find("did you mean"),
            std::string::npos);
}

TEST(ExperimentDefinition, UnknownTopLevelKey) {
  Json d = kEnergy;
  d["dtt"] = 0.01;
  EXPECT_EQ(definition_error(d),
            "def.json: unknown key 'dtt' (allowed: experiment, name, title, description, "
            "integrators, rtol, atol, newton_tol, cases)");
}

TEST(ExperimentDefinition, UnknownKeyInsideASecondCase) {
  Json d = kEnergy;
  d["cases"].push_back({{"scene", "oscillator"}, {"dt", 0.05}, {"t_end", 1}, {"step", 2}});
  EXPECT_EQ(definition_error(d),
            "def.json: cases[1]: unknown key 'step' (allowed: scene, parameters, dt, t_end, "
            "every)");
}

TEST(ExperimentDefinition, UnknownIntegratorName) {
  Json d = kEnergy;
  d["integrators"] = {"rk4", "forward-euler"};
  // The message lists every method, as the command line's does.
  EXPECT_EQ(definition_error(d).rfind("def.json: integrators: unknown integrator 'forward-euler' "
                                      "(integrators: arkode-dirk, ", 0),
            0u)
      << definition_error(d);
  d["integrators"] = {"rk4", "implicit_euler"};
  EXPECT_EQ(definition_error(d).rfind("def.json: integrators: unknown integrator 'implicit_euler' "
                                      "(did you mean 'implicit-euler'?) (integrators: ",
                                      0),
            0u)
      << definition_error(d);
  d["integrators"] = "implicit";
  EXPECT_EQ(definition_error(d),
            "def.json: integrators: expected \"all\", \"fixed-step\", \"adaptive\" or a list of "
            "names");
}

TEST(ExperimentDefinition, NonPositiveStep) {
  Json d = kEnergy;
  d["cases"][0]["dt"] = 0;
  EXPECT_EQ(definition_error(d), "def.json: cases[0].dt: must be > 0 (got 0)");
  d["cases"][0]["dt"] = -0.5;
  EXPECT_EQ(definition_error(d), "def.json: cases[0].dt: must be > 0 (got -0.5)");
  d["cases"][0]["dt"] = "0.1";
  EXPECT_EQ(definition_error(d), "def.json: cases[0].dt: expected a number, got string");
}

TEST(ExperimentDefinition, BuiltinParameterErrorInsideACase) {
  Json d = kEnergy;
  d["cases"][0]["parameters"] = {{"k", -1}};
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].parameters: scene 'oscillator': parameter 'k' must be > 0 "
            "(got -1)");
  d["cases"][0]["parameters"] = {{"stiffness", 5}};
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].parameters: scene 'oscillator': unknown parameter 'stiffness' "
            "(parameters: k, mass, rest, amplitude)");
}

TEST(ExperimentDefinition, StabilityRefusesAdaptiveIntegrators) {
  const Json d = {{"experiment", "stability"},
                  {"integrators", {"rk4", "cvode-bdf"}},
                  {"cases", {{{"scene", "oscillator"}, {"k", {100}}}}}};
  EXPECT_EQ(definition_error(d),
            "def.json: integrators: 'cvode-bdf' is adaptive: it has no step size to limit");
}

TEST(ExperimentDefinition, ClothFramesMustBeMultiplesOfTheStep) {
  Json d = {{"experiment", "cloth-showcase"},
            {"integrators", {"implicit-euler"}},
            {"scene", "cloth"},
            {"parameters", {{"n", 3}}},
            {"dt", 0.02},
            {"frames", {0.1, 0.13}}};
  EXPECT_EQ(definition_error(d), "def.json: frames: must increase and be whole multiples of dt");
  d["frames"] = {0.2, 0.1};
  EXPECT_EQ(definition_error(d), "def.json: frames: must increase and be whole multiples of dt");
  d["frames"] = {0.1, 0.2};
  EXPECT_EQ(definition_error(d), "");
}

// The name becomes file names: no folders, no hidden files, no control
// characters (a newline in a file name), nothing too long for one.
TEST(ExperimentDefinition, NameMustBeAPlainFileName) {
  const std::string plain =
      "def.json: name: must be a plain file name (no '/', no leading '.', no control characters)";
  Json d = kEnergy;
  for (const char* bad : {"results/energy", "..", "", "two\nlines", "tab\there", "bell\a"}) {
    d["name"] = bad;
    EXPECT_EQ(definition_error(d), plain) << bad;
  }
  d["name"] = std::string(101, 'e');
  EXPECT_EQ(definition_error(d),
            "def.json: name: longer than 100 characters (it names the output files)");
  d["name"] = std::string(100, 'e');
  EXPECT_EQ(definition_error(d), "");
}

// A key twice in one object is refused (the JSON library would keep the
// last one silently), naming the object, as scene files do.
TEST(ExperimentDefinition, DuplicateKeysAreRefused) {
  EXPECT_EQ(definition_error(std::string(R"({"experiment": "energy", "experiment": "energy",
                                 "cases": [{"scene": "spring", "dt": 0.01, "t_end": 1}]})")),
            "def.json: duplicate key 'experiment'");
  EXPECT_EQ(definition_error(std::string(R"({"experiment": "energy", "cases": [
                                 {"scene": "spring", "dt": 0.01, "t_end": 1},
                                 {"scene": "spring", "dt": 0.01, "dt": 0.02, "t_end": 1}]})")),
            "def.json: cases[1]: duplicate key 'dt'");
  EXPECT_EQ(definition_error(std::string(R"({"experiment": "energy", "cases": [{"scene": "chain",
                                 "parameters": {"n": 3, "n": 4}, "dt": 0.01, "t_end": 1}]})")),
            "def.json: cases[0].parameters: duplicate key 'n'");
}

// A scene name too long for the file system is a one-line refusal (it was a
// raw "filesystem error"), shown to 100 characters.
TEST(ExperimentDefinition, OverLongSceneNameIsRefused) {
  Json d = kEnergy;
  d["cases"][0]["scene"] = std::string(300, 's') + ".json";
  EXPECT_EQ(definition_error(d), "def.json: cases[0].scene: '" + std::string(100, 's') +
                                     "... (305 bytes)' is neither a built-in scene nor a file next "
                                     "to the definition");
}

TEST(ExperimentDefinition, AnIntegratorListedTwiceIsRefused) {
  Json d = kEnergy;
  d["integrators"] = {"rk4", "verlet", "rk4"};
  EXPECT_EQ(definition_error(d), "def.json: integrators: 'rk4' is listed twice");
}

// The JSON reader stops at a NUL byte: what follows must not be ignored.
TEST(ExperimentDefinition, NulByteIsRefused) {
  const std::string text = kEnergy.dump() + std::string(1, '\0') + "{garbage";
  EXPECT_EQ(definition_error(text),
            "def.json: malformed JSON: a NUL byte at line 1, column " +
                std::to_string(kEnergy.dump().size() + 1) + " (JSON text cannot hold one)");
}

// A sweep's own parameter cannot also be given as a fixed one.
TEST(ExperimentDefinition, SweptParameterGivenTwiceIsRefused) {
  const Json d = {{"experiment", "stability"},
                  {"integrators", {"rk4"}},
                  {"cases", {{{"scene", "oscillator"}, {"parameters", {{"k", 5}}}, {"k", {1, 2}}}}}};
  EXPECT_EQ(definition_error(d),
            "def.json: cases[0].parameters: 'k' is the parameter the sweep sets: leave it out");
}

TEST(ExperimentDefinition, ShippedDefinitionsParse) {
  // A definition's plug-ins named by file name are found in
  // SPRINGLAB_PLUGIN_PATH (the report's build sets it to the examples').
  const std::string plugin_dir = fs::path(SPRINGLAB_EXAMPLE_PLUGIN).parent_path().string();
  ASSERT_EQ(setenv("SPRINGLAB_PLUGIN_PATH", plugin_dir.c_str(), 1), 0);
  // experiments/long/: the definitions left out of the default report.
  const std::vector<std::pair<std::string, int>> dirs = {
      {SPRINGLAB_TEST_DATA "/experiments", 4},
      {SPRINGLAB_TEST_DATA "/../../experiments", 4},
      {SPRINGLAB_TEST_DATA "/../../experiments/long", 1}};
  for (const auto& [dir, at_least] : dirs) {
    int count = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() != ".json") continue;
      ++count;
      std::ifstream in(entry.path());
      if (nlohmann::json::parse(in).contains("python")) {
        // Python methods (own-methods.json) run from Python only (the
        // report runs it so); the command line, which loads its plug-ins
        // (this test binary cannot: it does not export springlab's
        // symbols), reads it up to the one-line refusal of "python".
        const fs::path io = fs::path(::testing::TempDir()) / "shipped-python-definition";
        fs::create_directories(io);
        const testing::ProcessResult r = testing::run_springlab(
            {"experiment", fs::absolute(entry.path()).string(), "--out", (io / "out").string()}, io, io);
        EXPECT_EQ(r.status, 1) << r.err;
        EXPECT_NE(r.err.find("python: methods written in Python run from Python"), std::string::npos)
            << r.err;
        continue;
      }
      EXPECT_NO_THROW({
        const LoadedExperiment loaded = load_experiment(entry.path().string());
        EXPECT_EQ(loaded.name, entry.path().stem().string());
        EXPECT_GT(loaded.experiment->task_count(), 0u);
      }) << entry.path();
    }
    EXPECT_GE(count, at_least) << dir;
  }
}

// ----------------------------------------------------------- ExperimentKinds --

TEST(ExperimentKinds, TablesStartWithSceneAndIntegrator) {
  const std::vector<Json> definitions = {
      kEnergy,
      {{"experiment", "stability"},
       {"integrators", {"rk4"}},
       {"cases", {{{"scene", "oscillator"}, {"k", {100}}}}}},
      {{"experiment", "damping-budget"},
       {"integrators", {"rk4"}},
       {"cases", {{{"scene", "spring"}, {"dt", 0.01}, {"t_end", 1}}}}},
      {{"experiment", "cloth-showcase"},
       {"integrators", {"rk4"}},
       {"scene", "cloth"},
       {"parameters", {{"n", 3}}},
       {"dt", 0.01},
       {"frames", {0.1}}},
      {{"experiment", "spectral"}, {"integrators", {"newmark"}}}};
  for (const Json& d : definitions) {
    const LoadedExperiment loaded = parse(d);
    for (const TableSpec& spec : loaded.experiment->tables()) {
      ASSERT_GE(spec.columns.size(), 3u);
      EXPECT_EQ(spec.columns[0], "scene") << d["experiment"] << " " << spec.suffix;
      EXPECT_EQ(spec.columns[1], "integrator") << d["experiment"] << " " << spec.suffix;
      EXPECT_EQ(std::count(spec.columns.begin(), spec.columns.end(), "task"), 0);
    }
  }
}

// The spectral experiment's rows are the measured spectrum: RK4's spectral
// radius is |R(i w h)| of its stability function, at every w h of the grid;
// a variant's parameters reach the method (generalized-alpha's rho_inf).
TEST(ExperimentKinds, SpectralRowsAreTheMeasuredSpectrum) {
  const LoadedExperiment loaded = parse(
      {{"experiment", "spectral"},
       {"integrators", {"rk4"}},
       {"variants", {{{"integrator", "generalized-alpha"}, {"label", "ga0"}, {"rho_inf", 0.0}}}},
       {"wh_min", 0.1},
       {"wh_max", 1000},
       {"points_per_decade", 2}});
  ASSERT_EQ(loaded.experiment->task_count(), 2u);
  const auto rk4 = run_task(loaded, 0);
  ASSERT_EQ(rk4[0].size(), 9u);  // 0.1 .. 1000, two per decade
  const IntegratorInfo info = make_integrator("rk4")->info();
  for (const Record& row : rk4[0]) {
    const double wh = number(row.at("wh"));
    const double expected = std::abs(info.stability_function(std::complex<double>(0.0, wh)));
    EXPECT_TRUE(close(number(row.at("spectral_radius")), expected, 1e-6)) << "w h " << wh;
    EXPECT_EQ(row.at("method"), "rk4");
  }
  const auto ga = run_task(loaded, 1);
  EXPECT_EQ(ga[0].back().at("method"), "ga0");
  EXPECT_EQ(ga[0].back().at("integrator"), "generalized-alpha");
  // rho_inf = 0 at w h = 1000: 0.0100665 by the closed form (test_second_order.cc).
  EXPECT_NEAR(number(ga[0].back().at("spectral_radius")), 0.0100665, 1e-6);
}

// A variant with a parameter out of the method's range is refused.
TEST(ExperimentDefinition, SpectralVariantOutOfRangeIsRefused) {
  const Json d = {{"experiment", "spectral"},
                  {"integrators", {"rk4"}},
                  {"variants", {{{"integrator", "generalized-alpha"}, {"label", "x"}, {"rho_inf", 2}}}}};
  EXPECT_NE(definition_error(d).find("--rho-inf: must be in [0, 1]"), std::string::npos)
      << definition_error(d);
}

// Explicit Euler on x'' = -w^2 x: E_{n+1} = (1 + w^2 dt^2) E_n exactly; at
// w = 10, dt = 0.05 that is 1.25 per step, so E passes 1000 E_s = 1000 E_0
// at step 31 (1.25^30 = 807.8, 1.25^31 = 1009.7).
TEST(ExperimentKinds, EnergyExplicitEulerGrowsByExactFactor) {
  const LoadedExperiment loaded = parse(
      {{"experiment", "energy"},
       {"integrators", {"explicit-euler", "symplectic-euler"}},
       {"cases",
        {{{"scene", "oscillator"}, {"parameters", {{"k", 100}, {"mass", 1}, {"rest", 0}}},
          {"dt", 0.05}, {"t_end", 3}},
         {{"scene", "oscillator"}, {"dt", 0.05}, {"t_end", 1}, {"every", 3}},
         {{"scene", "chain"}, {"parameters", {{"n", 4}, {"horizontal", 1}}}, {"dt", 0.005},
          {"t_end", 0.2}}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 6u);

  const auto euler = run_task(loaded, 0);
  const std::vector<Record>& energy = euler[0];
  ASSERT_EQ(energy.size(), 31u);  // t = 0 .. 30 dt, the last good state
  for (std::size_t k = 0; k < energy.size(); ++k) {
    EXPECT_EQ(energy[k].at("scene"), "oscillator");
    EXPECT_EQ(energy[k].at("integrator"), "explicit-euler");
    EXPECT_EQ(number(energy[k].at("dt")), 0.05);
    EXPECT_NEAR(number(energy[k].at("t")), static_cast<double>(k) * 0.05, 1e-12);
    EXPECT_EQ(number(energy[k].at("gravity")), 0.0);
    if (k > 0) {
      const double ratio = number(energy[k].at("total")) / number(energy[k - 1].at("total"));
      EXPECT_TRUE(close(ratio, 1.25, 1e-12)) << "step " << k << ": ratio " << ratio;
    }
  }
  EXPECT_TRUE(close(number(energy[0].at("total")), 0.5, 1e-15));  // k a^2 / 2
  ASSERT_EQ(euler[1].size(), 1u);
  const Record& run = euler[1][0];
  EXPECT_EQ(run.at("status"), "diverged");
  EXPECT_EQ(number(run.at("diverged_at")), 31 * 0.05);
  EXPECT_TRUE(close(number(run.at("energy_initial")), 0.5, 1e-15));
  EXPECT_TRUE(close(number(run.at("energy_scale")), 0.5, 1e-15));
  EXPECT_TRUE(close(number(run.at("energy_final")), 0.5 * std::pow(1.25, 30), 1e-12));
  EXPECT_EQ(run.at("energy_final"), energy.back().at("total"));
  EXPECT_GE(number(run.at("wall_seconds")), 0.0);

  // Symplectic Euler on the same case completes with a bounded energy.
  const auto symplectic = run_task(loaded, 1);
  EXPECT_EQ(symplectic[0].size(), 61u);
  EXPECT_EQ(symplectic[1][0].at("status"), "completed");
  EXPECT_EQ(symplectic[1][0].at("diverged_at"), "");
  // It conserves Q = |u|^2 + a u1 u2 exactly (u = (w x, v), a = w dt = 0.5),
  // so E stays within E0 / (1 +- a/2), the upper bound reached near t = 1 s.
  double highest = 0.0;
  for (const Record& r : symplectic[0]) {
    const double total = number(r.at("total"));
    EXPECT_LT(total, 0.5 / (1 - 0.25) + 1e-12) << "t " << r.at("t");
    EXPECT_GT(total, 0.5 / (1 + 0.25) - 1e-12) << "t " << r.at("t");
    highest = std::max(highest, total);
  }
  EXPECT_GT(highest, 0.6);

  // every = 3 over 20 steps: t = 0, 3, ..., 18 dt and always the last (20 dt).
  const auto every = run_task(loaded, 3);
  ASSERT_EQ(every[0].size(), 8u);
  for (std::size_t k = 0; k + 1 < every[0].size(); ++k) {
    EXPECT_NEAR(number(every[0][k].at("t")), 3.0 * static_cast<double>(k) * 0.05, 1e-12);
  }
  EXPECT_EQ(number(every[0].back().at("t")), 1.0);
  EXPECT_EQ(every[1][0].at("steps"), "20");

  // The parts add up to the total (the chain has gravity).
  const auto chain = run_task(loaded, 4);
  ASSERT_EQ(chain[0].size(), 41u);
  bool gravity_seen = false;
  for (const Record& r : chain[0]) {
    const double kinetic = number(r.at("kinetic")), spring = number(r.at("spring")),
                 gravity = number(r.at("gravity")), total = number(r.at("total"));
    gravity_seen = gravity_seen || gravity != 0.0;
    EXPECT_NEAR(kinetic + spring + gravity, total,
                1e-12 * (std::abs(kinetic) + std::abs(spring) + std::abs(gravity)))
        << "t = " << r.at("t");
    EXPECT_GE(kinetic, 0.0);
    EXPECT_GE(spring, 0.0);
  }
  EXPECT_TRUE(gravity_seen);
}

// Without a map in its definition, the stability experiment has no map
// table (no file with a header and no rows for the report to warn about).
TEST(ExperimentKinds, StabilityWithoutMapHasNoMapTable) {
  const LoadedExperiment loaded = parse({{"experiment", "stability"},
                                         {"integrators", {"symplectic-euler"}},
                                         {"cases", {{{"scene", "oscillator"}, {"k", {100}}}}}});
  const std::vector<TableSpec> specs = loaded.experiment->tables();
  ASSERT_EQ(specs.size(), 1u);
  EXPECT_EQ(specs[0].suffix, "");
  const LoadedExperiment with_map = parse(
      {{"experiment", "stability"},
       {"integrators", {"symplectic-euler"}},
       {"cases", {{{"scene", "oscillator"}, {"k", {100}}}}},
       {"map",
        {{"scene", "oscillator"},
         {"integrators", {"symplectic-euler"}},
         {"k", {100}},
         {"dt", {0.1}},
         {"t_end", 1}}}});
  ASSERT_EQ(with_map.experiment->tables().size(), 2u);
  EXPECT_EQ(with_map.experiment->tables()[1].suffix, "map");
}

TEST(ExperimentKinds, StabilityLimitsMatchTheory) {
  const LoadedExperiment loaded = parse(
      {{"experiment", "stability"},
       {"integrators", {"symplectic-euler", "verlet", "rk4", "implicit-euler", "explicit-euler"}},
       {"dt_max_factor", 5},
       {"cases", {{{"scene", "oscillator"}, {"k", {100}}}}},
       {"map",
        {{"scene", "oscillator"},
         {"integrators", {"explicit-euler", "implicit-euler"}},
         {"k", {100}},
         {"dt", {0.01, 0.1, 0.3}},
         {"t_end", 2}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 5u + 6u);

  const std::map<std::string, double> theory = {{"symplectic-euler", 2.0 / 10},
                                                {"verlet", 2.0 / 10},
                                                {"rk4", 2.0 * std::sqrt(2.0) / 10}};
  for (std::size_t task = 0; task < 5; ++task) {
    const auto tables = run_task(loaded, task);
    ASSERT_EQ(tables[0].size(), 1u);
    EXPECT_TRUE(tables[1].empty());
    const Record& r = tables[0][0];
    const std::string name = r.at("integrator");
    const double w = number(r.at("w_max"));
    EXPECT_TRUE(close(w, 10.0, 1e-9)) << name << ": w_max " << w;
    EXPECT_EQ(number(r.at("k")), 100.0);
    EXPECT_TRUE(close(number(r.at("t_end")), 100 * 2 * std::numbers::pi / w, 1e-12)) << name;
    const double limit = number(r.at("max_stable_dt"));
    EXPECT_EQ(limit, number(r.at("bracket_lo"))) << name;
    if (theory.count(name) != 0) {
      const double expected = theory.at(name);
      EXPECT_TRUE(close(number(r.at("theory_dt")), expected, 1e-9)) << name;
      EXPECT_TRUE(close(limit, expected, 0.01)) << name << ": " << limit << " vs " << expected;
      EXPECT_TRUE(close(number(r.at("ratio")), limit / number(r.at("theory_dt")), 1e-12)) << name;
      // The bracket is tight (rel_tol 1e-3) and straddles the limit.
      EXPECT_LE(number(r.at("bracket_hi")) / limit, 1.001 + 1e-12) << name;
    } else if (name == "implicit-euler") {
      EXPECT_EQ(r.at("theory_dt"), "");
      EXPECT_EQ(r.at("ratio"), "");
      EXPECT_EQ(limit, 5.0 / w);  // dt_max: nothing diverged
      EXPECT_EQ(number(r.at("bracket_hi")), limit);
    } else {
      ASSERT_EQ(name, "explicit-euler");
      // Unstable at every step: the finite-time limit (T/h) ln(1 + w^2 h^2) = ln B
      // (B the search's default blow-up factor, 10: stability.h) is exact for
      // the oscillator, whose energy is all in the top mode.
      const double predicted = number(r.at("theory_dt"));
      EXPECT_TRUE(close(limit, predicted, 0.01)) << limit << " vs " << predicted;
      const double t_end = number(r.at("t_end"));
      EXPECT_TRUE(close(t_end / predicted * std::log1p(w * w * predicted * predicted),
                        std::log(kStabilityBlowup), 1e-6));
      EXPECT_TRUE(close(number(r.at("ratio")), limit / predicted, 1e-12));
      EXPECT_LT(limit, 0.02);  // far below the symplectic limit 0.2
    }
  }

  // Map rows: tasks by integrator, then k, then dt.
  const std::vector<double> dts = {0.01, 0.1, 0.3};
  for (std::size_t m = 0; m < 6; ++m) {
    const auto tables = run_task(loaded, 5 + m);
    EXPECT_TRUE(tables[0].empty());
    ASSERT_EQ(tables[1].size(), 1u);
    const Record& r = tables[1][0];
    const double dt = dts[m % 3];
    EXPECT_EQ(number(r.at("dt")), dt);
    EXPECT_EQ(number(r.at("k")), 100.0);
    const double ratio = number(r.at("energy_ratio"));
    const double growth = 1 + 100 * dt * dt;  // per step, |R(i w h)|^2
    if (m < 3) {
      EXPECT_EQ(r.at("integrator"), "explicit-euler");
      if (dt == 0.01) {
        EXPECT_EQ(r.at("diverged"), "0");
        EXPECT_TRUE(close(ratio, std::pow(growth, 200), 1e-10)) << ratio;  // 7.3
      } else {
        EXPECT_EQ(r.at("diverged"), "1") << "dt " << dt;
        EXPECT_GT(ratio, 1.0);
        EXPECT_LE(ratio, 1000.0);  // the last good state
      }
    } else {
      EXPECT_EQ(r.at("integrator"), "implicit-euler");
      EXPECT_EQ(r.at("diverged"), "0") << "dt " << dt;
      EXPECT_LE(ratio, 1.0) << "dt " << dt;
      // Linear problem: implicit Euler's energy shrinks by 1 / (1 + w^2 h^2) per step.
      // 2 / 0.3 is not whole: six steps of 0.3, then one of 0.2 ending at t_end.
      const double whole = std::floor(2 / dt + 1e-9), rest = 2 - whole * dt;
      const double expected =
          std::pow(growth, -whole) / (rest > 1e-9 ? 1 + 100 * rest * rest : 1.0);
      EXPECT_TRUE(close(ratio, expected, 1e-6)) << "dt " << dt << ": " << ratio;
    }
  }
}

TEST(ExperimentKinds, DampingBudgetSeparatesPhysicsFromNumerics) {
  const LoadedExperiment loaded = parse(
      {{"experiment", "damping-budget"},
       {"integrators", {"rk4", "implicit-euler"}},
       {"cases",
        {{{"scene", "spring"}, {"dt", 0.001}, {"t_end", 1}, {"every", 100}},
         {{"scene", "spring"}, {"dt", 0.01}, {"t_end", 1}, {"every", 3}}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 4u);

  auto check_rows = [](const std::vector<Record>& rows, const std::string& name) {
    ASSERT_FALSE(rows.empty());
    EXPECT_EQ(rows[0].at("t"), "0");
    EXPECT_EQ(rows[0].at("work_nonconservative"), "0");
    EXPECT_EQ(rows[0].at("numerical"), "0");
    const double e0 = number(rows[0].at("mechanical"));
    EXPECT_TRUE(close(e0, -9.81, 1e-12)) << "m g y at y = -rest";
    double previous_work = 0.0;
    for (const Record& r : rows) {
      EXPECT_EQ(r.at("integrator"), name);
      const double mechanical = number(r.at("mechanical")), work = number(r.at("work_nonconservative")),
                   budget = number(r.at("budget")), numerical = number(r.at("numerical"));
      EXPECT_NEAR(budget, mechanical - work, 1e-13 * std::abs(e0)) << name << " t " << r.at("t");
      EXPECT_NEAR(numerical, budget - e0, 1e-13 * std::abs(e0)) << name << " t " << r.at("t");
      EXPECT_LE(work, previous_work) << name << ": drag only ever removes energy";
      previous_work = work;
    }
    EXPECT_EQ(number(rows.back().at("t")), 1.0);
  };

  const std::vector<Record> rk4 = run_task(loaded, 0)[0];
  check_rows(rk4, "rk4");
  EXPECT_EQ(rk4.size(), 11u);  // every 100 of 1000 steps
  const double rk4_work = number(rk4.back().at("work_nonconservative"));
  const double rk4_numerical = number(rk4.back().at("numerical"));
  EXPECT_LT(rk4_work, -0.01) << "the drag dissipates";
  EXPECT_LT(std::abs(rk4_numerical), 1e-6) << "RK4 at dt 1e-3 does not";

  const std::vector<Record> implicit = run_task(loaded, 3)[0];
  check_rows(implicit, "implicit-euler");
  EXPECT_EQ(implicit.size(), 35u);  // 0, 3, ..., 99 and the last step 100
  EXPECT_LT(number(implicit.back().at("numerical")), -1e-3) << "implicit Euler's own dissipation";
  // The same physics, so the same order of dissipated work as the accurate run.
  EXPECT_LT(number(implicit.back().at("work_nonconservative")), -0.01);
}

// step-energy: a row per step with the energy change and the compressed
// springs. On the 16 x 16 cloth at h = 0.1 s (w_max h ~ 100, as cloth 64 at
// 1/60 s) linear-implicit Euler with the exact stiffness blows up within a
// few steps while its definite variant stays bounded, and implicit Euler
// solved to convergence never gains energy.
TEST(ExperimentKinds, StepEnergyShowsTheLinearizedStepsGain) {
  const LoadedExperiment loaded =
      parse({{"experiment", "step-energy"},
             {"runs",
              {{{"integrator", "linear-implicit-euler"}, {"stiffness", "exact"}},
               {{"integrator", "linear-implicit-euler"}, {"stiffness", "definite"}},
               {{"integrator", "implicit-euler"}}}},
             {"cases",
              {{{"scene", "cloth"}, {"parameters", {{"n", 16}}}, {"dt", 0.1}, {"t_end", 1}}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 3u);
  std::vector<Record> runs;
  for (std::size_t task = 0; task < 3; ++task) {
    const auto tables = run_task(loaded, task);
    ASSERT_EQ(tables[1].size(), 1u);
    const Record& run = tables[1][0];
    runs.push_back(run);
    const double springs = number(run.at("springs"));
    EXPECT_EQ(springs, 2 * 16 * 15 + 2 * 15 * 15 + 2 * 16 * 14);  // structural, shear, bend
    // A row per good step from t = 0 (a diverged run's last step is not
    // one), each change the difference of the totals.
    const std::vector<Record>& rows = tables[0];
    const bool completed = run.at("status") == "completed";
    ASSERT_EQ(rows.size(), static_cast<std::size_t>(number(run.at("steps"))) + (completed ? 1 : 0));
    long gaining = 0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      EXPECT_EQ(number(rows[k].at("step")), static_cast<double>(k));
      EXPECT_LE(number(rows[k].at("compressed")), springs);
      EXPECT_LE(number(rows[k].at("indefinite_springs")), number(rows[k].at("compressed")));
      if (k == 0) {
        EXPECT_EQ(rows[k].at("change"), "");
        continue;
      }
      const double change = number(rows[k].at("change"));
      EXPECT_EQ(change, number(rows[k].at("total")) - number(rows[k - 1].at("total")));
      gaining += change > 0.0 ? 1 : 0;
    }
    EXPECT_EQ(number(run.at("gaining_steps")), static_cast<double>(gaining));
  }
  EXPECT_EQ(runs[0].at("stiffness"), "exact");
  EXPECT_EQ(runs[0].at("status"), "diverged");
  EXPECT_EQ(runs[1].at("stiffness"), "definite");
  EXPECT_EQ(runs[1].at("status"), "completed");
  EXPECT_LT(number(runs[1].at("energy_final")), number(runs[1].at("energy_initial")));
  EXPECT_EQ(runs[2].at("integrator"), "implicit-euler");
  EXPECT_EQ(runs[2].at("status"), "completed");
  EXPECT_EQ(number(runs[2].at("gaining_steps")), 0.0);
}

TEST(ExperimentDefinition, StepEnergyRefusesAnUnknownStiffness) {
  EXPECT_EQ(definition_error(std::string(R"({"experiment": "step-energy", "runs": [
      {"integrator": "linear-implicit-euler", "stiffness": "soft"}],
      "cases": [{"scene": "cloth", "dt": 0.1, "t_end": 1}]})")),
            "def.json: runs[0].stiffness: expected \"exact\" or \"definite\"");
}

// A row's first field may be empty (an unnamed scene): it still counts.
TEST(ExperimentRows, AnEmptyFirstFieldKeepsItsComma) {
  EXPECT_EQ(Row().add("").add("rk4").add(0.5).str(), ",rk4,0.5");
  EXPECT_EQ(Row().add_empty().add(2L).add_empty().str(), ",2,");
  EXPECT_EQ(Row().raw("a,b").add("c").str(), "a,b,c");
  // A value not measured is an empty field, never "nan"; infinity is a value.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Row().add("x").add(std::numeric_limits<double>::quiet_NaN()).add(1.0).str(), "x,,1");
  EXPECT_EQ(Row().add(inf).add(-inf).str(), "inf,-inf");
}

// contact: the closed form of each case is read off its scene (the slope's
// angle, friction and smoothing; the drop's height, mass and stiffness), and
// a run's measurement is compared with it: implicit Euler at 1e-3 s sticks,
// slides and stops within 1 %, and the bounce of RK4 at 1e-4 s reaches the
// energy-balance depth within 1 %. A case without planes is refused.
TEST(ExperimentKinds, ContactMeasuresEachCaseAgainstItsClosedForm) {
  const double g = 9.81, pi = 3.14159265358979323846;
  const Json drop = {{"dimension", 2}, {"gravity", {0, -g}},
                     {"contact", {{"stiffness", 1e4}}},
                     {"planes", {{{"point", {0, 0}}, {"normal", {0, 1}}}}},
                     {"particles", {{{"x", {0, 0.1}}, {"mass", 2}}, {{"x", {0, 0}}, {"fixed", true}}}},
                     {"springs", Json::array()}};
  const ScratchDir dir("contact");
  const std::string drop_file = dir.write("drop.json", drop);
  const LoadedExperiment loaded = parse(
      {{"experiment", "contact"},
       {"integrators", {"implicit-euler", "rk4"}},
       {"cases",
        {{{"scene", "slope"}, {"parameters", {{"angle", 20}, {"friction", 0.5}}}, {"dt", 1e-3},
          {"t_end", 1}},
         {{"scene", "slope"}, {"parameters", {{"angle", 30}, {"friction", 0.3}}}, {"dt", 1e-3},
          {"t_end", 1}},
         {{"scene", "slope"}, {"parameters", {{"angle", 0}, {"friction", 0.4}, {"speed", 2}}},
          {"dt", 1e-3}, {"t_end", 1}},
         {{"scene", drop_file}, {"dt", 1e-4}, {"t_end", 0.5}}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 8u);
  const Json cases = loaded.experiment->settings().at("cases");
  const double t20 = std::tan(20 * pi / 180);
  EXPECT_EQ(cases[0].at("regime"), "stick");
  EXPECT_NEAR(cases[0].at("theory").get<double>(), 1e-3 * (1 - std::sqrt(1 - t20 / 0.5)), 1e-15);
  EXPECT_EQ(cases[1].at("regime"), "slide");
  EXPECT_NEAR(cases[1].at("theory").get<double>(),
              g * (std::sin(30 * pi / 180) - 0.3 * std::cos(30 * pi / 180)), 1e-12);
  EXPECT_EQ(cases[2].at("regime"), "stop");
  EXPECT_NEAR(cases[2].at("theory").get<double>(), 4.0 / (2 * 0.4 * g), 1e-12);
  const double w = 2 * g;  // m g
  EXPECT_EQ(cases[3].at("regime"), "bounce");
  EXPECT_NEAR(cases[3].at("theory").get<double>(), (w + std::sqrt(w * w + 2e4 * w * 0.1)) / 1e4,
              1e-15);
  for (std::size_t task : {0u, 2u, 4u, 7u}) {  // implicit Euler on the slope, RK4 on the drop
    const auto rows = run_task(loaded, task);
    ASSERT_EQ(rows[0].size(), 1u);
    const Record& row = rows[0][0];
    EXPECT_EQ(row.at("status"), "completed") << task;
    const double theory = number(row.at("theory"));
    EXPECT_NEAR(number(row.at("measured")), theory, 0.01 * theory) << row.at("regime");
  }
  EXPECT_EQ(definition_error({{"experiment", "contact"},
                              {"cases", {{{"scene", "spring"}, {"dt", 0.01}, {"t_end", 1}}}}}),
            "def.json: cases: case 0: the scene has no planes, and the contact experiment "
            "measures contact");
}

TEST(ExperimentKinds, MotionRecordsEveryFrameAndTheFramesPastTheBlowUp) {
  const int n = 4;
  const LoadedExperiment loaded =
      parse({{"experiment", "motion"},
             {"integrators", {"explicit-euler", "implicit-euler"}},
             {"cases", {{{"scene", "cloth"}, {"parameters", {{"n", n}}}, {"dt", 0.02}, {"t_end", 0.4},
                         {"every", 2}}}}});
  ASSERT_EQ(loaded.experiment->task_count(), 2u);
  const Scene scene = make_builtin_scene("cloth", {{"n", std::to_string(n)}});
  EXPECT_EQ(loaded.experiment->settings().at("cases").at(0).at("cells").size(),
            scene.get<Springs>().size());

  // Implicit Euler: t = 0, 0.04, ..., 0.4, every particle, and its last frame
  // is the run's final state exactly.
  const auto implicit = run_task(loaded, 1);
  ASSERT_EQ(implicit[1].size(), 11u);
  ASSERT_EQ(implicit[0].size(), 11u * n * n);
  for (std::size_t k = 0; k < 11; ++k) {
    EXPECT_NEAR(number(implicit[1][k].at("t")), 0.04 * static_cast<double>(k), 1e-15);
    EXPECT_EQ(implicit[1][k].at("past_blowup"), "0");
  }
  const Model model(scene);
  RunSettings s;
  s.integrator = "implicit-euler";
  s.dt = 0.02;
  s.t_end = 0.4;
  const RunResult r = simulate(model, s);
  const Eigen::MatrixXd x = model.scene_positions(r.x_final);
  for (int i = 0; i < n * n; ++i) {
    const Record& row = implicit[0][10 * n * n + i];
    EXPECT_EQ(row.at("i"), std::to_string(i));
    for (int a = 0; a < 3; ++a) EXPECT_EQ(number(row.at(std::string(1, "xyz"[a]))), x(i, a));
  }
  EXPECT_EQ(number(implicit[1][10].at("energy")), r.energy_final);

  // Explicit Euler diverges: its good frames end before diverged_at, then up
  // to three frames past the blow-up bound, all finite.
  const auto euler = run_task(loaded, 0);
  ASSERT_EQ(euler[2][0].at("status"), "diverged");
  const double diverged_at = number(euler[2][0].at("diverged_at"));
  int past = 0;
  for (const Record& f : euler[1]) {
    const double t = number(f.at("t"));
    if (f.at("past_blowup") == "1") {
      ++past;
      EXPECT_GE(t, diverged_at - 1e-12);
      EXPECT_LE(t, diverged_at + 3 * 2 * 0.02 + 1e-12);
    } else {
      EXPECT_LT(t, diverged_at);
    }
  }
  EXPECT_GE(past, 1);
  EXPECT_LE(past, 3);
  EXPECT_EQ(euler[0].size(), euler[1].size() * n * n);
  for (const Record& row : euler[0]) {
    for (const char* axis : {"x", "y", "z"}) EXPECT_TRUE(std::isfinite(number(row.at(axis))));
  }
}

TEST(ExperimentKinds, ClothShowcaseKeepsTheLastGoodState) {
  const int n = 5;
  const LoadedExperiment loaded = parse({{"experiment", "cloth-showcase"},
                                         {"integrators", {"explicit-euler", "implicit-euler"}},
                                         {"scene", "cloth"},
                                         {"parameters", {{"n", n}}},
                                         {"dt", 0.02},
                                         {"frames", {0.1, 0.2}}});
  ASSERT_EQ(loaded.experiment->task_count(), 2u);
  EXPECT_EQ(loaded.experiment->settings().at("n"), n);

  // Rows grouped by frame time, in order.
  auto frames_of = [&](const std::vector<Record>& rows) {
    std::vector<std::pair<double, std::vector<Record>>> frames;
    for (const Record& r : rows) {
      const double t = number(r.at("t"));
      if (frames.empty() || frames.back().first != t) frames.push_back({t, {}});
      frames.back().second.push_back(r);
    }
    for (const auto& [t, particles] : frames) {
      EXPECT_EQ(particles.size(), static_cast<std::size_t>(n * n)) << "t " << t;
      for (std::size_t i = 0; i < particles.size(); ++i) {
        EXPECT_EQ(particles[i].at("i"), std::to_string(i));
      }
    }
    return frames;
  };

  // Explicit Euler: the frames it reached, its last two good states, then the
  // first two states past the blow-up bound (a rerun only a non-finite state
  // stops), marked past_blowup = 1.
  const auto euler = run_task(loaded, 0);
  ASSERT_EQ(euler[1].size(), 1u);
  EXPECT_EQ(euler[1][0].at("status"), "diverged");
  const double diverged_at = number(euler[1][0].at("diverged_at"));
  const auto euler_frames = frames_of(euler[0]);
  ASSERT_GE(euler_frames.size(), 4u);
  EXPECT_EQ(euler_frames.front().first, 0.0);
  std::vector<double> good, past;
  for (const auto& [t, particles] : euler_frames) {
    (particles[0].at("past_blowup") == "1" ? past : good).push_back(t);
    for (const Record& r : particles) {
      EXPECT_EQ(r.at("past_blowup"), particles[0].at("past_blowup"));
      for (const char* axis : {"x", "y", "z"}) {
        EXPECT_TRUE(std::isfinite(number(r.at(axis)))) << "t " << t;
      }
    }
  }
  ASSERT_GE(good.size(), 2u);
  EXPECT_NEAR(good.back(), diverged_at - 0.02, 1e-12) << "every step is checked";
  EXPECT_NEAR(good[good.size() - 2], diverged_at - 0.04, 1e-12);
  ASSERT_EQ(past.size(), 2u);
  EXPECT_EQ(past[0], diverged_at);
  EXPECT_NEAR(past[1], diverged_at + 0.02, 1e-12);
  if (diverged_at < 0.1) {
    EXPECT_EQ(good.size(), 3u) << "t = 0 and the last two good states only";
  }

  const auto implicit = run_task(loaded, 1);
  EXPECT_EQ(implicit[1][0].at("status"), "completed");
  EXPECT_EQ(implicit[1][0].at("diverged_at"), "");
  EXPECT_EQ(implicit[1][0].at("steps"), "10");
  const auto frames = frames_of(implicit[0]);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].first, 0.0);
  EXPECT_NEAR(frames[1].first, 0.1, 1e-12);
  EXPECT_NEAR(frames[2].first, 0.2, 1e-12);
  for (const auto& [t, particles] : frames) {
    for (int fixed : {0, n - 1}) {
      for (const char* axis : {"x", "y", "z"}) {
        EXPECT_EQ(particles[static_cast<std::size_t>(fixed)].at(axis),
                  frames[0].second[static_cast<std::size_t>(fixed)].at(axis))
            << "fixed particle " << fixed << " moved at t " << t;
      }
    }
  }
  // Initially flat in y = 0 on a grid of spacing 1/(n-1); the free corner falls.
  EXPECT_EQ(number(frames[0].second[n * n - 1].at("y")), 0.0);
  EXPECT_EQ(number(frames[0].second[n * n - 1].at("z")), 1.0);
  EXPECT_EQ(number(frames[0].second[n - 1].at("x")), 1.0);
  EXPECT_LT(number(frames[2].second[n * n - 1].at("y")), number(frames[1].second[n * n - 1].at("y")));
  EXPECT_LT(number(frames[1].second[n * n - 1].at("y")), 0.0);
}

// A damped oscillator, x'' = -(k/m) x - (gamma/m) x' in 2-D with k = 100,
// m = 1, gamma = 2: every eigenvalue of J is lambda = -1 +- i sqrt(99)
// (twice, one pair per axis), |lambda|^2 = 100. Explicit Euler's region is
// |1 + z| <= 1, so its limit is h* = 2 |Re lambda| / |lambda|^2 = 0.02, and
// at 1.1 h* all four modes are outside it (|R| = 1.0022 per step).
TEST(ExperimentKinds, StabilityRegionPlacesTheScaledEigenvaluesAndRunsBothSteps) {
  ScratchDir dir("region");
  Json scene = {{"name", "damped-oscillator"},
                {"dimension", 2},
                {"drag", 2.0},
                {"particles", {{{"x", {0, 0}}, {"mass", 1}, {"fixed", true}},
                               {{"x", {0.1, 0.05}}, {"mass", 1}}}},
                {"springs", {{{"i", 0}, {"j", 1}, {"k", 100}, {"rest", 0}}}}};
  dir.write("damped-oscillator.json", scene);
  const std::string file =
      dir.write("region.json", {{"experiment", "stability-region"},
                                {"integrators", {"explicit-euler", "rk4", "implicit-euler",
                                                 "symplectic-euler"}},
                                {"scene", "damped-oscillator.json"},
                                {"steps", 4000}});
  const LoadedExperiment loaded = load_experiment(file);
  ASSERT_EQ(loaded.experiment->task_count(), 4u);
  const double root = std::sqrt(99.0);

  const auto euler = run_task(loaded, 0);
  ASSERT_EQ(euler[0].size(), 2u);
  for (const Record& r : euler[0]) {
    const bool above = number(r.at("factor")) > 1.0;
    EXPECT_EQ(r.at("limit_from"), "R");
    EXPECT_TRUE(close(number(r.at("limit_dt")), 0.02, 1e-8)) << r.at("limit_dt");
    EXPECT_EQ(r.at("modes_outside"), above ? "4" : "0");
    EXPECT_EQ(r.at("diverged"), above ? "1" : "0") << "factor " << r.at("factor");
  }
  ASSERT_EQ(euler[1].size(), 8u);  // 4 modes x 2 steps
  for (const Record& m : euler[1]) {
    const double h = number(m.at("dt"));
    EXPECT_NEAR(number(m.at("lambda_re")), -1.0, 1e-9);
    EXPECT_NEAR(std::abs(number(m.at("lambda_im"))), root, 1e-9);
    EXPECT_NEAR(number(m.at("z_re")), -h, 1e-9 * h);
    const std::complex<double> z(number(m.at("z_re")), number(m.at("z_im")));
    EXPECT_NEAR(number(m.at("abs_R")), std::abs(1.0 + z), 1e-14);
  }
  ASSERT_FALSE(euler[2].empty());
  for (const Record& g : euler[2]) {
    const std::complex<double> z(number(g.at("z_re")), number(g.at("z_im")));
    EXPECT_NEAR(number(g.at("abs_R")), std::abs(1.0 + z), 1e-6);
  }

  // Prediction (a mode outside the region) and measurement (the run) agree.
  for (std::size_t task : {1u, 2u}) {
    const auto t = run_task(loaded, task);
    for (const Record& r : t[0]) {
      const bool outside = number(r.at("max_abs_R")) > 1.0 + 1e-12;
      EXPECT_EQ(r.at("diverged"), outside ? "1" : "0") << r.at("integrator") << " " << r.at("factor");
    }
  }
  const auto implicit = run_task(loaded, 2);
  EXPECT_EQ(implicit[0][0].at("limit_from"), "none");  // shown at 10 / |lambda| = 1 s

  // Symplectic Euler has no scalar R: its limit is measured, no |R| is given.
  const auto symplectic = run_task(loaded, 3);
  for (const Record& r : symplectic[0]) {
    EXPECT_EQ(r.at("limit_from"), "runs");
    EXPECT_EQ(r.at("max_abs_R"), "");
    EXPECT_EQ(r.at("diverged"), number(r.at("factor")) > 1.0 ? "1" : "0");
  }
  EXPECT_TRUE(symplectic[2].empty());
}

// ---------------------------------------------------------- ExperimentRunner --

const Json kBudget = {
    {"experiment", "damping-budget"},
    {"name", "budget"},
    {"integrators", {"symplectic-euler", "verlet", "implicit-euler", "rk4", "explicit-euler"}},
    {"cases", {{{"scene", "spring"}, {"dt", 0.01}, {"t_end", 0.5}, {"every", 5}}}}};

const Json kStability = {
    {"experiment", "stability"},
    {"name", "stab"},
    {"integrators", {"symplectic-euler", "rk4"}},
    {"periods", 10},
    {"cases", {{{"scene", "oscillator"}, {"k", {10, 100}}}}},
    {"map",
     {{"scene", "oscillator"},
      {"integrators", {"explicit-euler", "implicit-euler"}},
      {"k", {10, 100}},
      {"dt", {0.01, 0.1}},
      {"t_end", 1}}}};

// Task indices of a table's rows, checking the header and the leading column.
std::vector<long> task_column(const std::string& text, const std::string& expected_header) {
  const std::vector<std::string> lines = lines_of(text);
  EXPECT_FALSE(lines.empty());
  if (lines.empty()) return {};
  EXPECT_EQ(lines[0], expected_header);
  EXPECT_EQ(lines[0].rfind("task,", 0), 0u);
  std::vector<long> tasks;
  for (std::size_t k = 1; k < lines.size(); ++k) {
    std::size_t end = 0;
    const long task = std::stol(lines[k], &end);
    EXPECT_LT(end, lines[k].size());
    EXPECT_EQ(lines[k][end], ',') << lines[k];
    EXPECT_EQ(split(lines[k]).size(), split(lines[0]).size()) << lines[k];
    tasks.push_back(task);
  }
  return tasks;
}

const std::string kBudgetHeader =
    "task,scene,integrator,dt,t,mechanical,work_nonconservative,budget,numerical";
const std::string kMapHeader = "task,scene,integrator,k,dt,w_max,energy_ratio,diverged";
const std::string kLimitHeader =
    "task,scene,integrator,k,w_max,t_end,max_stable_dt,bracket_lo,bracket_hi,theory_dt,ratio";

// Shard i of n (run_experiment --shard i/n) and the merge of n shards.
ExperimentRunOptions shard(const fs::path& out, int i, int n, int jobs = 1) {
  ExperimentRunOptions o = quiet(out, jobs);
  o.shard_index = i;
  o.shard_count = n;
  return o;
}
ExperimentRunOptions merge_of(const fs::path& out, int n) {
  ExperimentRunOptions o = quiet(out);
  o.merge = n;
  return o;
}
// The message run_experiment refuses with ("" when it runs).
std::string run_error(const std::string& definition, const ExperimentRunOptions& o) {
  try {
    run_experiment(definition, o);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ExperimentRunner, ShardsMergeToTheUnshardedTables) {
  ScratchDir dir("shards");
  const std::string definition = dir.write("budget.json", kBudget);
  const fs::path whole = dir.path() / "whole", sharded = dir.path() / "sharded";
  EXPECT_EQ(run_experiment(definition, quiet(whole, 2)).tasks_done, 5u);

  const std::vector<std::size_t> expected_tasks = {2, 2, 1};  // 0 3 | 1 4 | 2
  for (int i = 1; i <= 3; ++i) {
    EXPECT_EQ(run_experiment(definition, shard(sharded, i, 3)).tasks_done,
              expected_tasks[static_cast<std::size_t>(i - 1)]);
    const fs::path shard = sharded / ("budget.shard-" + std::to_string(i) + "-of-3.csv");
    ASSERT_TRUE(fs::is_regular_file(shard)) << shard;
    for (long task : task_column(read_text(shard), kBudgetHeader)) EXPECT_EQ(task % 3, i - 1);
  }
  EXPECT_FALSE(fs::exists(sharded / "budget.csv"));

  EXPECT_EQ(run_experiment(definition, merge_of(sharded, 3)).tasks_done, 5u);
  const std::string merged = read_text(sharded / "budget.csv");
  EXPECT_EQ(merged, read_text(whole / "budget.csv"));
  const std::vector<long> tasks = task_column(merged, kBudgetHeader);
  EXPECT_TRUE(std::is_sorted(tasks.begin(), tasks.end()));
  EXPECT_EQ(std::set<long>(tasks.begin(), tasks.end()), (std::set<long>{0, 1, 2, 3, 4}));
  // 0.5 s at 0.01 every 5: 11 rows per run (explicit Euler stays bounded here).
  EXPECT_EQ(tasks.size(), 5u * 11u);
  EXPECT_EQ(read_text(sharded / "budget.json"), read_text(whole / "budget.json"));
}

TEST(ExperimentRunner, ShardsMergeTwoTables) {
  ScratchDir dir("shards2");
  const std::string definition = dir.write("stab.json", kStability);
  const fs::path whole = dir.path() / "whole", sharded = dir.path() / "sharded";
  EXPECT_EQ(run_experiment(definition, quiet(whole, 3)).tasks_done, 4u + 8u);
  for (int i = 1; i <= 3; ++i) run_experiment(definition, shard(sharded, i, 3, 2));
  run_experiment(definition, merge_of(sharded, 3));
  for (const char* table : {"stab.csv", "stab-map.csv"}) {
    EXPECT_EQ(read_text(sharded / table), read_text(whole / table)) << table;
  }
  const std::vector<long> limits = task_column(read_text(whole / "stab.csv"), kLimitHeader);
  EXPECT_EQ(limits, (std::vector<long>{0, 1, 2, 3}));
  const std::vector<long> map = task_column(read_text(whole / "stab-map.csv"), kMapHeader);
  EXPECT_EQ(map, (std::vector<long>{4, 5, 6, 7, 8, 9, 10, 11}));
}

TEST(ExperimentRunner, MergeRefusesAMissingShard) {
  ScratchDir dir("missing");
  const std::string definition = dir.write("budget.json", kBudget);
  const fs::path out = dir.path() / "out";
  for (int i : {1, 3}) run_experiment(definition, shard(out, i, 3));
  const std::string missing = (out / "budget.shard-2-of-3.json").string();
  EXPECT_EQ(run_error(definition, merge_of(out, 3)),
            missing + ": missing shard (run --shard 2/3 first)");
  EXPECT_FALSE(fs::exists(out / "budget.csv"));
  EXPECT_EQ(directory_entries(out),
            (std::vector<std::string>{"budget.shard-1-of-3.csv", "budget.shard-1-of-3.json",
                                      "budget.shard-3-of-3.csv", "budget.shard-3-of-3.json"}));
}

TEST(ExperimentRunner, MoreShardsThanTasks) {
  ScratchDir dir("many");
  const std::string definition = dir.write("budget.json", kBudget);
  const fs::path whole = dir.path() / "whole", sharded = dir.path() / "sharded";
  run_experiment(definition, quiet(whole, 4));
  for (int i = 1; i <= 7; ++i) {
    EXPECT_EQ(run_experiment(definition, shard(sharded, i, 7, 3)).tasks_done, i <= 5 ? 1u : 0u);
  }
  EXPECT_EQ(read_text(sharded / "budget.shard-7-of-7.csv"), kBudgetHeader + "\n");
  EXPECT_EQ(run_experiment(definition, merge_of(sharded, 7)).tasks_done, 5u);
  EXPECT_EQ(read_text(sharded / "budget.csv"), read_text(whole / "budget.csv"));
}

TEST(ExperimentRunner, MergeRefusesForeignShards) {
  ScratchDir dir("foreign");
  const std::string definition = dir.write("budget.json", kBudget);
  const fs::path out = dir.path() / "out";
  for (int i : {1, 2}) run_experiment(definition, shard(out, i, 2));
  const fs::path second = out / "budget.shard-2-of-2.csv";
  const std::string original = read_text(second);
  auto merge_error = [&] { return run_error(definition, merge_of(out, 2)); };
  // Any change to a shard's table (another header, rows without a task
  // index, rows of another run) shows in its digest.
  const std::string changed = second.string() +
                              ": not the table its shard wrote (its digest differs from the one "
                              "in the shard's settings file): run --shard 2/2 again";
  std::ofstream(second) << "task,scene,integrator,t\n1,spring,rk4,0\n";
  EXPECT_EQ(merge_error(), changed);
  std::ofstream(second) << kBudgetHeader << "\n1,spring\nspring,rk4\n";
  EXPECT_EQ(merge_error(), changed);
  EXPECT_FALSE(fs::exists(out / "budget.csv"));
  std::ofstream(second) << original;
  EXPECT_EQ(merge_error(), "");
  EXPECT_TRUE(fs::exists(out / "budget.csv"));
}

// Issue 17, class 3: each shard says what it was run from (the definition's
// digest), which shard of how many it is, and that it finished; a merge
// refuses shards of another definition, copies, the wrong count and
// incomplete shards, naming the shard and what to do.
TEST(ExperimentRunner, MergeRefusesShardsItCannotVouchFor) {
  ScratchDir dir("vouch");
  const std::string definition = dir.write("budget.json", kBudget);
  Json other_json = kBudget;
  other_json["cases"][0]["t_end"] = 0.6;  // another t_end: another sweep
  const std::string other = dir.write("other.json", other_json);
  const fs::path out = dir.path() / "out";
  auto run_shard = [&](const std::string& def, int i, int n) { run_experiment(def, shard(out, i, n)); };
  auto merge_error = [&](const std::string& def, int n) { return run_error(def, merge_of(out, n)); };
  const std::string shard2 = (out / "budget.shard-2-of-2.json").string();
  run_shard(definition, 1, 2);
  run_shard(other, 2, 2);  // same name, other definition
  const std::string expected_digest = Json::parse(read_text(out / "budget.shard-1-of-2.json"))
                                          .at("definition_digest")
                                          .get<std::string>();
  const std::string other_digest = Json::parse(read_text(shard2)).at("definition_digest").get<std::string>();
  EXPECT_NE(expected_digest, other_digest);
  EXPECT_EQ(merge_error(definition, 2), shard2 + ": made from a different definition (digest " +
                                            other_digest + ", this one gives " + expected_digest +
                                            "): run --shard 2/2 again with this definition");

  // A copy of shard 1 under shard 2's names.
  for (const char* ext : {".csv", ".json"}) {
    fs::copy_file(out / (std::string("budget.shard-1-of-2") + ext),
                  out / (std::string("budget.shard-2-of-2") + ext), fs::copy_options::overwrite_existing);
  }
  EXPECT_EQ(merge_error(definition, 2),
            shard2 + ": holds shard 1/2, not 2/2 (a copy or another split?): run --shard 2/2 again");

  // Shards of another split: 1/3 and 2/3 given to --merge 2 under 2's names.
  run_shard(definition, 2, 3);
  for (const char* ext : {".csv", ".json"}) {
    fs::copy_file(out / (std::string("budget.shard-2-of-3") + ext),
                  out / (std::string("budget.shard-2-of-2") + ext), fs::copy_options::overwrite_existing);
  }
  EXPECT_EQ(merge_error(definition, 2),
            shard2 + ": holds shard 2/3, not 2/2 (a copy or another split?): run --shard 2/2 again");

  // An interrupted shard (complete: false) leaves a gap.
  run_shard(definition, 2, 2);
  Json settings = Json::parse(read_text(shard2));
  settings["tasks_done"] = 1;
  settings["complete"] = false;
  std::ofstream(shard2) << settings.dump(2) << "\n";
  EXPECT_EQ(merge_error(definition, 2),
            shard2 + ": incomplete (1 of 2 tasks): run --shard 2/2 again");
  EXPECT_FALSE(fs::exists(out / "budget.csv"));
  EXPECT_FALSE(fs::exists(out / "budget.json"));

  run_shard(definition, 2, 2);
  EXPECT_EQ(merge_error(definition, 2), "");
  const Json merged = Json::parse(read_text(out / "budget.json"));
  EXPECT_EQ(merged.at("complete"), true);
  EXPECT_EQ(merged.at("tasks_total"), 5);
  EXPECT_FALSE(merged.contains("shard"));
  EXPECT_EQ(merged.at("definition_digest"), expected_digest);
}

// --merge with --shard is a usage error, not a merge of shard 1's files.
TEST(ExperimentRunner, MergeWithShardIsRefused) {
  ScratchDir dir("merge-shard");
  const std::string definition = dir.write("budget.json", kBudget);
  ExperimentRunOptions o = shard(dir.path() / "out", 1, 2);
  o.merge = 2;
  EXPECT_THROW(run_experiment(definition, o), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

TEST(ExperimentRunner, ThreadCountDoesNotChangeTables) {
  ScratchDir dir("jobs");
  const std::string definition = dir.write("stab.json", kStability);
  const fs::path one = dir.path() / "one", two = dir.path() / "two";
  EXPECT_EQ(run_experiment(definition, quiet(one, 1)).tasks_done, 12u);
  EXPECT_EQ(run_experiment(definition, quiet(two, 2)).tasks_done, 12u);
  for (const char* table : {"stab.csv", "stab-map.csv", "stab.json"}) {
    EXPECT_EQ(read_text(one / table), read_text(two / table)) << table;
  }
  const std::string budget = dir.write("budget.json", kBudget);
  run_experiment(budget, quiet(one, 1));
  run_experiment(budget, quiet(two, 2));
  EXPECT_EQ(read_text(one / "budget.csv"), read_text(two / "budget.csv"));
}

TEST(ExperimentRunner, SettingsFileHoldsIntegratorsAndDefinition) {
  ScratchDir dir("settings");
  const std::string definition = dir.write("budget.json", kBudget);
  run_experiment(definition, quiet(dir.path() / "out"));
  const Json settings = Json::parse(read_text(dir.path() / "out" / "budget.json"));
  EXPECT_EQ(settings.at("name"), "budget");
  EXPECT_EQ(settings.at("experiment"), "damping-budget");
  EXPECT_EQ(settings.at("title"), "budget");  // the name when no title is given
  EXPECT_EQ(settings.at("description"), "");
  EXPECT_EQ(settings.at("integrators"), kBudget.at("integrators"));
  EXPECT_EQ(settings.at("definition"), kBudget);
  ASSERT_EQ(settings.at("cases").size(), 1u);
  EXPECT_EQ(settings.at("cases")[0].at("dt"), 0.01);
  // The tables written, with the header each file starts with.
  ASSERT_EQ(settings.at("tables").size(), 1u);
  const Json& table = settings.at("tables")[0];
  EXPECT_EQ(table.at("file"), "budget.csv");
  EXPECT_EQ(table.at("suffix"), "");
  std::string header;
  for (const Json& c : table.at("columns")) header += (header.empty() ? "" : ",") + c.get<std::string>();
  EXPECT_EQ(header, lines_of(read_text(dir.path() / "out" / "budget.csv")).at(0));

  // A group name resolves to the list of registered methods.
  Json fixed = kBudget;
  fixed["integrators"] = "fixed-step";
  fixed["cases"][0]["t_end"] = 0.05;
  run_experiment(dir.write("fixed.json", fixed), quiet(dir.path() / "fixed"));
  const Json resolved = Json::parse(read_text(dir.path() / "fixed" / "budget.json"));
  EXPECT_EQ(resolved.at("definition").at("integrators"), "fixed-step");
  ASSERT_TRUE(resolved.at("integrators").is_array());
  const std::vector<std::string> names = resolved.at("integrators");
  for (const char* method : {"explicit-euler", "implicit-euler", "rk4", "symplectic-euler", "verlet"}) {
    EXPECT_EQ(std::count(names.begin(), names.end(), method), 1) << method;
  }
  EXPECT_EQ(std::count(names.begin(), names.end(), "cvode-bdf"), 0);
}

TEST(ExperimentRunner, ErrorsLeaveNoFiles) {
  ScratchDir dir("errors");
  const fs::path out = dir.path() / "out";
  fs::create_directories(out);

  // A definition error: nothing is written, not even a temporary.
  Json bad = kBudget;
  bad["cases"][0]["dtt"] = 0.1;
  const std::string bad_path = dir.write("bad.json", bad);
  try {
    run_experiment(bad_path, quiet(out));
    ADD_FAILURE() << "a bad definition ran";
  } catch (const DefinitionError& e) {
    EXPECT_EQ(std::string(e.what()),
              bad_path + ": cases[0]: unknown key 'dtt' (allowed: scene, parameters, dt, t_end, every)");
  }
  EXPECT_TRUE(directory_entries(out).empty());
  EXPECT_THROW(run_experiment(bad_path, quiet(dir.path() / "never")), DefinitionError);
  EXPECT_FALSE(fs::exists(dir.path() / "never"));

  // An output that cannot be written (a directory in the way of the second
  // table): the first table's temporary is removed again.
  Json energy = kEnergy;
  energy["name"] = "e";
  const std::string good = dir.write("e.json", energy);
  fs::create_directories(out / "e-runs.csv");
  try {
    run_experiment(good, quiet(out));
    ADD_FAILURE() << "wrote over a directory";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), (out / "e-runs.csv").string() + ": is a directory, not a file");
  }
  EXPECT_EQ(directory_entries(out), (std::vector<std::string>{"e-runs.csv"}));
  fs::remove(out / "e-runs.csv");

  // The settings file in the way: no table appears either.
  fs::create_directories(out / "e.json");
  EXPECT_THROW(run_experiment(good, quiet(out)), std::runtime_error);
  EXPECT_EQ(directory_entries(out), (std::vector<std::string>{"e.json"}));
}

TEST(ExperimentRunner, EveryTableStartsWithTheTaskColumn) {
  ScratchDir dir("columns");
  const Json energy = {{"experiment", "energy"},
                       {"integrators", {"explicit-euler", "verlet", "cvode-bdf"}},
                       {"cases",
                        {{{"scene", "oscillator"}, {"dt", 0.05}, {"t_end", 0.5}},
                         {{"scene", "spring"}, {"dt", 0.01}, {"t_end", 0.2}, {"every", 4}}}}};
  const Json cloth = {{"experiment", "cloth-showcase"},
                      {"integrators", {"explicit-euler", "implicit-euler"}},
                      {"scene", "cloth"},
                      {"parameters", {{"n", 3}}},
                      {"dt", 0.02},
                      {"frames", {0.04, 0.1}}};
  const fs::path out = dir.path() / "out";
  EXPECT_EQ(run_experiment(dir.write("energy.json", energy), quiet(out, 2)).tasks_done, 6u);
  EXPECT_EQ(run_experiment(dir.write("cloth.json", cloth), quiet(out, 2)).tasks_done, 2u);
  EXPECT_EQ(run_experiment(dir.write("budget.json", kBudget), quiet(out, 2)).tasks_done, 5u);
  EXPECT_EQ(run_experiment(dir.write("stab.json", kStability), quiet(out, 2)).tasks_done, 12u);
  EXPECT_EQ(directory_entries(out),
            (std::vector<std::string>{"budget.csv", "budget.json", "cloth-showcase-runs.csv",
                                      "cloth-showcase.csv", "cloth-showcase.json", "energy-runs.csv",
                                      "energy.csv", "energy.json", "stab-map.csv", "stab.csv",
                                      "stab.json"}));

  const std::vector<long> runs = task_column(
      read_text(out / "energy-runs.csv"),
      "task,scene,integrator,dt,status,diverged_at,steps,force_evals,wall_seconds,"
      "energy_initial,energy_final,energy_scale");
  EXPECT_EQ(runs, (std::vector<long>{0, 1, 2, 3, 4, 5}));
  const std::vector<long> rows =
      task_column(read_text(out / "energy.csv"), "task,scene,integrator,dt,t,kinetic,spring,gravity,total");
  EXPECT_TRUE(std::is_sorted(rows.begin(), rows.end()));
  for (long t = 0; t < 3; ++t) EXPECT_EQ(std::count(rows.begin(), rows.end(), t), 11) << t;
  for (long t = 3; t < 6; ++t) EXPECT_EQ(std::count(rows.begin(), rows.end(), t), 6) << t;

  const std::vector<long> cloth_rows =
      task_column(read_text(out / "cloth-showcase.csv"), "task,scene,integrator,dt,t,i,x,y,z,past_blowup");
  EXPECT_TRUE(std::is_sorted(cloth_rows.begin(), cloth_rows.end()));
  EXPECT_EQ(std::count(cloth_rows.begin(), cloth_rows.end(), 1L), 3 * 9);  // 3 frames x 9
  EXPECT_EQ(task_column(read_text(out / "cloth-showcase-runs.csv"),
                        "task,scene,integrator,dt,status,diverged_at,steps,wall_seconds"),
            (std::vector<long>{0, 1}));
  const std::vector<long> budget = task_column(read_text(out / "budget.csv"), kBudgetHeader);
  EXPECT_TRUE(std::is_sorted(budget.begin(), budget.end()));
  EXPECT_EQ(task_column(read_text(out / "stab.csv"), kLimitHeader), (std::vector<long>{0, 1, 2, 3}));
  EXPECT_EQ(task_column(read_text(out / "stab-map.csv"), kMapHeader),
            (std::vector<long>{4, 5, 6, 7, 8, 9, 10, 11}));
  const Json cloth_settings = Json::parse(read_text(out / "cloth-showcase.json"));
  EXPECT_EQ(cloth_settings.at("n"), 3);
  EXPECT_EQ(cloth_settings.at("frames"), (Json{0.0, 0.04, 0.1}));
}

// mode: on the linear beam every one-step method carries the first bending
// mode as it carries one oscillator of the mode's frequency w1. The step
// map read off one oscillator step gives implicit Euler's closed form
// (R = 1 / (1 - i w h): period 2 pi h / atan(w h), amplitude per period
// (1 + (w h)^2)^(-pi / atan(w h))) and symplectic Euler's
// (cos(theta) = 1 - (w h)^2 / 2, no damping), and what the beam run
// measures (zero crossings; the slope of log r) agrees with it to 1e-3.
// The explicit method diverges at 10 steps per period: the beam's fastest
// mode, not the first, limits it. A scene with gravity is refused.
TEST(ExperimentKinds, ModeMeasuresPeriodAndDampingAgainstTheStepMap) {
  const Json beam = {{"dimension", 2}, {"nx", 10}, {"ny", 1}, {"model", 0}, {"g", 0}};
  const LoadedExperiment loaded =
      parse({{"experiment", "mode"},
             {"integrators", {"implicit-euler", "symplectic-euler", "implicit-midpoint"}},
             {"scene", "beam"}, {"parameters", beam}, {"amplitude", 0.01}, {"periods", 10},
             {"steps_per_period", {10, 40}}});
  ASSERT_EQ(loaded.experiment->task_count(), 6u);
  const Json settings = loaded.experiment->settings();
  const double w = settings.at("w").get<double>();
  EXPECT_NEAR(settings.at("period_exact").get<double>(), 2 * std::numbers::pi / w, 1e-15);
  EXPECT_GT(settings.at("w_max").get<double>(), 20 * w);  // the stiff modes above
  for (std::size_t task = 0; task < 6; ++task) {
    const auto tables = run_task(loaded, task);
    const Record& row = tables[0][0];
    const double h = number(row.at("dt")), wh = w * h;
    const std::string name = row.at("integrator");
    SCOPED_TRACE(name + " at " + row.at("steps_per_period") + " steps per period");
    ASSERT_EQ(number(row.at("steps_per_period")) * h, 2 * std::numbers::pi / w);
    const double predicted = number(row.at("period_predicted"));
    const double predicted_amplitude = number(row.at("amplitude_per_period_predicted"));
    if (name == "implicit-euler") {
      EXPECT_NEAR(predicted, 2 * std::numbers::pi * h / std::atan(wh), 1e-9 * predicted);
      EXPECT_NEAR(predicted_amplitude, std::pow(1 + wh * wh, -std::numbers::pi / std::atan(wh)),
                  1e-9);
    }
    if (name == "symplectic-euler") {
      EXPECT_NEAR(predicted, 2 * std::numbers::pi * h / std::acos(1 - wh * wh / 2),
                  1e-9 * predicted);
      EXPECT_NEAR(predicted_amplitude, 1.0, 1e-9);
      EXPECT_EQ(row.at("status"), "diverged");
      continue;
    }
    ASSERT_EQ(row.at("status"), "completed");
    EXPECT_NEAR(number(row.at("period")), predicted, 1e-3 * predicted);
    EXPECT_NEAR(number(row.at("amplitude_per_period")), predicted_amplitude, 1e-3);
    EXPECT_NEAR(number(tables[1].front().at("q")), 1.0, 1e-12);  // starts at the amplitude
  }
  Json with_gravity = beam;
  with_gravity["g"] = 9.81;
  EXPECT_EQ(definition_error({{"experiment", "mode"}, {"scene", "beam"},
                              {"parameters", with_gravity}, {"amplitude", 0.01},
                              {"steps_per_period", {10}}}),
            "def.json: scene: the mode is measured about the rest shape, so the scene needs g = 0");
}

// rotation: every material model on the block's two rigid motions. Spinning
// at w, the linear block feels no force (the spin's velocity field is an
// infinitesimal rotation, strain-free to eps = (F + F^T)/2 - I), so its
// particles fly straight and its radius of gyration grows to exactly
// sqrt((r_h^2 (1 + (w t)^2) + r_v^2) / (r_h^2 + r_v^2)) = sqrt((2 (1 + (w t)^2) + 1) / 3)
// for a cube (r_h^2 = 2 r_v^2), with no elastic energy. Released turned by
// theta, it starts with V 2 (mu + lambda) (1 - cos theta)^2; the four
// rotation-invariant models stay rigid (1e-9) with no energy in both, and
// under implicit Euler too.
TEST(ExperimentKinds, RotationShowsLinearElasticityGhostForces) {
  const double w = 3, T = 0.5, theta = 60 * std::numbers::pi / 180, E = 1e5, nu = 0.3;
  const LoadedExperiment loaded = parse(
      {{"experiment", "rotation"},
       {"integrators", {"verlet", "implicit-euler"}},
       {"scene", "block"},
       {"parameters", {{"n", 2}, {"g", 0}, {"height", 0}, {"young", E}, {"poisson", nu}}},
       {"scenarios", {{{"title", "spin"}, {"parameters", {{"spin", w}}}},
                      {{"title", "turned"}, {"parameters", {{"spin", 0}, {"angle", 60}}}}}},
       {"dt", 1e-3},
       {"t_end", T}});
  const std::size_t models = 5, integrators = 2;
  ASSERT_EQ(loaded.experiment->task_count(), 2 * models * integrators);
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double V = 0.2 * 0.2 * 0.2;
  for (std::size_t task = 0; task < loaded.experiment->task_count(); ++task) {
    const auto tables = run_task(loaded, task);
    const Record& run = tables[1][0];
    const bool spin = task < models * integrators;
    SCOPED_TRACE(run.at("model") + ", " + run.at("integrator") + (spin ? ", spin" : ", turned"));
    ASSERT_EQ(run.at("status"), "completed");
    if (run.at("model") == "linear") {
      if (spin) {
        EXPECT_NEAR(number(run.at("gyration_final")), std::sqrt((2 * (1 + w * w * T * T) + 1) / 3),
                    1e-9);
        EXPECT_LT(number(run.at("elastic_max")), 1e-15);
      } else {
        const double ghost = V * 2 * (mu + lambda) * std::pow(1 - std::cos(theta), 2);
        EXPECT_NEAR(number(run.at("elastic_initial")), ghost, 1e-9 * ghost);
        EXPECT_GT(number(run.at("gyration_max")), 1.1);
      }
      continue;
    }
    if (spin) {
      EXPECT_NEAR(number(run.at("gyration_final")), 1.0, 1e-3);  // the centrifugal stretch
      EXPECT_LT(number(run.at("elastic_max")), 0.01 * number(run.at("kinetic_initial")));
    } else {
      EXPECT_NEAR(number(run.at("gyration_max")), 1.0, 1e-9);
      EXPECT_LT(std::abs(number(run.at("elastic_max"))), 1e-9);
    }
  }
}

// solver-error: every run steps from the tight implicit Euler run's states.
// On a linear spring of rest length 0 (the oscillator) one projective-
// dynamics iteration, one xpbd substep and one vbd iteration are that step
// exactly (solver error at round-off), and so is Newton; on the cloth more local/global
// iterations bring projective dynamics closer to the step, Newton at
// 1e-10 m/s is within 1e-9 of it, and 20 xpbd substeps land closer to the
// true motion than the exact implicit Euler step does.
TEST(ExperimentKinds, SolverErrorComparesEachStepWithTheSameStepSolvedTightly) {
  auto medians = [](const std::vector<Record>& rows, const char* column) {
    std::vector<double> v;
    for (const Record& r : rows) {
      EXPECT_EQ(r.at("status"), "completed") << r.at("failure");
      v.push_back(number(r.at(column)));
    }
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const Json runs = {{{"integrator", "implicit-euler"}, {"newton_tol", 1e-10}},
                     {{"integrator", "projective-dynamics"}, {"iterations", 1}},
                     {{"integrator", "projective-dynamics"}, {"iterations", 30}},
                     {{"integrator", "xpbd"}, {"substeps", 1}, {"iterations", 1}},
                     {{"integrator", "xpbd"}, {"substeps", 20}, {"iterations", 1}},
                     {{"integrator", "vbd"}, {"iterations", 1}}};
  const LoadedExperiment loaded = parse(
      {{"experiment", "solver-error"},
       {"cases", {{{"scene", "oscillator"}}, {{"scene", "cloth"}, {"parameters", {{"n", 6}}}}}},
       {"dt", 1.0 / 60.0}, {"steps", 12}, {"every", 4}, {"runs", runs}});
  ASSERT_EQ(loaded.experiment->task_count(), 12u);
  for (std::size_t task : {0u, 1u, 3u, 5u}) {  // the oscillator
    const auto rows = run_task(loaded, task)[0];
    ASSERT_EQ(rows.size(), 3u);  // steps 0, 4, 8
    EXPECT_LT(medians(rows, "solver_error"), 1e-12) << task;
  }
  const auto newton_task = run_task(loaded, 6);
  const double newton = medians(newton_task[0], "solver_error");
  // The whole run from rest: implicit Euler loses energy, and its springs
  // stretch (the cloth hangs).
  ASSERT_EQ(newton_task[1].size(), 1u);
  EXPECT_GT(number(newton_task[1][0].at("energy_lost")), 0.0);
  EXPECT_GT(number(newton_task[1][0].at("max_strain")), 0.0);
  const double pd1 = medians(run_task(loaded, 7)[0], "solver_error");
  const double pd30 = medians(run_task(loaded, 8)[0], "solver_error");
  const auto xpbd20 = run_task(loaded, 10)[0];
  EXPECT_LT(newton, 1e-9);
  EXPECT_LT(pd30, pd1);
  EXPECT_LT(medians(xpbd20, "total_error"), medians(xpbd20, "discretization_error"));
  EXPECT_EQ(definition_error({{"experiment", "solver-error"}, {"cases", {{{"scene", "cloth"}}}},
                              {"dt", 0.01}, {"runs", {{{"integrator", "implicit-euler"},
                                                       {"solver", "bfgs"}}}}}),
            "def.json: runs[0].solver: expected \"newton\" or \"quasi-newton\"");
}

}  // namespace
}  // namespace springlab::test_experiments
