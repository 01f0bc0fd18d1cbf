// Where output goes (issue 17, classes 1, 6 and 8), with targets each test
// makes itself: regular files, symbolic links, FIFOs, read-only and
// hard-linked files, pipes whose reader has gone, a file-size limit standing
// in for a full disk. Never a real device as an output.
//
//  - a symbolic link is written through to its target, and stays a link;
//  - a FIFO is written into as a stream, never replaced;
//  - an existing file keeps its permission bits, a hard link its other name;
//  - a write error (closed pipe, file-size limit) is one line and exit 1,
//    with the old file intact, on an output file and on stdout;
//  - SIGINT, SIGTERM and SIGHUP during a run remove its temporaries, and a
//    temporary left by a killed run is removed by the next run;
//  - an output file over the row cap is refused before anything runs.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "run_process.h"

extern char** environ;

namespace springlab::test_output_targets {
namespace {

namespace fs = std::filesystem;
using namespace springlab::testing;

const std::string kEnergyHeader = "t,kinetic,spring,gravity,total\n";

class OutputTargets : public ::testing::Test {
 protected:
  OutputTargets() : temp_("output-targets") {
    fs::create_directories(work());
    fs::create_directories(io());
  }
  fs::path work() const { return temp_.path() / "work"; }
  fs::path io() const { return temp_.path() / "io"; }

  // A short run of the oscillator writing its energy to `target`.
  static std::vector<std::string> energy_run(const std::string& target, const std::string& dt = "0.1") {
    return {"run", "oscillator", "--integrator", "rk4", "--dt", dt, "--t-end", "1", "--energy", target};
  }

  ProcessResult run(const std::vector<std::string>& args,
                    const std::function<void()>& child_setup = {}) {
    return run_springlab(args, work(), io(), 60.0, child_setup);
  }

  // The energy file the same run writes to a plain new file.
  std::string expected_energy(const std::string& dt = "0.1") {
    const fs::path dir = temp_.path() / "reference";
    fs::create_directories(dir);
    const ProcessResult r = run_springlab(energy_run("e.csv", dt), dir, io());
    EXPECT_TRUE(r.exited && r.status == 0) << describe(energy_run("e.csv", dt), r);
    const std::string text = read_text(dir / "e.csv");
    EXPECT_EQ(text.rfind(kEnergyHeader, 0), 0u);
    return text;
  }

  static mode_t mode_of(const fs::path& p) {
    struct stat st {};
    EXPECT_EQ(::lstat(p.c_str(), &st), 0) << p;
    return st.st_mode;
  }

  static void expect_exit(const std::vector<std::string>& args, const ProcessResult& r, int status) {
    ASSERT_TRUE(r.exited) << describe(args, r);
    EXPECT_EQ(r.status, status) << describe(args, r);
  }

