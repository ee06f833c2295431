#include "io/export.hpp"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "io/results_reader.hpp"
#include "io/results_writer.hpp"
#include "mesh/shell_mesh.hpp"

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

// Each part's symmetry planes (0 x, 1 y, 2 z, in that order) and fibre
// direction, from the run's job_as_run.json.
struct PartSymmetry {
  std::vector<int> planes;
  std::array<double, 3> fibre{1, 0, 0};
};

std::map<std::string, PartSymmetry> symmetry_planes(const std::filesystem::path& dir) {
  const auto path = dir / "job_as_run.json";
  std::ifstream in(path);
  if (!in)
    throw ExportInputError("--whole: '" + dir.string() +
                           "' holds no job_as_run.json, which gives the run's symmetry planes");
  nlohmann::json job;
  try {
    in >> job;
  } catch (const std::exception&) {
    throw std::runtime_error("cannot read '" + path.string() + "'");
  }
  std::map<std::string, PartSymmetry> planes;
  if (!job.contains("constraints") || !job["constraints"].is_array()) return planes;
  std::map<std::string, std::array<double, 3>> fibre;
  if (job.contains("parts") && job["parts"].is_array())
    for (const auto& p : job["parts"])
      if (p.is_object() && p.contains("fibre_direction") && p["fibre_direction"].is_array() &&
          p["fibre_direction"].size() == 3) {
        std::array<double, 3> a{};
        for (int c = 0; c < 3; ++c)
          a[c] = p["fibre_direction"][c].is_number() ? p["fibre_direction"][c].get<double>() : (c == 0 ? 1.0 : 0.0);
        fibre[p.value("name", "")] = a;
      }
  for (const auto& c : job["constraints"]) {
    if (!c.is_object() || c.value("type", "") != "symmetry") continue;
    const std::string plane = c.value("plane", ""), part = c.value("part", "");
    const int d = plane == "x" ? 0 : plane == "y" ? 1 : plane == "z" ? 2 : -1;
    if (d < 0) continue;
    std::vector<std::string> names;
    if (part == "*") {
      if (job.contains("parts") && job["parts"].is_array())
        for (const auto& p : job["parts"])
          if (p.is_object()) names.push_back(p.value("name", ""));
    } else {
      names.push_back(part);
    }
    for (const auto& n : names) {
      auto& v = planes[n].planes;
      if (std::find(v.begin(), v.end(), d) == v.end()) v.push_back(d);
    }
  }
  for (auto& [name, ps] : planes) {
    std::sort(ps.planes.begin(), ps.planes.end());
    if (const auto it = fibre.find(name); it != fibre.end()) ps.fibre = it->second;
  }
  return planes;
}

long long power_of_ten_at_least(long long n) {
  long long p = 1;
  while (p < n) p *= 10;
  return p;
}

