#include "mesh/shell_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include <thermostamp/sdk/math.hpp>

namespace ts {

using sdk::Vec3;

ShellMesh rectangle_mesh(const std::array<double, 3>& o, const std::array<double, 2>& s,
                         const std::array<int, 2>& div, bool crossed) {
  ShellMesh m;
  const int nx = div[0], ny = div[1];
  const int corners = (nx + 1) * (ny + 1);
  m.x.reserve(3 * (corners + (crossed ? nx * ny : 0)));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      m.x.push_back(o[0] + s[0] * i / nx);
      m.x.push_back(o[1] + s[1] * j / ny);
      m.x.push_back(o[2]);
    }
  auto id = [nx](int i, int j) { return j * (nx + 1) + i; };
  if (crossed) {
    // Four triangles per cell around its centre: edges along x, y and both
    // diagonals, so that fibres along either diagonal follow element edges.
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        m.x.push_back(o[0] + s[0] * (i + 0.5) / nx);
        m.x.push_back(o[1] + s[1] * (j + 0.5) / ny);
        m.x.push_back(o[2]);
      }
    m.triangles.reserve(12 * nx * ny);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
        const int e = corners + j * nx + i;
        m.triangles.insert(m.triangles.end(), {a, b, e, b, c, e, c, d, e, d, a, e});
      }
    finalize_mesh(m);
    return m;
  }
  m.triangles.reserve(6 * nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
      } else {
        m.triangles.insert(m.triangles.end(), {a, b, d, b, c, d});
      }
    }
  finalize_mesh(m);
  return m;
}

namespace {
struct LineReader {
  std::ifstream in;
  int line = 0;
  std::string path;
  std::string next() {
    std::string s;
    while (std::getline(in, s)) {
      ++line;
      if (!s.empty() && s.back() == '\r') s.pop_back();
      if (!s.empty()) return s;
    }
    fail("unexpected end of file");
    return {};
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
  }
};

template <class T>
T parse(LineReader& r, std::istringstream& ss, const char* what) {
  T v;
  if (!(ss >> v)) r.fail(std::string("expected ") + what);
  return v;
}
}  // namespace

