#pragma once
// Reading back what ResultsWriter wrote to results.h5: the frames (by
// time), the members of a group and datasets of numbers.
#include <hdf5.h>

#include <string>
#include <vector>

namespace ts {

// HDF5 without its error printing while it lives (an absent or truncated
// file is reported by the caller).
struct QuietHdf5 {
  H5E_auto2_t func = nullptr;
  void* data = nullptr;
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func, data); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;
};

// The frames of a results file, in the order written (by time).
struct Frames {
  std::vector<double> times;
  std::vector<std::string> names;  // group names under /frames, by time
};
Frames read_frames(hid_t file);

// The names of the members of group `path`, sorted (empty where there is none).
std::vector<std::string> members(hid_t file, const std::string& path);

// A dataset of numbers (of rank 1 or 2) as doubles, and its shape; empty
// where it cannot be read.
std::vector<double> read_values(hid_t file, const std::string& path, std::vector<hsize_t>& shape);

}  // namespace ts
