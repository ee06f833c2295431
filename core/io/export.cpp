#include "io/export.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "io/results_reader.hpp"
#include "io/results_writer.hpp"

namespace ts {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Tags of n entities as results.h5 holds them at `path` (those of the mesh
// file the run read), else 1 .. n (results of earlier versions).
std::vector<long long> tags(hid_t file, const std::string& path, std::size_t n) {
  std::vector<hsize_t> shape;
  const std::vector<double> v = read_values(file, path, shape);
  std::vector<long long> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = v.size() == n ? static_cast<long long>(v[i]) : static_cast<long long>(i + 1);
  return t;
}

// One $NodeData or $ElementData block (Gmsh 2.2): the name, the time, and
// rows of `components` values for the entities of these tags, as the
// file's only time step (0).
void write_data(std::ofstream& out, const char* section, const std::string& name, double time,
                const std::vector<double>& v, int components, const std::vector<long long>& tag) {
  const std::size_t n = v.size() / components;
  out << '$' << section << "\n1\n\"" << name << "\"\n1\n" << number(time) << "\n3\n0\n"
      << components << '\n' << n << '\n';
  for (std::size_t i = 0; i < n; ++i) {
    out << tag[i];
    for (int c = 0; c < components; ++c) out << ' ' << number(v[i * components + c]);
    out << '\n';
  }
  out << "$End" << section << '\n';
}

}  // namespace

ExportResult export_gmsh(const std::filesystem::path& dir, std::optional<double> time,
                         const std::filesystem::path& out) {
  const auto h5 = dir / "results.h5";
  if (!std::filesystem::is_directory(dir))
    throw ExportInputError("'" + dir.string() + "' is not a folder");
  if (!std::filesystem::exists(h5))
    throw ExportInputError("'" + dir.string() + "' holds no results.h5 (not the output folder of a run?)");
  QuietHdf5 quiet;
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("cannot read '" + h5.string() + "' (cut short?)");
  struct Close {
    hid_t f;
    ~Close() { H5Fclose(f); }
  } close{file};
  const Frames frames = read_frames(file);
  if (frames.times.empty()) throw ExportInputError("'" + h5.string() + "' holds no frame");
  ExportResult res;
  res.frames = static_cast<int>(frames.times.size());
  int k = res.frames - 1;
  if (time) {
    const double first = frames.times.front(), last = frames.times.back();
    const double eps = 1e-9 * std::max({1.0, std::abs(first), std::abs(last)});
    if (!(*time >= first - eps && *time <= last + eps))
      throw ExportInputError("no frame at t = " + number(*time) + " s: the " + std::to_string(res.frames) +
                             " frames are from t = " + number(first) + " to " + number(last) + " s");
    for (int j = 0; j < res.frames; ++j)
      if (std::abs(frames.times[j] - *time) < std::abs(frames.times[k] - *time)) k = j;
  }
  res.frame = k;
  res.time = frames.times[k];
  const std::string group = "frames/" + frames.names[k];
  // The frame's plies (a frame also holds the moving tools' surfaces).
  std::vector<std::string> plies;
  const auto parts = members(file, "parts");
  for (const auto& name : members(file, group))
    if (std::find(parts.begin(), parts.end(), name) != parts.end()) plies.push_back(name);
  if (plies.empty()) throw std::runtime_error("frame " + frames.names[k] + " of '" + h5.string() + "' holds no ply");
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw std::runtime_error("cannot create '" + out.string() + "': " + ec.message());
  for (const auto& name : plies) {
    std::vector<hsize_t> tshape, xshape;
    const std::vector<double> tri = read_values(file, "parts/" + name + "/triangles", tshape);
    const std::vector<double> x = read_values(file, group + "/" + name + "/nodes", xshape);
    if (tshape.size() != 2 || tshape[1] != 3 || xshape.size() != 2 || xshape[1] != 3)
      throw std::runtime_error("'" + h5.string() + "': the triangles or nodes of ply '" + name +
                               "' cannot be read (cut short?)");
    ExportedPly ply;
    ply.name = name;
    ply.nodes = static_cast<int>(xshape[0]);
    ply.triangles = static_cast<int>(tshape[0]);
    ply.file = out / (name + ".msh");
    const std::vector<long long> node_tag = tags(file, "parts/" + name + "/node_tags", ply.nodes),
                                 element_tag = tags(file, "parts/" + name + "/element_tags", ply.triangles);
    std::ofstream m(ply.file);
    if (!m) throw std::runtime_error("cannot write '" + ply.file.string() + "'");
    m << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"" << name << "\"\n$EndPhysicalNames\n";
    m << "$Nodes\n" << ply.nodes << '\n';
    for (std::size_t i = 0; i < static_cast<std::size_t>(ply.nodes); ++i)
      m << node_tag[i] << ' ' << number(x[3 * i]) << ' ' << number(x[3 * i + 1]) << ' ' << number(x[3 * i + 2]) << '\n';
    m << "$EndNodes\n$Elements\n" << ply.triangles << '\n';
    for (std::size_t e = 0; e < static_cast<std::size_t>(ply.triangles); ++e) {
      m << element_tag[e] << " 2 2 1 1";
      for (std::size_t c = 0; c < 3; ++c) m << ' ' << node_tag[static_cast<std::size_t>(tri[3 * e + c])];
      m << '\n';
    }
    m << "$EndElements\n";
    for (const auto& field : members(file, group + "/" + name)) {
      if (field == "nodes" || field == "layer_nodes") continue;
      std::vector<hsize_t> shape;
      const std::vector<double> v = read_values(file, group + "/" + name + "/" + field, shape);
      if (shape.empty()) throw std::runtime_error("'" + h5.string() + "': field '" + field + "' of ply '" + name +
                                                  "' cannot be read (cut short?)");
      const int components = shape.size() > 1 ? static_cast<int>(shape[1]) : 1;
      const bool cells = field_on_elements(field);
      // (the through-thickness `temperature` lies on the extruded mesh; its
      // mean, top and bottom values are fields of their own in the frame)
      if (shape[0] != static_cast<hsize_t>(cells ? ply.triangles : ply.nodes)) continue;
      write_data(m, cells ? "ElementData" : "NodeData", field, res.time, v, components, cells ? element_tag : node_tag);
      (cells ? ply.element_data : ply.node_data).push_back(field);
    }
    m.close();
    if (!m) throw std::runtime_error("cannot write '" + ply.file.string() + "'");
    res.plies.push_back(std::move(ply));
  }
  return res;
}

}  // namespace ts
