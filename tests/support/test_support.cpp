#include "test_support.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <unistd.h>

#include "io/logging.hpp"
#include "plugins/registry.hpp"

namespace ts::test {

sdk::PartView part_view(const ShellMesh& mesh, int index, double thickness) {
  sdk::PartView v;
  v.index = index;
  v.num_nodes = mesh.num_nodes();
  v.num_elements = mesh.num_elements();
  v.x0 = mesh.x;
  v.x = mesh.x;
  v.triangles = mesh.triangles;
  v.neighbours = mesh.neighbours;
  v.thickness = thickness;
  return v;
}

json ply_job(const std::string& splitter, int layers, double t_end, double interval) {
  json j = {
      {"format", "thermostamp-job/1"},
      {"name", "test"},
      {"time", {{"end", t_end}}},
      {"materials",
       {{"ply", {{"density", 1294.0}, {"specific_heat", 1775.0}, {"conductivity", {3.89, 0.31, 0.31}}}}}},
      {"parts",
       {{{"name", "ply"},
         {"mesh", {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {0.01, 0.01}}, {"divisions", {2, 2}}}},
         {"thickness", 0.0005},
         {"material", "ply"},
         {"initial_temperature", 300.0},
         {"thickness_layers", layers}}}},
      {"solvers", {{"mechanics", nullptr}, {"thermal", {{"splitter", splitter}, {"through_thickness", "implicit"}}}}},
      {"output",
       {{"interval", interval},
        {"fields", {"temperature"}},
        {"probes",
         {{{"name", "c"}, {"part", "ply"}, {"at", {0.005, 0.005, 0}}, {"quantities", {"temperature_profile"}},
           {"interval", interval}}}}}}};
  return j;
}

std::string xdmf_mismatch(const std::filesystem::path& dir) {
  std::ifstream in(dir / "results.xdmf");
  if (!in) return "no results.xdmf";
  std::stringstream text;
  text << in.rdbuf();
  const std::string x = text.str();
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return "cannot open results.h5";
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // a missing dataset is an answer, not an error to print
  std::string problem;
  int items = 0;
  const std::string open = "<DataItem Dimensions=\"", prefix = "results.h5:";
  for (std::size_t at = x.find(open); at != std::string::npos && problem.empty(); at = x.find(open, at + 1)) {
    ++items;
    const std::size_t d0 = at + open.size(), d1 = x.find('"', d0);
    const std::size_t p0 = x.find('>', d1) + 1, p1 = x.find("</DataItem>", p0);
    const std::string dims = x.substr(d0, d1 - d0), ref = x.substr(p0, p1 - p0);
    if (ref.rfind(prefix, 0) != 0) {
      problem = "DataItem '" + ref + "' not in results.h5";
      break;
    }
    const std::string path = ref.substr(prefix.size());
    if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0 || H5Oexists_by_name(file, path.c_str(), H5P_DEFAULT) <= 0) {
      problem = "results.h5 has no " + path;
      break;
    }
    const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(set);
    hsize_t d[2] = {0, 0};
    const int rank = H5Sget_simple_extent_dims(space, d, nullptr);
    H5Sclose(space);
    H5Dclose(set);
    std::string have = std::to_string(d[0]);
    if (rank > 1 && d[1] > 1) have += " " + std::to_string(d[1]);
    if (have != dims) problem = path + " holds " + have + " values, the index gives " + dims;
  }
  H5Fclose(file);
  if (problem.empty() && items == 0) problem = "no DataItem";
  return problem;
}

const ProbeSample* JobRun::sample(int probe, const std::string& quantity, double t) const {
  const ProbeSample* best = nullptr;
  double bd = 1e300;
  for (const auto& s : result.probes)
    if (s.probe == probe && s.quantity == quantity && std::abs(s.time - t) < bd) {
      bd = std::abs(s.time - t);
      best = &s;
    }
  return best;
}

JobRun run_json(const json& doc, int threads, const std::filesystem::path& out) {
  log_to_terminal(true);
  const Job job = parse_job(doc, source_dir() / "tests" / "inline.json");
  PluginRegistry registry;
  Simulation sim(job, registry);
  RunOptions opt;
  opt.threads = threads;
  opt.quiet = true;
  opt.write_files = !out.empty();
  opt.out_dir = out;
  JobRun r;
  r.result = sim.run(opt);
  return r;
}