// Mirrors the ply at the plane x_d = 0 (see export_gmsh); a0 is the ply's
// fibre direction in the job. False (nothing done) for a ply that lies in
// the plane: it is its own mirror image.
bool mirror(FramePly& p, int d, const std::string& name, const std::array<double, 3>& a0) {
  // Its mirror image's side: R a0 . a0 = |a0|^2 - 2 a0_d^2.
  const double turn = a0[0] * a0[0] + a0[1] * a0[1] + a0[2] * a0[2] - 2 * a0[d] * a0[d] < 0 ? -1.0 : 1.0;
  const std::size_t n = p.x0.size() / 3, m = p.tri.size() / 3;
  ShellMesh first;  // the ply in the first frame, for the run's own tolerance of a plane
  first.x = p.x0;
  first.triangles = p.tri;
  const double h = max_edge_length(first);
  const double tol = 1e-6 * h;
  bool above = false, below = false;
  for (std::size_t i = 0; i < n; ++i) {
    above = above || p.x0[3 * i + d] > tol;
    below = below || p.x0[3 * i + d] < -tol;
  }
  const char* axis = d == 0 ? "x" : d == 1 ? "y" : "z";
  if (above && below)
    throw ExportInputError("--whole: ply '" + name + "' lies on both sides of its symmetry plane " + axis + " = 0");
  if (!above && !below) return false;
  std::vector<int> image(n);
  const long long node_step = power_of_ten_at_least(*std::max_element(p.node_tag.begin(), p.node_tag.end()));
  const long long element_step = power_of_ten_at_least(*std::max_element(p.element_tag.begin(), p.element_tag.end()));
  std::vector<std::size_t> copied;  // the nodes off the plane, in order
  for (std::size_t i = 0; i < n; ++i) {
    if (std::abs(p.x0[3 * i + d]) <= tol) {
      image[i] = static_cast<int>(i);
      continue;
    }
    image[i] = static_cast<int>(n + copied.size());
    copied.push_back(i);
  }
  for (const std::size_t i : copied) {
    for (int c = 0; c < 3; ++c) {
      p.x.push_back(c == d ? -p.x[3 * i + c] : p.x[3 * i + c]);
      p.x0.push_back(c == d ? -p.x0[3 * i + c] : p.x0[3 * i + c]);
    }
    p.node_tag.push_back(p.node_tag[i] + node_step);
  }
  for (std::size_t e = 0; e < m; ++e) {
    p.tri.insert(p.tri.end(), {image[static_cast<std::size_t>(p.tri[3 * e])], image[static_cast<std::size_t>(p.tri[3 * e + 2])],
                               image[static_cast<std::size_t>(p.tri[3 * e + 1])]});
    p.element_tag.push_back(p.element_tag[e] + element_step);
  }
  for (PlyField& f : p.fields) {
    const std::size_t count = f.cells ? m : n;
    std::vector<double> add;
    for (std::size_t i = 0; i < count; ++i) {
      if (!f.cells && image[i] == static_cast<int>(i)) continue;  // a node on the plane
      for (int c = 0; c < f.components; ++c) {
        double v = f.v[i * f.components + c];
        if ((f.rule == MirrorRule::Vector && c == d) || f.rule == MirrorRule::Negate ||
            (f.rule == MirrorRule::Negate12 && c == 2))
          v = -v;
        if (f.rule == MirrorRule::Fibre) v = c == d ? -turn * v : turn * v;
        add.push_back(v);
      }
    }
    f.v.insert(f.v.end(), add.begin(), add.end());
  }
  return true;
}

// A number as Abaqus reads one: at most 20 characters (its limit for a
// floating-point field, which CalculiX keeps too), with as many
// significant digits as fit (15, at least 13).
std::string abaqus_number(double v) {
  char buf[40];
  for (int digits = 15; digits > 13; --digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strlen(buf) <= 20) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.13g", v);
  return buf;
}

