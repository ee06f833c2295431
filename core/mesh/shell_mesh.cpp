#include "mesh/shell_mesh.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
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

LineReader open_mesh_file(const std::filesystem::path& file) {
  LineReader r;
  r.path = file.string();
  r.in.open(file);
  if (!r.in) throw std::runtime_error("cannot open mesh file '" + file.string() + "'");
  return r;
}

template <class T>
T parse(LineReader& r, std::istringstream& ss, const char* what) {
  T v;
  if (!(ss >> v)) r.fail(std::string("expected ") + what);
  return v;
}
}  // namespace

namespace {
void number_nodes_by_first_use(ShellMesh& m) {
  std::vector<int> used(m.num_nodes(), -1);
  int count = 0;
  for (int& n : m.triangles) {
    if (used[n] < 0) used[n] = count++;
  }
  std::vector<double> x(3 * count);
  std::vector<long long> tags(m.node_tags.empty() ? 0 : count);
  for (int i = 0; i < m.num_nodes(); ++i)
    if (used[i] >= 0) {
      for (int d = 0; d < 3; ++d) x[3 * used[i] + d] = m.x[3 * i + d];
      if (!tags.empty()) tags[used[i]] = m.node_tags[i];
    }
  for (int& n : m.triangles) n = used[n];
  m.x = std::move(x);
  m.node_tags = std::move(tags);
}
// Gmsh's name of an element type (its manual's numbering).
std::string gmsh_element_name(int type) {
  switch (type) {
    case 3: return "4-node quadrangles";
    case 4: return "4-node tetrahedra";
    case 5: return "8-node hexahedra";
    case 6: return "6-node prisms";
    case 7: return "5-node pyramids";
    case 9: return "6-node triangles";
    case 10: return "9-node quadrangles";
    case 11: return "10-node tetrahedra";
    case 16: return "8-node quadrangles";
    case 20: return "9-node triangles";
    case 21: return "10-node triangles";
    default: return "elements";
  }
}
}  // namespace

double box_span(const std::vector<double>& xyz) {
  if (xyz.size() < 3) return 0.0;
  double lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
  for (std::size_t k = 3; k + 2 < xyz.size(); k += 3)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], xyz[k + d]);
      hi[d] = std::max(hi[d], xyz[k + d]);
    }
  return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
}

ShellMesh read_gmsh_triangles(const std::filesystem::path& file, double scale) {
  LineReader r = open_mesh_file(file);
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
  std::vector<long long> tri_tags, node_tags;
  std::map<int, long long> refused;  // element type -> count
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
            node_tags.push_back(tags[k]);
            m.x.insert(m.x.end(), {x * scale, y * scale, z * scale});
          }
        }
      } else {
        const long long n = parse<long long>(r, hs, "number of nodes");
        for (long long k = 0; k < n; ++k) {
          std::istringstream ns(r.next());
          const long long tag = parse<long long>(r, ns, "node tag");
          const double x = parse<double>(r, ns, "x"), y = parse<double>(r, ns, "y"), z = parse<double>(r, ns, "z");
          node_index[tag] = m.num_nodes();
          node_tags.push_back(tag);
          m.x.insert(m.x.end(), {x * scale, y * scale, z * scale});
        }
      }
      if (r.next() != "$EndNodes") r.fail("expected $EndNodes");
    } else if (section == "$Elements") {
      std::istringstream hs(r.next());
      // Points and lines (a surface's border, its corners) are left out;
      // surface or volume elements other than 3-node triangles are
      // counted and refused below.
      auto other = [&](int type) {
        if (type != 1 && type != 8 && type != 15 && type != 26 && type != 27 && type != 28) ++refused[type];
      };
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
            const long long tag = parse<long long>(r, es, "element tag");
            if (type == 2) {
              const long long a = parse<long long>(r, es, "node"), bb = parse<long long>(r, es, "node"),
                              c = parse<long long>(r, es, "node");
              add_tri(a, bb, c);
              tri_tags.push_back(tag);
            } else {
              other(type);
            }
          }
        }
      } else {
        const long long n = parse<long long>(r, hs, "number of elements");
        for (long long k = 0; k < n; ++k) {
          std::istringstream es(r.next());
          const long long tag = parse<long long>(r, es, "element tag");
          const int type = parse<int>(r, es, "element type");
          const int ntags = parse<int>(r, es, "tag count");
          for (int t = 0; t < ntags; ++t) parse<long long>(r, es, "tag");
          if (type == 2) {
            const long long a = parse<long long>(r, es, "node"), b = parse<long long>(r, es, "node"),
                            c = parse<long long>(r, es, "node");
            add_tri(a, b, c);
            tri_tags.push_back(tag);
          } else {
            other(type);
          }
        }
      }
      if (r.next() != "$EndElements") r.fail("expected $EndElements");
    }
  }
  if (!refused.empty()) {
    std::string list;
    for (const auto& [type, count] : refused) {
      if (!list.empty()) list += ", ";
      list += std::to_string(count) + " " + gmsh_element_name(type) + " (element type " + std::to_string(type) + ")";
    }
    throw std::runtime_error(file.string() + ": " + list +
                             ": only 3-node triangles are taken (in Gmsh: no recombination into quadrangles, "
                             "element order 1, a surface mesh)");
  }
  if (m.num_nodes() == 0) throw std::runtime_error(file.string() + ": no $Nodes section");
  if (m.num_elements() == 0) throw std::runtime_error(file.string() + ": no triangles (element type 2) found");
  m.element_tags = std::move(tri_tags);
  m.node_tags = std::move(node_tags);
  return m;
}

