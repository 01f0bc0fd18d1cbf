// The command line of docs/command-line.md "The command line", run as the real executable: each
// test works in a fresh temporary directory, captures stdout, stderr and the exit status,
// and checks the values in the JSON and CSV outputs.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "csv_fields.h"
#include "run_process.h"
#include "integrators/registry/registry.h"

#ifndef SPRINGLAB_EXE
#error "SPRINGLAB_EXE must name the springlab executable"
#endif
#ifndef SPRINGLAB_TEST_DATA
#error "SPRINGLAB_TEST_DATA must name tests/data"
#endif

namespace springlab::test_cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

const std::string kCliData = std::string(SPRINGLAB_TEST_DATA) + "/cli";

// ------------------------------------------------------------------ helpers

using Output = testing::ProcessResult;
using testing::describe;
using testing::read_text;
using testing::write_text;

std::string number(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// A fresh directory per test: `work` is the child's working directory (and
// must hold only what a test expects), `io` collects its stdout and stderr.
class Workspace {
 public:
  Workspace() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "-" + info->name();
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '_';
    }
    root_ = fs::temp_directory_path() / ("springlab-cli-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "work");
    fs::create_directories(root_ / "io");
  }
  ~Workspace() {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  fs::path work() const { return root_ / "work"; }
  fs::path file(const std::string& name) const { return work() / name; }

  // Names of everything in the work directory, sorted.
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(work())) names.push_back(entry.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }

  // Runs `springlab args...` in work(); a signal is reported as a failure.
  Output run(const std::vector<std::string>& args) {
    std::cout.flush();
    std::cerr.flush();
    Output result = testing::run_springlab(args, work(), root_ / "io");
    if (!result.started) {
      ADD_FAILURE() << "could not start springlab";
    } else if (!result.exited) {
      ADD_FAILURE() << "springlab killed by signal " << result.signal << "\nstderr: " << result.err;
    }
    return result;
  }

 private:
  fs::path root_;
};

// Parses one JSON object (a failure, not an exception, when it is not one).
Json parse_object(const std::string& text) {
  Json j = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) {
    ADD_FAILURE() << "not one JSON object: " << text;
    return Json::object();
  }
  return j;
}

using Csv = csv_fields::NumberCsv;

bool contains(const std::string& text, const std::string& fragment) {
  return text.find(fragment) != std::string::npos;
}

const std::vector<std::string> kStatisticsKeys = {"steps",          "rejected_steps",   "force_evals",
                                                  "jacobian_evals", "linear_solves",    "newton_iterations"};

// The keys docs/command-line.md "The command line" promises for `run --json`, with their types.
void expect_run_json_shape(Json j, std::size_t particles, int dimension) {
  for (const char* key : {"integrator", "dt", "t_end", "steps", "rejected_steps", "force_evals",
                          "jacobian_evals", "linear_solves", "newton_iterations", "wall_seconds",
                          "diverged", "diverged_at", "energy_initial", "energy_final",
                          "final_state"}) {
    EXPECT_TRUE(j.contains(key)) << "missing key " << key << " in " << j.dump();
  }
  if (!j.contains("final_state")) return;
  EXPECT_TRUE(j["integrator"].is_string());
  EXPECT_TRUE(j["dt"].is_number());
  EXPECT_TRUE(j["t_end"].is_number());
  for (const std::string& key : kStatisticsKeys) {
    EXPECT_TRUE(j[key].is_number_integer()) << key;
    if (j[key].is_number_integer()) {
      EXPECT_GE(j[key].get<long>(), 0) << key;
    }
  }
  EXPECT_TRUE(j["wall_seconds"].is_number());
  if (j["wall_seconds"].is_number()) {
    EXPECT_GE(j["wall_seconds"].get<double>(), 0.0);
  }
  EXPECT_TRUE(j["diverged"].is_boolean());
  EXPECT_TRUE(j["diverged_at"].is_null() || j["diverged_at"].is_number());
  EXPECT_TRUE(j["energy_initial"].is_number());
  EXPECT_TRUE(j["energy_final"].is_number());
  const Json& state = j["final_state"];
  for (const char* part : {"x", "v"}) {
    ASSERT_TRUE(state.contains(part)) << state.dump();
    ASSERT_TRUE(state[part].is_array());
    ASSERT_EQ(state[part].size(), particles) << part;
    for (const Json& row : state[part]) {
      ASSERT_TRUE(row.is_array());
      ASSERT_EQ(row.size(), static_cast<std::size_t>(dimension)) << part;
      for (const Json& value : row) {
        ASSERT_TRUE(value.is_number()) << part << ": " << row.dump();
        EXPECT_TRUE(std::isfinite(value.get<double>()));
      }
    }
  }
}