// <ply>.inp (see ExportFormat). Returns false where the file cannot be
// written.
bool write_abaqus(const std::filesystem::path& file, const std::string& name, const FramePly& d, double time,
                  const std::string& source, bool calculix, ExportedPly& ply) {
  std::ofstream m(file);
  if (!m) return false;
  const std::string set = abaqus_name(name);
  ply.elset = set;
  const std::size_t nodes = d.x.size() / 3, triangles = d.tri.size() / 3;
  m << "*Heading\n ply '" << name << "' at t = " << abaqus_number(time) << " s, from " << source << "\n"
    << "** Written by thermostamp export --format " << (calculix ? "calculix" : "abaqus")
    << ". Units: m, degC. The mid-surface at the frame's positions\n"
    << "** as 3-node shells (element set " << set << "); give them a section, for instance\n"
    << "**   *Shell Section, elset=" << set << ", material=..., orientation=" << set << "_ORIENTATION\n"
    << "** (with \"nodal thickness\" for the section to take the *Nodal Thickness below, where there is one)\n"
    << "*Node, nset=" << set << "_NODES\n";
  for (std::size_t i = 0; i < nodes; ++i)
    m << d.node_tag[i] << ", " << abaqus_number(d.x[3 * i]) << ", " << abaqus_number(d.x[3 * i + 1]) << ", "
      << abaqus_number(d.x[3 * i + 2]) << '\n';
  m << "*Element, type=S3, elset=" << set << '\n';
  for (std::size_t e = 0; e < triangles; ++e)
    m << d.element_tag[e] << ", " << d.node_tag[static_cast<std::size_t>(d.tri[3 * e])] << ", "
      << d.node_tag[static_cast<std::size_t>(d.tri[3 * e + 1])] << ", "
      << d.node_tag[static_cast<std::size_t>(d.tri[3 * e + 2])] << '\n';
  const PlyField* fibre = nullptr;
  const PlyField* temperature = nullptr;
  const PlyField* thickness = nullptr;
  for (const PlyField& f : d.fields) {
    if (f.name == "fibre_direction" && f.cells && f.components == 3) fibre = &f;
    if (f.name == "thickness" && f.cells && f.components == 1) thickness = &f;
    if (!f.cells && f.components == 1 && (f.name == "temperature_mean" || (f.name == "temperature" && !temperature)))
      temperature = &f;
  }
  if (fibre) {
    // The material frame of each element: the fibre direction a (1) and
    // n x a (2), n the element's unit normal at the frame's positions.
    ply.orientation_from = fibre->name;
    m << "** Each element's material directions: 1 along the fibres, 2 = n x 1 in the element's plane\n"
      << "*Distribution Table, name=" << set << "_FIBRES_TABLE\nCOORD3D, COORD3D\n"
      << "*Distribution, name=" << set << "_FIBRES, location=ELEMENT, table=" << set << "_FIBRES_TABLE\n";
    if (!calculix) m << ", 1., 0., 0., 0., 1., 0.\n";  // the default, which Abaqus asks for first
    for (std::size_t e = 0; e < triangles; ++e) {
      const double* p0 = &d.x[3 * static_cast<std::size_t>(d.tri[3 * e])];
      const double* p1 = &d.x[3 * static_cast<std::size_t>(d.tri[3 * e + 1])];
      const double* p2 = &d.x[3 * static_cast<std::size_t>(d.tri[3 * e + 2])];
      const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
      const double v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
      double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (double& c : n) c = ln > 0 ? c / ln : 0.0;
      const double* a = &fibre->v[3 * e];
      const double b[3] = {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]};
      m << d.element_tag[e];
      for (const double c : {a[0], a[1], a[2], b[0], b[1], b[2]}) m << ", " << abaqus_number(c);
      m << '\n';
    }
    m << "*Orientation, name=" << set << "_ORIENTATION\n" << set << "_FIBRES\n3, 0.\n";
  }
  if (thickness) {
    // Each node's thickness: the mean of its elements', weighted by their
    // areas at the frame (a collapsed element, NaN, left out).
    std::vector<double> sum(nodes, 0.0), weight(nodes, 0.0);
    for (std::size_t e = 0; e < triangles; ++e) {
      if (!std::isfinite(thickness->v[e])) continue;
      const int* t = &d.tri[3 * e];
      const double* p0 = &d.x[3 * static_cast<std::size_t>(t[0])];
      const double* p1 = &d.x[3 * static_cast<std::size_t>(t[1])];
      const double* p2 = &d.x[3 * static_cast<std::size_t>(t[2])];
      const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
      const double v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
      const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int k = 0; k < 3; ++k) {
        sum[static_cast<std::size_t>(t[k])] += area * thickness->v[e];
        weight[static_cast<std::size_t>(t[k])] += area;
      }
    }
    ply.thickness_from = thickness->name;
    m << "** Each node's thickness at constant volume (m, from the field " << thickness->name
      << "): the mean of its elements', weighted by their areas\n*Nodal Thickness\n";
    for (std::size_t i = 0; i < nodes; ++i)
      if (weight[i] > 0) m << d.node_tag[i] << ", " << abaqus_number(sum[i] / weight[i]) << '\n';
  }
  if (temperature) {
    ply.temperature_from = temperature->name;
    m << "** The nodes' temperatures (" << temperature->name << ", degC) at t = " << abaqus_number(time) << " s\n"
      << "*Initial Conditions, type=TEMPERATURE\n";
    for (std::size_t i = 0; i < nodes; ++i) m << d.node_tag[i] << ", " << abaqus_number(temperature->v[i]) << '\n';
  }
  m.close();
  return static_cast<bool>(m);
}

}  // namespace

