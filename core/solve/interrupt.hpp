#pragma once
// Stopping a run cleanly on SIGINT (Ctrl-C) or SIGTERM (a batch queue's
// time limit): the first signal asks the running simulation to stop at the
// end of its current step; it then writes a last frame at that time, its
// time series and summary.json (status "interrupted"), and returns. A
// second signal ends the process at once (one within half a second of the
// first counts as the same request).

namespace ts {

// Installs the handlers for SIGINT and SIGTERM (the command line does).
void install_stop_handlers();

// Asks the running simulation to stop (what the handlers do); `signal` is
// reported. Async-signal-safe.
void request_stop(int signal) noexcept;

// The signal of a pending stop request, 0 if none.
int stop_requested() noexcept;

// Forgets a stop request (before another run in the same process).
void clear_stop() noexcept;

// "SIGINT", "SIGTERM" or "a signal".
const char* signal_name(int signal) noexcept;

}  // namespace ts
