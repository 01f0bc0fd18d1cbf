#include "experiments/io/output_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "experiments/io/signals.h"
#include "models/model/energy_layout.h"

namespace springlab {

std::string format_number(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (ec != std::errc()) return "nan";
  return std::string(buffer, end);
}

namespace {

constexpr std::size_t kFileBuffer = std::size_t{1} << 20;   // a regular file: 1 MiB writes
constexpr std::size_t kStreamBuffer = std::size_t{1} << 16; // a stream: 64 KiB, or
constexpr auto kStreamLatency = std::chrono::milliseconds(250);  // a quarter second old

std::string error_text(int error) { return std::strerror(error); }

// A path for a one-line message: as given, unless it holds control
// characters (a newline), which are escaped.
std::string shown(const std::string& path) {
  const bool control = std::any_of(path.begin(), path.end(),
                                   [](char c) { return static_cast<unsigned char>(c) < 0x20; });
  return control ? printable(path) : path;
}

// The path a chain of symbolic links at its last component leads to (the
// links in the folders before it are the kernel's business). A link to
// nothing yet leads to the file it would create.
std::string follow_links(const std::string& path) {
  std::string current = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (::lstat(current.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return current;
    std::string target(PATH_MAX, '\0');
    const ssize_t n = ::readlink(current.c_str(), target.data(), target.size());
    if (n < 0) return current;
    target.resize(static_cast<std::size_t>(n));
    if (target.empty() || target[0] != '/') {
      const auto slash = current.rfind('/');
      if (slash != std::string::npos) target = current.substr(0, slash + 1) + target;
    }
    current = target;
  }
  errno = ELOOP;
  return "";
}

}  // namespace

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
  std::string host = name;
  for (char& c : host) {
    if (c == '/' || static_cast<unsigned char>(c) < 0x20) c = '_';
  }
  return host;
}

namespace {

// `<file>.springlab-tmp.` shortened so that the whole temporary name fits
// in 255 bytes: the stem every temporary of this file starts with.
std::string temporary_stem(const std::string& base, const std::string& host) {
  const std::string tag = ".springlab-tmp.";
  const std::size_t tail = tag.size() + 10 + 1 + host.size() + 1 + 6;  // pid.host.XXXXXX
  const std::size_t keep = tail < 255 ? std::min(base.size(), 255 - tail) : 0;
  return base.substr(0, keep) + tag;
}

// True when `name` is `<stem><pid>.<host>.XXXXXX` of this machine and its
// process is gone: a temporary that a killed run left behind.
bool is_stale_temporary(const std::string& name, const std::string& stem, const std::string& host) {
  if (name.compare(0, stem.size(), stem) != 0) return false;
  std::size_t at = stem.size(), digits = 0;
  while (at + digits < name.size() && std::isdigit(static_cast<unsigned char>(name[at + digits]))) ++digits;
  if (digits == 0 || digits > 9) return false;
  const std::string rest = name.substr(at + digits);
  if (rest.size() != 1 + host.size() + 1 + 6 || rest.compare(0, host.size() + 2, "." + host + ".") != 0) {
    return false;
  }
  const pid_t pid = static_cast<pid_t>(std::stol(name.substr(at, digits)));
  return pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH;  // alive, or not ours to know
}

// Removes temporaries of this file that a killed run of this user on this
// machine left behind (`<stem><pid>.<host>.XXXXXX` whose process is gone).
void remove_stale_temporaries(const std::string& dir, const std::string& stem,
                              const std::string& host) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return;
  while (const dirent* entry = ::readdir(d)) {
    const std::string name = entry->d_name;
    if (!is_stale_temporary(name, stem, host)) continue;
    const std::string full = dir + "/" + name;
    struct stat st {};
    if (::lstat(full.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == ::geteuid()) {
      ::unlink(full.c_str());
    }
  }
  ::closedir(d);
}

// Removes the regular files directly in `folder`, then the folder (if it
// is then empty).
void remove_flat_folder(const std::string& folder) {
  if (DIR* d = ::opendir(folder.c_str())) {
    while (const dirent* entry = ::readdir(d)) {
      const std::string full = folder + "/" + entry->d_name;
      struct stat st {};
      if (::lstat(full.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(full.c_str());
    }
    ::closedir(d);
  }
  ::rmdir(folder.c_str());
}

}  // namespace

void remove_stale_temporary_folders(const std::string& dir, const std::string& stem) {
  const std::string host = host_name();
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return;
  while (const dirent* entry = ::readdir(d)) {
    const std::string name = entry->d_name;
    if (!is_stale_temporary(name, stem, host)) continue;
    const std::string full = dir + "/" + name;
    struct stat st {};
    if (::lstat(full.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::geteuid()) continue;
    // The frames and .pvd, and the old series a publish had moved aside
    // (vtk_series.h): flat folders, one level deep.
    if (DIR* inner = ::opendir(full.c_str())) {
      while (const dirent* e = ::readdir(inner)) {
        const std::string sub = full + "/" + e->d_name;
        struct stat sst {};
        if (e->d_name[0] != '.' && ::lstat(sub.c_str(), &sst) == 0 && S_ISDIR(sst.st_mode)) {
          remove_flat_folder(sub);
        }
      }
      ::closedir(inner);
    }
    remove_flat_folder(full);
  }
  ::closedir(d);
}

namespace {

bool same_inode(int fd, const struct stat& st) {
  struct stat other {};
  return ::fstat(fd, &other) == 0 && other.st_dev == st.st_dev && other.st_ino == st.st_ino;
}

void write_all(int fd, const char* data, std::size_t size, int& error) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      error = errno;
      return;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

}  // namespace

void OutputFile::fail(const std::string& what, int error) const {
  throw std::runtime_error(shown(path_) + ": " + what + " (" + error_text(error) + ")");
}

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw std::runtime_error("an output path is empty");
  last_flush_ = std::chrono::steady_clock::now();
  struct stat st {};
  const bool exists = ::stat(path_.c_str(), &st) == 0;  // through any links
  if (!exists && errno != ENOENT) fail("cannot write", errno);
  if (exists && S_ISDIR(st.st_mode)) throw std::runtime_error(shown(path_) + ": is a directory, not a file");
  if (exists && S_ISREG(st.st_mode)) {
    // Our own standard output or error, redirected to a file
    // (`--energy /dev/stdout > log`): write on at its offset.
    for (int fd : {1, 2}) {
      if (same_inode(fd, st)) {
        mode_ = Mode::kStream;
        fd_ = ::fcntl(fd, F_DUPFD_CLOEXEC, 3);
        if (fd_ < 0) fail("cannot write", errno);
        return;
      }
    }
  }
  if (exists && !S_ISREG(st.st_mode)) {
    // A FIFO, a device, a socket: write into it (opening a FIFO waits for
    // its reader, as the shell's `>` does).
    mode_ = Mode::kStream;
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (fd_ < 0) fail("cannot write", errno);
    return;
  }
  if (exists && ::faccessat(AT_FDCWD, path_.c_str(), W_OK, AT_EACCESS) != 0) fail("cannot write", errno);

  target_ = follow_links(path_);
  if (target_.empty()) fail("cannot write", errno);
  mode_ = exists && (st.st_nlink > 1 || st.st_uid != ::geteuid()) ? Mode::kRewrite : Mode::kReplace;
  const auto slash = target_.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : target_.substr(0, slash);
  const std::string base = slash == std::string::npos ? target_ : target_.substr(slash + 1);
  if (base.empty() || base == "." || base == "..") {
    throw std::runtime_error(shown(path_) + ": is a directory, not a file");
  }
  const std::string host = host_name();
  const std::string stem = temporary_stem(base, host);
  remove_stale_temporaries(dir, stem, host);
  std::string name = (dir == "/" ? "/" : dir + "/") + stem + std::to_string(::getpid()) + "." + host +
                     ".XXXXXX";
  fd_ = create_temporary_file(name);  // registered as a temporary (signals.h)
  if (fd_ < 0 && errno == EACCES && exists) {
    // A file we may write in a folder we may not: rewritten in place, from
    // a temporary in the temporary-files folder.
    const char* tmp = std::getenv("TMPDIR");
    name = std::string(tmp != nullptr && tmp[0] != '\0' ? tmp : "/tmp") + "/" + stem +
           std::to_string(::getpid()) + "." + host + ".XXXXXX";
    mode_ = Mode::kRewrite;
    fd_ = create_temporary_file(name);
    if (fd_ < 0) errno = EACCES;
  }
  if (fd_ < 0) fail("cannot write", errno);
  temp_path_ = name;
  // The temporary is created 0600: give it the bits the target has, or the ones
  // any new file would get.
  mode_t bits = 0;
  if (exists) {
    bits = st.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    bits = 0666 & ~mask;
  }
  if (::fchmod(fd_, bits) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    ::unlink(temp_path_.c_str());
    unregister_temporary(temp_path_);
    fail("cannot write", error);
  }
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_path_.empty() && !published_) {
    ::unlink(temp_path_.c_str());
    unregister_temporary(temp_path_);
  }
}

void OutputFile::flush() {
  if (buffer_.empty() || fd_ < 0) return;
  int error = 0;
  write_all(fd_, buffer_.data(), buffer_.size(), error);
  buffer_.clear();
  last_flush_ = std::chrono::steady_clock::now();
  if (error != 0) fail("write failed", error);
}

void OutputFile::write(std::string_view text) {
  if (fd_ < 0) throw std::runtime_error(shown(path_) + ": written after it was closed");
  if (text.size() >= kFileBuffer) {  // a whole table: no copy
    flush();
    int error = 0;
    write_all(fd_, text.data(), text.size(), error);
    last_flush_ = std::chrono::steady_clock::now();
    if (error != 0) fail("write failed", error);
    return;
  }
  buffer_.append(text);
  if (mode_ != Mode::kStream) {
    if (buffer_.size() >= kFileBuffer) flush();
  } else if (buffer_.size() >= kStreamBuffer ||
             std::chrono::steady_clock::now() - last_flush_ >= kStreamLatency) {
    flush();
  }
}

void OutputFile::finish() {
  if (fd_ < 0) return;
  flush();
  const int closed = ::close(fd_);
  fd_ = -1;
  if (closed != 0 && errno != EINTR) fail("write failed", errno);
}

void OutputFile::publish() {
  finish();
  if (mode_ == Mode::kStream || published_) return;
  if (mode_ == Mode::kReplace) {
    if (::rename(temp_path_.c_str(), target_.c_str()) != 0) fail("write failed", errno);
  } else {
    // In place: the file's other names and its owner stay. Not atomic: a
    // failure here (a full disk) leaves it part-written, and says so.
    const int in = ::open(temp_path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (in < 0) fail("write failed", errno);
    const int out = ::open(target_.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC | O_NOCTTY);
    if (out < 0) {
      const int error = errno;
      ::close(in);
      fail("write failed", error);
    }
    int error = 0;
    std::string chunk(kFileBuffer, '\0');
    while (error == 0) {
      const ssize_t n = ::read(in, chunk.data(), chunk.size());
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) error = errno;
      if (n <= 0) break;
      write_all(out, chunk.data(), static_cast<std::size_t>(n), error);
    }
    ::close(in);
    if (::close(out) != 0 && error == 0 && errno != EINTR) error = errno;
    if (error != 0) fail("write failed, the file is incomplete", error);
    ::unlink(temp_path_.c_str());
  }
  unregister_temporary(temp_path_);
  published_ = true;
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0) {
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && !S_ISCHR(sa.st_mode);
  }
  namespace fs = std::filesystem;
  std::error_code ec;
  auto resolved = [&](const std::string& p) { return fs::weakly_canonical(fs::absolute(p, ec), ec); };
  return resolved(a) == resolved(b);
}

EnergyCsv::EnergyCsv(const Model& model, OutputFile& file)
    : model_(model), file_(file), energies_(model.energies(model.initial_positions(),
                                                          model.initial_velocities())) {
  std::string header = "t";
  for (const std::string& column : model.energy_columns()) header += ',' + column;
  file_.write(header + '\n');
}

void EnergyCsv::observe(double t, const Vector& x, const Vector& v) {
  model_.energies(x, v, energies_);
  const std::vector<std::size_t>& works = model_.energy_layout().works;
  work_.resize(works.size(), 0.0);
  power_.resize(works.size(), 0.0);
  for (std::size_t k = 0; k < works.size(); ++k) {
    const double power = model_.column_power(works[k], t, x, v);
    if (!first_) work_[k] -= 0.5 * (t - t_previous_) * (power + power_[k]);
    power_[k] = power;
    energies_.add(works[k], work_[k]);
  }
  t_previous_ = t;
  first_ = false;
  std::string row = format_number(t);
  for (double value : energies_.values()) row += ',' + format_number(value);
  file_.write(row + '\n');
}

TrajectoryCsv::TrajectoryCsv(const Model& model, OutputFile& file)
    : model_(model), file_(file) {
  static const char* axes[] = {"x", "y", "z"};
  std::string header = "t,i";
  for (int r = 0; r < model.dimension(); ++r) header += std::string(",") + axes[r];
  for (int r = 0; r < model.dimension(); ++r) header += std::string(",v") + axes[r];
  file_.write(header + '\n');
}

void TrajectoryCsv::observe(double t, const Vector& x, const Vector& v) {
  const Eigen::MatrixXd positions = model_.scene_positions(x);
  const Eigen::MatrixXd velocities = model_.scene_velocities(v);
  const std::string time = format_number(t);
  std::string rows;
  for (Eigen::Index i = 0; i < positions.rows(); ++i) {
    rows += time + ',' + std::to_string(i);
    for (Eigen::Index r = 0; r < positions.cols(); ++r) rows += ',' + format_number(positions(i, r));
    for (Eigen::Index r = 0; r < velocities.cols(); ++r) rows += ',' + format_number(velocities(i, r));
    rows += '\n';
  }
  file_.write(rows);
}

}  // namespace springlab
