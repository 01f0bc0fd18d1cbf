#include "experiments/output_files.h"

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace springlab {

std::string format_number(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (ec != std::errc()) return "nan";
  return std::string(buffer, end);
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (std::filesystem::is_directory(path_)) {
    throw std::runtime_error(path_ + ": is a directory, not a file");
  }
  // A unique temporary beside the target (same file system, so the final
  // rename is atomic); mkstemp never reuses an existing name.
  std::string name = path_ + ".tmpXXXXXX";
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw std::runtime_error(path_ + ": cannot write (" + std::strerror(errno) + ")");
  temp_path_ = name;
  // mkstemp creates 0600; give the file the mode any new file would get.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  file_ = ::fdopen(fd, "wb");
  if (file_ == nullptr) {
    ::close(fd);
    std::remove(temp_path_.c_str());
    throw std::runtime_error(path_ + ": cannot write (" + std::strerror(errno) + ")");
  }
}

AtomicFile::~AtomicFile() {
  if (file_ != nullptr) std::fclose(file_);
  if (!published_) std::remove(temp_path_.c_str());
}

void AtomicFile::write(const std::string& text) {
  if (file_ == nullptr) return;
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) failed_ = true;
}

void AtomicFile::finish() {
  if (file_ == nullptr) return;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (failed_ || !closed) {
    failed_ = true;
    throw std::runtime_error(path_ + ": write failed");
  }
}

void AtomicFile::publish() {
  finish();
  if (failed_ || std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": write failed");
  }
  published_ = true;
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  auto resolved = [&](const std::string& p) { return fs::weakly_canonical(fs::absolute(p, ec), ec); };
  return resolved(a) == resolved(b);
}

EnergyCsv::EnergyCsv(const MassSpringModel& model, AtomicFile& file) : model_(model), file_(file) {
  file_.write("t,kinetic,spring,gravity,total\n");
}

void EnergyCsv::observe(double t, const Vector& x, const Vector& v) {
  const Energies e = model_.energies(x, v);
  file_.write(format_number(t) + ',' + format_number(e.kinetic) + ',' + format_number(e.spring) +
              ',' + format_number(e.gravity) + ',' + format_number(e.total()) + '\n');
}

TrajectoryCsv::TrajectoryCsv(const MassSpringModel& model, AtomicFile& file)
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