  TempDir temp_;
};

TEST_F(OutputTargets, SymbolicLinkIsWrittenThroughAndStays) {
  fs::create_directories(work() / "data");
  write_text(work() / "data" / "real.csv", "precious\n");
  ::chmod((work() / "data" / "real.csv").c_str(), 0640);
  fs::create_symlink("data/real.csv", work() / "link.csv");
  const auto args = energy_run("link.csv");
  expect_exit(args, run(args), 0);
  EXPECT_TRUE(fs::is_symlink(work() / "link.csv"));
  EXPECT_EQ(fs::read_symlink(work() / "link.csv"), "data/real.csv");
  EXPECT_EQ(read_text(work() / "data" / "real.csv"), expected_energy());
  EXPECT_EQ(mode_of(work() / "data" / "real.csv") & 07777, 0640u);
  EXPECT_EQ(listing(work()), (std::vector<std::string>{"data", "link.csv"}));
  EXPECT_EQ(listing(work() / "data"), std::vector<std::string>{"real.csv"});
}

// A chain of links, the last one to a file that does not exist yet (and an
// absolute one): the file is created where the chain ends.
TEST_F(OutputTargets, LinkChainToANewFileCreatesIt) {
  fs::create_directories(work() / "a" / "b");
  fs::create_symlink(work() / "a" / "second.csv", work() / "first.csv");  // absolute
  fs::create_symlink("b/new.csv", work() / "a" / "second.csv");           // relative to a/
  const auto args = energy_run("first.csv");
  expect_exit(args, run(args), 0);
  EXPECT_TRUE(fs::is_symlink(work() / "first.csv"));
  EXPECT_TRUE(fs::is_symlink(work() / "a" / "second.csv"));
  EXPECT_EQ(read_text(work() / "a" / "b" / "new.csv"), expected_energy());
  EXPECT_EQ(listing(work() / "a" / "b"), std::vector<std::string>{"new.csv"});
}

// A FIFO is a stream: written into as rows come, still a FIFO afterwards,
// no temporary beside it.
TEST_F(OutputTargets, FifoIsWrittenIntoNotReplaced) {
  const fs::path fifo = work() / "out.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY);
    char buffer[4096];
    for (ssize_t n; fd >= 0 && (n = ::read(fd, buffer, sizeof buffer)) > 0;) received.append(buffer, n);
    if (fd >= 0) ::close(fd);
  });
  const auto args = energy_run("out.fifo");
  const ProcessResult r = run(args);
  reader.join();
  expect_exit(args, r, 0);
  EXPECT_EQ(received, expected_energy());
  EXPECT_TRUE(S_ISFIFO(mode_of(fifo)));
  EXPECT_EQ(listing(work()), std::vector<std::string>{"out.fifo"});
}

// "A full device": a FIFO whose reader goes away. The write fails (EPIPE,
// not a death by SIGPIPE): one line, exit 1.
TEST_F(OutputTargets, FifoWhoseReaderClosesIsAWriteError) {
  const fs::path fifo = work() / "out.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY);
    char buffer[100];
    if (fd >= 0) {
      [[maybe_unused]] const ssize_t n = ::read(fd, buffer, sizeof buffer);
      ::close(fd);
    }
  });
  const auto args = energy_run("out.fifo", "1e-5");  // 10^5 rows, ~8 MB
  const ProcessResult r = run(args);
  reader.join();
  expect_exit(args, r, 1);
  EXPECT_EQ(r.err, "springlab: error: out.fifo: write failed (Broken pipe)\n");
  EXPECT_EQ(r.out, "");
  EXPECT_TRUE(S_ISFIFO(mode_of(fifo)));
}

TEST_F(OutputTargets, OverwrittenFileKeepsItsPermissionBits) {
  write_text(work() / "e.csv", "old\n");
  ::chmod((work() / "e.csv").c_str(), 0604);
  const auto args = energy_run("e.csv");
  expect_exit(args, run(args), 0);
  EXPECT_EQ(mode_of(work() / "e.csv") & 07777, 0604u);
  EXPECT_EQ(read_text(work() / "e.csv"), expected_energy());
  // A new file gets what the umask leaves of 0666.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  const auto fresh = energy_run("new.csv");
  expect_exit(fresh, run(fresh), 0);
  EXPECT_EQ(mode_of(work() / "new.csv") & 07777, 0666u & ~mask);
}

// A read-only file is refused as the shell's `>` refuses it (root may write
// it, and then its bits stay).
TEST_F(OutputTargets, ReadOnlyFileIsRefusedOrKeepsItsBits) {
  write_text(work() / "e.csv", "old\n");
  ::chmod((work() / "e.csv").c_str(), 0444);
  const auto args = energy_run("e.csv");
  const ProcessResult r = run(args);
  if (::geteuid() != 0) {
    expect_exit(args, r, 1);
    EXPECT_EQ(r.err, "springlab: error: e.csv: cannot write (Permission denied)\n");
    EXPECT_EQ(read_text(work() / "e.csv"), "old\n");
  } else {
    expect_exit(args, r, 0);
    EXPECT_EQ(read_text(work() / "e.csv"), expected_energy());
  }
  EXPECT_EQ(mode_of(work() / "e.csv") & 07777, 0444u);
  EXPECT_EQ(listing(work()), std::vector<std::string>{"e.csv"});
}