std::string abaqus_name(const std::string& ply) {
  std::string s;
  for (const char c : ply)
    s += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::toupper(static_cast<unsigned char>(c)))
                                                      : '_';
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) s = "P_" + s;
  return s;
}

std::optional<MirrorRule> mirror_rule(const std::string& field) {
  if (field == "displacement" || field == "velocity") return MirrorRule::Vector;
  if (field == "fibre_direction") return MirrorRule::Fibre;
  if (field == "shear_angle") return MirrorRule::Negate;
  if (field == "membrane_stress" || field == "membrane_strain" || field == "curvature") return MirrorRule::Negate12;
  for (const char* f : {"temperature", "temperature_mean", "temperature_top", "temperature_bottom", "contact_status",
                        "contact_pressure", "conductance_bottom", "conductance_top", "tool_gap", "below_threshold_from",
                        "all_below_threshold_from", "crystallinity", "crystallinity_mean", "membrane_stability",
                        "thickness"})
    if (field == f) return MirrorRule::Keep;
  return std::nullopt;
}

ExportResult export_gmsh(const std::filesystem::path& dir, std::optional<double> time,
                         const std::filesystem::path& out, bool whole) {
  return export_plies(dir, time, out, whole, ExportFormat::Gmsh);
}

FramePlies read_frame_plies(const std::filesystem::path& dir, std::optional<double> time, bool whole, bool fields,
                            bool first) {
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
  FramePlies res;
  res.h5 = h5;
  res.frames = static_cast<int>(frames.times.size());
  int k = first ? 0 : res.frames - 1;
  if (time && !first) {
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
  res.group = "frames/" + frames.names[k];
  const std::string& group = res.group;
  // The frame's plies (a frame also holds the moving tools' surfaces).
  std::vector<std::string> plies;
  const auto parts = members(file, "parts");
  for (const auto& name : members(file, group))
    if (std::find(parts.begin(), parts.end(), name) != parts.end()) plies.push_back(name);
  if (plies.empty()) throw std::runtime_error("frame " + frames.names[k] + " of '" + h5.string() + "' holds no ply");
  const auto planes = whole ? symmetry_planes(dir) : std::map<std::string, PartSymmetry>{};
  const std::string first_group = "frames/" + frames.names.front();
  for (const auto& name : plies) {
    std::vector<hsize_t> tshape, xshape, shape0;
    const std::vector<double> tri = read_values(file, "parts/" + name + "/triangles", tshape);
    FramePly d;
    d.name = name;
    d.x = read_values(file, group + "/" + name + "/nodes", xshape);
    if (tshape.size() != 2 || tshape[1] != 3 || xshape.size() != 2 || xshape[1] != 3)
      throw std::runtime_error("'" + h5.string() + "': the triangles or nodes of ply '" + name +
                               "' cannot be read (cut short?)");
    d.x0 = read_values(file, first_group + "/" + name + "/nodes", shape0);
    if (d.x0.size() != d.x.size())
      throw std::runtime_error("'" + h5.string() + "': the nodes of ply '" + name + "' in " + first_group +
                               " cannot be read (cut short?)");
    const std::size_t nodes = xshape[0], triangles = tshape[0];
    d.tri.resize(tri.size());
    for (std::size_t k = 0; k < tri.size(); ++k) d.tri[k] = static_cast<int>(tri[k]);
    d.node_tag = tags(file, "parts/" + name + "/node_tags", nodes);
    d.element_tag = tags(file, "parts/" + name + "/element_tags", triangles);
    for (const auto& field : fields ? members(file, group + "/" + name) : std::vector<std::string>{}) {
      if (field == "nodes" || field == "layer_nodes") continue;
      std::vector<hsize_t> shape;
      PlyField f;
      f.name = field;
      f.v = read_values(file, group + "/" + name + "/" + field, shape);
      if (shape.empty()) throw std::runtime_error("'" + h5.string() + "': field '" + field + "' of ply '" + name +
                                                  "' cannot be read (cut short?)");
      f.components = shape.size() > 1 ? static_cast<int>(shape[1]) : 1;
      f.cells = field_on_elements(field);
      // (the through-thickness `temperature` lies on the extruded mesh; its
      // mean, top and bottom values are fields of their own in the frame)
      if (shape[0] != static_cast<hsize_t>(f.cells ? triangles : nodes)) continue;
      d.fields.push_back(std::move(f));
    }
    if (const auto it = planes.find(name); it != planes.end() && !it->second.planes.empty()) {
      for (PlyField& f : d.fields) {
        const auto rule = mirror_rule(f.name);
        if (!rule) throw std::runtime_error("--whole: no mirror image known for the field '" + f.name + "'");
        f.rule = *rule;
      }
      for (const int a : it->second.planes) {
        if (mirror(d, a, name, it->second.fibre)) d.mirrored.push_back(a == 0 ? "x" : a == 1 ? "y" : "z");
      }
    }
    res.plies.push_back(std::move(d));
  }
  return res;
}

void create_output_folder(const std::filesystem::path& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec || !std::filesystem::is_directory(out))
    throw ExportInputError("cannot create the output folder " + out.string() + " (--out): " +
                           (ec ? ec.message() : std::string("a file of that name is there")));
}

