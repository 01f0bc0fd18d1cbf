// Runs the real springlab executable as a child process (the approach of
// test_cli.cc): stdout and stderr captured through files, the working
// directory chosen, and the way the process ended recorded, so a test can
// tell an exit status from a signal. A child that runs past its time limit is
// killed and reported as such: a hang is a failure, not a stuck test run.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef SPRINGLAB_EXE
#error "SPRINGLAB_EXE must name the springlab executable"
#endif

namespace springlab::testing {

namespace fs = std::filesystem;

struct ProcessResult {
  bool started = false;
  bool exited = false;    // ended by exit(), not by a signal
  int status = -1;        // the exit status when exited
  int signal = 0;         // the signal when not exited
  bool timed_out = false; // killed by run_springlab after its time limit
  double seconds = 0.0;
  std::string out, err;
};

inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// Runs `springlab args...` in `cwd`; stdout and stderr go to files in `io_dir`
// (which must exist and should not be `cwd`, so that they are not mistaken
// for output files). `child_setup`, when given, runs in the child just before
// exec, after the redirections (to replace stdin or stdout, set a limit).
inline ProcessResult run_springlab(const std::vector<std::string>& args, const fs::path& cwd,
                                   const fs::path& io_dir, double timeout_seconds = 120.0,
                                   const std::function<void()>& child_setup = {}) {
  static int runs = 0;
  const std::string tag = std::to_string(::getpid()) + "-" + std::to_string(runs++);
  const std::string out_path = (io_dir / (tag + ".out")).string();
  const std::string err_path = (io_dir / (tag + ".err")).string();
  const std::string work_dir = cwd.string();
  std::vector<std::string> strings = {SPRINGLAB_EXE};
  strings.insert(strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);

  ProcessResult result;
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0 || err < 0 || ::chdir(work_dir.c_str()) != 0 || ::dup2(out, 1) < 0 ||
        ::dup2(err, 2) < 0) {
      ::_exit(126);
    }
    if (child_setup) child_setup();
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  if (pid < 0) return result;
  result.started = true;
  int wstatus = 0;
  while (true) {
    const pid_t done = ::waitpid(pid, &wstatus, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) return result;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed > timeout_seconds && !result.timed_out) {
      result.timed_out = true;
      ::kill(pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.out = read_text(out_path);
  result.err = read_text(err_path);
  std::error_code ignored;
  fs::remove(out_path, ignored);
  fs::remove(err_path, ignored);
  if (WIFEXITED(wstatus)) {
    result.exited = true;
    result.status = WEXITSTATUS(wstatus);
  } else if (WIFSIGNALED(wstatus)) {
    result.signal = WTERMSIG(wstatus);
  }
  return result;
}

inline std::string describe(const std::vector<std::string>& args, const ProcessResult& r) {
  std::string command = "springlab";
  for (const std::string& a : args) command += " " + a;
  std::string how = r.timed_out        ? "killed after the time limit"
                    : r.exited         ? "exit " + std::to_string(r.status)
                    : r.started        ? "killed by signal " + std::to_string(r.signal)
                                       : "could not start";
  return command + "\n" + how + "\nstdout: " + r.out + "\nstderr: " + r.err;
}

// A fresh temporary directory per test, removed afterwards.
class TempDir {
 public:
  explicit TempDir(const std::string& label) {
    std::string name = label;
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '_';
    }
    root_ = fs::temp_directory_path() /
            ("springlab-" + name + "-" + std::to_string(::getpid()) + "-" +
             std::to_string(counter()++));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return root_; }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  fs::path root_;
};

// Names of everything directly in `dir`, sorted.
inline std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    names.push_back(entry.path().filename());
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace springlab::testing
