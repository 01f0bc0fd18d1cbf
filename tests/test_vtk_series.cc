// --vtk DIR and refusals before the first step (issue 38, findings 3, 4, 6
// and 8; issue 33, "Refusals at t = 0 are errors"):
//
//  - a pairing the method refuses before its first step (xpbd and the
//    block's neo-Hookean material, projective dynamics and the barrier) is
//    one `springlab: error:` line naming the fix, exit 1, and no output file
//    created or changed; `stability` refuses it the same way;
//  - a --vtk write that fails leaves DIR exactly as it was (names, contents,
//    modes): a folder where the .pvd goes, another user's old frames in a
//    sticky folder;
//  - a new DIR gets 0777 minus the umask, its frames 0666 minus the umask;
//  - a temporary folder left by `kill -9` is removed by the next run;
//  - the series written is the state the trajectory holds, frame by frame,
//    and the same into a new folder as into an old one.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <grp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "csv_fields.h"
#include "run_process.h"

extern char** environ;

namespace springlab::test_vtk_series {
namespace {

namespace fs = std::filesystem;
using namespace springlab::testing;

// Everything under a folder: relative path -> type, mode bits and contents.
std::map<std::string, std::string> snapshot(const fs::path& root) {
  std::map<std::string, std::string> entries;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    struct stat st {};
    EXPECT_EQ(::lstat(e.path().c_str(), &st), 0) << e.path();
    std::string what = (S_ISDIR(st.st_mode) ? "dir " : "file ") + std::to_string(st.st_mode & 07777) +
                       " uid " + std::to_string(st.st_uid);
    if (S_ISREG(st.st_mode)) what += " " + read_text(e.path());
    entries[fs::relative(e.path(), root).string()] = what;
  }
  return entries;
}

bool has_temporary(const fs::path& dir) {
  for (const std::string& name : listing(dir)) {
    if (name.find(".springlab-tmp.") != std::string::npos) return true;
  }
  return false;
}

class VtkSeriesTest : public ::testing::Test {
 protected:
  VtkSeriesTest() : temp_("vtk-series") {
    fs::create_directories(work());
    fs::create_directories(io());
  }
  fs::path work() const { return temp_.path() / "work"; }
  fs::path io() const { return temp_.path() / "io"; }

  // The cloth n=3 with rk4 to t_end, frames every 0.01 s, into `dir`.
  static std::vector<std::string> cloth(const std::string& dir, const std::string& t_end,
                                        std::vector<std::string> more = {}) {
    std::vector<std::string> args = {"run", "cloth", "-p", "n=3", "--integrator", "rk4",
                                     "--dt", "0.01", "--t-end", t_end, "--vtk", dir};
    args.insert(args.end(), more.begin(), more.end());
    return args;
  }
  ProcessResult run(const std::vector<std::string>& args, const std::function<void()>& setup = {}) {
    return run_springlab(args, work(), io(), 60.0, setup);
  }
  void run_ok(const std::vector<std::string>& args) {
    const ProcessResult r = run(args);
    ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  }

