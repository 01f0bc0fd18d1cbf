// Runs that end early with output files requested (issue 6, failure paths):
// a divergence, a Newton failure, a SUNDIALS failure. The files are published
// and hold the rows up to the last good state; the --json summary says so
// ("outputs_complete": false, "last_output_t": the last row's time), and both
// files are still valid CSV: the exact header, then rows of finite numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "csv_fields.h"
#include "run_process.h"

namespace springlab::test_failure_paths {
namespace {

namespace fs = std::filesystem;
using namespace springlab::testing;
using Json = nlohmann::json;

using Csv = csv_fields::NumberCsv;
using csv_fields::read_number_csv;

class FailurePaths : public ::testing::Test {
 protected:
  FailurePaths() : temp_("failure-paths") {
    fs::create_directories(work());
    fs::create_directories(io());
  }
  fs::path work() const { return temp_.path() / "work"; }
  fs::path io() const { return temp_.path() / "io"; }

  // Runs with --energy e.csv --trajectory t.csv --json; expects exit 0 and
  // both files published (nothing else in the directory).
  Json run(std::vector<std::string> args) {
    args.insert(args.end(), {"--energy", "e.csv", "--trajectory", "t.csv", "--json"});
    const ProcessResult r = run_springlab(args, work(), io());
    EXPECT_TRUE(r.exited && r.status == 0) << describe(args, r);
    EXPECT_EQ(listing(work()), (std::vector<std::string>{"e.csv", "t.csv"})) << describe(args, r);
    Json j = Json::parse(r.out, nullptr, /*allow_exceptions=*/false);
    EXPECT_TRUE(j.is_object()) << describe(args, r);
    return j.is_object() ? j : Json::object();
  }

  // The files end at the last good state the summary names, and say what a
  // complete run's files would say otherwise.
  void expect_consistent(const Json& j, std::size_t particles, int dimension) {
    ASSERT_TRUE(j.contains("outputs_complete")) << j.dump();
    ASSERT_TRUE(j.contains("last_output_t")) << j.dump();
    ASSERT_TRUE(j["last_output_t"].is_number()) << j.dump();
    const bool completed = j["status"] == "completed";
    EXPECT_EQ(j["outputs_complete"], completed) << j.dump();
    EXPECT_EQ(j["diverged"], !completed) << j.dump();
    const double last = j["last_output_t"].get<double>();
    EXPECT_EQ(last, j["t_final"].get<double>()) << j.dump();
    if (completed) {
      EXPECT_EQ(last, j["t_end"].get<double>());
    } else {
      ASSERT_TRUE(j["diverged_at"].is_number()) << j.dump();
      EXPECT_LT(last, j["diverged_at"].get<double>());
    }

    const Csv energy = read_number_csv(work() / "e.csv");
    EXPECT_EQ(energy.header, "t,kinetic,spring,gravity,total");
    ASSERT_FALSE(energy.rows.empty());
    EXPECT_EQ(energy.rows.front()[0], 0.0);
    EXPECT_EQ(energy.rows.back()[0], last);
    EXPECT_EQ(energy.rows.back()[4], j["energy_final"].get<double>());
    for (std::size_t k = 1; k < energy.rows.size(); ++k) {
      EXPECT_LT(energy.rows[k - 1][0], energy.rows[k][0]) << "row " << k;
    }

    const Csv trajectory = read_number_csv(work() / "t.csv");
    EXPECT_EQ(trajectory.header, dimension == 2 ? "t,i,x,y,vx,vy" : "t,i,x,y,z,vx,vy,vz");
    ASSERT_EQ(trajectory.rows.size(), energy.rows.size() * particles);
    for (std::size_t k = 0; k < trajectory.rows.size(); ++k) {
      EXPECT_EQ(trajectory.rows[k][0], energy.rows[k / particles][0]) << "row " << k;
      EXPECT_EQ(trajectory.rows[k][1], static_cast<double>(k % particles)) << "row " << k;
    }
    // The last rows are the final state the summary reports.
    const Json& x = j["final_state"]["x"];
    ASSERT_EQ(x.size(), particles);
    for (std::size_t i = 0; i < particles; ++i) {
      const std::vector<double>& row = trajectory.rows[trajectory.rows.size() - particles + i];
      for (int r = 0; r < dimension; ++r) {
        const auto axis = static_cast<std::size_t>(r);
        EXPECT_EQ(row[2 + axis], x[i][axis].get<double>());
      }
    }
  }

