#include "io/blank.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "io/export.hpp"

namespace ts {

namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }
Vec at(const std::vector<double>& x, std::size_t i) { return {x[3 * i], x[3 * i + 1], x[3 * i + 2]}; }

// Text as a message quotes it: control characters escaped (\r, \n, \t,
// \xNN), so that a message stays on one line.
std::string shown(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\r') out += "\\r";
    else if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (u < 0x20 || u == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The area of a plane polygon (its points in order).
double polygon_area(const std::vector<Vec>& p) {
  Vec s{0, 0, 0};
  for (std::size_t k = 1; k + 1 < p.size(); ++k) {
    const Vec c = cross(sub(p[k], p[0]), sub(p[k + 1], p[0]));
    for (int d = 0; d < 3; ++d) s[d] += c[d];
  }
  return 0.5 * norm(s);
}

double cross2(const std::array<double, 2>& o, const std::array<double, 2>& a, const std::array<double, 2>& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Whether the closed segments ab and cd share a point.
bool segments_meet(const std::array<double, 2>& a, const std::array<double, 2>& b, const std::array<double, 2>& c,
                   const std::array<double, 2>& d) {
  const double d1 = cross2(c, d, a), d2 = cross2(c, d, b), d3 = cross2(a, b, c), d4 = cross2(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto on = [](const std::array<double, 2>& p, const std::array<double, 2>& q, const std::array<double, 2>& r) {
    return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  return (d1 == 0 && on(c, d, a)) || (d2 == 0 && on(c, d, b)) || (d3 == 0 && on(a, b, c)) || (d4 == 0 && on(a, b, d));
}

using Ring = std::vector<std::array<double, 2>>;

// The largest coordinate a trim takes (m): beyond it the distances lose
// their digits, and no press is that large.
constexpr double kFar = 1e6;

// A polygon's vertices from a CSV file: a row "x,y" per vertex; a first
// row that is not two numbers is a header; empty rows and rows starting
// with '#' are skipped.
Ring read_csv_ring(const std::string& file, const std::string& what) {
  std::ifstream in(file);
  if (!in) throw ExportInputError(what + "cannot read '" + shown(file) + "'");
  Ring p;
  std::string line;
  int row = 0;
  while (std::getline(in, line)) {
    ++row;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    const auto comma = line.find(',');
    std::array<double, 2> v{};
    bool ok = comma != std::string::npos && line.find(',', comma + 1) == std::string::npos;
    for (int c = 0; c < 2 && ok; ++c) {
      std::string item = c == 0 ? line.substr(0, comma) : line.substr(comma + 1);
      const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
      item = b == std::string::npos ? std::string() : item.substr(b, e - b + 1);
      char* end = nullptr;
      v[static_cast<std::size_t>(c)] = std::strtod(item.c_str(), &end);
      ok = !item.empty() && end == item.c_str() + item.size() && std::isfinite(v[static_cast<std::size_t>(c)]);
    }
    if (!ok) {
      if (p.empty() && row == 1) continue;  // a header
      throw ExportInputError(what + "'" + shown(file) + "' row " + std::to_string(row) +
                             ": expected x,y (m), found '" + shown(line) + "'");
    }
    p.push_back(v);
  }
  return p;
}

// The closed polylines of a DXF file's ENTITIES section (LWPOLYLINE, and
// POLYLINE with its VERTEX entities), in x and y, their arcs (bulges)
// drawn as sides of at most 2 degrees of arc, x mirrored for a polyline
// whose extrusion points along -z; open polylines and other entities are
// left out. `scale` (m per drawing unit): the given one, or
// from the header's $INSUNITS.
std::vector<Ring> read_dxf_rings(const std::string& file, const std::string& what, double& scale, bool scale_given) {
  std::ifstream in(file);
  if (!in) throw ExportInputError(what + "cannot read '" + shown(file) + "'");
  struct Vertex {
    double x = 0, y = 0, bulge = 0;
  };
  std::vector<Ring> rings;
  std::vector<Vertex> vs;
  bool closed = false, in_polyline = false;
  double extrusion_z = 1;  // a polyline drawn with its extrusion along -z has its x mirrored (the OCS)
  int open = 0, units = -1;
  std::string section, entity, code, value, variable;
  auto finish = [&]() {  // the polyline read so far, as a ring
    if (vs.empty()) return;
    if (!closed) {
      ++open;
    } else {
      Ring r;
      for (std::size_t k = 0; k < vs.size(); ++k) {
        const Vertex& a = vs[k];
        const Vertex& b = vs[(k + 1) % vs.size()];
        r.push_back({a.x, a.y});
        if (a.bulge == 0 || !std::isfinite(a.bulge)) continue;
        const double theta = 4 * std::atan(a.bulge), cx = b.x - a.x, cy = b.y - a.y, c = std::hypot(cx, cy);
        if (!(c > 0)) continue;
        const double h = c / 2 / std::tan(theta / 2);  // from the chord's middle to the centre, on its left
        const double ox = (a.x + b.x) / 2 - cy / c * h, oy = (a.y + b.y) / 2 + cx / c * h;
        const double radius = std::hypot(a.x - ox, a.y - oy), a0 = std::atan2(a.y - oy, a.x - ox);
        const int n = std::max(1, static_cast<int>(std::ceil(std::abs(theta) / (2 * M_PI / 180))));
        for (int i = 1; i < n; ++i)
          r.push_back({ox + radius * std::cos(a0 + theta * i / n), oy + radius * std::sin(a0 + theta * i / n)});
      }
      if (extrusion_z < 0)
        for (auto& v : r) v[0] = -v[0];
      rings.push_back(std::move(r));
    }
    vs.clear();
    closed = false;
    extrusion_z = 1;
  };
  int line = 0;
  auto trimmed = [](std::string t) {
    if (!t.empty() && t.back() == '\r') t.pop_back();
    const auto b = t.find_first_not_of(" \t"), e = t.find_last_not_of(" \t");
    return b == std::string::npos ? std::string() : t.substr(b, e - b + 1);
  };
  auto number = [&](const std::string& t) {
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v))
      throw ExportInputError(what + "'" + shown(file) + "' line " + std::to_string(line) +
                             ": expected a number, found '" + shown(t) + "'");
    return v;
  };
  auto integer = [&](const std::string& t) {  // a flag or a code's number
    const double v = number(t);
    if (!(std::abs(v) <= 1e9) || v != std::floor(v))
      throw ExportInputError(what + "'" + shown(file) + "' line " + std::to_string(line) +
                             ": expected an integer, found '" + shown(t) + "'");
    return static_cast<int>(v);
  };
  while (std::getline(in, code) && std::getline(in, value)) {
    line += 2;
    code = trimmed(code);
    value = trimmed(value);
    if (code == "0") {
      if (entity == "LWPOLYLINE" || (entity == "SEQEND" && in_polyline) || value == "ENDSEC") finish();
      if (entity == "SEQEND") in_polyline = false;
      if (value == "SECTION") section.clear();
      entity = value;
      if (entity == "POLYLINE" && section == "ENTITIES") {
        finish();
        in_polyline = true;
      }
      if (entity == "VERTEX" && in_polyline) vs.push_back({});
      if (entity == "LWPOLYLINE" && section == "ENTITIES") {
        vs.clear();
        closed = false;
      }
      continue;
    }
    if (code == "2" && entity == "SECTION" && section.empty()) {  // the pair after "0 SECTION" names it
      section = value;
      continue;
    }
    if (section == "HEADER") {
      if (code == "9") variable = value;
      else if (code == "70" && variable == "$INSUNITS") units = integer(value);
      continue;
    }
    if (section != "ENTITIES") continue;
    const bool lw = entity == "LWPOLYLINE", vertex = entity == "VERTEX" && in_polyline;
    if ((lw || (entity == "POLYLINE" && in_polyline)) && code == "70")
      closed = (integer(value) & 1) != 0;
    if ((lw || (entity == "POLYLINE" && in_polyline)) && code == "230") extrusion_z = number(value);
    if (lw && code == "10") vs.push_back({number(value), 0, 0});
    if ((lw && !vs.empty()) || (vertex && !vs.empty())) {
      if (vertex && code == "10") vs.back().x = number(value);
      if (code == "20") vs.back().y = number(value);
      if (code == "42") vs.back().bulge = number(value);
    }
  }
  finish();
  if (!scale_given) {
    switch (units) {
      case 1: scale = 0.0254; break;
      case 2: scale = 0.3048; break;
      case 4: scale = 0.001; break;
      case 5: scale = 0.01; break;
      case 6: scale = 1.0; break;
      default:
        throw ExportInputError(what + "'" + shown(file) + "' does not give its units (" +
                               (units < 0 ? std::string("no $INSUNITS") : "$INSUNITS " + std::to_string(units)) +
                               "): give them after a comma, polygon:" + shown(file) + ",0.001 for millimetres");
    }
  }
  if (rings.empty())
    throw ExportInputError(what + "'" + shown(file) + "' holds no closed polyline" +
                           (open ? " (its " + std::to_string(open) + " open one" + (open > 1 ? "s are" : " is") +
                                       " not a trim line: close it in CAD)"
                                 : std::string(" (lines and arcs are not joined: join them into a polyline in CAD)")));
  return rings;
}

// The rings of a polygon trim: "FILE" or "FILE,SCALE" (m per unit of the
// file; a CSV file's default 1, a DXF file's from its $INSUNITS), each
// ring's first vertex repeated at its end dropped, and checked: at least
// 3 vertices, none twice in a row, an area, no side crossing or touching
// another (of its ring or another ring).
std::vector<Ring> read_polygon(const std::string& spec, const std::string& what) {
  std::string file = spec;
  double scale = 1.0;
  bool scale_given = false;
  if (const auto comma = spec.rfind(','); comma != std::string::npos) {
    const std::string tail = spec.substr(comma + 1);
    char* end = nullptr;
    const double v = std::strtod(tail.c_str(), &end);
    if (!tail.empty() && end == tail.c_str() + tail.size()) {
      if (!(std::isfinite(v) && v > 0))
        throw ExportInputError(what + "the scale must be a number above 0, found '" + shown(tail) + "'");
      file = spec.substr(0, comma);
      scale = v;
      scale_given = true;
    }
  }
  std::string ext = std::filesystem::path(file).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool dxf = ext == ".dxf";
  std::vector<Ring> rings =
      dxf ? read_dxf_rings(file, what, scale, scale_given) : std::vector<Ring>{read_csv_ring(file, what)};
  const std::string at = what + "'" + shown(file) + "'";
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring& p = rings[r];
    for (std::size_t k = 0; k < p.size(); ++k) {
      p[k][0] *= scale;
      p[k][1] *= scale;
      if (!(std::abs(p[k][0]) <= kFar && std::abs(p[k][1]) <= kFar))
        throw ExportInputError(at + (dxf ? ": polyline " + std::to_string(r + 1) : std::string(":")) + " vertex " +
                               std::to_string(k + 1) + " lies beyond 1e6 m: not a trim in a press (the scale?)");
    }
    const std::string which = dxf ? ": polyline " + std::to_string(r + 1) : std::string();
    if (p.size() > 1 && p.front() == p.back()) p.pop_back();
    if (p.size() < 3)
      throw ExportInputError(at + which + (dxf ? " has " : " holds ") + std::to_string(p.size()) +
                             " vertices: a polygon needs at least 3");
    const std::size_t n = p.size();
    double area = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (p[k] == p[(k + 1) % n])
        throw ExportInputError(at + (dxf ? which : std::string(":")) + " vertex " + std::to_string(k + 1) +
                               " is there twice in a row");
      area += cross2({0, 0}, p[k], p[(k + 1) % n]) / 2;
    }
    if (!(std::abs(area) > 0))
      throw ExportInputError(at + (dxf ? which : std::string(":")) + " the polygon has no area");
  }
  // Sides that cross or touch: each side against those whose extent in x
  // overlaps its own (sorted by their smallest x).
  struct Side {
    std::size_t ring, index;
    double x0, x1, y0, y1;
  };
  std::vector<Side> sides;
  for (std::size_t r = 0; r < rings.size(); ++r)
    for (std::size_t i = 0; i < rings[r].size(); ++i) {
      const auto& a = rings[r][i];
      const auto& b = rings[r][(i + 1) % rings[r].size()];
      sides.push_back({r, i, std::min(a[0], b[0]), std::max(a[0], b[0]), std::min(a[1], b[1]), std::max(a[1], b[1])});
    }
  std::sort(sides.begin(), sides.end(), [](const Side& a, const Side& b) {
    return a.x0 != b.x0 ? a.x0 < b.x0 : (a.ring != b.ring ? a.ring < b.ring : a.index < b.index);
  });
  std::optional<std::array<std::size_t, 4>> first;
  for (std::size_t u = 0; u < sides.size(); ++u)
    for (std::size_t w = u + 1; w < sides.size() && sides[w].x0 <= sides[u].x1; ++w) {
      const Side& a = sides[u].ring < sides[w].ring || (sides[u].ring == sides[w].ring && sides[u].index < sides[w].index)
                          ? sides[u]
                          : sides[w];
      const Side& b = &a == &sides[u] ? sides[w] : sides[u];
      if (a.y1 < b.y0 || b.y1 < a.y0) continue;
      const Ring& ra = rings[a.ring];
      const Ring& rb = rings[b.ring];
      if (a.ring == b.ring && (b.index == a.index + 1 || (a.index == 0 && b.index == ra.size() - 1)))
        continue;  // neighbours
      if (!segments_meet(ra[a.index], ra[(a.index + 1) % ra.size()], rb[b.index], rb[(b.index + 1) % rb.size()]))
        continue;
      const std::array<std::size_t, 4> pair{a.ring, a.index, b.ring, b.index};
      if (!first || pair < *first) first = pair;  // the first pair in the file's order is named
    }
  if (first) {
    const auto [ra, ia, rb, ib] = *first;
    if (ra == rb)
      throw ExportInputError(at + (dxf ? ": polyline " + std::to_string(ra + 1) : std::string(":")) +
                             " the polygon crosses itself (sides " + std::to_string(ia + 1) + " and " +
                             std::to_string(ib + 1) + ")");
    throw ExportInputError(at + ": polylines " + std::to_string(ra + 1) + " and " + std::to_string(rb + 1) +
                           " cross or touch");
  }
  return rings;
}

// The signed distance of (x, y) to a polygon of one or more rings:
// negative inside (an odd number of sides crossed on the way out).
double polygon_level(const std::vector<Ring>& rings, double x, double y) {
  double d2 = std::numeric_limits<double>::infinity();
  bool inside = false;
  for (const Ring& p : rings) {
    const std::size_t n = p.size();
    for (std::size_t k = 0, j = n - 1; k < n; j = k++) {
      const auto& a = p[j];
      const auto& b = p[k];
      if ((a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])) inside = !inside;
      const double ex = b[0] - a[0], ey = b[1] - a[1];
      const double t = std::clamp(((x - a[0]) * ex + (y - a[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
      const double dx = x - a[0] - t * ex, dy = y - a[1] - t * ey;
      d2 = std::min(d2, dx * dx + dy * dy);
    }
  }
  return inside ? -std::sqrt(d2) : std::sqrt(d2);
}

}  // namespace

TrimSurface parse_trim(const std::string& text) {
  const std::string what = "--trim '" + shown(text) + "': ";
  const auto colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  TrimSurface t;
  t.text = text;
  std::size_t count = 0;
  std::string takes;
  if (kind == "plane") {
    t.kind = TrimSurface::Kind::Plane;
    count = 6;
    takes = "a plane takes 6 numbers (a point and the normal, which points into the part; m)";
  } else if (kind == "cylinder") {
    t.kind = TrimSurface::Kind::Cylinder;
    count = 7;
    takes = "a cylinder takes 7 numbers (a point on its axis, the axis's direction and the radius; m)";
  } else if (kind == "sphere") {
    t.kind = TrimSurface::Kind::Sphere;
    count = 4;
    takes = "a sphere takes 4 numbers (the centre and the radius; m)";
  } else if (kind == "polygon" && colon != std::string::npos) {
    t.kind = TrimSurface::Kind::Polygon;
    t.rings = read_polygon(text.substr(colon + 1), what);
    return t;
  } else {
    throw ExportInputError(what + "expected plane:X,Y,Z,NX,NY,NZ, cylinder:X,Y,Z,DX,DY,DZ,R, sphere:X,Y,Z,R (m) or "
                                  "polygon:FILE");
  }
  std::vector<double> v;
  if (colon != std::string::npos) {
    std::size_t from = colon + 1;
    while (true) {
      const auto comma = text.find(',', from);
      const std::string item = text.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
      char* end = nullptr;
      const double d = std::strtod(item.c_str(), &end);
      if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(d))
        throw ExportInputError(what + "'" + shown(item) + "' is not a number");
      v.push_back(d);
      if (comma == std::string::npos) break;
      from = comma + 1;
    }
  }
  if (v.size() != count) throw ExportInputError(what + takes + ", found " + std::to_string(v.size()));
  for (const double d : v)
    if (std::abs(d) > kFar) throw ExportInputError(what + g(d) + " is beyond 1e6 (m): not a trim in a press");
  t.point = {v[0], v[1], v[2]};
  if (t.kind != TrimSurface::Kind::Sphere) {
    const Vec d{v[3], v[4], v[5]};
    const double l = norm(d);
    if (!(l > 0))
      throw ExportInputError(what + (t.kind == TrimSurface::Kind::Plane ? "the normal" : "the axis's direction") +
                             " is zero");
    t.direction = {d[0] / l, d[1] / l, d[2] / l};
  }
  if (t.kind != TrimSurface::Kind::Plane) {
    t.radius = v.back();
    if (!(t.radius > 0)) throw ExportInputError(what + "the radius must be above 0, found " + g(t.radius));
  }
  return t;
}

double trim_level(const std::vector<TrimSurface>& trims, const double* x) {
  double level = -std::numeric_limits<double>::infinity();
  for (const TrimSurface& t : trims) {
    const Vec r{x[0] - t.point[0], x[1] - t.point[1], x[2] - t.point[2]};
    double f = 0;
    switch (t.kind) {
      case TrimSurface::Kind::Plane:
        f = -dot(r, t.direction);
        break;
      case TrimSurface::Kind::Cylinder: {
        const double a = dot(r, t.direction);
        const Vec off{r[0] - a * t.direction[0], r[1] - a * t.direction[1], r[2] - a * t.direction[2]};
        f = norm(off) - t.radius;
        break;
      }
      case TrimSurface::Kind::Sphere:
        f = norm(r) - t.radius;
        break;
      case TrimSurface::Kind::Polygon:
        f = polygon_level(t.rings, x[0], x[1]);
        break;
    }
    level = std::max(level, f);
  }
  return level;
}

CutPattern cut_pattern(const std::vector<double>& x0, const std::vector<double>& x, const std::vector<int>& tri,
                       const std::vector<TrimSurface>& trims, double margin) {
  const std::size_t n = x0.size() / 3, m = tri.size() / 3;
  if (x.size() != x0.size()) throw std::runtime_error("the blank and the formed ply have other numbers of nodes");
  for (std::size_t k = 0; k < x0.size(); ++k)
    if (!std::isfinite(x0[k]) || !std::isfinite(x[k]))
      throw std::runtime_error("node " + std::to_string(k / 3) + " has a position that is not finite");
  std::vector<double> level(n, -1.0);
  if (!trims.empty()) {
    const long long nodes = static_cast<long long>(n);
#pragma omp parallel for schedule(static) if (nodes > 4096)
    for (long long i = 0; i < nodes; ++i) level[static_cast<std::size_t>(i)] = trim_level(trims, &x[3 * i]) - margin;
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(level[i]))
        throw std::runtime_error("the distance of node " + std::to_string(i) + " to the trim is not finite");
  }
  // The edges, each once (smaller node first), and how many triangles have it.
  std::unordered_map<std::uint64_t, int> edge_id;
  std::vector<std::array<int, 2>> edges;
  std::vector<int> uses;
  auto edge = [&](int a, int b) {
    const int lo = std::min(a, b), hi = std::max(a, b);
    const std::uint64_t key = (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi);
    const auto [it, added] = edge_id.emplace(key, static_cast<int>(edges.size()));
    if (added) {
      edges.push_back({lo, hi});
      uses.push_back(0);
    }
    return it->second;
  };
  for (std::size_t e = 0; e < m; ++e)
    for (int k = 0; k < 3; ++k) ++uses[static_cast<std::size_t>(edge(tri[3 * e + k], tri[3 * e + (k + 1) % 3]))];
  // Points: a node (key < n) or the crossing of an edge (key n + edge),
  // placed from the edge's smaller node, so that both of its triangles
  // place it alike.
  const int nn = static_cast<int>(n);
  auto point = [&](int key, const std::vector<double>& pos) -> Vec {
    if (key < nn) return at(pos, static_cast<std::size_t>(key));
    const auto& ed = edges[static_cast<std::size_t>(key - nn)];
    const double la = level[static_cast<std::size_t>(ed[0])], lb = level[static_cast<std::size_t>(ed[1])];
    const double t = la / (la - lb);
    const Vec a = at(pos, static_cast<std::size_t>(ed[0])), b = at(pos, static_cast<std::size_t>(ed[1]));
    return {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
  };
  CutPattern p;
  std::vector<std::array<int, 2>> segments;  // directed, the pattern on their left
  std::vector<Vec> poly0, poly;
  for (std::size_t e = 0; e < m; ++e) {
    const int c[3] = {tri[3 * e], tri[3 * e + 1], tri[3 * e + 2]};
    bool in[3];
    for (int k = 0; k < 3; ++k) in[k] = level[static_cast<std::size_t>(c[k])] <= 0;
    p.blank_area += polygon_area({at(x0, static_cast<std::size_t>(c[0])), at(x0, static_cast<std::size_t>(c[1])),
                                  at(x0, static_cast<std::size_t>(c[2]))});
    poly0.clear();
    poly.clear();
    int leave = -1, enter = -1;  // the crossings where the walk round the triangle leaves and enters the part
    for (int k = 0; k < 3; ++k) {
      const int a = c[k], b = c[(k + 1) % 3];
      const int cross_key = nn + edge(a, b);
      if (in[k]) {
        poly0.push_back(point(a, x0));
        poly.push_back(point(a, x));
      }
      if (in[k] != in[(k + 1) % 3]) {
        poly0.push_back(point(cross_key, x0));
        poly.push_back(point(cross_key, x));
        (in[k] ? leave : enter) = cross_key;
      }
      if (uses[static_cast<std::size_t>(cross_key - nn)] != 1) continue;  // not on the blank's edge
      if (in[k] && in[(k + 1) % 3]) segments.push_back({a, b});
      else if (in[k]) segments.push_back({a, cross_key});
      else if (in[(k + 1) % 3]) segments.push_back({cross_key, b});
    }
    if (leave >= 0) segments.push_back({leave, enter});
    if (poly0.size() >= 3) {
      p.kept_blank_area += polygon_area(poly0);
      p.kept_formed_area += polygon_area(poly);
    }
  }
  // The segments joined into closed outlines, in the order of their
  // triangles (where two outlines touch at a point, the first segment
  // not yet taken out of it).
  std::unordered_map<int, std::vector<int>> out_of;
  for (std::size_t s = 0; s < segments.size(); ++s) out_of[segments[s][0]].push_back(static_cast<int>(s));
  std::vector<char> taken(segments.size(), 0);
  for (std::size_t s0 = 0; s0 < segments.size(); ++s0) {
    if (taken[s0]) continue;
    std::vector<int> keys;
    int s = static_cast<int>(s0);
    const int start = segments[s0][0];
    while (true) {
      taken[static_cast<std::size_t>(s)] = 1;
      keys.push_back(segments[static_cast<std::size_t>(s)][0]);
      const int next = segments[static_cast<std::size_t>(s)][1];
      if (next == start) break;
      int follow = -1;
      if (const auto it = out_of.find(next); it != out_of.end())
        for (const int t : it->second)
          if (!taken[static_cast<std::size_t>(t)]) {
            follow = t;
            break;
          }
      if (follow < 0)
        throw std::runtime_error(
            "the outline does not close at " +
            (next < nn ? "node " + std::to_string(next)
                       : "the edge of nodes " + std::to_string(edges[static_cast<std::size_t>(next - nn)][0]) +
                             " and " + std::to_string(edges[static_cast<std::size_t>(next - nn)][1])) +
            " (triangles not alike oriented?)");
      s = follow;
    }
    Outline o;
    for (const int k : keys) {
      OutlinePoint q{point(k, x0), point(k, x), k >= nn};
      if (!o.points.empty() && o.points.back().blank == q.blank) {  // a node on the trim surface
        o.points.back().on_trim = o.points.back().on_trim || q.on_trim;
        continue;
      }
      o.points.push_back(q);
    }
    while (o.points.size() > 1 && o.points.back().blank == o.points.front().blank) {
      o.points.front().on_trim = o.points.front().on_trim || o.points.back().on_trim;
      o.points.pop_back();
    }
    if (o.points.size() < 3) continue;  // a touch of the trim surface at a point or along an edge
    for (std::size_t k = 0; k < o.points.size(); ++k) {
      const OutlinePoint& a = o.points[k];
      const OutlinePoint& b = o.points[(k + 1) % o.points.size()];
      const double l0 = norm(sub(b.blank, a.blank));
      o.length_blank += l0;
      o.length_formed += norm(sub(b.formed, a.formed));
      if (a.on_trim && b.on_trim) o.trim_length_blank += l0;
    }
    p.outlines.push_back(std::move(o));
  }
  return p;
}

std::vector<FibreMark> fibre_marks(const std::vector<double>& x0, const std::vector<double>& x,
                                   const std::vector<int>& tri, const std::vector<TrimSurface>& trims,
                                   const std::vector<double>& fibre, const std::array<double, 3>& e1,
                                   const std::array<double, 3>& e2, double spacing, double margin) {
  const std::size_t n = x0.size() / 3, m = tri.size() / 3;
  std::vector<double> level(n, -1.0);
  if (!trims.empty())
    for (std::size_t i = 0; i < n; ++i) level[i] = trim_level(trims, &x[3 * i]) - margin;
  std::vector<FibreMark> marks;
  std::set<std::pair<long long, long long>> taken;  // grid points already marked
  for (std::size_t e = 0; e < m; ++e) {
    double u[3], v[3], l[3];
    for (int k = 0; k < 3; ++k) {
      const Vec p = at(x0, static_cast<std::size_t>(tri[3 * e + k]));
      u[k] = dot(p, e1);
      v[k] = dot(p, e2);
      l[k] = level[static_cast<std::size_t>(tri[3 * e + k])];
    }
    const double det = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (!(std::abs(det) > 0)) continue;
    const Vec a = at(fibre, e);
    Vec d{dot(a, e1), dot(a, e2), 0};  // in the plane
    const double ld = std::hypot(d[0], d[1]);
    if (!(ld > 0)) continue;
    d = {d[0] / ld, d[1] / ld, 0};
    const long long i0 = static_cast<long long>(std::ceil(std::min({u[0], u[1], u[2]}) / spacing - 1e-9));
    const long long i1 = static_cast<long long>(std::floor(std::max({u[0], u[1], u[2]}) / spacing + 1e-9));
    const long long j0 = static_cast<long long>(std::ceil(std::min({v[0], v[1], v[2]}) / spacing - 1e-9));
    const long long j1 = static_cast<long long>(std::floor(std::max({v[0], v[1], v[2]}) / spacing + 1e-9));
    for (long long i = i0; i <= i1; ++i)
      for (long long j = j0; j <= j1; ++j) {
        const double pu = static_cast<double>(i) * spacing, pv = static_cast<double>(j) * spacing;
        const double b1 = ((pu - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (pv - v[0])) / det;
        const double b2 = ((u[1] - u[0]) * (pv - v[0]) - (pu - u[0]) * (v[1] - v[0])) / det;
        const double b0 = 1 - b1 - b2;
        const double tol = -1e-12;
        if (b0 < tol || b1 < tol || b2 < tol) continue;
        if (b0 * l[0] + b1 * l[1] + b2 * l[2] > 0) continue;  // outside the pattern
        if (!taken.emplace(i, j).second) continue;
        Vec c{0, 0, 0};  // the point on the triangle

        for (int k = 0; k < 3; ++k) {
          const Vec p = at(x0, static_cast<std::size_t>(tri[3 * e + k]));
          const double w = k == 0 ? b0 : k == 1 ? b1 : b2;
          for (int q = 0; q < 3; ++q) c[q] += w * p[q];
        }
        const double half = 0.3 * spacing;
        FibreMark mk;
        for (int q = 0; q < 3; ++q) {
          const double dir = d[0] * e1[q] + d[1] * e2[q];
          mk.from[q] = c[q] - half * dir;
          mk.to[q] = c[q] + half * dir;
        }
        // The ends formed: their barycentric coordinates in the blank's triangle, on its corners formed.
        for (const int end : {0, 1}) {
          const double qu = pu + (end ? half : -half) * d[0], qv = pv + (end ? half : -half) * d[1];
          const double c1 = ((qu - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (qv - v[0])) / det;
          const double c2 = ((u[1] - u[0]) * (qv - v[0]) - (qu - u[0]) * (v[1] - v[0])) / det;
          const double w[3] = {1 - c1 - c2, c1, c2};
          Vec f{0, 0, 0};
          for (int k = 0; k < 3; ++k) {
            const Vec p = at(x, static_cast<std::size_t>(tri[3 * e + k]));
            for (int q = 0; q < 3; ++q) f[q] += w[k] * p[q];
          }
          (end ? mk.formed_to : mk.formed_from) = f;
        }
        marks.push_back(mk);
      }
  }
  return marks;
}

namespace {

// The blank's plane: flat when every node lies within 1e-6 of its
// largest extent from the plane through the nodes' mean with the normal of
// the triangles' summed area vectors.
bool flat_blank(const std::vector<double>& x0, const std::vector<int>& tri, Vec& normal) {
  const std::size_t n = x0.size() / 3, m = tri.size() / 3;
  Vec s{0, 0, 0}, mean{0, 0, 0}, lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::size_t e = 0; e < m; ++e) {
    const Vec a = at(x0, static_cast<std::size_t>(tri[3 * e]));
    const Vec c = cross(sub(at(x0, static_cast<std::size_t>(tri[3 * e + 1])), a),
                        sub(at(x0, static_cast<std::size_t>(tri[3 * e + 2])), a));
    for (int d = 0; d < 3; ++d) s[d] += c[d];
  }
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      mean[d] += x0[3 * i + d] / static_cast<double>(n);
      lo[d] = std::min(lo[d], x0[3 * i + d]);
      hi[d] = std::max(hi[d], x0[3 * i + d]);
    }
  const double l = norm(s);
  if (!(l > 0)) return false;
  normal = {s[0] / l, s[1] / l, s[2] / l};
  double off = 0;
  for (std::size_t i = 0; i < n; ++i) off = std::max(off, std::abs(dot(sub(at(x0, i), mean), normal)));
  return off <= 1e-6 * norm(sub(hi, lo));
}

// In-plane coordinates of a flat blank for the DXF file: x and y where the
// plane is normal to z (seen from +z); otherwise along e1, the global axis
// least aligned with the normal n' (n turned to have its largest component
// positive) projected into the plane, and e2 = n' x e1.
std::array<Vec, 2> plane_axes(const Vec& n) {
  if (std::abs(n[2]) >= 1 - 1e-9) return {Vec{1, 0, 0}, Vec{0, 1, 0}};
  int big = 0, least = 0;
  for (int d = 1; d < 3; ++d) {
    if (std::abs(n[d]) > std::abs(n[big])) big = d;
    if (std::abs(n[d]) < std::abs(n[least])) least = d;
  }
  const Vec nn = n[big] < 0 ? Vec{-n[0], -n[1], -n[2]} : n;
  Vec a{0, 0, 0};
  a[least] = 1;
  const double an = dot(a, nn);
  Vec e1{a[0] - an * nn[0], a[1] - an * nn[1], a[2] - an * nn[2]};
  const double l = norm(e1);
  for (double& c : e1) c /= l;
  return {e1, cross(nn, e1)};
}

// The fibre marks' spacing for a pattern `extent` across (m): of 1, 2 or
// 5 times a power of 10, the nearest to extent / 15 (at least 1 mm).
double mark_spacing(double extent) {
  const double want = std::max(extent / 15, 1e-3);
  double best = 1e-3;
  for (double p = 1e-3; p < 1e3; p *= 10)
    for (const double f : {1.0, 2.0, 5.0})
      if (std::abs(std::log(f * p / want)) < std::abs(std::log(best / want))) best = f * p;
  return best;
}

// A DXF file (AutoCAD R12, ASCII; units mm, $INSUNITS 4): each outline as a
// closed POLYLINE, the blank's on layer BLANK, the pattern's on PATTERN,
// and the fibre marks as LINEs on layer FIBRE.
bool write_dxf(const std::filesystem::path& file, const BlankPly& ply) {
  std::ofstream f(file);
  if (!f) return false;
  const auto axes = plane_axes(ply.normal);
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return std::string(buf);
  };
  f << "999\nthermostamp blank: ply '" << ply.name << "', mm\n"
    << "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1009\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n"
    << "0\nSECTION\n2\nTABLES\n0\nTABLE\n2\nLAYER\n70\n3\n"
    << "0\nLAYER\n2\nBLANK\n70\n0\n62\n8\n6\nCONTINUOUS\n"
    << "0\nLAYER\n2\nPATTERN\n70\n0\n62\n1\n6\nCONTINUOUS\n"
    << "0\nLAYER\n2\nFIBRE\n70\n0\n62\n5\n6\nCONTINUOUS\n"
    << "0\nENDTAB\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n";
  auto outline = [&](const Outline& o, const char* layer) {
    f << "0\nPOLYLINE\n8\n" << layer << "\n66\n1\n70\n1\n10\n0.0\n20\n0.0\n30\n0.0\n";
    for (const OutlinePoint& q : o.points)
      f << "0\nVERTEX\n8\n" << layer << "\n10\n" << num(1000 * dot(q.blank, axes[0])) << "\n20\n"
        << num(1000 * dot(q.blank, axes[1])) << "\n30\n0.0\n";
    f << "0\nSEQEND\n8\n" << layer << "\n";
  };
  for (const Outline& o : ply.blank.outlines) outline(o, "BLANK");
  for (const Outline& o : ply.pattern.outlines) outline(o, "PATTERN");
  for (const FibreMark& k : ply.marks)
    f << "0\nLINE\n8\nFIBRE\n10\n" << num(1000 * dot(k.from, axes[0])) << "\n20\n" << num(1000 * dot(k.from, axes[1]))
      << "\n30\n0.0\n11\n" << num(1000 * dot(k.to, axes[0])) << "\n21\n" << num(1000 * dot(k.to, axes[1]))
      << "\n31\n0.0\n";
  f << "0\nENDSEC\n0\nEOF\n";
  f.close();
  return static_cast<bool>(f);
}

bool write_csv(const std::filesystem::path& file, const CutPattern& pattern, const CutPattern& edge,
               const std::vector<FibreMark>& marks) {
  std::ofstream f(file);
  if (!f) return false;
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return std::string(buf);
  };
  f << "kind,outline,point,on_trim,blank_x_m,blank_y_m,blank_z_m,formed_x_m,formed_y_m,formed_z_m\n";
  for (const auto& [kind, p] : {std::pair<const char*, const CutPattern*>{"pattern", &pattern},
                                std::pair<const char*, const CutPattern*>{"edge", &edge}})
    for (std::size_t o = 0; o < p->outlines.size(); ++o)
      for (std::size_t k = 0; k < p->outlines[o].points.size(); ++k) {
        const OutlinePoint& q = p->outlines[o].points[k];
        f << kind << ',' << o << ',' << k << ',' << (q.on_trim ? 1 : 0);
        for (const double v : q.blank) f << ',' << num(v);
        for (const double v : q.formed) f << ',' << num(v);
        f << '\n';
      }
  for (std::size_t k = 0; k < marks.size(); ++k)
    for (const int end : {0, 1}) {
      f << "fibre," << k << ',' << end << ",0";
      for (const double v : end ? marks[k].to : marks[k].from) f << ',' << num(v);
      for (const double v : end ? marks[k].formed_to : marks[k].formed_from) f << ',' << num(v);
      f << '\n';
    }
  f.close();
  return static_cast<bool>(f);
}

}  // namespace