namespace {
std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}
std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}
// The comma-separated fields of a line, trimmed (an empty last field where
// the line ends with a comma).
std::vector<std::string> fields(const std::string& s) {
  std::vector<std::string> out;
  std::size_t b = 0;
  for (;;) {
    const auto e = s.find(',', b);
    out.push_back(trim(s.substr(b, e == std::string::npos ? std::string::npos : e - b)));
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return out;
}
// A keyword line's name (upper case, without the '*') and its parameters
// (names upper case; values as written, without quotes).
struct Keyword {
  std::string name;
  std::map<std::string, std::string> params;
};
Keyword keyword(const std::string& line) {
  Keyword k;
  const std::vector<std::string> f = fields(line.substr(1));
  k.name = upper(f[0]);
  for (std::size_t i = 1; i < f.size(); ++i) {
    if (f[i].empty()) continue;
    const auto eq = f[i].find('=');
    std::string v = eq == std::string::npos ? std::string() : trim(f[i].substr(eq + 1));
    if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
    k.params[upper(trim(f[i].substr(0, eq)))] = v;
  }
  return k;
}
long long integer_field(const LineReader& r, const std::string& f, const char* what) {
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(f, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != f.size()) r.fail(std::string("expected ") + what + ", found '" + f + "'");
  return v;
}
double real_field(const LineReader& r, const std::string& f, const char* what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(f, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != f.size() || !std::isfinite(v)) r.fail(std::string("expected ") + what + ", found '" + f + "'");
  return v;
}
// Abaqus element types by their nodes on the surface: 3-node triangles
// (shells, membranes, surfaces, rigid facets, plane elements), the
// 4-node quadrilaterals and second-order surface elements that are
// refused with their counts, and lines, which are left out.
int abaqus_corner_count(const std::string& type) {
  for (const char* t : {"S3", "S3R", "S3RS", "STRI3", "DS3", "M3D3", "R3D3", "SFM3D3", "CPS3", "CPE3", "CAX3"})
    if (type == t) return 3;
  return 0;
}
bool abaqus_line(const std::string& type) {
  for (const char* t : {"B31", "B32", "B21", "B22", "T3D2", "T2D2", "R3D2", "RAX2", "R2D2", "SPRINGA", "CONN3D2", "DASHPOTA"})
    if (type == t) return true;
  return false;
}
}  // namespace

