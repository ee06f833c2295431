#pragma once
#include <filesystem>
#include <string>

namespace ts::cli {

// Runs a study file (thermostamp-study/1); returns the exit status.
// flush_subnormals: RunOptions::flush_subnormals of every run;
// checkpoint_wall_s: RunOptions::checkpoint_wall_s of every run. restart:
// continue the study in its output folder from its state file
// (study_state.json): the runs it completed are not run again, a run
// stopped with a checkpoint continues from it.
int run_study(const std::filesystem::path& study, const std::filesystem::path& out, int threads, bool quiet,
              bool flush_subnormals, bool restart = false, double checkpoint_wall_s = 0);
// Runs the plotting script on an output folder (and, when `against` is not
// empty, draws the two runs on the same axes); returns its exit status.
int run_report(const std::filesystem::path& dir, const std::filesystem::path& against = {});
std::filesystem::path share_dir();
// Creates the output folder `dir` (and its parents); throws JobError
// ("--out DIR: cannot create the output folder: reason", exit status 2)
// where it cannot, before anything runs.
void make_output_folder(const std::filesystem::path& dir);

}  // namespace ts::cli
