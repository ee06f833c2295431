#pragma once
#include <filesystem>
#include <string>

namespace ts::cli {

// Runs a study file (thermostamp-study/1); returns the exit status.
// flush_subnormals: RunOptions::flush_subnormals of every run.
int run_study(const std::filesystem::path& study, const std::filesystem::path& out, int threads, bool quiet,
              bool flush_subnormals);
// Runs the plotting script on an output folder; returns its exit status.
int run_report(const std::filesystem::path& dir);
std::filesystem::path share_dir();

}  // namespace ts::cli