  TempDir temp_;
};

// issue 38.6, issue 33: refused before the first step, nothing written.
TEST_F(VtkSeriesTest, RefusedPairingIsAnErrorAndWritesNothing) {
  // An old energy file and an old series of the block in keepv/.
  write_text(work() / "keep2.csv", "old\n");
  const std::vector<std::string> old_block = {"run", "block", "-p", "n=2", "-p", "model=1",
                                              "--integrator", "xpbd", "--dt", "0.01",
                                              "--t-end", "0.02", "--vtk", "keepv"};
  run_ok(old_block);
  const auto before = snapshot(work());
  ASSERT_EQ(before.count("keepv/block.pvd"), 1u);

  const std::vector<std::string> refused = {"run", "block", "-p", "n=2", "-p", "model=3",
                                            "--integrator", "xpbd", "--dt", "0.01", "--t-end",
                                            "0.05", "--energy", "keep2.csv", "--vtk", "keepv",
                                            "--json"};
  const ProcessResult r = run(refused);
  ASSERT_TRUE(r.exited) << describe(refused, r);
  EXPECT_EQ(r.status, 1) << describe(refused, r);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err.rfind("springlab: error: --integrator xpbd: this scene's tetrahedron elements are "
                        "of material 'material' (neo-hookean, poisson 0.3), which has no projective "
                        "form",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find("(for this scene: -p model=corotated)\n"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(snapshot(work()), before);  // keep2.csv and keepv/ untouched, nothing new

  // The barrier with either projection method: the same, naming -p contact=0.
  for (const char* method : {"xpbd", "projective-dynamics"}) {
    const std::vector<std::string> barrier = {
        "run", "cloth", "-p", "n=4", "-p", "ground=0.5", "-p", "contact=1", "--integrator", method,
        "--dt", "0.01", "--t-end", "0.05", "--energy", "keep2.csv", "--vtk", "keepv"};
    const ProcessResult b = run(barrier);
    ASSERT_TRUE(b.exited) << describe(barrier, b);
    EXPECT_EQ(b.status, 1) << describe(barrier, b);
    EXPECT_EQ(b.err, "springlab: error: --integrator " + std::string(method) +
                         ": this scene's contact is the barrier, whose energy is infinite on the "
                         "plane, where a projection puts a particle; use the penalty contact with " +
                         method + ", or implicit-euler with the barrier (for this scene: -p "
                                  "contact=0 (penalty))\n");
    EXPECT_EQ(snapshot(work()), before);
  }

  // A scene file has no -p: the method's own words, no hint.
  write_text(work() / "block.json",
             run_springlab({"scene", "block", "-p", "n=2"}, work(), io()).out);
  const auto with_file = snapshot(work());
  const std::vector<std::string> file = {"run", "block.json", "--integrator", "projective-dynamics",
                                         "--dt", "0.01", "--t-end", "0.05", "--energy", "keep2.csv"};
  const ProcessResult f = run(file);
  EXPECT_EQ(f.status, 1) << describe(file, f);
  EXPECT_EQ(f.err.find("(for this scene"), std::string::npos) << f.err;
  EXPECT_NE(f.err.find("use such a material, or implicit-euler\n"), std::string::npos) << f.err;
  EXPECT_EQ(snapshot(work()), with_file);

  // A failure during the run stays a result: exit 0, status failed.
  const std::vector<std::string> during = {"run", "chain", "-p", "n=10", "-p", "horizontal=1",
                                           "--integrator", "implicit-euler", "--dt", "0.02",
                                           "--t-end", "2", "--max-newton", "3", "--json"};
  const ProcessResult d = run(during);
  ASSERT_TRUE(d.exited && d.status == 0) << describe(during, d);
  EXPECT_NE(d.out.find("\"status\":\"failed\""), std::string::npos) << d.out;
}

// `stability` with a refused pairing said "diverged even at --dt-min".
TEST_F(VtkSeriesTest, StabilityOfARefusedPairingIsAnError) {
  const std::vector<std::string> args = {"stability", "beam", "--integrator", "xpbd", "--t-end", "0.1"};
  const ProcessResult r = run(args);
  ASSERT_TRUE(r.exited) << describe(args, r);
  EXPECT_EQ(r.status, 1) << describe(args, r);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err.rfind("springlab: error: --integrator xpbd: this scene's ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("(for this scene: -p model=corotated)\n"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("diverged"), std::string::npos) << r.err;
}

// issue 38.3: DIR/<name>.pvd is a folder. The run used to replace frames,
// delete the old later ones and then fail on the .pvd.
TEST_F(VtkSeriesTest, FolderWhereThePvdGoesLeavesDirAsItWas) {
  run_ok(cloth("v", "0.05"));  // frames 0..5
  ASSERT_EQ(listing(work() / "v").size(), 7u);
  fs::remove(work() / "v" / "cloth.pvd");
  fs::create_directories(work() / "v" / "cloth.pvd");
  write_text(work() / "v" / "cloth.pvd" / "inside", "x");
  const auto before = snapshot(work());
  const auto args = cloth("v", "0.02");
  const ProcessResult r = run(args);
  ASSERT_TRUE(r.exited) << describe(args, r);
  EXPECT_EQ(r.status, 1) << describe(args, r);
  EXPECT_EQ(r.err,
            "springlab: error: v/cloth.pvd: is a folder, where the series' file goes (--vtk v): "
            "remove or rename it\n");
  EXPECT_EQ(snapshot(work()), before);
  EXPECT_FALSE(has_temporary(work() / "v"));
}

// issue 38.3: a sticky shared folder whose old series is partly another
// user's: refused before the run (it used to replace the frames it could,
// then fail), DIR as it was.
TEST_F(VtkSeriesTest, AnotherUsersSeriesInAStickyFolderLeavesDirAsItWas) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give files to two users";
  const uid_t nobody = 65534;
  const fs::path shared = work() / "shared";
  fs::create_directories(shared);
  ASSERT_EQ(::chmod(shared.c_str(), 01777), 0);
  ASSERT_EQ(::chmod(temp_.path().c_str(), 0755), 0);
  ASSERT_EQ(::chmod(work().c_str(), 0755), 0);
  run_ok(cloth("shared", "0.05"));  // frames 0..5, root's
  // Frames 0 and 1 and the .pvd are nobody's, 2..5 stay root's.
  for (const char* name : {"cloth_000000.vtu", "cloth_000001.vtu", "cloth.pvd"}) {
    ASSERT_EQ(::chown((shared / name).c_str(), nobody, nobody), 0);
  }
  const auto before = snapshot(work());
  const auto args = cloth("shared", "0.02");
  const ProcessResult r = run(args, [] {
    ::setgroups(0, nullptr);
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(125);
  });
  ASSERT_TRUE(r.exited) << describe(args, r);
  EXPECT_EQ(r.status, 1) << describe(args, r);
  EXPECT_EQ(r.err,
            "springlab: error: shared/cloth_000002.vtu: belongs to another user in a sticky "
            "folder, so it cannot be replaced: choose another --vtk folder\n");
  EXPECT_EQ(snapshot(work()), before);
}

// issue 38.8: a new DIR gets 0777 minus the umask (it was 0700 whatever
// the umask), its files 0666 minus the umask.
TEST_F(VtkSeriesTest, NewFolderHonoursTheUmask) {
  for (const mode_t mask : {mode_t{022}, mode_t{027}, mode_t{077}}) {
    SCOPED_TRACE(mask);
    const std::string dir = "v" + std::to_string(mask);
    const auto args = cloth(dir, "0.01");
    const ProcessResult r = run(args, [mask] { ::umask(mask); });
    ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
    struct stat st {};
    ASSERT_EQ(::stat((work() / dir).c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 07777, 0777 & ~mask);
    for (const std::string& name : listing(work() / dir)) {
      ASSERT_EQ(::stat((work() / dir / name).c_str(), &st), 0);
      EXPECT_EQ(st.st_mode & 07777, 0666 & ~mask) << name;
    }
  }
}

// issue 38.8: `kill -9` during --vtk left its temporary folder for good;
// the next run beside it removes it (a live process's stays).
TEST_F(VtkSeriesTest, TemporaryFoldersOfAKilledRunAreRemoved) {
  for (const bool existing : {true, false}) {
    SCOPED_TRACE(existing ? "into an existing folder" : "into a new folder");
    fs::remove_all(work());
    fs::create_directories(work());
    if (existing) fs::create_directories(work() / "v");
    const fs::path where = existing ? work() / "v" : work();
    std::vector<std::string> args = {SPRINGLAB_EXE, "run", "chain", "-p", "n=50", "--integrator",
                                     "rk4", "--dt", "1e-4", "--t-end", "1000", "--every", "100",
                                     "--vtk", (work() / "v").string()};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid = 0;
    ASSERT_EQ(posix_spawn(&pid, SPRINGLAB_EXE, &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    // Wait until its temporary folder holds a few frames.
    const auto start = std::chrono::steady_clock::now();
    fs::path temporary;
    while (std::chrono::steady_clock::now() - start < std::chrono::seconds(30)) {
      for (const std::string& name : listing(where)) {
        if (name.find(".springlab-tmp.") != std::string::npos) temporary = where / name;
      }
      if (!temporary.empty() && listing(temporary).size() >= 3) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_FALSE(temporary.empty());
    ASSERT_EQ(::kill(pid, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(fs::is_directory(temporary));
    // A folder of a live process (this one) of the same pattern stays.
    char host[256] = {};
    ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
    const fs::path alive =
        where / ((existing ? std::string() : std::string("v")) + ".springlab-tmp." +
                 std::to_string(::getpid()) + "." + host + ".AbC123");
    fs::create_directories(alive);
    write_text(alive / "cloth_000000.vtu", "x");

    run_ok(cloth("v", "0.02"));
    EXPECT_FALSE(fs::exists(temporary)) << temporary;
    EXPECT_TRUE(fs::exists(alive / "cloth_000000.vtu"));
    fs::remove_all(alive);
    EXPECT_FALSE(has_temporary(where));
    EXPECT_EQ(listing(work() / "v"), (std::vector<std::string>{"cloth.pvd", "cloth_000000.vtu",
                                                                 "cloth_000001.vtu", "cloth_000002.vtu"}));
  }
}

// issue 38.4 changed how frames are written (straight into the temporary
// folder): each frame still holds the state the trajectory holds, and a
// series is the same byte for byte into a new folder as over an old,
// longer one.
TEST_F(VtkSeriesTest, FramesHoldTheTrajectoryAndAnOldFolderGetsTheSameSeries) {
  run_ok(cloth("fresh", "0.05", {"--trajectory", "t.csv"}));
  std::vector<std::vector<std::string>> rows;
  {
    std::istringstream lines(read_text(work() / "t.csv"));
    std::string line;
    std::getline(lines, line);  // the header
    while (std::getline(lines, line)) rows.push_back(csv_fields::split_fields(line));
  }
  ASSERT_EQ(rows.size(), 6u * 9u);
  for (int k = 0; k <= 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "cloth_%06d.vtu", k);
    const std::string frame = read_text(work() / "fresh" / name);
    std::string points, velocities;
    for (int i = 0; i < 9; ++i) {
      const std::vector<std::string>& row = rows[static_cast<std::size_t>(k * 9 + i)];
      ASSERT_EQ(row.size(), 8u);  // t,i,x,y,z,vx,vy,vz
      points += row[2] + ' ' + row[3] + ' ' + row[4] + ' ';
      velocities += row[5] + ' ' + row[6] + ' ' + row[7] + ' ';
    }
    EXPECT_NE(frame.find("format=\"ascii\">" + rows[static_cast<std::size_t>(k * 9)][0] +
                         "</DataArray>"),
              std::string::npos)
        << name;
    EXPECT_NE(frame.find("NumberOfComponents=\"3\" format=\"ascii\">" + points + "</DataArray>"),
              std::string::npos)
        << name;
    EXPECT_NE(frame.find("format=\"ascii\">" + velocities + "</DataArray>"), std::string::npos)
        << name;
  }
  // An old folder with a longer series of the same scene and a file of its own.
  fs::create_directories(work() / "old");
  write_text(work() / "old" / "mine.txt", "x");
  run_ok(cloth("old", "0.09"));
  run_ok(cloth("old", "0.05"));
  auto fresh = snapshot(work() / "fresh");
  auto old = snapshot(work() / "old");
  EXPECT_EQ(old.erase("mine.txt"), 1u);
  EXPECT_EQ(old, fresh);
}

}  // namespace
}  // namespace springlab::test_vtk_series