// Energy CSV: exact header, five finite columns, total = kinetic+spring+gravity.
void expect_energy_csv(const Csv& csv) {
  EXPECT_EQ(csv.header, "t,kinetic,spring,gravity,total");
  for (const std::vector<double>& row : csv.rows) {
    ASSERT_GE(row.size(), 5u);
    for (const double value : row) EXPECT_TRUE(std::isfinite(value));
    const double sum = row[1] + row[2] + row[3];
    const double scale = std::abs(row[1]) + std::abs(row[2]) + std::abs(row[3]);
    EXPECT_NEAR(row[4], sum, 1e-12 * scale) << "t = " << row[0];
  }
}

std::vector<double> column(const Csv& csv, std::size_t c) {
  std::vector<double> values;
  for (const auto& row : csv.rows) values.push_back(row.at(c));
  return values;
}

class CliFixture : public ::testing::Test {
 protected:
  // Runs and requires exit 0; returns the output.
  Output run_ok(const std::vector<std::string>& args) {
    Output o = ws.run(args);
    EXPECT_TRUE(o.exited && o.status == 0) << describe(args, o);
    return o;
  }
  Json run_json(const std::vector<std::string>& args) { return parse_object(run_ok(args).out); }
  Json scene(const std::string& name, const std::vector<std::string>& parameters = {}) {
    std::vector<std::string> args = {"scene", name};
    args.insert(args.end(), parameters.begin(), parameters.end());
    return parse_object(run_ok(args).out);
  }
  Workspace ws;
};

using CliRun = CliFixture;
using CliScene = CliFixture;
using CliList = CliFixture;
using CliStability = CliFixture;

// ----------------------------------------------------------------- 1. run

TEST_F(CliRun, SpringImplicitEulerJsonAndEnergyCsv) {
  Json s = scene("spring");
  ASSERT_EQ(s["particles"].size(), 2u);
  const std::vector<std::string> args = {"run",   "spring", "--integrator", "implicit-euler",
                                         "--dt",  "0.01",   "--t-end",      "5",
                                         "--energy", "e.csv", "--json"};
  const Output o = ws.run(args);
  ASSERT_TRUE(o.exited && o.status == 0) << describe(args, o);
  Json j = parse_object(o.out);
  expect_run_json_shape(j, 2, 2);
  ASSERT_TRUE(j.contains("final_state"));

  EXPECT_EQ(j["integrator"], "implicit-euler");
  EXPECT_EQ(j["dt"], 0.01);
  EXPECT_EQ(j["t_end"], 5.0);
  EXPECT_EQ(j["steps"], 500);
  EXPECT_EQ(j["diverged"], false);
  EXPECT_TRUE(j["diverged_at"].is_null());
  EXPECT_GE(j["force_evals"].get<long>(), 500);
  EXPECT_GE(j["jacobian_evals"].get<long>(), 1);
  EXPECT_GE(j["linear_solves"].get<long>(), 500);
  EXPECT_GE(j["newton_iterations"].get<long>(), 500);  // at least one per step

  // The fixed particle 0 sits at its place, at rest; the mass hangs below it
  // on the y axis (no horizontal force), between the rest length and twice
  // the static stretch m g / k.
  Json& state = j["final_state"];
  EXPECT_EQ(state["x"][0], Json::array({0.0, 0.0}));
  EXPECT_EQ(state["v"][0], Json::array({0.0, 0.0}));
  const double mass = s["particles"][1].value("mass", 1.0);
  const double k = s["springs"][0]["k"].get<double>();
  const double rest = s["springs"][0]["rest"].get<double>();
  const double g = -s["gravity"][1].get<double>();
  EXPECT_EQ(state["x"][1][0].get<double>(), 0.0);
  EXPECT_LE(state["x"][1][1].get<double>(), -rest);
  EXPECT_GE(state["x"][1][1].get<double>(), -rest - 2.0 * mass * g / k);

  // Starting undeformed at rest: only gravity's energy -m g.x.
  const double e0 = -mass * g * rest;
  EXPECT_NEAR(j["energy_initial"].get<double>(), e0, 1e-12 * std::abs(e0));
  EXPECT_LT(j["energy_final"].get<double>(), j["energy_initial"].get<double>());  // drag damps

  const Csv csv = csv_fields::read_number_csv(ws.file("e.csv"));
  expect_energy_csv(csv);
  ASSERT_EQ(csv.rows.size(), 501u);
  EXPECT_EQ(csv.rows.front()[0], 0.0);
  EXPECT_EQ(csv.rows.back()[0], 5.0);
  for (std::size_t k_row = 1; k_row < 500; ++k_row) {
    EXPECT_EQ(csv.rows[k_row][0], static_cast<double>(k_row) / 100.0) << "row " << k_row;  // k x 0.01
  }
  // The JSON energies are the first and last rows' totals (same doubles).
  EXPECT_EQ(csv.rows.front()[4], j["energy_initial"].get<double>());
  EXPECT_EQ(csv.rows.back()[4], j["energy_final"].get<double>());
  EXPECT_EQ(csv.rows.front()[1], 0.0);  // at rest
  EXPECT_EQ(csv.rows.front()[2], 0.0);  // undeformed
}

