#include "experiments/io/signals.h"

#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

namespace springlab {
namespace {

// One table entry: kFree, being written (kClaimed, invisible to the
// handler), or kReady (the handler may unlink its path).
enum SlotState : int { kFree = 0, kClaimed = 1, kReady = 2 };
struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
constexpr int kSlots = 64;
Slot slots[kSlots];

// The frame series (register_temporary_series).
struct Series {
  std::atomic<bool> ready{false};
  const std::atomic<int>* frames = nullptr;
  char dir[PATH_MAX];
  char stem[256];
};
Series series;

// `dir/stem` + suffix into `out` (PATH_MAX), by hand: async-signal-safe.
void series_path(char* out, const char* suffix) {
  std::size_t n = 0;
  for (const char* part : {static_cast<const char*>(series.dir), "/", static_cast<const char*>(series.stem), suffix}) {
    for (const char* c = part; *c != '\0' && n + 1 < PATH_MAX; ++c) out[n++] = *c;
  }
  out[n] = '\0';
}

void remove_series() {
  if (!series.ready.load(std::memory_order_acquire)) return;
  char path[PATH_MAX];
  const int frames = series.frames->load();
  for (int k = 0; k <= frames; ++k) {  // <= : the frame being written
    char suffix[] = "_000000.vtu";
    for (int digit = 6, rest = k; digit >= 1; --digit, rest /= 10) suffix[digit] = static_cast<char>('0' + rest % 10);
    series_path(path, suffix);
    ::unlink(path);
  }
  series_path(path, ".pvd");
  ::unlink(path);
  ::rmdir(series.dir);
}

std::atomic<bool> stop_requested{false};
std::atomic<bool> stop_mode{false};  // StopOnSignals alive: a signal is a request

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

// Async-signal-safe: unlink, rmdir, signal, raise.
void remove_temporaries_and_die(int signal_number) {
  for (Slot& slot : slots) {
    if (slot.state.load(std::memory_order_acquire) == kReady) ::unlink(slot.path);
  }
  remove_series();
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);  // delivered when the handler returns
}

extern "C" void on_signal(int signal_number) {
  if (stop_mode.load() && !stop_requested.exchange(true)) return;  // the first: a request
  remove_temporaries_and_die(signal_number);
}

}  // namespace

void install_signal_handlers() {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  ::sigaction(SIGPIPE, &ignore, nullptr);  // a closed pipe: EPIPE
  ::sigaction(SIGXFSZ, &ignore, nullptr);  // over a file-size limit: EFBIG
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  for (int s : kSignals) sigaddset(&action.sa_mask, s);  // one handler at a time
  for (int s : kSignals) {
    // A signal ignored at start (nohup, a background job) stays ignored.
    struct sigaction old {};
    ::sigaction(s, nullptr, &old);
    if (old.sa_handler != SIG_IGN) ::sigaction(s, &action, nullptr);
  }
}

void register_temporary(const std::string& path) {
  if (path.size() >= PATH_MAX) return;
  for (Slot& slot : slots) {
    int expected = kFree;
    if (!slot.state.compare_exchange_strong(expected, kClaimed)) continue;
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    slot.state.store(kReady, std::memory_order_release);
    return;
  }
}

void unregister_temporary(const std::string& path) {
  for (Slot& slot : slots) {
    if (slot.state.load(std::memory_order_acquire) == kReady && path == slot.path) {
      slot.state.store(kFree, std::memory_order_release);
      return;
    }
  }
}

void register_temporary_series(const std::string& dir, const std::string& stem,
                               const std::atomic<int>* frames) {
  if (dir.size() >= PATH_MAX || stem.size() >= sizeof series.stem) return;
  series.ready.store(false, std::memory_order_release);
  std::memcpy(series.dir, dir.c_str(), dir.size() + 1);
  std::memcpy(series.stem, stem.c_str(), stem.size() + 1);
  series.frames = frames;
  series.ready.store(true, std::memory_order_release);
}

void unregister_temporary_series() { series.ready.store(false, std::memory_order_release); }

namespace {

// Replaces the last six characters of `name` by random letters and digits.
void randomize_suffix(std::string& name) {
  static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 random{std::random_device{}()};
  for (std::size_t k = name.size() - 6; k < name.size(); ++k) name[k] = kChars[random() % 62];
}

// Registers a path, then makes it with `make` (a new file or folder, failing
// with EEXIST where the name is taken), with another name while it is taken.
// A signal between the two finds nothing at the path, or what was made. (A
// taken name holds this process's id and host, so it is no other running
// program's file.)
template <typename Register, typename Unregister, typename Make>
bool make_registered(std::string& name, const Register& reg, const Unregister& unreg,
                     const Make& make) {
  if (name.size() < 6) {
    errno = EINVAL;
    return false;
  }
  for (int attempt = 0; attempt < 100; ++attempt) {
    randomize_suffix(name);
    reg();
    if (make()) return true;
    const int error = errno;
    unreg();
    errno = error;
    if (error != EEXIST) return false;
  }
  return false;
}

}  // namespace

int create_temporary_file(std::string& name) {
  int fd = -1;
  make_registered(
      name, [&] { register_temporary(name); }, [&] { unregister_temporary(name); },
      [&] {
        fd = ::open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        return fd >= 0;
      });
  return fd;
}

bool create_temporary_series(std::string& dir, const std::string& stem,
                             const std::atomic<int>* frames) {
  return make_registered(
      dir, [&] { register_temporary_series(dir, stem, frames); },
      [] { unregister_temporary_series(); }, [&] { return ::mkdir(dir.c_str(), 0700) == 0; });
}

StopOnSignals::StopOnSignals() {
  stop_requested.store(false);
  stop_mode.store(true);
}

StopOnSignals::~StopOnSignals() { stop_mode.store(false); }

const std::atomic<bool>& StopOnSignals::flag() const { return stop_requested; }

}  // namespace springlab
