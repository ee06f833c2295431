#include "io/results_writer.hpp"

#include <hdf5.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "io/files.hpp"

namespace ts {

namespace {
// No HDF5 clean-up at the process's exit: every file is closed where it is
// written or read, and after a write that failed (a full disk) HDF5 1.10
// crashes at exit closing the file again. (Before any HDF5 call.)
const bool kNoHdf5AtExit = H5dont_atexit() >= 0;
// A dataset of rows x cols values (a vector where cols is 1 and rank_2 is
// false); with `level` > 0 and at least 256 values, stored as one chunk
// through the shuffle and deflate filters (gzip at that level).
template <class T>
void write_dataset(hid_t loc, const std::string& name, const T* data, hsize_t rows, hsize_t cols, int level,
                   bool rank_2) {
  hsize_t dims[2] = {rows, cols};
  const int rank = rank_2 || cols > 1 ? 2 : 1;
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  hid_t dcpl = H5P_DEFAULT;
  if (level > 0 && rows * cols >= 256) {
    dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, rank, dims);
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, static_cast<unsigned>(level));
  }
  const hid_t type = std::is_same_v<T, int>         ? H5T_NATIVE_INT
                     : std::is_same_v<T, long long> ? H5T_NATIVE_LLONG
                                                    : H5T_NATIVE_DOUBLE;
  const hid_t ds = H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (dcpl != H5P_DEFAULT) H5Pclose(dcpl);
  if (ds < 0) {
    H5Sclose(space);
    throw std::runtime_error("HDF5: cannot create dataset " + name);
  }
  const herr_t written = H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  H5Dclose(ds);
  H5Sclose(space);
  if (written < 0 && rows * cols > 0) throw std::runtime_error("HDF5: cannot write dataset " + name);
}
void write_dataset(hid_t loc, const std::string& name, const double* data, hsize_t rows, hsize_t cols, int level) {
  write_dataset(loc, name, data, rows, cols, level, false);
}
void write_dataset(hid_t loc, const std::string& name, const int* data, hsize_t rows, hsize_t cols, int level) {
  write_dataset(loc, name, data, rows, cols, level, true);
}
void write_dataset(hid_t loc, const std::string& name, const long long* data, hsize_t rows, int level) {
  write_dataset(loc, name, data, rows, 1, level, false);
}
hid_t make_group(hid_t loc, const std::string& name) {
  const hid_t g = H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) throw std::runtime_error("HDF5: cannot create group " + name);
  return g;
}
// Closes every object of the file that is still open (left by a write that
// failed half way), so that closing the file, and the library at the
// process's end, find none.
void close_open_objects(hid_t file) {
  const unsigned types = H5F_OBJ_DATASET | H5F_OBJ_GROUP | H5F_OBJ_DATATYPE | H5F_OBJ_ATTR | H5F_OBJ_LOCAL;
  const ssize_t n = H5Fget_obj_count(file, types);
  if (n <= 0) return;
  std::vector<hid_t> ids(static_cast<std::size_t>(n));
  const ssize_t got = H5Fget_obj_ids(file, types, static_cast<std::size_t>(n), ids.data());
  for (ssize_t i = 0; i < got; ++i) {
    const H5I_type_t type = H5Iget_type(ids[i]);
    if (type == H5I_ATTR)
      H5Aclose(ids[i]);
    else if (type == H5I_DATATYPE)
      H5Tclose(ids[i]);
    else
      H5Oclose(ids[i]);
  }
}
std::string frame_name(int k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d", k);
  return buf;
}
int extruded_levels(int nz) { return nz > 1 ? nz : 2; }

// A string attribute of an object (a dataset or group).
void write_text_attribute(hid_t obj, const char* name, const std::string& text) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, text.size() + 1);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t at = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(at, type, text.c_str());
  H5Aclose(at);
  H5Sclose(space);
  H5Tclose(type);
}
// Writes the attribute "units" of dataset `name` of loc.
void write_units(hid_t loc, const std::string& name, const std::string& units) {
  const hid_t ds = H5Dopen2(loc, name.c_str(), H5P_DEFAULT);
  write_text_attribute(ds, "units", units);
  H5Dclose(ds);
}
}  // namespace