ShellMesh read_gmsh(const std::filesystem::path& file) {
  LineReader r;
  r.path = file.string();
  r.in.open(file);
  if (!r.in) throw std::runtime_error("cannot open mesh file '" + file.string() + "'");
  std::string s = r.next();
  if (s != "$MeshFormat") r.fail("not a Gmsh ASCII file (no $MeshFormat)");
  std::istringstream fs(r.next());
  const double version = parse<double>(r, fs, "format version");
  const int filetype = parse<int>(r, fs, "file type");
  if (filetype != 0) r.fail("binary Gmsh files are not supported; export as ASCII");
  const bool v4 = version >= 4.0;
  if (!(std::abs(version - 2.2) < 1e-9 || std::abs(version - 4.1) < 1e-9))
    r.fail("Gmsh format " + std::to_string(version) + " is not supported; use 2.2 or 4.1");

  std::unordered_map<long long, int> node_index;
  ShellMesh m;
  std::vector<long long> tri_tags;
  while (r.in) {
    std::string section;
    while (std::getline(r.in, section)) {
      ++r.line;
      if (!section.empty() && section.back() == '\r') section.pop_back();
      if (!section.empty() && section[0] == '$') break;
    }
    if (!r.in) break;
    if (section == "$Nodes") {
      std::istringstream hs(r.next());
      if (v4) {
        const long long blocks = parse<long long>(r, hs, "number of entity blocks");
        for (long long b = 0; b < blocks; ++b) {
          std::istringstream bs(r.next());
          parse<int>(r, bs, "entity dim");
          parse<int>(r, bs, "entity tag");
          const int parametric = parse<int>(r, bs, "parametric flag");
          const long long n = parse<long long>(r, bs, "node count");
          std::vector<long long> tags(n);
          for (long long k = 0; k < n; ++k) {
            std::istringstream ts(r.next());
            tags[k] = parse<long long>(r, ts, "node tag");
          }
          for (long long k = 0; k < n; ++k) {
            std::istringstream cs(r.next());
            const double x = parse<double>(r, cs, "x"), y = parse<double>(r, cs, "y"), z = parse<double>(r, cs, "z");
            (void)parametric;
            node_index[tags[k]] = m.num_nodes();
            m.x.insert(m.x.end(), {x, y, z});
          }
        }
      } else {
        const long long n = parse<long long>(r, hs, "number of nodes");
        for (long long k = 0; k < n; ++k) {
          std::istringstream ns(r.next());
          const long long tag = parse<long long>(r, ns, "node tag");
          const double x = parse<double>(r, ns, "x"), y = parse<double>(r, ns, "y"), z = parse<double>(r, ns, "z");
          node_index[tag] = m.num_nodes();
          m.x.insert(m.x.end(), {x, y, z});
        }
      }
      if (r.next() != "$EndNodes") r.fail("expected $EndNodes");
    } else if (section == "$Elements") {
      std::istringstream hs(r.next());
      auto add_tri = [&](long long a, long long b, long long c) {
        for (long long t : {a, b, c}) {
          auto it = node_index.find(t);
          if (it == node_index.end()) r.fail("element refers to unknown node " + std::to_string(t));
          m.triangles.push_back(it->second);
        }
      };
      if (v4) {
        const long long blocks = parse<long long>(r, hs, "number of entity blocks");
        for (long long b = 0; b < blocks; ++b) {
          std::istringstream bs(r.next());
          parse<int>(r, bs, "entity dim");
          parse<int>(r, bs, "entity tag");
          const int type = parse<int>(r, bs, "element type");
          const long long n = parse<long long>(r, bs, "element count");
          for (long long k = 0; k < n; ++k) {
            std::istringstream es(r.next());
            parse<long long>(r, es, "element tag");
            if (type == 2) {
              const long long a = parse<long long>(r, es, "node"), bb = parse<long long>(r, es, "node"),
                              c = parse<long long>(r, es, "node");
              add_tri(a, bb, c);
            }
          }
        }
      } else {
        const long long n = parse<long long>(r, hs, "number of elements");
        for (long long k = 0; k < n; ++k) {
          std::istringstream es(r.next());
          parse<long long>(r, es, "element tag");
          const int type = parse<int>(r, es, "element type");
          const int ntags = parse<int>(r, es, "tag count");
          for (int t = 0; t < ntags; ++t) parse<long long>(r, es, "tag");
          if (type == 2) {
            const long long a = parse<long long>(r, es, "node"), b = parse<long long>(r, es, "node"),
                            c = parse<long long>(r, es, "node");
            add_tri(a, b, c);
          }
        }
      }
      if (r.next() != "$EndElements") r.fail("expected $EndElements");
    }
  }
  if (m.num_nodes() == 0) throw std::runtime_error(file.string() + ": no $Nodes section");
  if (m.num_elements() == 0) throw std::runtime_error(file.string() + ": no triangles (element type 2) found");
  // Drop nodes no triangle uses (points, geometry vertices) and renumber.
  std::vector<int> used(m.num_nodes(), -1);
  int count = 0;
  for (int& n : m.triangles) {
    if (used[n] < 0) used[n] = count++;
  }
  std::vector<double> x(3 * count);
  for (int i = 0; i < m.num_nodes(); ++i)
    if (used[i] >= 0)
      for (int d = 0; d < 3; ++d) x[3 * used[i] + d] = m.x[3 * i + d];
  for (int& n : m.triangles) n = used[n];
  m.x = std::move(x);
  finalize_mesh(m);
  return m;
}