// A file with a second name is rewritten in place: both names see the new
// rows, it is still one file.
TEST_F(OutputTargets, HardLinkedFileKeepsItsOtherName) {
  write_text(work() / "e.csv", "old\n");
  fs::create_hard_link(work() / "e.csv", work() / "other-name.csv");
  const auto args = energy_run("e.csv");
  expect_exit(args, run(args), 0);
  EXPECT_EQ(read_text(work() / "e.csv"), expected_energy());
  EXPECT_EQ(read_text(work() / "other-name.csv"), expected_energy());
  EXPECT_EQ(fs::hard_link_count(work() / "e.csv"), 2u);
  EXPECT_TRUE(fs::equivalent(work() / "e.csv", work() / "other-name.csv"));
}

// Another user's file we may write (here: root's, given to nobody) keeps
// its owner: rewritten in place, not replaced by a file of ours.
TEST_F(OutputTargets, AnotherUsersFileKeepsItsOwner) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
  write_text(work() / "e.csv", "old\n");
  ASSERT_EQ(::chown((work() / "e.csv").c_str(), 65534, 65534), 0);
  const auto args = energy_run("e.csv");
  expect_exit(args, run(args), 0);
  struct stat st {};
  ASSERT_EQ(::stat((work() / "e.csv").c_str(), &st), 0);
  EXPECT_EQ(st.st_uid, 65534u);
  EXPECT_EQ(read_text(work() / "e.csv"), expected_energy());
}

// "A full disk": a file-size limit of 4 KiB (RLIMIT_FSIZE) on a run that
// writes ~80 KB. The write fails (EFBIG, not a death by SIGXFSZ): one line,
// exit 1, the old file intact and no temporary left.
TEST_F(OutputTargets, FileSizeLimitIsAWriteErrorAndTheOldFileStays) {
  write_text(work() / "e.csv", "old\n");
  const auto args = energy_run("e.csv", "0.001");
  const ProcessResult r = run(args, [] {
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
  });
  expect_exit(args, r, 1);
  EXPECT_EQ(r.err, "springlab: error: e.csv: write failed (File too large)\n");
  EXPECT_EQ(read_text(work() / "e.csv"), "old\n");
  EXPECT_EQ(listing(work()), std::vector<std::string>{"e.csv"});
}

// stdout whose reader has gone (`springlab scene cloth -p n=100 | head -c0`)
// and stdout on a size-limited file: exit 1 with one line, not exit 0 with a
// truncated document.
TEST_F(OutputTargets, StdoutWriteErrorsAreErrors) {
  const auto closed_pipe = [] {
    int fds[2];
    if (::pipe(fds) == 0) {
      ::close(fds[0]);
      ::dup2(fds[1], 1);
      ::close(fds[1]);
    }
  };
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"scene", "cloth", "-p", "n=100"},
        std::vector<std::string>{"run", "oscillator", "--integrator", "rk4", "--dt", "0.1",
                                 "--t-end", "1", "--json"},
        std::vector<std::string>{"list"}}) {
    const ProcessResult r = run(args, closed_pipe);
    expect_exit(args, r, 1);
    EXPECT_EQ(r.err, "springlab: error: stdout: write failed (Broken pipe)\n") << describe(args, r);
  }
  const std::vector<std::string> scene = {"scene", "cloth", "-p", "n=100"};
  const ProcessResult r = run(scene, [] {
    const rlimit limit{65536, 65536};
    ::setrlimit(RLIMIT_FSIZE, &limit);
  });
  expect_exit(scene, r, 1);
  EXPECT_EQ(r.err, "springlab: error: stdout: write failed (File too large)\n");
}