std::filesystem::path binary_dir() { return THERMOSTAMP_TEST_BINARY_DIR; }
std::filesystem::path source_dir() { return THERMOSTAMP_TEST_SOURCE_DIR; }

json pa66_carbon_mixture() {
  return read_job_document(source_dir() / "share" / "materials" / "pa66_cf_ud_mixture.json").at("mixture");
}

std::filesystem::path temp_dir(const std::string& name) {
  auto d = binary_dir() / "test_tmp" / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& file) {
  std::ifstream csv(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(csv, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

static std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult thermostamp(const std::string& args) { return thermostamp_after("", args); }

CommandResult thermostamp_after(const std::string& before, const std::string& args) {
  static int counter = 0;
  const auto dir = binary_dir() / "test_tmp" / "cmd";
  std::filesystem::create_directories(dir);
  const std::string tag = std::to_string(getpid()) + "_" + std::to_string(counter++);
  const auto out = dir / ("out" + tag + ".txt");
  const auto err = dir / ("err" + tag + ".txt");
  const std::string cmd = before + " " + (binary_dir() / "bin" / "thermostamp").string() + " " + args + " >" +
                          out.string() + " 2>" + err.string() + " </dev/null";
  const int rc = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

namespace {
// The slab's eigen-series: the sum over n of c_n exp(-l_n^2 alpha t / L^2)
// shape(l_n), with l_n tan l_n = Bi and c_n = 4 sin l_n / (2 l_n + sin 2 l_n).
// The roots of the last Bi asked for are kept (callers evaluate the series
// many times for one slab).
template <class Shape>
double slab_robin_sum(double t, double L, double alpha, double Bi, Shape shape) {
  static double roots_bi = std::numeric_limits<double>::quiet_NaN();
  static std::vector<double> roots;
  if (!(Bi == roots_bi)) {
    roots.clear();
    const double pi = 3.14159265358979323846;
    for (int n = 0; n < 400; ++n) {
      // Root of f(l) = l tan l - Bi in (n pi, n pi + pi/2), by bisection.
      double lo = n * pi + 1e-12, hi = n * pi + pi / 2 - 1e-12;
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid * std::tan(mid) - Bi > 0) hi = mid;
        else lo = mid;
      }
      roots.push_back(0.5 * (lo + hi));
    }
    roots_bi = Bi;
  }
  double theta = 0;
  for (const double l : roots) {
    const double c = 4 * std::sin(l) / (2 * l + std::sin(2 * l));
    theta += c * std::exp(-l * l * alpha * t / (L * L)) * shape(l);
  }
  return theta;
}
}  // namespace

double slab_robin_series(double x, double t, double L, double alpha, double Bi, double T0, double Tinf) {
  return Tinf + (T0 - Tinf) * slab_robin_sum(t, L, alpha, Bi, [&](double l) { return std::cos(l * x / L); });
}

double slab_robin_mean(double t, double L, double alpha, double Bi, double T0, double Tinf) {
  return Tinf + (T0 - Tinf) * slab_robin_sum(t, L, alpha, Bi, [](double l) { return std::sin(l) / l; });
}

void write_square_stl(const std::filesystem::path& file, double lo, double hi, double z) {
  std::ofstream s(file);
  s << "solid square\n";
  for (const auto& tri : {std::array<double, 6>{lo, lo, hi, lo, hi, hi}, std::array<double, 6>{lo, lo, hi, hi, lo, hi}}) {
    s << " facet normal 0 0 1\n  outer loop\n";
    for (int k = 0; k < 3; ++k) s << "   vertex " << tri[2 * k] << ' ' << tri[2 * k + 1] << ' ' << z << "\n";
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid square\n";
}

void write_revolved_stl(const std::filesystem::path& file, const json& surface, double step_deg) {
  const double pi = std::acos(-1.0), step = step_deg * pi / 180;
  const json origin = surface.contains("axis") ? surface["axis"].value("origin", json{0.0, 0.0, 0.0})
                                               : json{0.0, 0.0, 0.0};
  std::vector<std::array<double, 4>> segs;  // (ra, za, rb, zb)
  for (const auto& piece : surface["profile"]) {
    std::vector<std::array<double, 2>> pts;
    if (piece.contains("line")) {
      pts = {piece["line"][0].get<std::array<double, 2>>(), piece["line"][1].get<std::array<double, 2>>()};
    } else {
      const auto a = piece["arc"]["from"].get<std::array<double, 2>>(), b = piece["arc"]["to"].get<std::array<double, 2>>();
      const auto c = piece["arc"]["centre"].get<std::array<double, 2>>();
      const double rad = std::hypot(a[0] - c[0], a[1] - c[1]);
      const double t0 = std::atan2(a[1] - c[1], a[0] - c[0]), t1 = std::atan2(b[1] - c[1], b[0] - c[0]);
      const double cross = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
      double sweep = t1 - t0;
      if (cross > 0 && sweep < 0) sweep += 2 * pi;
      if (cross < 0 && sweep > 0) sweep -= 2 * pi;
      const int n = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / step)));
      for (int k = 0; k <= n; ++k)
        pts.push_back({c[0] + rad * std::cos(t0 + sweep * k / n), c[1] + rad * std::sin(t0 + sweep * k / n)});
      pts.front() = a;
      pts.back() = b;
    }
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) segs.push_back({pts[k][0], pts[k][1], pts[k + 1][0], pts[k + 1][1]});
  }
  const double margin = 3.0 * pi / 180, span = pi / 2 + 2 * margin;
  const int ns = static_cast<int>(std::ceil(span / step));
  std::ofstream s(file);
  s.precision(17);
  s << "solid revolved\n";
  auto xyz = [&](double r, double z, double t) {
    return std::array<double, 3>{origin[0].get<double>() + r * std::cos(t), origin[1].get<double>() + r * std::sin(t),
                                 origin[2].get<double>() + z};
  };
  for (const auto& g : segs)
    for (int k = 0; k < ns; ++k) {
      const double t0 = -margin + span * k / ns, t1 = -margin + span * (k + 1) / ns, tm = 0.5 * (t0 + t1);
      const std::array<std::array<double, 3>, 4> q = {xyz(g[0], g[1], t0), xyz(g[2], g[3], t0), xyz(g[2], g[3], t1),
                                                      xyz(g[0], g[1], t1)};
      const std::array<double, 3> want = {-(g[3] - g[1]) * std::cos(tm), -(g[3] - g[1]) * std::sin(tm), g[2] - g[0]};
      for (auto tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        std::array<double, 3> u{}, v{};
        for (int d = 0; d < 3; ++d) {
          u[d] = q[tri[1]][d] - q[tri[0]][d];
          v[d] = q[tri[2]][d] - q[tri[0]][d];
        }
        const std::array<double, 3> n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len < 1e-14) continue;  // a corner on the axis
        if (n[0] * want[0] + n[1] * want[1] + n[2] * want[2] < 0) std::swap(tri[1], tri[2]);
        s << " facet normal 0 0 0\n  outer loop\n";
        for (int c : tri) s << "   vertex " << q[c][0] << ' ' << q[c][1] << ' ' << q[c][2] << "\n";
        s << "  endloop\n endfacet\n";
      }
    }
  s << "endsolid revolved\n";
}