BlankResult blank_plies(const std::filesystem::path& dir, std::optional<double> time,
                        const std::filesystem::path& out, bool whole, const std::vector<TrimSurface>& trims,
                        double margin) {
  if (trims.empty()) throw ExportInputError("no --trim: give the surface the part is trimmed at");
  if (!(std::abs(margin) <= kFar)) throw ExportInputError("--margin " + g(margin) + ": beyond 1e6 (m)");
  FramePlies frame = read_frame_plies(dir, time, whole, false);
  for (const FramePly& d : frame.plies)
    for (std::size_t k = 0; k < d.x.size(); ++k)
      if (!std::isfinite(d.x[k]))
        throw ExportInputError("ply '" + d.name + "' has a position that is not finite at t = " + g(frame.time) +
                               " s (node " + std::to_string(d.node_tag[k / 3]) +
                               "): take an earlier frame with --time");
  create_output_folder(out);
  BlankResult res;
  res.time = frame.time;
  res.frame = frame.frame;
  res.frames = frame.frames;
  nlohmann::json doc;
  doc["time_s"] = frame.time;
  doc["frame"] = frame.group;
  doc["results"] = frame.h5.string();
  doc["trims"] = nlohmann::json::array();
  for (const TrimSurface& t : trims) doc["trims"].push_back(t.text);
  doc["margin_m"] = margin;
  doc["plies"] = nlohmann::json::object();
  // The fibre directions of the blank: the first frame's field.
  const FramePlies first = read_frame_plies(dir, std::nullopt, whole, true, true);
  for (const FramePly& d : frame.plies) {
    BlankPly ply;
    ply.name = d.name;
    ply.mirrored = d.mirrored;
    try {
      ply.pattern = cut_pattern(d.x0, d.x, d.tri, trims, margin);
      ply.blank = cut_pattern(d.x0, d.x, d.tri, {});
    } catch (const std::exception& e) {
      throw std::runtime_error("ply '" + d.name + "': " + e.what());
    }
    ply.flat = flat_blank(d.x0, d.tri, ply.normal);
    const std::vector<double>* fibre = nullptr;
    for (const FramePly& f0 : first.plies)
      if (f0.name == d.name && f0.tri == d.tri)
        for (const PlyField& f : f0.fields)
          if (f.name == "fibre_direction" && f.cells && f.components == 3) fibre = &f.v;
    if (ply.flat && fibre && !ply.pattern.outlines.empty()) {
      const auto axes = plane_axes(ply.normal);
      double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
      for (const Outline& o : ply.pattern.outlines)
        for (const OutlinePoint& q : o.points)
          for (int c = 0; c < 2; ++c) {
            lo[c] = std::min(lo[c], dot(q.blank, axes[static_cast<std::size_t>(c)]));
            hi[c] = std::max(hi[c], dot(q.blank, axes[static_cast<std::size_t>(c)]));
          }
      ply.mark_spacing = mark_spacing(std::max(hi[0] - lo[0], hi[1] - lo[1]));
      ply.marks = fibre_marks(d.x0, d.x, d.tri, trims, *fibre, axes[0], axes[1], ply.mark_spacing, margin);
    }
    ply.csv = out / (d.name + ".csv");
    if (!write_csv(ply.csv, ply.pattern, ply.blank, ply.marks))
      throw std::runtime_error("cannot write '" + ply.csv.string() + "'");
    if (ply.flat) {
      ply.dxf = out / (d.name + ".dxf");
      if (!write_dxf(ply.dxf, ply)) throw std::runtime_error("cannot write '" + ply.dxf.string() + "'");
    }
    const CutPattern& p = ply.pattern;
    nlohmann::json j;
    j["blank_area_m2"] = p.blank_area;
    j["kept_blank_area_m2"] = p.kept_blank_area;
    j["kept_formed_area_m2"] = p.kept_formed_area;
    j["kept_share"] = p.blank_area > 0 ? p.kept_blank_area / p.blank_area : 0.0;
    j["outlines"] = nlohmann::json::array();
    for (const Outline& o : p.outlines)
      j["outlines"].push_back({{"points", o.points.size()},
                               {"length_blank_m", o.length_blank},
                               {"length_formed_m", o.length_formed},
                               {"trim_length_blank_m", o.trim_length_blank}});
    j["blank_outlines"] = ply.blank.outlines.size();
    // The largest draw-in: the blank's edge's displacement in the blank's plane.
    double draw_in = 0;
    for (const Outline& o : ply.blank.outlines)
      for (const OutlinePoint& q : o.points) {
        Vec u = sub(q.formed, q.blank);
        if (ply.flat) {
          const double un = dot(u, ply.normal);
          for (int c = 0; c < 3; ++c) u[c] -= un * ply.normal[c];
        }
        draw_in = std::max(draw_in, norm(u));
      }
    j["edge_displacement_max_m"] = draw_in;
    j["csv"] = ply.csv.filename().string();
    j["dxf"] = ply.flat ? nlohmann::json(ply.dxf.filename().string()) : nlohmann::json(nullptr);
    j["flat"] = ply.flat;
    j["normal"] = ply.normal;
    j["mirrored"] = ply.mirrored;
    j["fibre_marks"] = ply.marks.size();
    j["fibre_mark_spacing_m"] = ply.mark_spacing > 0 ? nlohmann::json(ply.mark_spacing) : nlohmann::json(nullptr);
    if (ply.flat && !fibre) j["fibre_marks_left_out"] = "the first frame holds no fibre_direction (output.fields)";
    doc["plies"][d.name] = j;
    res.plies.push_back(std::move(ply));
  }
  res.json = out / "blank.json";
  std::ofstream f(res.json);
  f << doc.dump(2) << "\n";
  f.close();
  if (!f) throw std::runtime_error("cannot write '" + res.json.string() + "'");
  return res;
}

}  // namespace ts
