// Output files written whole or not at all (SPEC §6): rows go to a temporary
// file beside the target, renamed over it only by commit(). The temporary is
// created up front, so an unwritable path fails before any work is done, and
// removed if the run ends without commit().
#pragma once

#include <cstdio>
#include <string>

#include "experiments/simulation.h"

namespace springlab {

class AtomicFile {
 public:
  // Throws std::runtime_error naming the path when it cannot be created.
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const std::string& text);
  // Flushes and closes the temporary; throws on an I/O error. Finish every
  // file of a run before publishing any, so they appear all or none.
  void finish();
  // Renames the finished temporary into place (finishing it if needed).
  void publish();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
  bool published_ = false;
};

// True when two paths name the same file (after resolving ".", ".." and links).
bool same_file(const std::string& a, const std::string& b);

// Shortest decimal text that reads back to the same double (deterministic).
std::string format_number(double value);

// --energy: t,kinetic,spring,gravity,total
class EnergyCsv final : public Observer {
 public:
  EnergyCsv(const MassSpringModel& model, AtomicFile& file);
  void observe(double t, const Vector& x, const Vector& v) override;

 private:
  const MassSpringModel& model_;
  AtomicFile& file_;
};

// --trajectory: t,i,x,y[,z],vx,vy[,vz], one row per particle in scene order.
class TrajectoryCsv final : public Observer {
 public:
  TrajectoryCsv(const MassSpringModel& model, AtomicFile& file);
  void observe(double t, const Vector& x, const Vector& v) override;

 private:
  const MassSpringModel& model_;
  AtomicFile& file_;
};

}  // namespace springlab
