#pragma once
#include <filesystem>
#include <string>

namespace ts::cli {

// Runs a study file (thermostamp-study/1); returns the exit status.
int run_study(const std::filesystem::path& study, const std::filesystem::path& out, int threads, bool quiet);
// Runs the plotting script on an output folder; returns its exit status.
int run_report(const std::filesystem::path& dir);
std::filesystem::path share_dir();

}  // namespace ts::cli