std::string field_units(const std::string& name) {
  if (name.rfind("temperature", 0) == 0) return "degC";
  if (name == "nodes" || name == "layer_nodes" || name == "displacement") return "m";
  if (name == "velocity") return "m/s";
  if (name == "tool_gap" || name == "thickness") return "m";
  if (name == "below_threshold_from" || name == "all_below_threshold_from") return "s";
  if (name == "shear_angle") return "deg";
  if (name == "contact_pressure") return "Pa";
  if (name.rfind("conductance", 0) == 0) return "W/(m^2 K)";
  if (name == "membrane_stress" || name == "membrane_stability") return "N/m";
  if (name == "curvature") return "1/m";
  return "1";  // fibre_direction, contact_status, membrane_strain
}

bool field_on_elements(const std::string& name) {
  for (const char* f :
       {"shear_angle", "fibre_direction", "membrane_stress", "membrane_strain", "curvature", "membrane_stability",
        "thickness"})
    if (name == f) return true;
  return false;
}

std::string series_column_units(const std::string& column) {
  auto ends = [&](const char* e) {
    const std::size_t n = std::strlen(e);
    return column.size() >= n && column.compare(column.size() - n, n, e) == 0;
  };
  if (column == "time") return "s";
  if (column == "balance_error" || ends("fraction_below") || ends("fraction_over_shear_limit") ||
      ends("_crystallinity_min") || ends("_crystallinity_mean") || ends("_crystallinity_max") ||
      ends("_fibre_strain_min") || ends("_fibre_strain_max") || ends("_fraction_unstable"))
    return "1";
  if (ends("_stability_min")) return "N/m";
  if (ends("_shear_angle_min") || ends("_shear_angle_max")) return "deg";
  if (ends("_temperature_min") || ends("_temperature_mean") || ends("_temperature_max") || ends("_temperature"))
    return "degC";
  if (column.rfind("reaction", 0) == 0 || ends("_fx") || ends("_fy") || ends("_fz")) return "N";
  if (ends("_ux") || ends("_uy") || ends("_uz") || ends("_thickness_min") || ends("_thickness_max")) return "m";
  return "J";  // the energies and works, the tools' heat
}

ResultsBytes results_bytes(const std::vector<WriterPart>& parts, const std::vector<std::vector<FrameField>>& fields,
                           const std::vector<WriterTool>& tools) {
  constexpr double d = sizeof(double), i = sizeof(int), ll = sizeof(long long);
  ResultsBytes b;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const WriterPart& wp = parts[p];
    const double nn = wp.num_nodes, ne = wp.num_elements, nl = extruded_levels(wp.nz);
    b.once += 3 * ne * i + nn * ll + ne * ll;  // triangles, node_tags, element_tags
    b.per_frame += 3 * nn * d;                 // nodes
    if (wp.layers) {
      b.once += 6 * ne * (nl - 1) * i;  // wedges
      b.per_frame += 3 * nn * nl * d;   // layer_nodes
    }
    if (p < fields.size())
      for (const FrameField& f : fields[p])
        b.per_frame += (f.on_layers ? nn * nl : (f.on_cells ? ne : nn) * f.components) * d;
  }
  for (const WriterTool& t : tools) {
    b.once += static_cast<double>(t.nodes.size()) * d + static_cast<double>(t.triangles.size()) * i;
    if (t.moves) b.per_frame += static_cast<double>(t.nodes.size()) * d;
  }
  return b;
}

void ResultsWriter::check_compression() const {
  unsigned info = 0;
  if (compression_ > 0 && (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0 || H5Zfilter_avail(H5Z_FILTER_SHUFFLE) <= 0 ||
                           H5Zget_filter_info(H5Z_FILTER_DEFLATE, &info) < 0 ||
                           !(info & H5Z_FILTER_CONFIG_ENCODE_ENABLED)))
    throw std::runtime_error("this HDF5 library cannot compress (no deflate filter): set output.compression to 0");
}

namespace {

// A part's extruded through-thickness mesh (/parts/<ply>/wedges): wedges
// between consecutive levels of the through-thickness values.
void write_wedges(hid_t pg, const WriterPart& p, int compression) {
  const int nl = extruded_levels(p.nz);
  std::vector<int> wedges;
  wedges.reserve(static_cast<std::size_t>(6) * p.num_elements * (nl - 1));
  for (int l = 0; l + 1 < nl; ++l)
    for (int e = 0; e < p.num_elements; ++e) {
      for (int a = 0; a < 3; ++a) wedges.push_back((*p.triangles)[3 * e + a] * nl + l);
      for (int a = 0; a < 3; ++a) wedges.push_back((*p.triangles)[3 * e + a] * nl + l + 1);
    }
  write_dataset(pg, "wedges", wedges.data(), static_cast<hsize_t>(p.num_elements) * (nl - 1), 6, compression);
}

}  // namespace