void slab_heat_flows(const std::vector<double>& T, double k, double e, double h, double Ta, std::vector<double>& q) {
  const std::size_t n = T.size() - 1;
  q.assign(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double f = k / e * (T[i + 1] - T[i]);
    q[i] += f;
    q[i + 1] -= f;
  }
  q[n] += h * (Ta - T[n]);
}

json bias_job(const json& mesh, double speed, double t_end) {
  const double H = 0.230;
  return {{"format", "thermostamp-job/1"},
          {"name", "bias"},
          {"time", {{"end", t_end}}},
          {"materials",
           {{"woven",
             {{"density", 1500.0},
              {"membrane",
               {{"law", "woven_hyperelastic"},
                {"k_warp", 1.0e5},
                {"k_weft", 1.0e5},
                {"k_sh", {kBiasKsh[0], kBiasKsh[1], kBiasKsh[2]}}}}}}}},
          {"parts",
           {{{"name", "specimen"},
             {"mesh", mesh},
             {"thickness", 0.0005},
             {"material", "woven"},
             {"fibre_direction", {1.0, 1.0, 0.0}},
             {"initial_temperature", 20.0}}}},
          {"constraints",
           {{{"type", "fix"},
             {"part", "specimen"},
             {"box", {{-1e-6, -1, -1}, {1e-6, 1, 1}}},
             {"dofs", {"x", "y", "z"}}},
            {{"type", "velocity"},
             {"part", "specimen"},
             {"box", {{H - 1e-6, -1, -1}, {H + 1e-6, 1, 1}}},
             {"dofs", {"x"}},
             {"velocity", {speed, 0.0, 0.0}}},
            {{"type", "fix"}, {"part", "specimen"}, {"box", {{H - 1e-6, -1, -1}, {H + 1e-6, 1, 1}}}, {"dofs", {"y"}}},
            {{"type", "fix"}, {"part", "*"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"z"}}}}},
          {"solvers", {{"mechanics", {{"dt_safety", 0.8}, {"damping", 10.0}}}, {"thermal", nullptr}}}};
}

