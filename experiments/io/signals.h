// What springlab does when it is told to stop (SIGINT from Ctrl-C, SIGTERM
// from a job scheduler, SIGHUP when the terminal goes away), in two ways:
//
//  - A command that makes one result (`run`, `stability`, `scene`, a merge)
//    ends by the signal, as any Unix tool does, after removing the
//    temporaries of its output files (register_temporary): the files at the
//    output paths keep what they held before.
//  - A sweep (`experiment`) turns the first signal into a stop request
//    (StopOnSignals): no task starts, running ones stop at their next step,
//    and the finished ones are written whole and marked incomplete. A second
//    signal ends it at once, as above.
//
// SIGPIPE and SIGXFSZ are ignored, so writing into a closed pipe (EPIPE) or
// past a file-size limit (EFBIG) is an error that the writer reports, not a
// silent death.
#pragma once

#include <atomic>
#include <string>

namespace springlab {

// Ignores SIGPIPE and SIGXFSZ and installs the removing-then-dying handler for SIGINT,
// SIGTERM and SIGHUP (once per process; the command line calls it first).
void install_signal_handlers();

// The temporaries a signal removes before the process ends. The removal runs
// inside the signal handler: paths live in a fixed table (64 at once; more
// are not removed by a signal, only by their owner).
void register_temporary(const std::string& path);
void unregister_temporary(const std::string& path);

// Creates a new file at `name`, its last six characters (XXXXXX) replaced by
// random letters and digits as mkostemp does (O_CREAT | O_EXCL | O_CLOEXEC,
// mode 0600), and returns its descriptor; -1 with errno where it cannot.
// The path is registered as a temporary before the file exists, so that no
// signal can come between the two and leave the file behind.
int create_temporary_file(std::string& name);

// A folder of numbered frames being written (--vtk): a signal removes
// `<dir>/<stem>_NNNNNN.vtu` for N < *frames, `<dir>/<stem>.pvd` and the
// folder itself. One series at a time; `frames` must outlive the
// registration.
void register_temporary_series(const std::string& dir, const std::string& stem,
                               const std::atomic<int>* frames);
void unregister_temporary_series();
// The folder for such a series: as create_temporary_file, a new folder
// (mkdtemp, mode 0700) registered before it exists; false with errno where
// it cannot be made.
bool create_temporary_series(std::string& dir, const std::string& stem,
                             const std::atomic<int>* frames);

// While alive, SIGINT, SIGTERM and SIGHUP set stop_requested() instead of
// ending the process (a second one ends it, removing the temporaries).
class StopOnSignals {
 public:
  StopOnSignals();
  ~StopOnSignals();
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;
  const std::atomic<bool>& flag() const;
};

}  // namespace springlab