// A trajectory over the row cap is refused before any step (or model) is
// made: 10^5 particles x 1001 output times.
TEST_F(OutputTargets, TrajectoryOverTheRowCapIsRefusedBeforeRunning) {
  write_text(work() / "t.csv", "old\n");
  const std::vector<std::string> args = {"run",  "chain", "-p",      "n=100000", "--integrator",
                                         "rk4",  "--dt",  "0.001",   "--t-end",  "1",
                                         "--trajectory", "t.csv"};
  const ProcessResult r = run(args);
  expect_exit(args, r, 1);
  EXPECT_EQ(r.err,
            "springlab: error: --trajectory: would hold 100100000 rows (100000 particles x 1001 "
            "output times), over the cap of 10000000 per file: write every K-th step with "
            "--every\n");
  EXPECT_LT(r.seconds, 10.0);
  EXPECT_EQ(read_text(work() / "t.csv"), "old\n");
  // With --every 100: 12 output times, 1.2 million rows, under the cap.
  const std::vector<std::string> every = {"run", "chain", "-p", "n=1000", "--integrator", "rk4",
                                          "--dt", "0.0001", "--t-end", "0.1", "--every", "100",
                                          "--trajectory", "t.csv"};
  expect_exit(every, run(every), 0);
}

// Temporaries named by process and host: a later run writing the same file
// removes the ones whose process is gone, and only those.
TEST_F(OutputTargets, StaleTemporariesOfAKilledRunAreRemoved) {
  char host[256] = {};
  ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ASSERT_GT(gone, 0);
  ASSERT_EQ(::waitpid(gone, nullptr, 0), gone);
  const std::string stale = "e.csv.springlab-tmp." + std::to_string(gone) + "." + host + ".AbC123";
  const std::string alive = "e.csv.springlab-tmp." + std::to_string(::getpid()) + "." + host + ".AbC123";
  const std::string elsewhere = "e.csv.springlab-tmp." + std::to_string(gone) + ".other-host.AbC123";
  const std::string other_file = "f.csv.springlab-tmp." + std::to_string(gone) + "." + host + ".AbC123";
  for (const std::string& name : {stale, alive, elsewhere, other_file}) write_text(work() / name, "x");
  const auto args = energy_run("e.csv");
  expect_exit(args, run(args), 0);
  std::vector<std::string> expected = {"e.csv", alive, elsewhere, other_file};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(listing(work()), expected);
}

// SIGINT, SIGTERM and SIGHUP during a run: the process ends by the signal,
// after removing its temporaries; the old files stay as they were.
TEST_F(OutputTargets, SignalsDuringARunRemoveItsTemporaries) {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE(signal_number);
    fs::remove_all(work());
    fs::create_directories(work());
    write_text(work() / "e.csv", "old\n");
    std::vector<std::string> args = {SPRINGLAB_EXE, "run", "chain", "-p", "n=200", "--integrator",
                                     "rk4", "--dt", "1e-5", "--t-end", "1000", "--every", "100000",
                                     "--energy", (work() / "e.csv").string(), "--trajectory",
                                     (work() / "t.csv").string()};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    // The default action for the signal even if this process ignores it
    // (a background job ignores SIGINT, and springlab keeps it ignored).
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, signal_number);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
    pid_t pid = 0;
    ASSERT_EQ(posix_spawn(&pid, SPRINGLAB_EXE, &actions, &attr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    // Wait until both temporaries exist: the run is under way.
    const auto start = std::chrono::steady_clock::now();
    while (listing(work()).size() < 3 &&
           std::chrono::steady_clock::now() - start < std::chrono::seconds(20)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_EQ(listing(work()).size(), 3u);
    ASSERT_EQ(::kill(pid, signal_number), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << WEXITSTATUS(status);
    EXPECT_EQ(WTERMSIG(status), signal_number);
    EXPECT_EQ(listing(work()), std::vector<std::string>{"e.csv"});
    EXPECT_EQ(read_text(work() / "e.csv"), "old\n");
  }
}

}  // namespace
}  // namespace springlab::test_output_targets