void write_yarn_lattice_gmsh(const std::filesystem::path& file, double width, int nx, int ny) {
  const double a = width / ny;
  std::map<std::pair<int, int>, int> id;
  std::vector<std::array<double, 2>> nodes;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      if ((i + j) % 2 == 0) {
        id[{i, j}] = static_cast<int>(nodes.size()) + 1;
        nodes.push_back({i * a, j * a});
      }
  std::vector<std::array<int, 3>> tris;
  auto add = [&](std::pair<int, int> p, std::pair<int, int> q, std::pair<int, int> r) {
    std::array<int, 3> t = {id.at(p), id.at(q), id.at(r)};
    const auto& A = nodes[t[0] - 1];
    const auto& B = nodes[t[1] - 1];
    const auto& C = nodes[t[2] - 1];
    if ((B[0] - A[0]) * (C[1] - A[1]) - (B[1] - A[1]) * (C[0] - A[0]) < 0) std::swap(t[1], t[2]);
    tris.push_back(t);
  };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      if ((i + j) % 2 == 0) continue;  // diamond centres
      if (i == 0) {
        add({0, j - 1}, {1, j}, {0, j + 1});
      } else if (i == nx) {
        add({nx, j - 1}, {nx, j + 1}, {nx - 1, j});
      } else {
        if (j < ny) add({i - 1, j}, {i + 1, j}, {i, j + 1});
        if (j > 0) add({i - 1, j}, {i, j - 1}, {i + 1, j});
      }
    }
  std::ofstream m(file);
  m << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << nodes.size() << "\n";
  for (std::size_t k = 0; k < nodes.size(); ++k) m << k + 1 << ' ' << nodes[k][0] << ' ' << nodes[k][1] << " 0\n";
  m << "$EndNodes\n$Elements\n" << tris.size() << "\n";
  for (std::size_t k = 0; k < tris.size(); ++k)
    m << k + 1 << " 2 0 " << tris[k][0] << ' ' << tris[k][1] << ' ' << tris[k][2] << "\n";
  m << "$EndElements\n";
}

void write_shuffled_gmsh(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed) {
  std::vector<int> order(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) order[e] = e;
  if (seed != 0) std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  std::ofstream f(file);
  f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << mesh.num_nodes() << '\n';
  f.precision(17);
  for (int i = mesh.num_nodes() - 1; i >= 0; --i)
    f << shuffled_node_tag(i) << ' ' << mesh.x[3 * i] << ' ' << mesh.x[3 * i + 1] << ' ' << mesh.x[3 * i + 2] << '\n';
  f << "$EndNodes\n$Elements\n" << mesh.num_elements() << '\n';
  for (const int e : order) {
    f << shuffled_element_tag(e) << " 2 2 1 1";
    for (int k = 0; k < 3; ++k) f << ' ' << shuffled_node_tag(mesh.triangles[3 * e + k]);
    f << '\n';
  }
  f << "$EndElements\n";
}

