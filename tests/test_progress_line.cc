// The run's progress line on a terminal (docs/command-line.md "Progress";
// issue 38.10: arkode-dirk on the block at E = 1e9 creeps at about 80 s per
// simulated second, and says so): after a second, one line on stderr,
// rewritten in place, with the simulated time, the share done, the seconds
// so far and the seconds left at that pace; cleared at the end. Run under a
// pseudo-terminal, as a user's shell runs it.
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

namespace springlab_test_progress_line {
namespace {

namespace fs = std::filesystem;

// Runs argv on a new pseudo-terminal (stdin, stdout and stderr); returns
// what it printed there and its exit status in `status`.
// With `seconds` > 0, SIGINT is sent that long after the start.
std::string run_on_terminal(std::vector<std::string> args, int& status, double seconds = 0.0) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int master = -1;
  const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
  if (pid == 0) {
    ::execv(argv[0], argv.data());
    std::_Exit(127);
  }
  std::string out;
  if (pid < 0) return out;
  const auto start = std::chrono::steady_clock::now();
  bool interrupted = false;
  char buffer[4096];
  for (;;) {
    if (seconds > 0.0 && !interrupted) {
      // Wait for output up to the deadline, then interrupt.
      const double left =
          seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      pollfd ready{.fd = master, .events = POLLIN, .revents = 0};
      if (left <= 0.0 || ::poll(&ready, 1, static_cast<int>(1000.0 * left) + 1) == 0) {
        ::kill(pid, SIGINT);
        interrupted = true;
        continue;
      }
    }
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n > 0) {
      out.append(buffer, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;  // EIO once the child has closed the terminal
    }
  }
  ::close(master);
  ::waitpid(pid, &status, 0);
  return out;
}

TEST(ProgressLine, SaysTheTimeLeftOfASlowRunAndIsClearedAtTheEnd) {
  const fs::path dir = fs::temp_directory_path() / ("springlab-progress-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  int status = -1;
  const std::string out = run_on_terminal(
      {SPRINGLAB_EXE, "run", "block", "-p", "young=1e9", "--integrator", "arkode-dirk", "--dt",
       "0.0025", "--t-end", "0.04", "--energy", (dir / "e.csv").string()},
      status);
  fs::remove_all(dir);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << out;
  // [arkode-dirk] t = 0.02 of 0.04 s (50%), 1 s, about 1 s left
  const std::regex line(
      R"(\[arkode-dirk\] t = ([0-9.e+-]+) of 0\.04 s \(([0-9]+)%\), ([0-9]+) s, about ([0-9]+) s left)");
  int lines = 0;
  std::size_t end_of_last = 0;
  for (auto it = std::sregex_iterator(out.begin(), out.end(), line); it != std::sregex_iterator();
       ++it) {
    const double t = std::stod((*it)[1]);
    const int percent = std::stoi((*it)[2]);
    const double elapsed = std::stod((*it)[3]), left = std::stod((*it)[4]);
    SCOPED_TRACE((*it)[0].str());
    EXPECT_GT(t, 0.0);
    EXPECT_LE(t, 0.04);
    EXPECT_EQ(percent, static_cast<int>(100.0 * t / 0.04));
    EXPECT_GE(elapsed, 1.0) << "nothing in the first second";
    // The time left at the pace so far, each figure rounded to a second.
    EXPECT_NEAR(left, elapsed * (0.04 - t) / t, 0.5 + 0.5 * (0.04 - t) / t);
    end_of_last = static_cast<std::size_t>(it->position(0) + it->length(0));
    ++lines;
  }
  // The run takes about 3 s of CPU on the quiet 2-core machine (9 s loaded,
  // about 90 s under ASan): the line appears after the first second.
  ASSERT_GE(lines, 1) << "no progress line in: " << out;
  // The line is cleared before the run's summary is printed.
  EXPECT_EQ(out.compare(end_of_last, 4, "\r\033[K"), 0) << out.substr(end_of_last, 40);
  EXPECT_NE(out.find("status completed", end_of_last), std::string::npos) << out;
}

// The stability search's line (issue 46.14): an adaptive method's trial
// can spend minutes inside one output interval (arkode-dirk on two hinged
// boxes: each interval of 1 s took 7 s, and the search's first trial, at
// --dt-max, runs 100 of them), so the line is redrawn every second, not
// only at output times. At --dt-max 50 the first interval takes minutes:
// within 3 s the line says so, at t = 0, with the seconds spent.
TEST(StabilityProgress, ShowsATrialThatIsStillInItsFirstInterval) {
  int status = -1;
  const std::string out = run_on_terminal(
      {SPRINGLAB_EXE, "stability", "box-chain", "-p", "n=2", "--integrator", "arkode-dirk",
       "--t-end", "0.5", "--dt-max", "50"},
      status, 3.0);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << out;
  // [stability arkode-dirk] run 1: dt 50, t = 0 of 5000 s, 2 s
  const std::regex line(R"(\[stability arkode-dirk\] run 1: dt 50, t = 0 of 5000 s, ([0-9]+) s)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, line)) << "no progress line in: " << out;
  EXPECT_GE(std::stoi(m[1]), 1) << "nothing in the first second";
}

}  // namespace
}  // namespace springlab_test_progress_line