// ------------------------------------------------------------ 2. --every K

TEST_F(CliRun, EveryKthStepAndTheLast) {
  run_ok({"run", "spring", "--integrator", "rk4", "--dt", "0.01", "--t-end", "1", "--every", "7",
          "--energy", "e.csv"});
  const Csv csv = csv_fields::read_number_csv(ws.file("e.csv"));
  expect_energy_csv(csv);
  std::vector<double> expected = {0.0};
  for (int k = 7; k < 100; k += 7) expected.push_back(static_cast<double>(k) / 100.0);
  expected.push_back(1.0);
  ASSERT_EQ(expected.size(), 16u);
  EXPECT_EQ(column(csv, 0), expected);
}

// ------------------- 3. the grid of docs/command-line.md "The command line"

// The --json of xpbd adds its substeps per --dt (given, or the default 10);
// other methods have no such key.
TEST_F(CliRun, XpbdJsonCarriesSubsteps) {
  Json j = run_json({"run", "chain", "-p", "n=4", "--integrator", "xpbd", "--dt", "0.01",
                     "--t-end", "0.02", "--substeps", "3", "--json"});
  EXPECT_EQ(j["substeps"], 3);
  EXPECT_EQ(j["newton_iterations"], 6);  // 2 steps x 3 substeps x 1 iteration
  j = run_json({"run", "chain", "-p", "n=4", "--integrator", "xpbd", "--dt", "0.01", "--t-end",
                "0.02", "--json"});
  EXPECT_EQ(j["substeps"], 10);
  j = run_json({"run", "chain", "-p", "n=4", "--integrator", "verlet", "--dt", "0.01", "--t-end",
                "0.02", "--json"});
  EXPECT_FALSE(j.contains("substeps"));
}

TEST_F(CliRun, LastStepShortenedToEndAtT) {
  Json j = run_json({"run", "spring", "--integrator", "verlet", "--dt", "0.3", "--t-end", "1",
                           "--energy", "e.csv", "--json"});
  EXPECT_EQ(j["steps"], 4);
  EXPECT_EQ(j["diverged"], false);
  const std::vector<double> t = column(csv_fields::read_number_csv(ws.file("e.csv")), 0);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t[0], 0.0);
  EXPECT_EQ(t[1], 0.3);
  EXPECT_EQ(t[2], 0.6);
  EXPECT_EQ(t[3], 0.9);
  EXPECT_EQ(t[4], 1.0);
  // As text, the decimals a reader expects.
  const std::vector<std::string> lines = [&] {
    std::vector<std::string> out;
    std::istringstream in(read_text(ws.file("e.csv")));
    for (std::string line; std::getline(in, line);) out.push_back(line.substr(0, line.find(',')));
    return out;
  }();
  EXPECT_EQ(lines, (std::vector<std::string>{"t", "0", "0.3", "0.6", "0.9", "1"}));
}

TEST_F(CliRun, WholeStepCountWhenTOverDtIsInexact) {
  // 1 / 0.1 is not exactly 10 in binary: still 10 steps, none shortened.
  Json j = run_json({"run", "spring", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1",
                           "--energy", "e.csv", "--json"});
  EXPECT_EQ(j["steps"], 10);
  const std::vector<double> t = column(csv_fields::read_number_csv(ws.file("e.csv")), 0);
  ASSERT_EQ(t.size(), 11u);
  for (std::size_t k = 0; k < 10; ++k) EXPECT_EQ(t[k], static_cast<double>(k) / 10.0) << k;
  EXPECT_EQ(t[10], 1.0);
}

// ------------------------------------------------------- 4. --trajectory