  TempDir temp_;
};

TEST_F(FailurePaths, CompletedRunSaysItsOutputsAreComplete) {
  const Json j = run({"run", "spring", "--integrator", "rk4", "--dt", "0.01", "--t-end", "0.5",
                      "--every", "7"});
  EXPECT_EQ(j["status"], "completed");
  expect_consistent(j, 2, 2);
}

// Explicit Euler blows up; --every 7 makes the last good state fall between
// two regular rows, so it is appended as a row of its own.
TEST_F(FailurePaths, DivergenceMidRun) {
  const Json j = run({"run", "oscillator", "--integrator", "explicit-euler", "--dt", "0.05",
                      "--t-end", "100", "--every", "7"});
  EXPECT_EQ(j["status"], "diverged");
  EXPECT_GT(j["t_final"].get<double>(), 0.0);
  // The message says what the rule saw and what to try (issue 38: it was
  // null). E_s = T(0) + U_spring(0) = 0.5 J for the oscillator (k = m = 1,
  // x0 = 1): the bound is 1000 x 0.5 = 500 J.
  ASSERT_TRUE(j["failure"].is_string()) << j.dump();
  const std::string failure = j["failure"].get<std::string>();
  EXPECT_EQ(failure.find("kinetic + spring energy "), 0u) << failure;
  EXPECT_NE(failure.find(" J exceeded --blowup 1000 x E_s = 500 J; explicit-euler is unstable "
                         "or inaccurate at this step: try a smaller --dt"),
            std::string::npos)
      << failure;
  expect_consistent(j, 2, 2);
}

TEST_F(FailurePaths, DivergenceOfAClothIn3D) {
  const Json j = run({"run", "cloth", "-p", "n=5", "--integrator", "explicit-euler", "--dt",
                      "0.02", "--t-end", "10"});
  EXPECT_EQ(j["status"], "diverged");
  expect_consistent(j, 25, 3);
}

// Newton-Raphson capped at too few iterations for this step.
TEST_F(FailurePaths, NewtonNotConverging) {
  const Json j = run({"run", "chain", "-p", "n=10", "-p", "horizontal=1", "--integrator",
                      "implicit-euler", "--dt", "0.02", "--t-end", "2", "--max-newton", "3"});
  EXPECT_EQ(j["status"], "failed");
  ASSERT_TRUE(j["failure"].is_string()) << j.dump();
  EXPECT_NE(j["failure"].get<std::string>().find("Newton failed"), std::string::npos) << j.dump();
  expect_consistent(j, 10, 2);
}

// CVODE out of internal steps (--max-steps) part-way through.
TEST_F(FailurePaths, SundialsTooMuchWork) {
  const Json j = run({"run", "cloth", "-p", "n=6", "--integrator", "cvode-bdf", "--rtol", "1e-8",
                      "--dt", "0.1", "--t-end", "2", "--max-steps", "10"});
  EXPECT_EQ(j["status"], "failed");
  ASSERT_TRUE(j["failure"].is_string()) << j.dump();
  EXPECT_NE(j["failure"].get<std::string>().find("mxstep"), std::string::npos) << j["failure"];
  expect_consistent(j, 36, 3);
}

// A tolerance no double can meet is refused before anything is written
// (it used to fail on the first call and replace the old files).
TEST_F(FailurePaths, SundialsImpossibleToleranceIsRefusedUpFront) {
  write_text(work() / "e.csv", "old\n");
  const std::vector<std::string> args = {"run",   "spring", "--integrator", "ida",     "--dt",
                                         "0.1",   "--t-end", "1",           "--rtol",  "1e-300",
                                         "--atol", "1e-300", "--energy",    "e.csv",   "--json"};
  const ProcessResult r = run_springlab(args, work(), io());
  ASSERT_TRUE(r.exited) << describe(args, r);
  EXPECT_EQ(r.status, 1) << describe(args, r);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err,
            "springlab: error: --rtol 1e-300: below double precision's unit roundoff (2.2e-16), a "
            "tolerance no solver can meet: use --rtol 1e-14 or more\n");
  EXPECT_EQ(read_text(work() / "e.csv"), "old\n");
  EXPECT_EQ(listing(work()), std::vector<std::string>{"e.csv"});
}

// Near double precision's limit SUNDIALS can still fail; the failure says
// what to try.
TEST_F(FailurePaths, SundialsErrorTestFailuresSayWhatToTry) {
  const Json j = run({"run", "spring", "--integrator", "ida", "--dt", "0.1", "--t-end", "1",
                      "--rtol", "3e-16", "--atol", "1e-20"});
  EXPECT_EQ(j["status"], "failed");
  ASSERT_TRUE(j["failure"].is_string()) << j.dump();
  EXPECT_NE(j["failure"].get<std::string>().find("(flag -3)"), std::string::npos) << j["failure"];
  EXPECT_NE(j["failure"].get<std::string>().find("try a looser --rtol or --atol"), std::string::npos)
      << j["failure"];
  expect_consistent(j, 2, 2);
}

// Without output files there is no last row: last_output_t is null.
TEST_F(FailurePaths, NoOutputFilesNoLastRow) {
  const std::vector<std::string> args = {"run",   "oscillator", "--integrator", "explicit-euler",
                                         "--dt",  "0.05",       "--t-end",      "100",
                                         "--json"};
  const ProcessResult r = run_springlab(args, work(), io());
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  const Json j = Json::parse(r.out);
  EXPECT_EQ(j["outputs_complete"], false);
  EXPECT_TRUE(j["last_output_t"].is_null()) << j.dump();
  EXPECT_EQ(listing(work()), std::vector<std::string>{});
}

// The text summary says the files are incomplete, and up to when.
TEST_F(FailurePaths, TextSummaryNamesTheLastRow) {
  const std::vector<std::string> args = {"run",  "oscillator", "--integrator", "explicit-euler",
                                         "--dt", "0.05",       "--t-end",      "100",
                                         "--energy", "e.csv"};
  const ProcessResult r = run_springlab(args, work(), io());
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  EXPECT_NE(r.out.find("output files incomplete: rows up to t = 1.5, the last good state"),
            std::string::npos)
      << r.out;
}

}  // namespace
}  // namespace springlab::test_failure_paths
