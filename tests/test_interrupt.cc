// Ctrl-C during a sweep: the finished tasks are written as whole tables, the
// settings say "complete": false, the exit status is 130, no temporary is
// left, and no signal kills the process.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "integrators/registry/registry.h"

extern char** environ;

namespace springlab_test_interrupt {
namespace {

namespace fs = std::filesystem;

// The child gets the default action for the signals a test sends, even if
// this process was started with them ignored (a background job ignores
// SIGINT; springlab keeps a signal ignored at start ignored, as nohup needs).
struct DefaultSignals {
  DefaultSignals() {
    posix_spawnattr_init(&attr);
    sigset_t set;
    sigemptyset(&set);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, s);
    posix_spawnattr_setsigdefault(&attr, &set);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  }
  ~DefaultSignals() { posix_spawnattr_destroy(&attr); }
  posix_spawnattr_t attr;
};

TEST(Interrupt, CtrlCDuringASweepWritesFinishedTasksMarkedIncomplete) {
  const fs::path dir = fs::temp_directory_path() / ("springlab-interrupt-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Every integrator x 3 chains, one at a time: several seconds of work.
  const fs::path definition = dir / "sweep.json";
  std::ofstream(definition) << R"({"experiment": "energy", "name": "sweep", "cases": [
      {"scene": "chain", "parameters": {"n": 300, "horizontal": 1}, "dt": 0.0005, "t_end": 1, "every": 200},
      {"scene": "chain", "parameters": {"n": 300}, "dt": 0.0005, "t_end": 1, "every": 200},
      {"scene": "chain", "parameters": {"n": 200, "horizontal": 1}, "dt": 0.0005, "t_end": 1, "every": 200}]})";
  const fs::path out = dir / "out";
  std::vector<std::string> args = {SPRINGLAB_EXE, "experiment", definition.string(), "--out",
                                   out.string(), "--jobs", "1", "--no-progress"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const DefaultSignals defaults;
  ASSERT_EQ(posix_spawn(&pid, SPRINGLAB_EXE, nullptr, &defaults.attr, argv.data(), environ), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 130);

  nlohmann::json settings;
  std::ifstream(out / "sweep.json") >> settings;
  EXPECT_EQ(settings["complete"], false);
  const auto total = settings["tasks_total"].get<std::size_t>();
  const auto done = settings["tasks_done"].get<std::size_t>();
  EXPECT_EQ(total, 3 * springlab::integrator_names().size());
  EXPECT_LT(done, total);
  // The runs table has exactly one whole row per finished task, in order.
  std::ifstream runs(out / "sweep-runs.csv");
  std::string line;
  std::getline(runs, line);
  EXPECT_EQ(line.rfind("task,scene,integrator", 0), 0u);
  std::size_t rows = 0;
  long previous = -1;
  while (std::getline(runs, line)) {
    const long task = std::stol(line.substr(0, line.find(',')));
    EXPECT_GT(task, previous);
    previous = task;
    ++rows;
  }
  EXPECT_EQ(rows, done);
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace springlab_test_interrupt

namespace springlab_test_interrupt {
namespace {

// A single task that would run for minutes (a bisection at --rel-tol 1e-16
// over 10^5 periods): SIGTERM stops it inside the task, within a second, and
// the sweep is written, marked incomplete, with exit status 130.
TEST(Interrupt, SignalStopsALongTaskWithinASecond) {
  const fs::path dir = fs::temp_directory_path() / ("springlab-interrupt-task-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path definition = dir / "long.json";
  std::ofstream(definition) << R"({"experiment": "stability", "name": "long", "integrators": ["rk4"],
      "periods": 1e5, "rel_tol": 1e-16, "cases": [{"scene": "oscillator", "k": [1]}]})";
  const fs::path out = dir / "out";
  std::vector<std::string> args = {SPRINGLAB_EXE, "experiment", definition.string(), "--out",
                                   out.string(), "--no-progress"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const DefaultSignals defaults;
  ASSERT_EQ(posix_spawn(&pid, SPRINGLAB_EXE, nullptr, &defaults.attr, argv.data(), environ), 0);
  // The task is running once the tables' temporaries exist (they are made
  // after the definition is read, before any task starts).
  const auto started = std::chrono::steady_clock::now();
  auto temporaries = [&] {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(out, ec)) {
      if (entry.path().string().find("springlab-tmp") != std::string::npos) return true;
    }
    return false;
  };
  while (!temporaries() && std::chrono::steady_clock::now() - started < std::chrono::seconds(30)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // well inside the task
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const auto signalled = std::chrono::steady_clock::now();
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_LT(seconds, 1.0);
  nlohmann::json settings;
  std::ifstream(out / "long.json") >> settings;
  EXPECT_EQ(settings["complete"], false);
  EXPECT_EQ(settings["tasks_done"], 0);
  std::ifstream table(out / "long.csv");
  std::string header;
  std::getline(table, header);
  EXPECT_EQ(header.rfind("task,scene,integrator", 0), 0u);
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
  fs::remove_all(dir);
}

// Issue 46.8: the rigid experiment's reference runs inside an observer of
// the run it is compared with, and one output step of dt = 1 s at
// reference_step 2e-9 is 5e8 of its steps: the stop request is read inside
// the reference too, so SIGTERM ends the sweep within a second.
TEST(Interrupt, SignalStopsTheRigidReferenceWithinASecond) {
  const fs::path dir = fs::temp_directory_path() / ("springlab-interrupt-rigid-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path definition = dir / "rigid.json";
  std::ofstream(definition) << R"({"experiment": "rigid", "name": "rigid", "scene": "tumbling-box",
      "integrators": ["symplectic-euler"], "dt": 1, "t_end": 2, "reference_step": 2e-9})";
  const fs::path out = dir / "out";
  std::vector<std::string> args = {SPRINGLAB_EXE, "experiment", definition.string(), "--out",
                                   out.string(), "--no-progress"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const DefaultSignals defaults;
  ASSERT_EQ(posix_spawn(&pid, SPRINGLAB_EXE, nullptr, &defaults.attr, argv.data(), environ), 0);
  const auto started = std::chrono::steady_clock::now();
  auto temporaries = [&] {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(out, ec)) {
      if (entry.path().string().find("springlab-tmp") != std::string::npos) return true;
    }
    return false;
  };
  while (!temporaries() && std::chrono::steady_clock::now() - started < std::chrono::seconds(30)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // inside the reference's step
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const auto signalled = std::chrono::steady_clock::now();
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_LT(seconds, 1.0);
  nlohmann::json settings;
  std::ifstream(out / "rigid.json") >> settings;
  EXPECT_EQ(settings["complete"], false);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace springlab_test_interrupt