// Checks the trajectory against the scene it came from: rows grouped by time,
// i = 0..N-1 in scene order, t = 0 holds the initial state, fixed particles
// keep their position and zero velocity throughout, free ones move.
void expect_trajectory(const Csv& csv, Json scene, const std::string& header,
                       std::size_t times) {
  EXPECT_EQ(csv.header, header);
  const std::size_t n = scene["particles"].size();
  const std::size_t dim = scene["dimension"].get<std::size_t>();
  ASSERT_EQ(csv.rows.size(), times * n);
  bool free_moved = false;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<double>& row = csv.rows[r];
    ASSERT_EQ(row.size(), 2 + 2 * dim) << "row " << r;
    const std::size_t i = r % n;
    EXPECT_EQ(row[0], csv.rows[r - i][0]) << "row " << r << ": one time per group";
    EXPECT_EQ(row[1], static_cast<double>(i)) << "row " << r;
    const Json& p = scene["particles"][i];
    const bool fixed = p.value("fixed", false);
    for (std::size_t c = 0; c < dim; ++c) {
      const double x0 = p["x"][c].get<double>();
      const double v0 = p.contains("v") ? p["v"][c].get<double>() : 0.0;
      if (fixed || r < n) {
        EXPECT_EQ(row[2 + c], x0) << "row " << r << " particle " << i;
        EXPECT_EQ(row[2 + dim + c], fixed ? 0.0 : v0) << "row " << r << " particle " << i;
      } else if (row[2 + c] != x0) {
        free_moved = true;
      }
    }
  }
  EXPECT_TRUE(free_moved);
  EXPECT_EQ(csv.rows.front()[0], 0.0);
}

TEST_F(CliRun, TrajectoryOfA2DChain) {
  Json s = scene("chain", {"-p", "n=4"});
  ASSERT_EQ(s["particles"].size(), 4u);
  ASSERT_EQ(s["dimension"], 2);
  run_ok({"run", "chain", "-p", "n=4", "--integrator", "rk4", "--dt", "0.001", "--t-end", "0.1",
          "--every", "10", "--trajectory", "t.csv"});
  const Csv csv = csv_fields::read_number_csv(ws.file("t.csv"));
  expect_trajectory(csv, s, "t,i,x,y,vx,vy", 11);
  EXPECT_EQ(csv.rows.back()[0], 0.1);
  EXPECT_EQ(ws.listing(), std::vector<std::string>{"t.csv"});
}

TEST_F(CliRun, TrajectoryOfA3DCloth) {
  Json s = scene("cloth", {"-p", "n=3"});
  ASSERT_EQ(s["particles"].size(), 9u);
  ASSERT_EQ(s["dimension"], 3);
  int fixed = 0;
  for (const Json& p : s["particles"]) fixed += p.value("fixed", false) ? 1 : 0;
  EXPECT_EQ(fixed, 2);
  run_ok({"run", "cloth", "-p", "n=3", "--integrator", "implicit-euler", "--dt", "0.01",
          "--t-end", "0.05", "--trajectory", "t.csv"});
  const Csv csv = csv_fields::read_number_csv(ws.file("t.csv"));
  expect_trajectory(csv, s, "t,i,x,y,z,vx,vy,vz", 6);
  EXPECT_EQ(csv.rows.back()[0], 0.05);
}

// ------------------------------------------------- 5. byte-identical runs

TEST_F(CliRun, SameRunTwiceGivesIdenticalOutput) {
  for (const char* integrator : {"rk4", "implicit-euler"}) {
    SCOPED_TRACE(integrator);
    Json reports[2];
    for (int r = 0; r < 2; ++r) {
      const std::string tag = std::to_string(r);
      reports[r] = run_json({"run", "chain", "-p", "n=5", "-p", "horizontal=1", "--integrator",
                             integrator, "--dt", "0.005", "--t-end", "1", "--energy",
                             "e" + tag + ".csv", "--trajectory", "t" + tag + ".csv", "--json"});
      ASSERT_TRUE(reports[r].contains("wall_seconds"));
      reports[r].erase("wall_seconds");
    }
    EXPECT_EQ(reports[0], reports[1]);
    EXPECT_EQ(reports[0]["steps"], 200);
    for (const char* kind : {"e", "t"}) {
      const std::string a = read_text(ws.file(std::string(kind) + "0.csv"));
      const std::string b = read_text(ws.file(std::string(kind) + "1.csv"));
      EXPECT_GT(a.size(), 1000u) << kind;
      EXPECT_TRUE(a == b) << kind << ".csv differs between identical runs";
    }
    // The chain released from horizontal swings: a nonlinear run.
    const Csv e = csv_fields::read_number_csv(ws.file("e0.csv"));
    EXPECT_EQ(e.rows.size(), 201u);
    const std::vector<double> kinetic = column(e, 1);
    EXPECT_GT(*std::max_element(kinetic.begin(), kinetic.end()), 0.1);
    for (const char* name : {"e0.csv", "e1.csv", "t0.csv", "t1.csv"}) fs::remove(ws.file(name));
  }
}