ExportResult export_plies(const std::filesystem::path& dir, std::optional<double> time,
                          const std::filesystem::path& out, bool whole, ExportFormat format) {
  FramePlies frame = read_frame_plies(dir, time, whole, true);
  create_output_folder(out);
  ExportResult res;
  res.time = frame.time;
  res.frame = frame.frame;
  res.frames = frame.frames;
  const std::string source = frame.h5.string() + " (" + frame.group + ")";
  for (FramePly& d : frame.plies) {
    const std::string& name = d.name;
    ExportedPly ply;
    ply.name = name;
    ply.mirrored = d.mirrored;
    ply.nodes = static_cast<int>(d.x.size() / 3);
    ply.triangles = static_cast<int>(d.tri.size() / 3);
    if (format != ExportFormat::Gmsh) {
      ply.file = out / (name + ".inp");
      if (!write_abaqus(ply.file, name, d, res.time, source, format == ExportFormat::CalculiX, ply))
        throw std::runtime_error("cannot write '" + ply.file.string() + "'");
      res.plies.push_back(std::move(ply));
      continue;
    }
    ply.file = out / (name + ".msh");
    std::ofstream m(ply.file);
    if (!m) throw std::runtime_error("cannot write '" + ply.file.string() + "'");
    m << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"" << name << "\"\n$EndPhysicalNames\n";
    m << "$Nodes\n" << ply.nodes << '\n';
    for (std::size_t i = 0; i < static_cast<std::size_t>(ply.nodes); ++i)
      m << d.node_tag[i] << ' ' << number(d.x[3 * i]) << ' ' << number(d.x[3 * i + 1]) << ' ' << number(d.x[3 * i + 2])
        << '\n';
    m << "$EndNodes\n$Elements\n" << ply.triangles << '\n';
    for (std::size_t e = 0; e < static_cast<std::size_t>(ply.triangles); ++e) {
      m << d.element_tag[e] << " 2 2 1 1";
      for (std::size_t c = 0; c < 3; ++c) m << ' ' << d.node_tag[static_cast<std::size_t>(d.tri[3 * e + c])];
      m << '\n';
    }
    m << "$EndElements\n";
    for (const PlyField& f : d.fields) {
      write_data(m, f.cells ? "ElementData" : "NodeData", f.name, res.time, f.v, f.components,
                 f.cells ? d.element_tag : d.node_tag);
      (f.cells ? ply.element_data : ply.node_data).push_back(f.name);
    }
    m.close();
    if (!m) throw std::runtime_error("cannot write '" + ply.file.string() + "'");
    res.plies.push_back(std::move(ply));
  }
  return res;
}

}  // namespace ts