void finalize_mesh(ShellMesh& m) {
  const int ne = m.num_elements();
  for (int e = 0; e < ne; ++e) {
    const int* t = &m.triangles[3 * e];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw std::runtime_error("triangle " + std::to_string(e) + " repeats a node");
    const Vec3 a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    if (sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a))) == 0.0)
      throw std::runtime_error("triangle " + std::to_string(e) + " has zero area");
  }
  // Edge -> (element, local edge) table.
  std::unordered_map<unsigned long long, std::array<int, 4>> edges;  // e0, k0, e1, k1
  edges.reserve(3 * ne);
  auto key = [](int a, int b) {
    if (a > b) std::swap(a, b);
    return (static_cast<unsigned long long>(a) << 32) | static_cast<unsigned>(b);
  };
  for (int e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles[3 * e + (k + 1) % 3], b = m.triangles[3 * e + (k + 2) % 3];
      auto [it, inserted] = edges.try_emplace(key(a, b), std::array<int, 4>{e, k, -1, -1});
      if (!inserted) {
        if (it->second[2] >= 0)
          throw std::runtime_error("edge " + std::to_string(a) + "-" + std::to_string(b) +
                                   " is shared by more than two triangles");
        it->second[2] = e;
        it->second[3] = k;
      }
    }
  m.neighbours.assign(3 * ne, -1);
  for (const auto& [k, v] : edges)
    if (v[2] >= 0) {
      m.neighbours[3 * v[0] + v[1]] = v[2];
      m.neighbours[3 * v[2] + v[3]] = v[0];
    }
  // Consistent orientation by breadth-first propagation: two neighbours are
  // consistent when they traverse their common edge in opposite directions.
  std::vector<char> done(ne, 0);
  auto traverses = [&](int e, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (m.triangles[3 * e + k] == a && m.triangles[3 * e + (k + 1) % 3] == b) return true;
    return false;
  };
  auto flip = [&](int e) {
    std::swap(m.triangles[3 * e + 1], m.triangles[3 * e + 2]);
    std::swap(m.neighbours[3 * e + 1], m.neighbours[3 * e + 2]);
  };
  for (int seed = 0; seed < ne; ++seed) {
    if (done[seed]) continue;
    done[seed] = 1;
    std::queue<int> q;
    q.push(seed);
    while (!q.empty()) {
      const int e = q.front();
      q.pop();
      for (int k = 0; k < 3; ++k) {
        const int f = m.neighbours[3 * e + k];
        if (f < 0 || done[f]) continue;
        const int a = m.triangles[3 * e + (k + 1) % 3], b = m.triangles[3 * e + (k + 2) % 3];
        if (traverses(f, a, b)) flip(f);
        done[f] = 1;
        q.push(f);
      }
    }
  }
  // Prefer normals pointing to +z on average (flat plies in the xy plane).
  double nz = 0;
  for (int e = 0; e < ne; ++e) {
    const int* t = &m.triangles[3 * e];
    const Vec3 a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    nz += sdk::cross(sdk::sub(b, a), sdk::sub(c, a))[2];
  }
  if (nz < 0)
    for (int e = 0; e < ne; ++e) flip(e);
}

std::vector<double> element_areas(const ShellMesh& m) {
  std::vector<double> area(m.num_elements());
  for (int e = 0; e < m.num_elements(); ++e) {
    const int* t = &m.triangles[3 * e];
    const Vec3 a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    area[e] = 0.5 * sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
  }
  return area;
}

std::vector<double> node_areas(const ShellMesh& m) {
  std::vector<double> area(m.num_nodes(), 0.0);
  const std::vector<double> A = element_areas(m);
  for (int e = 0; e < m.num_elements(); ++e)
    for (int k = 0; k < 3; ++k) area[m.triangles[3 * e + k]] += A[e] / 3.0;
  return area;
}

static double edge_length_extreme(const ShellMesh& m, bool want_max) {
  double best = want_max ? 0.0 : std::numeric_limits<double>::infinity();
  for (int e = 0; e < m.num_elements(); ++e)
    for (int k = 0; k < 3; ++k) {
      const double l = sdk::norm(sdk::sub(sdk::load3(m.x.data(), m.triangles[3 * e + k]),
                                          sdk::load3(m.x.data(), m.triangles[3 * e + (k + 1) % 3])));
      best = want_max ? std::max(best, l) : std::min(best, l);
    }
  return best;
}
double min_edge_length(const ShellMesh& m) { return edge_length_extreme(m, false); }
double max_edge_length(const ShellMesh& m) { return edge_length_extreme(m, true); }

}  // namespace ts
