#include "solve/interrupt.hpp"

#include <time.h>

#include <atomic>
#include <csignal>

namespace ts {
namespace {

std::atomic<int> g_stop{0};
std::atomic<long long> g_stop_ns{0};  // when the first signal came (monotonic clock)
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<long long>::is_always_lock_free,
              "the stop flag is set from a signal handler");

long long now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);  // async-signal-safe
  return static_cast<long long>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

extern "C" void on_stop_signal(int sig) {
  if (g_stop.load(std::memory_order_relaxed) == 0) {
    request_stop(sig);
    return;
  }
  // A second signal ends the process at once, unless it comes within half
  // a second of the first: tools such as timeout send a signal to the
  // process and to its process group, so one request can arrive twice.
  if (now_ns() - g_stop_ns.load(std::memory_order_relaxed) < 500000000LL) return;
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

void install_stop_handlers() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}

void request_stop(int signal) noexcept {
  g_stop_ns.store(now_ns(), std::memory_order_relaxed);
  g_stop.store(signal, std::memory_order_relaxed);
}

int stop_requested() noexcept { return g_stop.load(std::memory_order_relaxed); }

void clear_stop() noexcept { g_stop.store(0, std::memory_order_relaxed); }

const char* signal_name(int signal) noexcept {
  switch (signal) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
  }
}

}  // namespace ts