ShellMesh read_abaqus_triangles(const std::filesystem::path& file, double scale) {
  LineReader r = open_mesh_file(file);
  // Node numbers are those of a part: each part's nodes apart ("" for
  // those outside any *PART, such as an assembly's reference points).
  struct PartNodes {
    std::unordered_map<long long, int> index;
    std::vector<double> x;
    std::vector<long long> tags;
  };
  std::map<std::string, PartNodes> nodes;
  struct Pending {
    long long tag;
    std::vector<long long> nodes;
    int line;
  };
  std::map<std::string, std::vector<Pending>> tris;  // by part
  std::map<std::string, long long> refused;          // element type -> count
  std::string part;                                  // the *PART being read ("" outside one)
  enum class Block { None, Node, Element, Instance, Other } block = Block::None;
  std::string type;      // the *ELEMENT block's TYPE
  int corners = 0;       // its corners (3), or 0
  bool line_type = false;
  std::string pending;   // an element's data line continued on the next line
  int pending_line = 0;
  auto element_line = [&](const std::string& text, int line) {
    const std::vector<std::string> f = fields(text);
    const long long tag = integer_field(r, f[0], "element number");
    if (corners == 3) {
      std::vector<long long> nodes;
      for (std::size_t i = 1; i < f.size(); ++i)
        if (!f[i].empty()) nodes.push_back(integer_field(r, f[i], "node number"));
      if (nodes.size() != 3)
        r.fail("element " + std::to_string(tag) + " of type " + type + " has " + std::to_string(nodes.size()) +
               " nodes, expected 3");
      tris[part].push_back({tag, nodes, line});
    } else if (!line_type) {
      ++refused[type];
    }
  };
  std::string s;
  while (std::getline(r.in, s)) {
    ++r.line;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    const std::string t = trim(s);
    if (t.empty() || t.rfind("**", 0) == 0) continue;
    if (!pending.empty()) {  // the rest of an element's node list
      pending += t;
      if (t.back() == ',') continue;
      const int here = r.line;
      r.line = pending_line;
      element_line(pending, pending_line);
      r.line = here;
      pending.clear();
      continue;
    }
    if (t[0] == '*') {
      const Keyword k = keyword(t);
      block = Block::Other;
      if (k.name == "NODE") {
        if (auto it = k.params.find("SYSTEM"); it != k.params.end() && upper(it->second) != "R")
          r.fail("*NODE with SYSTEM=" + it->second + ": only rectangular coordinates (SYSTEM=R) are taken");
        if (k.params.count("INPUT")) r.fail("*NODE with INPUT=: nodes from another file are not read; write them here");
        block = Block::Node;
      } else if (k.name == "ELEMENT") {
        if (k.params.count("INPUT")) r.fail("*ELEMENT with INPUT=: elements from another file are not read; write them here");
        auto it = k.params.find("TYPE");
        if (it == k.params.end() || it->second.empty()) r.fail("*ELEMENT without TYPE=");
        type = upper(it->second);
        corners = abaqus_corner_count(type);
        line_type = abaqus_line(type);
        block = Block::Element;
      } else if (k.name == "INCLUDE") {
        r.fail("*INCLUDE: included files are not read; write the nodes and elements into this file");
      } else if (k.name == "NGEN" || k.name == "NFILL" || k.name == "NCOPY" || k.name == "NMAP" ||
                 k.name == "ELGEN" || k.name == "ELCOPY") {
        r.fail("*" + k.name + ": generated nodes and elements are not read; write every node and element out");
      } else if (k.name == "PART") {
        part = k.params.count("NAME") ? k.params.at("NAME") : std::string("(unnamed)");
      } else if (k.name == "END PART") {
        part.clear();
      } else if (k.name == "INSTANCE") {
        block = Block::Instance;
      }
      continue;
    }
    switch (block) {
      case Block::Node: {
        const std::vector<std::string> f = fields(t);
        if (f.size() < 3) r.fail("expected a node: number, x, y[, z]");
        const long long tag = integer_field(r, f[0], "node number");
        const double x = real_field(r, f[1], "x"), y = real_field(r, f[2], "y"),
                     z = f.size() > 3 && !f[3].empty() ? real_field(r, f[3], "z") : 0.0;
        PartNodes& pn = nodes[part];
        if (!pn.index.emplace(tag, static_cast<int>(pn.tags.size())).second)
          r.fail("node " + std::to_string(tag) + " given twice");
        pn.tags.push_back(tag);
        pn.x.insert(pn.x.end(), {x * scale, y * scale, z * scale});
        break;
      }
      case Block::Element:
        if (t.back() == ',') {
          pending = t;
          pending_line = r.line;
        } else {
          element_line(t, r.line);
        }
        break;
      case Block::Instance:
        r.fail("an *INSTANCE placed by a translation or rotation: write the mesh without them (the part's own "
               "coordinates are read)");
      default:
        break;  // data of keywords that carry no mesh (sets, materials, steps, ...)
    }
  }
  if (!pending.empty()) r.fail("an element's node list ends with a comma at the end of the file");
  if (!refused.empty()) {
    std::string list;
    for (const auto& [name, count] : refused) list += (list.empty() ? "" : ", ") + std::to_string(count) + " " + name;
    throw std::runtime_error(file.string() + ": " + list +
                             " elements: only 3-node triangles are taken (S3, S3R, M3D3, R3D3, SFM3D3, ...; mesh "
                             "with triangles, not quadrilaterals or second-order elements)");
  }
  if (tris.empty()) throw std::runtime_error(file.string() + ": no 3-node triangles (*ELEMENT, TYPE=S3, ...) found");
  if (tris.size() > 1) {
    std::string list;
    for (const auto& [p, t] : tris) list += (list.empty() ? "" : ", ") + (p.empty() ? "outside a *PART" : p);
    throw std::runtime_error(file.string() + ": triangles in " + std::to_string(tris.size()) + " parts (" + list +
                             "): give each ply and each tool a file of its own");
  }
  const std::string& used = tris.begin()->first;
  PartNodes& pn = nodes[used];
  ShellMesh m;
  std::vector<long long> tri_tags;
  for (const Pending& e : tris.begin()->second) {
    for (long long n : e.nodes) {
      auto it = pn.index.find(n);
      if (it == pn.index.end())
        throw std::runtime_error(file.string() + ":" + std::to_string(e.line) + ": element " + std::to_string(e.tag) +
                                 " refers to unknown node " + std::to_string(n));
      m.triangles.push_back(it->second);
    }
    tri_tags.push_back(e.tag);
  }
  m.x = std::move(pn.x);
  m.element_tags = std::move(tri_tags);
  m.node_tags = std::move(pn.tags);
  return m;
}