// --------------------------------------------------- 6. divergence: a result

TEST_F(CliRun, DivergenceIsAResult) {
  const std::vector<std::string> args = {"run",      "oscillator", "--integrator", "explicit-euler",
                                         "--dt",     "0.05",       "--t-end",      "100",
                                         "--energy", "e.csv",      "--json"};
  const Output o = ws.run(args);
  ASSERT_TRUE(o.exited && o.status == 0) << describe(args, o);
  Json j = parse_object(o.out);
  expect_run_json_shape(j, 2, 2);
  EXPECT_EQ(j["diverged"], true);
  ASSERT_TRUE(j["diverged_at"].is_number()) << j.dump();
  const double at = j["diverged_at"].get<double>();
  EXPECT_GT(at, 0.0);
  EXPECT_LE(at, 100.0);
  EXPECT_LT(j["steps"].get<long>(), 2000);  // it stopped

  const Csv csv = csv_fields::read_number_csv(ws.file("e.csv"));
  expect_energy_csv(csv);
  ASSERT_GE(csv.rows.size(), 2u);
  EXPECT_EQ(csv.rows.front()[0], 0.0);
  EXPECT_LE(csv.rows.back()[0], at - 0.05 + 1e-9);
  // The last row is the last good state, the one the JSON reports.
  EXPECT_EQ(csv.rows.back()[4], j["energy_final"].get<double>());
  EXPECT_GT(j["energy_final"].get<double>(), 10.0 * std::abs(j["energy_initial"].get<double>()));
  EXPECT_EQ(ws.listing(), std::vector<std::string>{"e.csv"});
}

// A SUNDIALS failure (too much work for --max-steps) is a result like a
// divergence: exit 0, diverged true, the failing call in "failure", and the
// energy file still valid up to the last good output.
TEST_F(CliRun, SolverFailureIsAResult) {
  const std::vector<std::string> args = {
      "run",      "cloth", "-p",     "n=6",           "--integrator", "cvode-bdf", "--rtol",
      "1e-8",     "--dt",  "0.1",    "--t-end",       "2",            "--max-steps", "10",
      "--energy", "e.csv", "--json"};
  const Output o = ws.run(args);
  ASSERT_TRUE(o.exited && o.status == 0) << describe(args, o);
  Json j = parse_object(o.out);
  EXPECT_EQ(j["diverged"], true);
  EXPECT_EQ(j["status"], "failed");
  ASSERT_TRUE(j["failure"].is_string()) << j.dump();
  EXPECT_TRUE(contains(j["failure"].get<std::string>(), "cvode-bdf: CVode failed at t = "))
      << j["failure"];
  EXPECT_TRUE(contains(j["failure"].get<std::string>(), "mxstep")) << j["failure"];
  ASSERT_TRUE(j["diverged_at"].is_number());
  const Csv csv = csv_fields::read_number_csv(ws.file("e.csv"));
  expect_energy_csv(csv);
  EXPECT_EQ(csv.rows.back()[0], j["t_final"].get<double>());
}

// Without --json the run still exits 0 and says it diverged.
TEST_F(CliRun, DivergenceWithoutJsonExitsZero) {
  const Output o = run_ok({"run", "oscillator", "--integrator", "explicit-euler", "--dt", "0.05",
                           "--t-end", "100"});
  EXPECT_TRUE(contains(o.out, "diverged")) << o.out;
}

// An existing file at an output path survives a run that fails.
TEST_F(CliRun, FailedRunLeavesExistingFileUntouched) {
  write_text(ws.file("e.csv"), "old\n");
  const std::vector<std::string> args = {"run",      "spring", "--integrator", "rk4",
                                         "--dt",     "0.01",   "--t-end",      "1",
                                         "--energy", "e.csv",  "--trajectory", "/nonexistent-dir/t.csv"};
  const Output o = ws.run(args);
  EXPECT_TRUE(o.exited && o.status != 0) << describe(args, o);
  EXPECT_TRUE(contains(o.err, "/nonexistent-dir/t.csv")) << o.err;
  EXPECT_EQ(read_text(ws.file("e.csv")), "old\n");
  EXPECT_EQ(ws.listing(), std::vector<std::string>{"e.csv"});
}

// ------------------------------------------------------------ 7. bad input

struct BadInput {
  std::string name;
  std::vector<std::string> args;       // "@DATA/x": tests/data/cli/x; "@REL/x": the same, relative
  std::vector<std::string> fragments;  // each must appear in stderr (same substitutions)
};

std::ostream& operator<<(std::ostream& os, const BadInput& c) { return os << c.name; }

