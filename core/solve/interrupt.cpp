#include "solve/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace ts {
namespace {

std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "the stop flag is set from a signal handler");

extern "C" void on_stop_signal(int sig) {
  if (g_stop.load(std::memory_order_relaxed) != 0) {  // second signal: default action, now
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_stop.store(sig, std::memory_order_relaxed);
}

}  // namespace

void install_stop_handlers() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}

void request_stop(int signal) noexcept { g_stop.store(signal, std::memory_order_relaxed); }

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