void write_shuffled_abaqus(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed,
                           const std::string& type) {
  std::vector<int> order(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) order[e] = e;
  if (seed != 0) std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  std::ofstream f(file);
  f.precision(17);
  f << "*Heading\n** Job name: ply Model name: Model-1\n*Preprint, echo=NO, model=NO, history=NO, contact=NO\n"
       "**\n** PARTS\n**\n*Part, name=\"Ply\"\n*Node\n";
  for (int i = mesh.num_nodes() - 1; i >= 0; --i)
    f << "  " << shuffled_node_tag(i) << ", " << mesh.x[3 * i] << ", " << mesh.x[3 * i + 1] << ", " << mesh.x[3 * i + 2]
      << '\n';
  f << "*element, TYPE=" << type << ", elset=PLY\n";
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int e = order[k];
    f << shuffled_element_tag(e) << ", " << shuffled_node_tag(mesh.triangles[3 * e]) << ","
      << (k % 7 == 3 ? "\n" : " ") << shuffled_node_tag(mesh.triangles[3 * e + 1]) << ", "
      << shuffled_node_tag(mesh.triangles[3 * e + 2]) << '\n';
  }
  f << "*Nset, nset=EDGE\n " << shuffled_node_tag(0) << ", " << shuffled_node_tag(1) << "\n*Elset, elset=ALL, generate\n"
    << " 1, 10000, 1\n*Shell Section, elset=PLY, material=PA66\n0.0003, 5\n*End Part\n**\n** ASSEMBLY\n**\n"
       "*Assembly, name=Assembly\n*Instance, name=Ply-1, part=Ply\n*End Instance\n*Node\n      1, 5., 5., 5.\n"
       "*Nset, nset=RP\n 1,\n*End Assembly\n*Material, name=PA66\n*Density\n 1500.,\n";
}

void write_shuffled_lsdyna(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed,
                           const std::string& style, const std::string& shell_option) {
  std::vector<int> order(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) order[e] = e;
  if (seed != 0) std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  const bool free = style == "free", wide = style == "long", i10 = style == "i10";
  const int iw = wide ? 20 : i10 ? 10 : 8, rw = wide ? 20 : 16, digits = wide ? 14 : 10;
  const char* suffix = i10 ? " %" : "";
  std::ofstream f(file);
  char buf[64];
  auto integer = [&](long long v) {
    if (free) return std::to_string(v) + ",";
    std::snprintf(buf, sizeof buf, "%*lld", iw, v);
    return std::string(buf);
  };
  auto real = [&](double v) {
    if (free) {
      std::snprintf(buf, sizeof buf, "%.17g,", v);
      return std::string(buf);
    }
    std::snprintf(buf, sizeof buf, "%*.*e", rw, digits - 1, v);
    return std::string(buf);
  };
  f << (wide ? "*KEYWORD LONG=Y\n" : "*KEYWORD\n") << "*TITLE\nply for ThermoStamp\n$ a comment card\n"
    << "*PART\nply\n" << integer(3) << integer(1) << integer(1) << "\n*SECTION_SHELL\n" << integer(1)
    << integer(2) << "\n" << real(0.0005) << real(0.0005) << real(0.0005) << "\n"
    << "*NODE" << suffix << "\n$#   nid               x               y               z\n";
  for (int i = mesh.num_nodes() - 1; i >= 0; --i)
    f << integer(shuffled_node_tag(i)) << real(mesh.x[3 * i]) << real(mesh.x[3 * i + 1]) << real(mesh.x[3 * i + 2])
      << "\n";
  f << "*ELEMENT_SHELL" << (shell_option.empty() ? "" : "_" + shell_option) << suffix << "\n";
  const bool second = shell_option.find("THICKNESS") != std::string::npos ||
                      shell_option.find("BETA") != std::string::npos || shell_option.find("MCID") != std::string::npos;
  const bool offset = shell_option.find("OFFSET") != std::string::npos;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int e = order[k];
    f << integer(shuffled_element_tag(e)) << integer(3);
    for (int c = 0; c < 3; ++c) f << integer(shuffled_node_tag(mesh.triangles[3 * e + c]));
    if (k % 5 != 2) f << integer(shuffled_node_tag(mesh.triangles[3 * e + 2]));
    f << "\n";
    if (k % 7 == 3) f << "$ a comment card between the cards of an element\n";
    if (second) f << real(0.0005) << real(0.00051) << real(0.00052) << real(0.00052) << real(30.0 + k) << "\n";
    if (offset) f << real(-0.00025) << "\n";
  }
  f << "*END\n*NODE\n       1     not read\n";
}