class CliBadInputCase : public ::testing::TestWithParam<BadInput> {
 protected:
  std::string substitute(const std::string& text) const {
    std::string out = text;
    for (const auto& [key, value] :
         {std::pair<std::string, std::string>{"@DATA", kCliData},
          std::pair<std::string, std::string>{"@REL", fs::relative(kCliData, ws.work()).string()}}) {
      for (std::size_t at; (at = out.find(key)) != std::string::npos;) out.replace(at, key.size(), value);
    }
    return out;
  }
  Workspace ws;
};

TEST_P(CliBadInputCase, RefusedBeforeAnyOutput) {
  const BadInput& c = GetParam();
  std::vector<std::string> args;
  for (const std::string& a : c.args) args.push_back(substitute(a));
  const Output o = ws.run(args);
  ASSERT_TRUE(o.exited) << describe(args, o);
  EXPECT_NE(o.status, 0) << describe(args, o);
  for (const std::string& fragment : c.fragments) {
    EXPECT_TRUE(contains(o.err, substitute(fragment)))
        << "stderr lacks '" << substitute(fragment) << "'\n" << describe(args, o);
  }
  // Nothing at the output paths, no temporary left behind.
  EXPECT_EQ(ws.listing(), std::vector<std::string>{}) << describe(args, o);
}

