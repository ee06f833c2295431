#pragma once
// One logger per module ("job", "plugins", "solve", "io"), all writing to
// the same sinks: the terminal (warnings and above when quiet) and, during
// a run, DIR/log.txt.
#include <filesystem>
#include <memory>
#include <spdlog/spdlog.h>

namespace ts {

std::shared_ptr<spdlog::logger> logger(const std::string& module);
void log_to_terminal(bool quiet);
// Keeps what is logged from here on (at most 4096 lines) until
// log_to_file, which writes it first: the set-up of a run (job, meshes,
// initial temperatures), before its output folder is known, reaches log.txt.
void log_hold();
void log_to_file(const std::filesystem::path& file, bool append = false);
void log_close_file();

}  // namespace ts