namespace {
// The fields of an LS-DYNA keyword data card: comma-separated (free
// format) where the card has a comma, else in columns of `widths` (the
// last width repeated); blank fields are empty strings.
std::vector<std::string> dyna_fields(const std::string& card, const std::vector<int>& widths, std::size_t count) {
  if (card.find(',') != std::string::npos) {
    std::vector<std::string> f = fields(card);
    f.resize(std::max(f.size(), count));
    return f;
  }
  std::vector<std::string> f;
  std::size_t at = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t w = static_cast<std::size_t>(widths[std::min(k, widths.size() - 1)]);
    f.push_back(at < card.size() ? trim(card.substr(at, w)) : std::string());
    at += w;
  }
  return f;
}
}  // namespace

namespace {
// Cards per element of *ELEMENT_SHELL and of its options whose extra cards
// carry no mesh: THICKNESS, BETA and MCID (one card of nodal thicknesses
// and an angle or a coordinate system), OFFSET (one card); 0 for another
// keyword.
int shell_cards(const std::string& k) {
  if (k == "ELEMENT_SHELL") return 1;
  if (k.rfind("ELEMENT_SHELL_", 0) != 0) return 0;
  bool second = false, offset = false;
  std::stringstream in(k.substr(14));
  for (std::string t; std::getline(in, t, '_');) {
    if (t == "THICKNESS" || t == "BETA" || t == "MCID")
      second = true;
    else if (t == "OFFSET")
      offset = true;
    else
      return 0;
  }
  return 1 + (second ? 1 : 0) + (offset ? 1 : 0);
}
}  // namespace