ResultsWriter::ResultsWriter(const std::filesystem::path& dir, std::vector<WriterPart> parts, int compression)
    : dir_(dir), parts_(std::move(parts)), compression_(compression) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  check_compression();
  const std::string path = (dir_ / "results.h5").string();
  // Compressed, the file takes the format of HDF5 1.10, whose index of a
  // dataset stored as one chunk costs a few bytes instead of a B-tree of
  // about 2 kB per dataset (read by HDF5 1.10 and later, as in ParaView).
  hid_t fapl = H5P_DEFAULT;
  if (compression_ > 0) {
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST);
  }
  file_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (fapl != H5P_DEFAULT) H5Pclose(fapl);
  if (file_ < 0) throw std::runtime_error("cannot create " + path);
  const hid_t g = make_group(file_, "parts");
  for (const auto& p : parts_) {
    const hid_t pg = make_group(g, p.name);
    write_dataset(pg, "triangles", p.triangles->data(), p.num_elements, 3, compression_);
    write_dataset(pg, "node_tags", p.node_tags.data(), p.node_tags.size(), compression_);
    write_dataset(pg, "element_tags", p.element_tags.data(), p.element_tags.size(), compression_);
    if (p.layers) write_wedges(pg, p, compression_);
    H5Gclose(pg);
  }
  H5Gclose(g);
  H5Gclose(make_group(file_, "frames"));
  H5Fflush(file_, H5F_SCOPE_GLOBAL);
}

ResultsWriter::ResultsWriter(const std::filesystem::path& dir, std::vector<WriterPart> parts,
                             const std::vector<double>& kept_times, const std::vector<std::vector<FrameField>>& fields,
                             int compression)
    : dir_(dir), parts_(std::move(parts)), compression_(compression) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  check_compression();
  const std::string path = (dir_ / "results.h5").string();
  if (!std::filesystem::exists(path)) throw std::runtime_error("no " + path + " of the run to continue");
  hid_t fapl = H5P_DEFAULT;  // as a new file's (above), for the frames to come
  if (compression_ > 0) {
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST);
  }
  file_ = H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl);
  if (fapl != H5P_DEFAULT) H5Pclose(fapl);
  if (file_ < 0) throw std::runtime_error("cannot open " + path);
  auto refuse = [&](hid_t group, const std::string& why) {  // the file as it was, closed
    if (group >= 0) H5Gclose(group);
    H5Fclose(file_);
    file_ = -1;
    throw std::runtime_error(why);
  };
  const hid_t frames_g = H5Gopen2(file_, "frames", H5P_DEFAULT);
  if (frames_g < 0) refuse(-1, path + " has no frames");
  const int kept = static_cast<int>(kept_times.size());
  for (int k = 0; k < kept; ++k)
    if (H5Lexists(frames_g, frame_name(k).c_str(), H5P_DEFAULT) <= 0)
      refuse(frames_g, path + " holds " + std::to_string(k) + " frames, the checkpoint " + std::to_string(kept) +
                           ": not the results of the run that wrote it");
  for (int k = kept; H5Lexists(frames_g, frame_name(k).c_str(), H5P_DEFAULT) > 0; ++k)
    H5Ldelete(frames_g, frame_name(k).c_str(), H5P_DEFAULT);
  H5Gclose(frames_g);
  // The through-thickness mesh of a part whose frames to come show a field
  // on it, where those before did not (a restart with other fields).
  for (const WriterPart& p : parts_) {
    const std::string wedges = "parts/" + p.name + "/wedges";
    if (!p.layers || H5Lexists(file_, wedges.c_str(), H5P_DEFAULT) > 0) continue;
    const hid_t pg = H5Gopen2(file_, ("parts/" + p.name).c_str(), H5P_DEFAULT);
    if (pg < 0) refuse(-1, path + " has no part '" + p.name + "'");
    write_wedges(pg, p, compression_);
    H5Gclose(pg);
  }
  H5Fflush(file_, H5F_SCOPE_GLOBAL);
  times_ = kept_times;
  std::vector<std::vector<FrameField>> kinds = fields;
  for (auto& v : kinds)
    for (auto& f : v) f.data = nullptr;
  frame_fields_.assign(times_.size(), kinds);
  frame_tools_.assign(times_.size(), {});
  write_xdmf();
}