void write_parallelogram(const std::filesystem::path& file, double L, double W, double s, int nx, int ny) {
  std::ofstream f(file);
  f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << (nx + 1) * (ny + 1) << "\n";
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double y = W * j / ny, xi = L * i / nx;
      f << j * (nx + 1) + i + 1 << " " << xi + s * y << " " << y << " 0\n";
    }
  f << "$EndNodes\n$Elements\n" << 2 * nx * ny << "\n";
  int id = 1;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i + 1, b = a + 1, c = b + nx + 1, d = a + nx + 1;
      f << id++ << " 2 2 0 1 " << a << " " << b << " " << c << "\n";
      f << id++ << " 2 2 0 1 " << a << " " << c << " " << d << "\n";
    }
  f << "$EndElements\n";
}

double profile_at(const std::vector<double>& T, double h, double z) {
  const int n = static_cast<int>(T.size()) - 1;
  const double s = (z / h + 0.5) * n;
  const int i = std::min(n - 1, static_cast<int>(s));
  return (1 - (s - i)) * T[i] + (s - i) * T[i + 1];
}

double largest_difference(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                          double h) {
  double d = 0;
  for (std::size_t t = 0; t < std::min(a.size(), b.size()); ++t)
    for (int m = 0; m <= 16; ++m) {
      const double z = (m / 16.0 - 0.5) * h;
      d = std::max(d, std::abs(profile_at(a[t], h, z) - profile_at(b[t], h, z)));
    }
  return d;
}

json two_ply_job(const std::string& splitter, int layers, double hc) {
  json j = ply_job(splitter, layers, 2.0, 0.5);
  json lower = j["parts"][0];
  lower["name"] = "lower";
  lower["mesh"]["origin"] = {0, 0, 0.00025};
  json upper = lower;
  upper["name"] = "upper";
  upper["mesh"]["origin"] = {0, 0, 0.00075};
  j["parts"] = {lower, upper};
  j["tools"] = {{{"name", "die"}, {"surface", {{"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 0, 1}}}},
                 {"temperature", 260.0}}};
  j["interactions"] = {
      {{"type", "contact"}, {"handler", "penalty_node_surface"}, {"between", {"die", "lower"}}, {"conductance", 1000.0}},
      {{"type", "contact"}, {"handler", "penalty_node_surface"}, {"between", {"upper", "lower"}}, {"conductance", hc}}};
  j["output"]["probes"] = {
      {{"name", "lo"}, {"part", "lower"}, {"at", {0.005, 0.005, 0.00025}}, {"quantities", {"temperature_profile"}}, {"interval", 0.5}},
      {{"name", "up"}, {"part", "upper"}, {"at", {0.005, 0.005, 0.00075}}, {"quantities", {"temperature_profile"}}, {"interval", 0.5}}};
  return j;
}

double mode_decay_rate(const json& j, const std::filesystem::path& dir, double L, double slant, double a,
                       double (*T_of)(double), double (*u_of)(double), RunResult* result) {
  log_to_terminal(true);
  const Job job = parse_job(j, dir / "job.json");
  PluginRegistry reg;
  Simulation sim(job, reg);
  const auto x0 = sim.initial_coordinates(0);
  const int n = static_cast<int>(x0.size() / 3);
  std::vector<double> T0(n), mode(n);
  for (int i = 0; i < n; ++i) {
    mode[i] = std::cos(M_PI * (x0[3 * i] - slant * x0[3 * i + 1]) / L);
    T0[i] = T_of(a * mode[i]);
  }
  sim.set_initial_temperature(0, T0);
  RunOptions opt;
  opt.write_files = false;
  opt.quiet = true;
  const RunResult r = sim.run(opt);
  if (result) *result = r;
  if (!r.ok) return std::numeric_limits<double>::quiet_NaN();
  const auto T = sim.temperature(0);
  const int nz = sim.values_per_node(0);
  double num = 0, den = 0;
  for (int i = 0; i < n; ++i) {
    double u = 0;  // the mean through the thickness (uniform here)
    for (int k = 0; k < nz; ++k) u += u_of(T[static_cast<std::size_t>(nz) * i + k]) / nz;
    num += u * mode[i];
    den += a * mode[i] * mode[i];
  }
  return -std::log(num / den) / job.t_end;
}

}  // namespace ts::test