ShellMesh read_lsdyna_triangles(const std::filesystem::path& file, double scale) {
  LineReader r = open_mesh_file(file);
  std::unordered_map<long long, int> node_index;
  std::vector<double> x;
  std::vector<long long> node_tags;
  struct Pending {
    long long tag, part;
    std::array<long long, 3> nodes;
    int line;
  };
  std::vector<Pending> tris;
  std::map<long long, long long> quads;      // part -> quadrilaterals
  std::map<std::string, long long> refused;  // other element keywords -> cards
  enum class Block { None, Node, Shell, Other, Refused } block = Block::None;
  std::string keyword_name;
  // Column widths of integers and reals: 8 and 16 (standard), 20 and 20
  // (*KEYWORD LONG=Y, or a keyword ending in +), 10 and 16 (a keyword
  // ending in %).
  bool long_all = false;
  int int_w = 8, real_w = 16;
  // The shells' cards per element (shell_cards) and the cards of this block so far.
  int cards = 1;
  long long card = 0;
  auto element_complete = [&]() {
    if (block == Block::Shell && card % cards != 0)
      r.fail("*" + keyword_name + ": the last element has " + std::to_string(card % cards) + " of its " +
             std::to_string(cards) + " cards");
  };
  std::string s;
  while (std::getline(r.in, s)) {
    ++r.line;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    if (s.empty() || s[0] == '$') continue;
    if (s[0] == '*') {
      element_complete();
      std::string k = upper(trim(s.substr(1)));
      int_w = long_all ? 20 : 8;
      real_w = long_all ? 20 : 16;
      if (!k.empty() && k.back() == '+') {  // "*NODE +" or "*NODE+"
        int_w = real_w = 20;
        k = trim(k.substr(0, k.size() - 1));
      } else if (!k.empty() && k.back() == '%') {
        int_w = 10;
        real_w = 16;
        k = trim(k.substr(0, k.size() - 1));
      } else if (!k.empty() && k.back() == '-') {
        int_w = 8;
        real_w = 16;
        k = trim(k.substr(0, k.size() - 1));
      }
      const auto space = k.find_first_of(" \t,");
      const std::string rest = space == std::string::npos ? std::string() : k.substr(space);
      k = k.substr(0, space);
      keyword_name = k;
      if (k == "KEYWORD") {
        long_all = rest.find("LONG=Y") != std::string::npos || rest.find("LONG=S") != std::string::npos;
        block = Block::None;
      } else if (k == "END") {
        break;
      } else if (k == "NODE") {
        block = Block::Node;
      } else if (shell_cards(k) > 0) {
        block = Block::Shell;
        cards = shell_cards(k);
        card = 0;
      } else if (k.rfind("INCLUDE", 0) == 0) {
        r.fail("*" + k + ": included files are not read; write the nodes and elements into this file");
      } else if (k.rfind("ELEMENT_", 0) == 0) {
        block = Block::Refused;
      } else {
        block = Block::Other;
      }
      continue;
    }
    switch (block) {
      case Block::Node: {
        const std::vector<std::string> f = dyna_fields(s, {int_w, real_w}, 4);
        const long long tag = integer_field(r, f[0], "node number");
        const double px = f[1].empty() ? 0.0 : real_field(r, f[1], "x");
        const double py = f[2].empty() ? 0.0 : real_field(r, f[2], "y");
        const double pz = f[3].empty() ? 0.0 : real_field(r, f[3], "z");
        if (!node_index.emplace(tag, static_cast<int>(node_tags.size())).second)
          r.fail("node " + std::to_string(tag) + " given twice");
        node_tags.push_back(tag);
        x.insert(x.end(), {px * scale, py * scale, pz * scale});
        break;
      }
      case Block::Shell: {
        if (card++ % cards != 0) break;  // thicknesses, an angle, an offset: the job gives its own
        const std::vector<std::string> f = dyna_fields(s, {int_w}, 6);
        const long long tag = integer_field(r, f[0], "element number");
        const long long part = integer_field(r, f[1], "part number");
        std::array<long long, 4> n{};
        for (int k = 0; k < 4; ++k) n[k] = f[2 + k].empty() ? 0 : integer_field(r, f[2 + k], "node number");
        if (n[0] == 0 || n[1] == 0 || n[2] == 0) r.fail("element " + std::to_string(tag) + " has fewer than 3 nodes");
        if (n[3] != 0 && n[3] != n[2]) {
          ++quads[part];
          break;
        }
        tris.push_back({tag, part, {n[0], n[1], n[2]}, r.line});
        break;
      }
      case Block::Refused:
        ++refused[keyword_name];
        break;
      default:
        break;  // cards of keywords that carry no mesh (parts, sections, materials, controls, ...)
    }
  }
  element_complete();
  if (!refused.empty() || !quads.empty()) {
    std::string list;
    long long q = 0;
    for (const auto& [part, count] : quads) q += count;
    if (q > 0) list = std::to_string(q) + " 4-node shells (*ELEMENT_SHELL with N4 other than N3)";
    for (const auto& [name, count] : refused)
      list += (list.empty() ? "" : ", ") + std::to_string(count) + " cards of *" + name;
    throw std::runtime_error(file.string() + ": " + list +
                             ": only 3-node shells are taken (*ELEMENT_SHELL with N4 = N3 or blank; mesh with "
                             "triangles)");
  }
  if (tris.empty()) throw std::runtime_error(file.string() + ": no 3-node shells (*ELEMENT_SHELL, N4 = N3) found");
  std::map<long long, long long> parts;
  for (const Pending& e : tris) ++parts[e.part];
  if (parts.size() > 1) {
    std::string list;
    for (const auto& [part, count] : parts) list += (list.empty() ? "" : ", ") + std::to_string(part);
    throw std::runtime_error(file.string() + ": shells of " + std::to_string(parts.size()) + " parts (PID " + list +
                             "): give each ply and each tool a file of its own");
  }
  ShellMesh m;
  for (const Pending& e : tris) {
    for (long long n : e.nodes) {
      auto it = node_index.find(n);
      if (it == node_index.end())
        throw std::runtime_error(file.string() + ":" + std::to_string(e.line) + ": element " + std::to_string(e.tag) +
                                 " refers to unknown node " + std::to_string(n));
      m.triangles.push_back(it->second);
    }
    m.element_tags.push_back(e.tag);
  }
  m.x = std::move(x);
  m.node_tags = std::move(node_tags);
  return m;
}