ResultsWriter::~ResultsWriter() {
  if (xdmf_behind_) {
    try {
      write_xdmf();
    } catch (...) {  // a destructor does not throw; results.h5 holds every frame
    }
  }
  if (file_ >= 0) {
    if (!failed_.empty()) close_open_objects(file_);
    H5Fclose(file_);
  }
}

template <class F>
void ResultsWriter::guard(const std::string& what, F&& write) {
  if (!failed_.empty()) throw std::runtime_error(failed_);
  errno = 0;
  try {
    write();
    if (H5Fflush(file_, H5F_SCOPE_GLOBAL) < 0) throw std::runtime_error("HDF5: cannot flush the file");
  } catch (const std::runtime_error& e) {
    const int err = errno;  // the system's reason, where a write of the file set one
    close_open_objects(file_);
    failed_ = "cannot write " + (dir_ / "results.h5").string() + " (" + what + "): " +
              write_failure_reason(dir_, err, e.what());
    throw std::runtime_error(failed_);
  }
}

void ResultsWriter::set_tools(std::vector<WriterTool> tools) {
  tools_ = std::move(tools);
  guard("the tools' surfaces", [&] {
    if (H5Lexists(file_, "tools", H5P_DEFAULT) > 0) H5Ldelete(file_, "tools", H5P_DEFAULT);
    if (tools_.empty()) return;
    const hid_t g = make_group(file_, "tools");
    for (const WriterTool& t : tools_) {
      const hid_t tg = make_group(g, t.name);
      write_dataset(tg, "nodes", t.nodes.data(), t.nodes.size() / 3, 3, compression_);
      write_units(tg, "nodes", field_units("nodes"));
      write_dataset(tg, "triangles", t.triangles.data(), t.triangles.size() / 3, 3, compression_);
      H5Gclose(tg);
    }
    H5Gclose(g);
  });
  // The frames already in the file (a restart) show a moving tool where
  // they hold its nodes, and not at all where they do not.
  frame_tools_.assign(times_.size(), std::vector<char>(tools_.size(), 1));
  for (std::size_t k = 0; k < times_.size(); ++k)
    for (std::size_t t = 0; t < tools_.size(); ++t)
      if (tools_[t].moves) {
        const std::string path = "frames/" + frame_name(static_cast<int>(k)) + "/" + tools_[t].name;
        frame_tools_[k][t] = H5Lexists(file_, path.c_str(), H5P_DEFAULT) > 0;
      }
  write_xdmf();
}

