#include "io/results_reader.hpp"

#include <algorithm>
#include <cstdio>

namespace ts {

Frames read_frames(hid_t file) {
  Frames f;
  const hid_t g = H5Gopen2(file, "frames", H5P_DEFAULT);
  if (g < 0) return f;
  hsize_t n = 0;
  H5Gget_num_objs(g, &n);
  for (hsize_t k = 0; k < n; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "%06d", static_cast<int>(k));
    if (H5Aexists_by_name(g, name, "time", H5P_DEFAULT) <= 0) continue;
    double t = 0;
    const hid_t at = H5Aopen_by_name(g, name, "time", H5P_DEFAULT, H5P_DEFAULT);
    H5Aread(at, H5T_NATIVE_DOUBLE, &t);
    H5Aclose(at);
    f.times.push_back(t);
    f.names.push_back(name);
  }
  H5Gclose(g);
  return f;
}

// The names of the members of group `path` (empty where there is none).
std::vector<std::string> members(hid_t file, const std::string& path) {
  std::vector<std::string> out;
  if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0) return out;
  const hid_t g = H5Gopen2(file, path.c_str(), H5P_DEFAULT);
  if (g < 0) return out;
  hsize_t n = 0;
  H5Gget_num_objs(g, &n);
  for (hsize_t k = 0; k < n; ++k) {
    char name[256];
    if (H5Gget_objname_by_idx(g, k, name, sizeof name) > 0) out.push_back(name);
  }
  H5Gclose(g);
  std::sort(out.begin(), out.end());
  return out;
}

// A dataset of doubles and its shape (empty where it cannot be read).
std::vector<double> read_values(hid_t file, const std::string& path, std::vector<hsize_t>& shape) {
  shape.clear();
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  const int rank = H5Sget_simple_extent_ndims(space);
  hsize_t dims[2] = {0, 1};
  if (rank >= 1 && rank <= 2) H5Sget_simple_extent_dims(space, dims, nullptr);
  std::vector<double> v;
  if (rank >= 1 && rank <= 2) {
    shape.assign(dims, dims + rank);
    v.resize(dims[0] * (rank > 1 ? dims[1] : 1));
    if (H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0) {
      v.clear();
      shape.clear();
    }
  }
  H5Sclose(space);
  H5Dclose(set);
  return v;
}

}  // namespace ts