std::vector<std::string> run_args(const std::string& scene, std::vector<std::string> extra,
                                  const std::string& integrator = "rk4") {
  std::vector<std::string> args = {"run", scene, "--integrator", integrator};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

const std::vector<std::string> kOutputs = {"--energy", "e.csv", "--trajectory", "t.csv", "--json"};

std::vector<std::string> plus(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, CliBadInputCase,
    ::testing::Values(
        BadInput{"SpringIndexPastTheEnd",
                 run_args("@DATA/bad_spring_index.json", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"@DATA/bad_spring_index.json: springs[0]: particle 5 does not exist (scene has 2 particles)"}},
        BadInput{"SpringIndexPastTheEndRelativePath",
                 run_args("@REL/bad_spring_index.json", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"@REL/bad_spring_index.json: springs[0]: particle 5 does not exist (scene has 2 particles)"}},
        BadInput{"MalformedJson",
                 run_args("@DATA/malformed.json", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"@DATA/malformed.json: ", "JSON"}},
        BadInput{"UnknownKey",
                 run_args("@DATA/unknown_key.json", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"@DATA/unknown_key.json: springs[0]", "stiffness"}},
        BadInput{"UnknownBuiltinScene",
                 run_args("no-such-scene", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"no-such-scene", "no such scene file or built-in scene"}},
        BadInput{"MissingSceneFile",
                 run_args("missing-dir/scene.json", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"missing-dir/scene.json", "no such scene file or built-in scene"}},
        BadInput{"UnknownIntegrator",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs), "foo"),
                 {"unknown integrator 'foo'"}},
        BadInput{"BuiltinSceneTypo",
                 run_args("oscilator", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"oscilator: no such scene file or built-in scene (did you mean 'oscillator'?) "
                  "(built-in scenes: "}},
        BadInput{"IntegratorTypo",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1"}, kOutputs), "RK4"),
                 {"unknown integrator 'RK4' (did you mean 'rk4'?) (integrators: "}},
        BadInput{"UnknownStiffness",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1", "--stiffness", "soft"},
                                         kOutputs), "linear-implicit-euler"),
                 {"--stiffness: unknown 'soft' (exact, definite)"}},
        BadInput{"UnknownSolver",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1", "--solver", "bfgs"},
                                         kOutputs), "implicit-euler"),
                 {"--solver: unknown 'bfgs' (newton, quasi-newton)"}},
        BadInput{"ChebyshevRadiusOfOne",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1", "--chebyshev", "1"},
                                         kOutputs), "projective-dynamics"),
                 {"--chebyshev: must be in [0, 1) (0: off)"}},
        BadInput{"UnknownBuiltinParameter",
                 run_args("spring", plus({"-p", "stiffness=3", "--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"unknown parameter 'stiffness'"}},
        BadInput{"NonNumericBuiltinParameter",
                 run_args("spring", plus({"-p", "k=abc", "--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"'k'", "abc"}},
        BadInput{"ParameterOnASceneFile",
                 run_args("@DATA/two_particles.json",
                          plus({"-p", "k=3", "--dt", "0.01", "--t-end", "1"}, kOutputs)),
                 {"@DATA/two_particles.json", "-p"}},
        BadInput{"ZeroDt", run_args("spring", plus({"--dt", "0", "--t-end", "1"}, kOutputs)), {"--dt"}},
        BadInput{"NegativeDt", run_args("spring", plus({"--dt", "-1", "--t-end", "1"}, kOutputs)), {"--dt"}},
        BadInput{"NanDt", run_args("spring", plus({"--dt", "nan", "--t-end", "1"}, kOutputs)), {"--dt"}},
        BadInput{"ZeroTEnd", run_args("spring", plus({"--dt", "0.01", "--t-end", "0"}, kOutputs)),
                 {"--t-end"}},
        BadInput{"ZeroEvery",
                 run_args("spring", plus({"--dt", "0.01", "--t-end", "1", "--every", "0"}, kOutputs)),
                 {"--every"}},
        BadInput{"MissingDt", run_args("spring", plus({"--t-end", "1"}, kOutputs)), {"--dt"}},
        BadInput{"UnwritableEnergyPath",
                 run_args("chain", {"-p", "n=50", "--dt", "1e-4", "--t-end", "100", "--every", "100",
                                    "--energy", "/nonexistent-dir/e.csv", "--trajectory", "t.csv"}),
                 {"/nonexistent-dir/e.csv"}},
        BadInput{"UnwritableTrajectoryPath",
                 run_args("spring", {"--dt", "0.01", "--t-end", "1", "--energy", "e.csv",
                                     "--trajectory", "/nonexistent-dir/t.csv"}),
                 {"/nonexistent-dir/t.csv"}},
        BadInput{"SameFileTwice",
                 run_args("spring", {"--dt", "0.01", "--t-end", "1", "--energy", "e.csv",
                                     "--trajectory", "e.csv"}),
                 {"--energy"}},
        // The same file under two spellings must not end up holding a mix of
        // both outputs (nor anything, since the run is refused or fails).
        BadInput{"SameFileTwoSpellings",
                 run_args("spring", {"--dt", "0.01", "--t-end", "1", "--energy", "e.csv",
                                     "--trajectory", "./e.csv"}),
                 {"e.csv"}},
        BadInput{"StabilityDtRangeReversed",
                 {"stability", "spring", "--integrator", "rk4", "--t-end", "1", "--dt-min", "0.5",
                  "--dt-max", "0.1"},
                 {"--dt-max"}},
        BadInput{"SceneUnknownBuiltin", {"scene", "no-such-scene"}, {"no-such-scene"}},
        BadInput{"SceneUnknownParameter", {"scene", "chain", "-p", "m=2"}, {"unknown parameter 'm'"}}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

// ------------------------------------------------ 8. scene NAME round trip

TEST_F(CliScene, EveryBuiltinRoundTripsThroughAFile) {
  for (const char* name : {"chain", "cloth", "oscillator", "slope", "spring"}) {
    SCOPED_TRACE(name);
    Json s = scene(name);
    EXPECT_TRUE(s.contains("dimension"));
    EXPECT_TRUE(s.contains("particles"));
    EXPECT_TRUE(s.contains("springs"));
    const std::string file = std::string(name) + ".json";
    write_text(ws.file(file), run_ok({"scene", name}).out);
    const std::vector<std::string> rest = {"--integrator", "implicit-euler", "--dt", "0.01",
                                           "--t-end", "0.1", "--json"};
    Json by_name = run_json(plus({"run", name}, rest));
    Json by_file = run_json(plus({"run", file}, rest));
    ASSERT_TRUE(by_name.contains("final_state"));
    EXPECT_EQ(by_name["diverged"], false);
    EXPECT_EQ(by_name["final_state"], by_file["final_state"]);
    EXPECT_EQ(by_name["energy_initial"], by_file["energy_initial"]);
    EXPECT_EQ(by_name["energy_final"], by_file["energy_final"]);
    EXPECT_EQ(by_name["final_state"]["x"].size(), s["particles"].size());
  }
}

// ---------------------------------------------------------------- 9. list

TEST_F(CliList, NamesEveryIntegratorAndScene) {
  const Output o = run_ok({"list"});
  for (const char* name : {"explicit-euler", "symplectic-euler", "verlet", "rk4", "implicit-euler",
                           "linear-implicit-euler", "implicit-midpoint", "chain", "cloth",
                           "oscillator", "slope", "spring"}) {
    EXPECT_TRUE(contains(o.out, name)) << name << " not in\n" << o.out;
  }
}

// The table the report draws every integrator from: one entry per
// registered method, its facts as its IntegratorInfo states them (the text
// output says the same property), and a colour and marker of its own.
TEST_F(CliList, JsonGivesEachIntegratorsFactsAndItsOwnStyle) {
  const Json j = run_json({"list", "--json"});
  const std::string text = run_ok({"list"}).out;
  ASSERT_TRUE(j["integrators"].is_array());
  std::set<std::string> names, colours, markers;
  for (const Json& e : j["integrators"]) {
    const std::string name = e["name"];
    const IntegratorInfo info = make_integrator(name)->info();
    names.insert(name);
    EXPECT_EQ(e["order"], info.order) << name;
    EXPECT_EQ(e["adaptive"], info.adaptive) << name;
    EXPECT_EQ(e["implicit"], info.implicit) << name;
    EXPECT_EQ(e["stability"]["kind"], to_string(info.stability)) << name;
    EXPECT_NE(e["stability"]["kind"], "unknown") << name;
    EXPECT_TRUE(contains(text, name + "  order " + std::to_string(info.order)));
    EXPECT_TRUE(contains(text, e["stability"]["text"].get<std::string>())) << name;
    colours.insert(e["colour"].get<std::string>());
    markers.insert(e["marker"].get<std::string>());
  }
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.end()), integrator_names());
  EXPECT_EQ(colours.size(), names.size()) << "two integrators share a colour";
  EXPECT_EQ(markers.size(), names.size()) << "two integrators share a marker";
  EXPECT_TRUE(contains(text, "rk4  order 4, fixed step, explicit, conditionally stable: "
                             "w h <= 2.828 undamped"));
  EXPECT_TRUE(contains(text, "cvode-bdf  order 5, adaptive, implicit, A(51.8 deg)-stable"));
  EXPECT_TRUE(contains(text, "arkode-erk  order 4, adaptive, explicit, conditionally stable"));
}

// ----------------------------------------------------------- 10. stability

// w of the built-in oscillator, read from its scene file. It is asked for
// with rest = 0 (a zero-rest-length spring, linear in every direction) so the
// linear stability limits hold however far the unstable runs swing.
double oscillator_omega(Json s) {
  double mass = 0.0;
  for (const Json& p : s["particles"]) {
    if (!p.value("fixed", false)) mass = p.value("mass", 1.0);
  }
  EXPECT_GT(mass, 0.0);
  EXPECT_EQ(s["springs"][0]["rest"], 0.0);
  return std::sqrt(s["springs"][0]["k"].get<double>() / mass);
}

void expect_stability_json(Json j, const std::string& integrator, double limit) {
  EXPECT_EQ(j["integrator"], integrator);
  ASSERT_TRUE(j["max_stable_dt"].is_number()) << j.dump();
  ASSERT_TRUE(j["bracket"].is_array() && j["bracket"].size() == 2) << j.dump();
  const double dt = j["max_stable_dt"].get<double>();
  const double lo = j["bracket"][0].get<double>(), hi = j["bracket"][1].get<double>();
  EXPECT_LE(lo, dt);
  EXPECT_LE(dt, hi);
  EXPECT_LE(hi / lo, 1.001 + 1e-12);
  EXPECT_GE(dt, 0.97 * limit) << j.dump();
  EXPECT_LE(dt, 1.001 * limit) << j.dump();
}

TEST_F(CliStability, SymplecticEulerNearTwoOverOmega) {
  const double w = oscillator_omega(scene("oscillator", {"-p", "rest=0"}));
  Json j = run_json({"stability", "oscillator", "-p", "rest=0", "--integrator",
                           "symplectic-euler", "--t-end", number(100.0 / w), "--dt-min",
                           number(0.05 / w), "--json"});
  expect_stability_json(j, "symplectic-euler", 2.0 / w);
}

// Just past 2 sqrt(2) / w RK4 grows only slowly: a long run is needed.
TEST_F(CliStability, Rk4NearTwoRootTwoOverOmega) {
  const double w = oscillator_omega(scene("oscillator", {"-p", "rest=0"}));
  Json j = run_json({"stability", "oscillator", "-p", "rest=0", "--integrator", "rk4",
                           "--t-end", number(1e4 / w), "--dt-min", number(0.5 / w), "--json"});
  expect_stability_json(j, "rk4", 2.0 * std::sqrt(2.0) / w);
}

TEST_F(CliStability, ImplicitEulerStableUpToDtMax) {
  Json j = run_json({"stability", "oscillator", "--integrator", "implicit-euler", "--dt-max",
                           "1", "--t-end", "10", "--json"});
  EXPECT_EQ(j["integrator"], "implicit-euler");
  EXPECT_EQ(j["max_stable_dt"], 1.0);
  ASSERT_TRUE(j["bracket"].is_array() && j["bracket"].size() == 2) << j.dump();
  EXPECT_LE(j["bracket"][0].get<double>(), 1.0);
  EXPECT_GE(j["bracket"][1].get<double>(), 1.0);
}

}  // namespace
}  // namespace springlab::test_cli
