// Every refusal of the command line is one `springlab: error: ...` line with
// exit status 1, nothing on stdout, and the old output file intact (issue
// 17, classes 4, 5 and 10; issue 16, "The command line"). Each case runs
// with `--energy e.csv` where it applies, in a folder holding an old e.csv.
#include <fcntl.h>
#include <sched.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "run_process.h"

namespace springlab::test_cli_refusals {
namespace {

namespace fs = std::filesystem;
using namespace springlab::testing;

struct Refusal {
  std::string name;
  std::vector<std::string> args;
  std::string message;  // after "springlab: error: "
};

std::ostream& operator<<(std::ostream& os, const Refusal& r) { return os << r.name; }

std::vector<std::string> run_args(const std::string& integrator, std::vector<std::string> more,
                                  const std::string& scene = "oscillator") {
  std::vector<std::string> args = {"run", scene, "--integrator", integrator, "--dt", "0.1",
                                   "--t-end", "1", "--energy", "e.csv"};
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

class CliRefusal : public ::testing::TestWithParam<Refusal> {
 protected:
  CliRefusal() : temp_("cli-refusal") {
    fs::create_directories(work());
    fs::create_directories(io());
    write_text(work() / "e.csv", "old\n");
  }
  fs::path work() const { return temp_.path() / "work"; }
  fs::path io() const { return temp_.path() / "io"; }
  TempDir temp_;
};

TEST_P(CliRefusal, OneLineExitOneOldFileIntact) {
  const Refusal& c = GetParam();
  const ProcessResult r = run_springlab(c.args, work(), io(), 30.0, [] {
    const int null = ::open("/dev/null", O_RDONLY);  // an empty stdin
    if (null >= 0) ::dup2(null, 0);
  });
  ASSERT_TRUE(r.exited) << describe(c.args, r);
  EXPECT_EQ(r.status, 1) << describe(c.args, r);
  EXPECT_EQ(r.out, "") << describe(c.args, r);
  EXPECT_EQ(r.err, "springlab: error: " + c.message + "\n") << describe(c.args, r);
  EXPECT_EQ(read_text(work() / "e.csv"), "old\n");
  EXPECT_EQ(listing(work()), std::vector<std::string>{"e.csv"});
  EXPECT_LT(r.seconds, 10.0);
}

const std::string kLong(5000, 'a');

INSTANTIATE_TEST_SUITE_P(
    Cli, CliRefusal,
    ::testing::Values(
        // CLI11's own errors, in springlab's words.
        Refusal{"NotANumber", {"run", "oscillator", "--integrator", "rk4", "--dt", "abc", "--t-end", "1"},
                "--dt: 'abc' is not a number"},
        Refusal{"NoCommand", {}, "a command is required: run, stability, scene, list, experiment or check (springlab --help)"},
        Refusal{"UnknownCommand", {"simulate"},
                "unknown command 'simulate' (commands: run, stability, scene, list, experiment, check; springlab --help)"},
        Refusal{"UnknownOption", {"run", "oscillator", "--bogus"},
                "unknown option --bogus (springlab run --help lists the options)"},
        Refusal{"UnknownOptionWithValue", run_args("rk4", {"--tend=3"}),
                "unknown option --tend (did you mean '--t-end'?) (springlab run --help lists the "
                "options)"},
        Refusal{"OptionTwice", run_args("rk4", {"--dt", "0.2"}), "--dt: given more than once"},
        Refusal{"OptionTwiceOnceWithEquals", run_args("rk4", {"--t-end=2"}),
                "--t-end: given more than once"},
        Refusal{"NotAWholeNumber", run_args("rk4", {"--every", "1.5"}),
                "--every: '1.5' is not a whole number"},
        Refusal{"MissingRequired", {"run", "oscillator", "--integrator", "rk4", "--t-end", "1"},
                "--dt is required (springlab run --help)"},
        Refusal{"ExtraArgument", run_args("rk4", {"extra"}),
                "unexpected argument extra (springlab run --help lists the arguments)"},
        // SCENE that is not a scene file.
        Refusal{"DirectoryAsScene", run_args("rk4", {}, "."), ".: is a directory, not a scene file"},
        Refusal{"EmptyStdinAsScene", run_args("rk4", {}, "-"),
                "stdin: malformed JSON: parse error at line 1, column 1: syntax error while parsing "
                "value - unexpected end of input; expected '[', '{', or a literal"},
        Refusal{"OverLongName", run_args("rk4", {}, kLong),
                std::string(100, 'a') + "... (5000 bytes): cannot open (File name too long) "
                                        "(built-in scenes: beam, block, box-chain, box-drop, box-on-slope, box-pile, box-tower, chain, cloth, dam-break, dam-break-obstacle, membrane, oscillator, slope, sloshing, spring, tank, tumbling-box)"},
        Refusal{"ParameterTwice", run_args("rk4", {"-p", "k=3", "-p", "k=4"}), "-p k: given twice (3 and 4)"},
        // -p takes one value: the scene after it is not swallowed.
        Refusal{"ParameterTakesOneValue",
                {"run", "-p", "n=3", "-p", "n=4", "chain", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1"},
                "-p n: given twice (3 and 4)"},
        // Options checked against the method (class 4).
        Refusal{"CvodeBdfMaxOrder", run_args("cvode-bdf", {"--max-order", "99"}),
                "--max-order 99: cvode-bdf takes 1-5 (its highest BDF order)"},
        Refusal{"IdaMaxOrder", run_args("ida", {"--max-order", "6"}),
                "--max-order 6: ida takes 1-5 (its highest BDF order)"},
        Refusal{"AdamsMaxOrder", run_args("cvode-adams", {"--max-order", "13"}),
                "--max-order 13: cvode-adams takes 1-12 (its highest Adams-Moulton order)"},
        Refusal{"ErkMaxOrderSeven", run_args("arkode-erk", {"--max-order", "7"}),
                "--max-order 7: arkode-erk takes 2-6, 8 (the order of ARKODE's default explicit table)"},
        Refusal{"StaldWithIda", run_args("ida", {"--stald"}),
                "--stald: stability limit detection is cvode-bdf's, ida has none"},
        Refusal{"DifferenceQuotientsWithKlu", run_args("cvode-bdf", {"--dq-jacobian", "--linear-solver", "klu"}),
                "--dq-jacobian: SUNDIALS forms difference-quotient Jacobians only as dense matrices: add "
                "--linear-solver dense or gmres"},
        Refusal{"DifferenceQuotientsWithAutoReduced",
                {"run", "cloth", "-p", "n=8", "--integrator", "ida", "--dq-jacobian", "--dt", "0.1",
                 "--t-end", "1", "--energy", "e.csv"},
                "--dq-jacobian: SUNDIALS forms difference-quotient Jacobians only as dense matrices "
                "(--linear-solver auto picks reduced above 100 unknowns; this system has 372): add "
                "--linear-solver dense or gmres"},
        Refusal{"DenseTooLarge",
                {"run", "cloth", "-p", "n=40", "--integrator", "cvode-bdf", "--linear-solver", "dense",
                 "--dt", "0.1", "--t-end", "1", "--energy", "e.csv"},
                "--linear-solver dense: a 9588 x 9588 Newton matrix, over the cap of 1000 unknowns for "
                "a dense one (each factorization would take seconds): use --linear-solver reduced, klu "
                "or gmres"},
        Refusal{"ToleranceBelowRoundoff", run_args("cvode-bdf", {"--rtol", "1e-300"}),
                "--rtol 1e-300: below double precision's unit roundoff (2.2e-16), a tolerance no solver "
                "can meet: use --rtol 1e-14 or more"},
        // Runs that could never be: refused before any run.
        Refusal{"StabilityImpossibleRange",
                {"stability", "oscillator", "--integrator", "rk4", "--t-end", "1000", "--dt-min", "1e-12"},
                "--dt-min 1e-12 with --t-end 1000: t_end / dt exceeds 1e9 steps"},
        // Experiments.
        Refusal{"MergeZero", {"experiment", "x.json", "--out", "out", "--merge", "0"}, "--merge: must be >= 1"},
        Refusal{"MergeWithShard", {"experiment", "x.json", "--out", "out", "--merge", "2", "--shard", "1/2"},
                "--merge and --shard: merge the shards in a run of its own, without --shard"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return info.param.name; });

// Issue 46: NaN was the method's default in disguise; a value out of range
// is printed as given (not rounded into the range); two outputs at one new
// path are refused before the run (it used to run, publish e2.csv, then
// fail); a NUL byte is refused where it is read (/dev/zero: at once, not
// after the 512 MiB cap).
INSTANTIATE_TEST_SUITE_P(
    Issue46, CliRefusal,
    ::testing::Values(
        Refusal{"BetaNan", run_args("newmark", {"--beta", "nan"}),
                "--beta: must be a finite number (got nan)"},
        Refusal{"GammaInfinite", run_args("newmark", {"--gamma", "inf"}),
                "--gamma: must be a finite number (got inf)"},
        Refusal{"AlphaNan", run_args("hht-alpha", {"--alpha", "nan"}),
                "--alpha: must be a finite number (got nan)"},
        Refusal{"RhoInfNan", run_args("generalized-alpha", {"--rho-inf", "nan"}),
                "--rho-inf: must be a finite number (got nan)"},
        Refusal{"BetaAsGiven", run_args("newmark", {"--beta", "0.5000001"}),
                "--beta: must be in [0, 0.5], got 0.5000001"},
        Refusal{"RhoInfAsGiven", run_args("generalized-alpha", {"--rho-inf", "1.0000001"}),
                "--rho-inf: must be in [0, 1] (the spectral radius at infinity), got 1.0000001"},
        Refusal{"EnergyAndVtkAtOneNewPath",
                {"run", "oscillator", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1",
                 "--energy", "e2.csv", "--vtk", "e2.csv"},
                "--energy e2.csv and --vtk e2.csv name the same path"},
        Refusal{"TrajectoryAndVtkAtOneNewPath",
                {"run", "oscillator", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1",
                 "--trajectory", "t.csv", "--vtk", "./t.csv"},
                "--trajectory t.csv and --vtk ./t.csv name the same path"},
        Refusal{"NulAtTheFirstByte", run_args("rk4", {}, "/dev/zero"),
                "/dev/zero: malformed JSON: a NUL byte at line 1, column 1 (JSON text cannot hold "
                "one)"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return info.param.name; });

// Options a method does not read are named on stderr, and the run goes on.
// Issue 38.8: counts past the experiment definitions' cap of 100000 (a
// --substeps of 2147483647 spun for ever) and empty output names (an unset
// shell variable: they were silently no output at all).
INSTANTIATE_TEST_SUITE_P(
    Limits, CliRefusal,
    ::testing::Values(
        Refusal{"SubstepsOverTheCap", run_args("xpbd", {"--substeps", "2147483647"}),
                "--substeps: must be between 1 and 100000 (got 2147483647)"},
        Refusal{"SubstepsJustOverTheCap", run_args("xpbd", {"--substeps", "100001"}),
                "--substeps: must be between 1 and 100000 (got 100001)"},
        Refusal{"IterationsOverTheCap", run_args("projective-dynamics", {"--iterations", "1000000000"}),
                "--iterations: must be between 1 and 100000 (got 1000000000)"},
        Refusal{"StabilityIterationsOverTheCap",
                {"stability", "oscillator", "--integrator", "xpbd", "--t-end", "1", "--iterations",
                 "2147483647"},
                "--iterations: must be between 1 and 100000 (got 2147483647)"},
        Refusal{"EmptyEnergyName",
                {"run", "oscillator", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1", "--energy", ""},
                "--energy: the file name is empty"},
        Refusal{"EmptyTrajectoryName", run_args("rk4", {"--trajectory", ""}),
                "--trajectory: the file name is empty"},
        Refusal{"EmptyVtkName", run_args("rk4", {"--vtk", ""}), "--vtk: the folder name is empty"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return info.param.name; });

TEST(CliNotes, OptionsTheMethodIgnoresAreNamed) {
  TempDir temp("cli-notes");
  fs::create_directories(temp.path() / "io");
  const std::vector<std::string> args = {"run", "oscillator", "--integrator", "rk4", "--dt", "0.1",
                                         "--t-end", "1", "--rtol", "1e-3", "--max-newton", "3",
                                         "--stald"};
  const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io");
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  EXPECT_EQ(r.err, "springlab: note: rk4 does not use --rtol, --max-newton, --stald (ignored)\n");
  // An adaptive method reads them; no note.
  const std::vector<std::string> adaptive = {"run", "oscillator", "--integrator", "cvode-bdf", "--dt",
                                             "0.1", "--t-end", "1", "--rtol", "1e-3"};
  const ProcessResult quiet = run_springlab(adaptive, temp.path(), temp.path() / "io");
  ASSERT_TRUE(quiet.exited && quiet.status == 0) << describe(adaptive, quiet);
  EXPECT_EQ(quiet.err, "");
}

// --help shows every default, without CLI11's "{false}" for flags.
TEST(CliHelp, ShowsDefaultsAndNoFlagNoise) {
  TempDir temp("cli-help");
  fs::create_directories(temp.path() / "io");
  for (const char* command : {"run", "stability", "experiment"}) {
    const std::vector<std::string> args = {command, "--help"};
    const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io");
    ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
    EXPECT_EQ(r.out.find('{'), std::string::npos) << r.out;
    if (std::string(command) != "experiment") {
      for (const char* shown : {"--rtol FLOAT=1e-06", "--atol FLOAT=1e-08", "--newton-tol FLOAT=0.0001",
                                "--max-newton INT=20", "--linear-solver TEXT=auto"}) {
        EXPECT_NE(r.out.find(shown), std::string::npos) << command << ": " << shown << "\n" << r.out;
      }
      // run's divergence rule, and the stability search's lower default (stability.h).
      const char* blowup = std::string(command) == "run" ? "--blowup FLOAT=1000" : "--blowup FLOAT=10 ";
      EXPECT_NE(r.out.find(blowup), std::string::npos) << command << "\n" << r.out;
    }
  }
  const ProcessResult stability =
      run_springlab({"stability", "--help"}, temp.path(), temp.path() / "io");
  for (const char* shown : {"--dt-min FLOAT=1e-06", "--dt-max FLOAT=1", "--rel-tol FLOAT=0.001"}) {
    EXPECT_NE(stability.out.find(shown), std::string::npos) << shown;
  }
}

// A scene can come through a FIFO (`<(springlab scene cloth)`) or stdin.
TEST(CliScenes, FifoAndStdinAreRead) {
  TempDir temp("cli-fifo");
  fs::create_directories(temp.path() / "io");
  const fs::path fifo = temp.path() / "scene.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string scene = run_springlab({"scene", "spring"}, temp.path(), temp.path() / "io").out;
  ASSERT_NE(scene.find("\"particles\""), std::string::npos);
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd >= 0) {
      [[maybe_unused]] const ssize_t n = ::write(fd, scene.data(), scene.size());
      ::close(fd);
    }
  });
  const std::vector<std::string> args = {"run", fifo.string(), "--integrator", "rk4", "--dt", "0.1",
                                         "--t-end", "1", "--json"};
  const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io");
  writer.join();
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  const nlohmann::json by_fifo = nlohmann::json::parse(r.out);
  const ProcessResult by_name =
      run_springlab({"run", "spring", "--integrator", "rk4", "--dt", "0.1", "--t-end", "1", "--json"},
                    temp.path(), temp.path() / "io");
  EXPECT_EQ(by_fifo["final_state"], nlohmann::json::parse(by_name.out)["final_state"]);

  write_text(temp.path() / "scene.json", scene);
  const std::vector<std::string> from_stdin = {"run", "-", "--integrator", "rk4", "--dt", "0.1",
                                               "--t-end", "1", "--json"};
  const std::string path = (temp.path() / "scene.json").string();
  const ProcessResult s = run_springlab(from_stdin, temp.path(), temp.path() / "io", 30.0, [&path] {
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd >= 0) ::dup2(fd, 0);
  });
  ASSERT_TRUE(s.exited && s.status == 0) << describe(from_stdin, s);
  EXPECT_EQ(nlohmann::json::parse(s.out)["final_state"], by_fifo["final_state"]);
}

// The bisection ends whatever --rel-tol asks: with 1e-16 it stops when the
// bracket's ends are neighbouring doubles, after about 60 runs.
TEST(CliStabilityBounds, BisectionEndsAtNeighbouringDoubles) {
  TempDir temp("cli-bisection");
  fs::create_directories(temp.path() / "io");
  const std::vector<std::string> args = {"stability", "oscillator", "--integrator", "rk4", "--t-end",
                                         "1", "--rel-tol", "1e-16", "--json"};
  const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io", 60.0);
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const double lo = j["bracket"][0].get<double>(), hi = j["bracket"][1].get<double>();
  EXPECT_LT(lo, hi);
  EXPECT_LE(hi, lo * (1.0 + 4 * std::numeric_limits<double>::epsilon()));
  EXPECT_LE(j["runs"].get<int>(), 70);
  EXPECT_EQ(j["outcome"], "bracketed");
  EXPECT_EQ(j["w_max"], 10.0);
  EXPECT_NEAR(j["theory_dt"].get<double>(), 2.0 * std::sqrt(2.0) / 10.0, 1e-15);
}

TEST(CliStabilityBounds, NothingDivergingIsSaidSo) {
  TempDir temp("cli-stable");
  fs::create_directories(temp.path() / "io");
  const std::vector<std::string> args = {"stability", "oscillator", "--integrator", "implicit-euler",
                                         "--t-end", "10"};
  const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io");
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  EXPECT_EQ(r.out,
            "implicit-euler on oscillator for t_end 10: no step diverged up to --dt-max 1 (1 run)\n"
            "the trial at 1 ran 100 s, past --t-end: every trial runs at least 100 steps and 20 "
            "periods of the fastest mode\n"
            "w_max 10 rad/s; theory: none: L-stable\n");
}

}  // namespace
}  // namespace springlab::test_cli_refusals

namespace springlab::test_cli_refusals {
namespace {

// --jobs above the usable CPUs holds that many more models for no speed:
// capped, and said so.
TEST(CliNotes, JobsAreCappedAtTheUsableCpus) {
  TempDir temp("cli-jobs");
  fs::create_directories(temp.path() / "io");
  write_text(temp.path() / "def.json",
             R"({"experiment": "energy", "integrators": ["rk4"],
                 "cases": [{"scene": "spring", "dt": 0.1, "t_end": 1}]})");
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(::sched_getaffinity(0, sizeof set, &set), 0);
  const int cpus = CPU_COUNT(&set);
  const std::vector<std::string> args = {"experiment", "def.json", "--out", "out", "--jobs", "1000",
                                         "--no-progress"};
  const ProcessResult r = run_springlab(args, temp.path(), temp.path() / "io");
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  EXPECT_EQ(r.err, "springlab: note: --jobs 1000 capped at " + std::to_string(cpus) +
                       ", the CPUs this process may use\n");
}

}  // namespace
}  // namespace springlab::test_cli_refusals