bool is_lsdyna_file(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".k" || ext == ".key" || ext == ".dyn";
}

bool is_abaqus_file(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".inp";
}

ShellMesh read_mesh_triangles(const std::filesystem::path& file, double scale) {
  if (is_abaqus_file(file)) return read_abaqus_triangles(file, scale);
  if (is_lsdyna_file(file)) return read_lsdyna_triangles(file, scale);
  return read_gmsh_triangles(file, scale);
}

namespace {
// A file's triangles as a ply's mesh: the nodes no triangle uses (points,
// geometry vertices, reference points) dropped, the others in the order in
// which the triangles first use them; oriented, with neighbours; with
// `reorder`, in locality_order.
ShellMesh ply_mesh(ShellMesh m, bool reorder) {
  number_nodes_by_first_use(m);
  finalize_mesh(m);
  if (reorder) {
    reorder_elements(m, locality_order(m));
    number_nodes_by_first_use(m);
  }
  return m;
}
}  // namespace

ShellMesh read_mesh(const std::filesystem::path& file, bool reorder, double scale) {
  return ply_mesh(read_mesh_triangles(file, scale), reorder);
}

ShellMesh read_gmsh(const std::filesystem::path& file, bool reorder, double scale) {
  return ply_mesh(read_gmsh_triangles(file, scale), reorder);
}

void finalize_mesh(ShellMesh& m) {
  const int ne = m.num_elements();
  // Triangles and nodes by their tags in the file where they have some.
  auto triangle = [&](int e) {
    return "triangle " + std::to_string(e) +
           (m.element_tags.empty() ? std::string() : " (element " + std::to_string(m.element_tags[e]) + ")");
  };
  auto node = [&](int n) { return std::to_string(m.node_tags.empty() ? n : m.node_tags[n]); };
  for (int e = 0; e < ne; ++e) {
    const int* t = &m.triangles[3 * e];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) throw std::runtime_error(triangle(e) + " repeats a node");
    const Vec3 a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    if (sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a))) == 0.0)
      throw std::runtime_error(triangle(e) + " has zero area");
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
          throw std::runtime_error("edge " + node(a) + "-" + node(b) + " is shared by more than two triangles");
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

namespace {
// Breadth-first levels of the elements reachable from `start` within one
// component: returns the last level, writes the number of levels.
std::vector<int> last_level(const ShellMesh& m, int start, std::vector<int>& mark, int stamp, int& depth) {
  std::vector<int> level{start}, next;
  mark[start] = stamp;
  depth = 1;
  for (;;) {
    next.clear();
    for (const int e : level)
      for (int k = 0; k < 3; ++k)
        if (const int f = m.neighbours[3 * e + k]; f >= 0 && mark[f] != stamp) {
          mark[f] = stamp;
          next.push_back(f);
        }
    if (next.empty()) return level;
    level.swap(next);
    ++depth;
  }
}
}  // namespace

