#include "experiments/signals.h"

#include <limits.h>
#include <signal.h>
#include <unistd.h>

#include <cstring>

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

std::atomic<bool> stop_requested{false};
std::atomic<bool> stop_mode{false};  // StopOnSignals alive: a signal is a request

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

// Async-signal-safe: unlink, signal, raise.
void remove_temporaries_and_die(int signal_number) {
  for (Slot& slot : slots) {
    if (slot.state.load(std::memory_order_acquire) == kReady) ::unlink(slot.path);
  }
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

StopOnSignals::StopOnSignals() {
  stop_requested.store(false);
  stop_mode.store(true);
}

StopOnSignals::~StopOnSignals() { stop_mode.store(false); }

const std::atomic<bool>& StopOnSignals::flag() const { return stop_requested; }

}  // namespace springlab
