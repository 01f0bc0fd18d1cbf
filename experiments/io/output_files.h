// Output files (--energy, --trajectory, an experiment's tables), written the
// way careful Unix tools write them:
//
//  - A path that names a regular file, or nothing yet, is written whole or
//    not at all: rows go to a temporary beside it, which publish() renames
//    over it when the run ends (finish() every file of a run first, so they
//    appear all or none). An existing file keeps its permission bits; a new
//    one gets 0666 minus the umask. A file we may not write (read-only, or
//    another user's that we could only replace, not write) is refused, as
//    the shell's `>` would refuse it. A file with other hard links, or owned
//    by another user, or in a folder we may not write, is rewritten in place
//    at publish() (its other names and its owner stay), from the finished
//    temporary (then in $TMPDIR or /tmp).
//  - A symbolic link is followed: its target is written, the link stays.
//  - Anything else (a FIFO, a terminal, /dev/null, /dev/stdout) is a stream:
//    written directly, as the rows come, never replaced or renamed over.
//  - A write error (a full disk, a closed pipe) throws std::runtime_error
//    naming the path, at the write that failed.
//
// The temporary is created up front (an unwritable path fails before any
// work is done) and named `<file>.springlab-tmp.<pid>.<host>.XXXXXX`; it is
// removed if the run ends without publish(), also when a signal ends it
// (signals.h). A temporary left by a killed run (kill -9, a power cut) is
// removed by the next run that writes the same file, once its process is
// gone.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include "experiments/driver/simulation.h"

namespace springlab {

class OutputFile {
 public:
  // Throws std::runtime_error naming the path when it cannot be written.
  explicit OutputFile(std::string path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(std::string_view text);
  // Flushes and closes; throws on an I/O error.
  void finish();
  // Puts the finished temporary in place (finishing it if needed). A stream
  // has nothing to publish.
  void publish();
  const std::string& path() const { return path_; }
  bool is_stream() const { return mode_ == Mode::kStream; }

 private:
  enum class Mode { kStream, kReplace, kRewrite };
  void flush();
  [[noreturn]] void fail(const std::string& what, int error) const;

  std::string path_;     // as given (for messages)
  std::string target_;   // after following symbolic links
  std::string temp_path_;
  Mode mode_ = Mode::kReplace;
  int fd_ = -1;
  std::string buffer_;
  std::chrono::steady_clock::time_point last_flush_;
  bool published_ = false;
};

// True when two output paths name the same file (after resolving ".", ".."
// and links). Two character devices (/dev/null twice) do not count.
bool same_file(const std::string& a, const std::string& b);

// Removes the temporary folders (`<dir>/<stem><pid>.<host>.XXXXXX`, as
// --vtk makes them: vtk_series.h) that a killed run of this user on this
// machine left behind, once its process is gone: their regular files, those
// of the folders directly in them, and the folders.
void remove_stale_temporary_folders(const std::string& dir, const std::string& stem);

// This machine's name as temporaries carry it ('/' and control characters
// made '_'; "localhost" when it has none).
std::string host_name();

// Shortest decimal text that reads back to the same double (deterministic).
std::string format_number(double value);

// --energy: t and the model's energy columns (t,kinetic,spring,gravity,total,
// then elastic, contact when the scene has them: models/core/energies.h).
class EnergyCsv final : public Observer {
 public:
  EnergyCsv(const Model& model, OutputFile& file);
  void observe(double t, const Vector& x, const Vector& v) override;

 private:
  const Model& model_;
  OutputFile& file_;
  Energies energies_;
  // The work columns (models/core/energies.h: viscous-work): the work done
  // against their forces, -integral F.v dt, by the trapezoid rule over the
  // rows written.
  std::vector<double> work_, power_;
  double t_previous_ = 0.0;
  bool first_ = true;
};

// --trajectory: t,i,x,y[,z],vx,vy[,vz], one row per particle in scene order.
class TrajectoryCsv final : public Observer {
 public:
  TrajectoryCsv(const Model& model, OutputFile& file);
  void observe(double t, const Vector& x, const Vector& v) override;

 private:
  const Model& model_;
  OutputFile& file_;
};

}  // namespace springlab