std::vector<int> locality_order(const ShellMesh& m) {
  const int ne = m.num_elements();
  std::vector<int> degree(ne, 0);
  for (int e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) degree[e] += m.neighbours[3 * e + k] >= 0;
  auto before = [&](int a, int b) { return degree[a] != degree[b] ? degree[a] < degree[b] : a < b; };
  std::vector<int> order, mark(ne, -1), placed(ne, 0);
  order.reserve(ne);
  int stamp = 0;
  for (int seed = 0; seed < ne; ++seed) {
    if (placed[seed]) continue;
    // A pseudo-peripheral start (George and Liu): from the component's first
    // element, the smallest-degree element of the last breadth-first level,
    // while that deepens the levels.
    int start = seed, depth = 0;
    std::vector<int> last = last_level(m, start, mark, stamp++, depth);
    for (int it = 0; it < 8; ++it) {
      const int cand = *std::min_element(last.begin(), last.end(), before);
      int d = 0;
      std::vector<int> l = last_level(m, cand, mark, stamp++, d);
      if (d <= depth) break;
      start = cand;
      depth = d;
      last.swap(l);
    }
    // Cuthill-McKee from there: neighbours by increasing degree.
    std::size_t head = order.size();
    order.push_back(start);
    placed[start] = 1;
    int nb[3];
    while (head < order.size()) {
      const int e = order[head++];
      int n = 0;
      for (int k = 0; k < 3; ++k)
        if (const int f = m.neighbours[3 * e + k]; f >= 0 && !placed[f]) nb[n++] = f;
      for (int i = 1; i < n; ++i)  // at most three: by insertion
        for (int j = i; j > 0 && before(nb[j], nb[j - 1]); --j) std::swap(nb[j], nb[j - 1]);
      for (int i = 0; i < n; ++i) {
        placed[nb[i]] = 1;
        order.push_back(nb[i]);
      }
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

void reorder_elements(ShellMesh& m, const std::vector<int>& order) {
  const int ne = m.num_elements();
  std::vector<int> new_index(ne);
  for (int i = 0; i < ne; ++i) new_index[order[i]] = i;
  std::vector<int> tri(3 * static_cast<std::size_t>(ne)), nbr(3 * static_cast<std::size_t>(ne));
  for (int i = 0; i < ne; ++i)
    for (int k = 0; k < 3; ++k) {
      tri[3 * i + k] = m.triangles[3 * order[i] + k];
      const int f = m.neighbours[3 * order[i] + k];
      nbr[3 * i + k] = f < 0 ? -1 : new_index[f];
    }
  m.triangles.swap(tri);
  m.neighbours.swap(nbr);
  if (!m.element_tags.empty()) {
    std::vector<long long> tags(ne);
    for (int i = 0; i < ne; ++i) tags[i] = m.element_tags[order[i]];
    m.element_tags.swap(tags);
  }
}

std::string element_label(const ShellMesh& m, int e) {
  std::string s = "element " + std::to_string(e);
  if (static_cast<std::size_t>(e) < m.element_tags.size())
    s += " (element " + std::to_string(m.element_tags[e]) + " of the mesh file)";
  return s;
}

std::string node_label(const ShellMesh& m, int n) {
  std::string s = "node " + std::to_string(n);
  if (static_cast<std::size_t>(n) < m.node_tags.size()) s += " (node " + std::to_string(m.node_tags[n]) + " of the mesh file)";
  return s;
}

int element_bandwidth(const ShellMesh& m) {
  int w = 0;
  for (int e = 0; e < m.num_elements(); ++e)
    for (int k = 0; k < 3; ++k)
      if (const int f = m.neighbours[3 * e + k]; f >= 0) w = std::max(w, std::abs(f - e));
  return w;
}

long long node_tag(const ShellMesh& m, int n) { return m.node_tags.empty() ? n + 1LL : m.node_tags[n]; }
long long element_tag(const ShellMesh& m, int e) { return m.element_tags.empty() ? e + 1LL : m.element_tags[e]; }

std::vector<double> element_areas(const ShellMesh& m) {
  std::vector<double> area(m.num_elements());
  for (int e = 0; e < m.num_elements(); ++e) {
    const int* t = &m.triangles[3 * e];
    const Vec3 a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    area[e] = 0.5 * sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
  }
  return area;
}

void constant_volume_thickness(const ShellMesh& m, const std::vector<double>& area0, const double* x, double h0,
                               double* thickness) {
  for (int e = 0; e < m.num_elements(); ++e) {
    const int* t = &m.triangles[3 * e];
    const Vec3 a = sdk::load3(x, t[0]), b = sdk::load3(x, t[1]), c = sdk::load3(x, t[2]);
    const double area = 0.5 * sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
    thickness[e] = area > 0 ? h0 * (area0[e] / area) : std::numeric_limits<double>::quiet_NaN();
  }
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