void ResultsWriter::write_frame(double time, const std::vector<const double*>& x,
                                const std::vector<const double*>& normals,
                                const std::vector<std::vector<FrameField>>& fields,
                                const std::vector<std::array<double, 3>>& tool_displacements) {
  const int k = frames();
  char what[64];
  std::snprintf(what, sizeof what, "the frame at t = %g s", time);
  guard(what, [&] {
    const hid_t frames_g = H5Gopen2(file_, "frames", H5P_DEFAULT);
    const hid_t fg = make_group(frames_g, frame_name(k));
    {
      const hid_t space = H5Screate(H5S_SCALAR);
      const hid_t at = H5Acreate2(fg, "time", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(at, H5T_NATIVE_DOUBLE, &time);
      H5Aclose(at);
      H5Sclose(space);
    }
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const WriterPart& wp = parts_[p];
      const hid_t pg = make_group(fg, wp.name);
      write_dataset(pg, "nodes", x[p], wp.num_nodes, 3, compression_);
      write_units(pg, "nodes", field_units("nodes"));
      const int nl = extruded_levels(wp.nz);
      if (wp.layers) {
        std::vector<double> layer_nodes(static_cast<std::size_t>(3) * wp.num_nodes * nl);
        for (int i = 0; i < wp.num_nodes; ++i)
          for (int l = 0; l < nl; ++l) {
            const double z = -0.5 * wp.thickness + wp.thickness * l / (nl - 1);
            for (int d = 0; d < 3; ++d)
              layer_nodes[3 * (static_cast<std::size_t>(i) * nl + l) + d] =
                  x[p][3 * i + d] + z * normals[p][3 * i + d];
          }
        write_dataset(pg, "layer_nodes", layer_nodes.data(), static_cast<hsize_t>(wp.num_nodes) * nl, 3,
                      compression_);
        write_units(pg, "layer_nodes", field_units("layer_nodes"));
      }
      for (const auto& f : fields[p]) {
        if (f.on_layers) {
          // Values bottom to top; a single value per node is repeated on both levels.
          std::vector<double> v(static_cast<std::size_t>(wp.num_nodes) * nl);
          for (int i = 0; i < wp.num_nodes; ++i)
            for (int l = 0; l < nl; ++l)
              v[static_cast<std::size_t>(i) * nl + l] = f.data[static_cast<std::size_t>(i) * wp.nz + (wp.nz > 1 ? l : 0)];
          write_dataset(pg, f.name, v.data(), static_cast<hsize_t>(wp.num_nodes) * nl, 1, compression_);
        } else {
          const hsize_t rows = f.on_cells ? wp.num_elements : wp.num_nodes;
          write_dataset(pg, f.name, f.data, rows, f.components, compression_);
        }
        write_units(pg, f.name, field_units(f.name));
      }
      H5Gclose(pg);
    }
    for (std::size_t t = 0; t < tools_.size(); ++t) {
      const WriterTool& wt = tools_[t];
      if (!wt.moves) continue;
      const std::array<double, 3> u = t < tool_displacements.size() ? tool_displacements[t] : std::array<double, 3>{};
      std::vector<double> moved(wt.nodes);
      for (std::size_t i = 0; i < moved.size(); ++i) moved[i] += u[i % 3];
      const hid_t tg = make_group(fg, wt.name);
      write_dataset(tg, "nodes", moved.data(), moved.size() / 3, 3, compression_);
      write_units(tg, "nodes", field_units("nodes"));
      H5Gclose(tg);
    }
    H5Gclose(fg);
    H5Gclose(frames_g);
  });
  frame_tools_.emplace_back(tools_.size(), 1);
  times_.push_back(time);
  std::vector<std::vector<FrameField>> kinds = fields;
  for (auto& v : kinds)
    for (auto& f : v) f.data = nullptr;
  frame_fields_.push_back(std::move(kinds));
  // The index names every frame, so rewriting it after each one costs in
  // proportion to the frames so far: past the first 100 frames it is
  // rewritten at most once a second of wall time (and when the writer
  // closes, at the end of any run, failed or interrupted included).
  const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  if (times_.size() <= 100 || now - xdmf_written_at_ >= 1.0) {
    write_xdmf();
    xdmf_written_at_ = now;
    xdmf_behind_ = false;
  } else {
    xdmf_behind_ = true;
  }
}

