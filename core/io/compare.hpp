#pragma once
// `thermostamp compare A B`: how far the results of two output folders are
// apart: the probe samples (probes.csv), the fields of the frames
// (results.h5), the energy, tool and ply histories (energy.csv, tools.csv,
// plies.csv) and the summaries' figures (summary.json), each as the largest
// absolute difference over what the two folders share.
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace ts {

struct Difference {
  std::string what;    // "pole_top temperature_profile", "ply_top/temperature_mean", "energy/balance_error"
  std::string units;   // of the values ("degC", "m", ...; "" where unknown)
  double max_abs = 0;  // the largest |A - B|
  double scale = 0;    // the largest |A| over the values compared (to judge max_abs against)
  double at_time = 0;  // s, A's time of the sample or frame with the largest difference
  double at_time_b = 0;  // s, the time of B's sample or frame matched with it
  long long values = 0;  // values compared
  double a = 0, b = 0;   // summary figures: the two values
  std::string note;      // why it was not compared, if it was not
};

struct Comparison {
  // series: the columns of energy.csv, tools.csv (by tool) and plies.csv (by ply).
  std::vector<Difference> probes, fields, series, summary;
  // Samples and frames are matched by time: the largest offset between the
  // times of matched samples or frames (s), and what was left unmatched.
  double largest_time_offset = 0;
  std::vector<std::string> notes;
  // Every value compared is equal, and the folders hold the same probes,
  // frames and fields.
  bool identical = true;
  // The folders hold the same probes, frames, fields, rows and figures,
  // each with a counterpart in the other at its time (the values may
  // differ; a profile of another layer count counts as matched).
  bool matched = true;
  // The largest max_abs / scale over every quantity compared (infinite
  // where A's values are all zero and B's are not, or a difference is not a
  // number); where: that quantity's name.
  double largest_relative(std::string* where = nullptr) const;
  // matched, and every quantity's largest difference at most rtol times
  // its largest |A|.
  bool within(double rtol) const;
  nlohmann::json to_json() const;
  std::string to_text(const std::filesystem::path& a, const std::filesystem::path& b) const;
};

// For each time of a (ascending), the index of b's (ascending) nearest time
// if it lies within a quarter of the median spacing of a's times, -1
// otherwise (the median, as a first sample after t = 0 or a last one at the
// end may come close to its neighbour); raises `offset` to the largest
// distance matched. With the mechanics, samples and rows fall at the first
// step at or after each multiple of their interval, and two runs' steps
// differ: this pairs the samples of the same multiple.
std::vector<int> match_times(const std::vector<double>& a, const std::vector<double>& b, double& offset);

// Compares the output folders a and b (of `thermostamp run`), the samples,
// frames and rows at times from `from` on (s; all by default). Throws
// std::runtime_error when a folder does not exist or holds none of
// summary.json, probes.csv and results.h5, or when a probes.csv holds
// something other than numbers where they belong.
Comparison compare_outputs(const std::filesystem::path& a, const std::filesystem::path& b,
                           double from = -std::numeric_limits<double>::infinity());

}  // namespace ts