void ResultsWriter::write_series(const std::string& name, const std::vector<std::string>& columns,
                                 const std::vector<double>& rows) {
  guard("the time series '" + name + "'", [&] {
    if (H5Lexists(file_, "series", H5P_DEFAULT) <= 0) H5Gclose(make_group(file_, "series"));
    const hid_t g = H5Gopen2(file_, "series", H5P_DEFAULT);
    if (H5Lexists(g, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(g, name.c_str(), H5P_DEFAULT);
    const hsize_t cols = columns.size(), nrows = cols ? rows.size() / cols : 0;
    write_dataset(g, name, rows.data(), nrows, cols, compression_);
    // Column names and their units as attributes: "time,kinetic,..." and
    // "s,J,...".
    std::string joined, units;
    for (std::size_t i = 0; i < columns.size(); ++i) {
      joined += (i ? "," : "") + columns[i];
      units += (i ? "," : "") + series_column_units(columns[i]);
    }
    const hid_t ds = H5Dopen2(g, name.c_str(), H5P_DEFAULT);
    write_text_attribute(ds, "columns", joined);
    write_text_attribute(ds, "units", units);
    H5Dclose(ds);
    H5Gclose(g);
  });
}

void ResultsWriter::write_xdmf() const {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n <Domain>\n";
  x << "  <Grid Name=\"frames\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < times_.size(); ++k) {
    const std::string fpath = "results.h5:/frames/" + frame_name(static_cast<int>(k));
    x << "   <Grid Name=\"frame_" << k << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
    x << "    <Time Value=\"" << times_[k] << "\" />\n";
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const WriterPart& wp = parts_[p];
      const int nl = extruded_levels(wp.nz);
      const std::string ppath = fpath + "/" + wp.name;
      // Mid-surface.
      x << "    <Grid Name=\"" << wp.name << "\" GridType=\"Uniform\">\n";
      x << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << wp.num_elements << "\">\n";
      x << "      <DataItem Dimensions=\"" << wp.num_elements << " 3\" NumberType=\"Int\" Format=\"HDF\">results.h5:/parts/"
        << wp.name << "/triangles</DataItem>\n     </Topology>\n";
      x << "     <Geometry GeometryType=\"XYZ\">\n      <DataItem Dimensions=\"" << wp.num_nodes
        << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << ppath << "/nodes</DataItem>\n     </Geometry>\n";
      for (const auto& f : frame_fields_[k][p]) {
        if (f.on_layers) continue;
        const int rows = f.on_cells ? wp.num_elements : wp.num_nodes;
        x << "     <Attribute Name=\"" << f.name << "\" AttributeType=\"" << (f.components == 3 ? "Vector" : "Scalar")
          << "\" Center=\"" << (f.on_cells ? "Cell" : "Node") << "\">\n      <DataItem Dimensions=\"" << rows;
        if (f.components > 1) x << " " << f.components;
        x << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << ppath << "/" << f.name
          << "</DataItem>\n     </Attribute>\n";
      }
      x << "    </Grid>\n";
      // Extruded through-thickness view.
      bool any_layer = false;
      for (const auto& f : frame_fields_[k][p]) any_layer = any_layer || f.on_layers;
      if (any_layer) {
        const long long nw = static_cast<long long>(wp.num_elements) * (nl - 1);
        x << "    <Grid Name=\"" << wp.name << "_thickness\" GridType=\"Uniform\">\n";
        x << "     <Topology TopologyType=\"Wedge\" NumberOfElements=\"" << nw << "\">\n";
        x << "      <DataItem Dimensions=\"" << nw << " 6\" NumberType=\"Int\" Format=\"HDF\">results.h5:/parts/"
          << wp.name << "/wedges</DataItem>\n     </Topology>\n";
        x << "     <Geometry GeometryType=\"XYZ\">\n      <DataItem Dimensions=\""
          << static_cast<long long>(wp.num_nodes) * nl << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
          << ppath << "/layer_nodes</DataItem>\n     </Geometry>\n";
        for (const auto& f : frame_fields_[k][p]) {
          if (!f.on_layers) continue;
          x << "     <Attribute Name=\"" << f.name << "\" AttributeType=\"Scalar\" Center=\"Node\">\n"
            << "      <DataItem Dimensions=\"" << static_cast<long long>(wp.num_nodes) * nl
            << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << ppath << "/" << f.name
            << "</DataItem>\n     </Attribute>\n";
        }
        x << "    </Grid>\n";
      }
    }
    // The tools, where they stand at this frame.
    for (std::size_t t = 0; t < tools_.size(); ++t) {
      const WriterTool& wt = tools_[t];
      if (k < frame_tools_.size() && !frame_tools_[k][t]) continue;
      const std::size_t nn = wt.nodes.size() / 3, nt = wt.triangles.size() / 3;
      x << "    <Grid Name=\"" << wt.name << "\" GridType=\"Uniform\">\n";
      x << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << nt << "\">\n";
      x << "      <DataItem Dimensions=\"" << nt << " 3\" NumberType=\"Int\" Format=\"HDF\">results.h5:/tools/"
        << wt.name << "/triangles</DataItem>\n     </Topology>\n";
      x << "     <Geometry GeometryType=\"XYZ\">\n      <DataItem Dimensions=\"" << nn
        << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
        << (wt.moves ? fpath + "/" + wt.name : "results.h5:/tools/" + wt.name) << "/nodes</DataItem>\n     </Geometry>\n";
      x << "    </Grid>\n";
    }
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  const auto tmp = dir_ / "results.xdmf.tmp";
  {
    std::ofstream out(tmp);
    out << x.str();
  }
  std::filesystem::rename(tmp, dir_ / "results.xdmf");
}

}  // namespace ts
