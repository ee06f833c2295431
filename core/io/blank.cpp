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
#include <tuple>
#include <unordered_map>
#include <utility>

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

// The area of the triangle of nodes c of positions x.
double triangle_area(const std::vector<double>& x, const int c[3]) {
  const Vec a = at(x, static_cast<std::size_t>(c[0])), b = at(x, static_cast<std::size_t>(c[1]));
  return 0.5 * norm(cross(sub(b, a), sub(at(x, static_cast<std::size_t>(c[2])), a)));
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

// The first two sides, in the rings' order (ring and index of each), that
// cross or touch, other than neighbours: each side against those whose
// extent in x overlaps its own (sorted by their smallest x).
std::optional<std::array<std::size_t, 4>> first_meeting_sides(const std::vector<Ring>& rings) {
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
      const bool u_first =
          sides[u].ring < sides[w].ring || (sides[u].ring == sides[w].ring && sides[u].index < sides[w].index);
      const Side& a = u_first ? sides[u] : sides[w];
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
  return first;
}

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
// POLYLINE with its VERTEX entities) and its circles (CIRCLE), their arcs
// (bulges) drawn as sides of at most 2 degrees of arc, in the coordinates of the plane they are
// drawn in (the object coordinate system of their extrusion direction,
// `normal`, which every one of them must share; a 3D POLYLINE's vertices
// in x and y, seen along z); open polylines, polygon meshes and other
// entities are left out. `scale` (m per drawing unit): the given one, or
// from the header's $INSUNITS.
std::vector<Ring> read_dxf_rings(const std::string& file, const std::string& what, double& scale, bool scale_given,
                                 Vec& normal) {
  std::ifstream in(file);
  if (!in) throw ExportInputError(what + "cannot read '" + shown(file) + "'");
  struct Vertex {
    double x = 0, y = 0, bulge = 0;
  };
  std::vector<Ring> rings;
  std::vector<Vertex> vs;
  bool closed = false, in_polyline = false, three_d = false, mesh = false;
  Vec extrusion{0, 0, 1};  // the normal of the plane the polyline is drawn in
  std::array<double, 3> circle{};  // a CIRCLE's centre and radius
  int circle_line = 0;
  std::optional<Vec> first_normal;
  int open = 0, units = -1, count = 0;
  std::string section, entity, code, value, variable;
  auto finish = [&]() {  // the polyline read so far, as a ring
    if (vs.empty() || mesh) {
    } else if (!closed) {
      ++open;
    } else {
      ++count;
      const double l = norm(extrusion);
      if (!(l > 0) || !std::isfinite(l))
        throw ExportInputError(what + "'" + shown(file) + "': polyline " + std::to_string(count) +
                               " has no extrusion direction (the normal of its plane, codes 210-230)");
      const Vec n = three_d ? Vec{0, 0, 1} : Vec{extrusion[0] / l, extrusion[1] / l, extrusion[2] / l};
      if (!first_normal) first_normal = n;
      if (norm(sub(n, *first_normal)) > 1e-9)
        throw ExportInputError(what + "'" + shown(file) + "': polyline " + std::to_string(count) +
                               " is drawn in another plane than polyline 1 (normal " + g(n[0]) + ", " + g(n[1]) +
                               ", " + g(n[2]) + " against " + g((*first_normal)[0]) + ", " + g((*first_normal)[1]) +
                               ", " + g((*first_normal)[2]) + "): draw a trim outline's polylines in one plane");
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
      rings.push_back(std::move(r));
    }
    vs.clear();
    closed = false;
    three_d = false;
    mesh = false;
    extrusion = {0, 0, 1};
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
      if (entity == "CIRCLE" && section == "ENTITIES") {  // a closed polyline of two half circles
        if (!(circle[2] > 0) || !std::isfinite(circle[2]))
          throw ExportInputError(what + "'" + shown(file) + "' line " + std::to_string(circle_line) +
                                 ": a CIRCLE without a radius above 0");
        vs = {{circle[0] + circle[2], circle[1], 1.0}, {circle[0] - circle[2], circle[1], 1.0}};
        closed = true;
        finish();
      }
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
      if (entity == "CIRCLE") {
        circle = {0, 0, 0};
        circle_line = line;
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
    if (entity == "CIRCLE") {  // its centre in the plane of its extrusion direction, and its radius
      if (code == "10" || code == "20") circle[code == "10" ? 0 : 1] = number(value);
      if (code == "40") circle[2] = number(value);
      if (code == "210" || code == "220" || code == "230")
        extrusion[static_cast<std::size_t>(code[1] - '1')] = number(value);
      continue;
    }
    const bool header = lw || (entity == "POLYLINE" && in_polyline);
    if (header && code == "70") {
      const int flags = integer(value);
      closed = (flags & 1) != 0;
      if (!lw) {
        three_d = (flags & 8) != 0;
        mesh = (flags & (16 | 64)) != 0;
      }
    }
    if (header && (code == "210" || code == "220" || code == "230"))
      extrusion[static_cast<std::size_t>(code[1] - '1')] = number(value);
    if (lw && code == "10") vs.push_back({number(value), 0, 0});
    if ((lw && !vs.empty()) || (vertex && !vs.empty())) {
      if (vertex && code == "10") vs.back().x = number(value);
      if (code == "20") vs.back().y = number(value);
      if (code == "42") vs.back().bulge = number(value);
    }
  }
  finish();
  normal = first_normal.value_or(Vec{0, 0, 1});
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
std::vector<Ring> read_polygon(const std::string& spec, const std::string& what, Vec& normal) {
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
      dxf ? read_dxf_rings(file, what, scale, scale_given, normal) : std::vector<Ring>{read_csv_ring(file, what)};
  if (!dxf) normal = {0, 0, 1};
  const std::string at = what + "'" + shown(file) + "'";
  double lo[2] = {kFar, kFar}, hi[2] = {-kFar, -kFar};
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring& p = rings[r];
    for (std::size_t k = 0; k < p.size(); ++k) {
      p[k][0] *= scale;
      p[k][1] *= scale;
      if (!(std::abs(p[k][0]) <= kFar && std::abs(p[k][1]) <= kFar))
        throw ExportInputError(at + (dxf ? ": polyline " + std::to_string(r + 1) : std::string(":")) + " vertex " +
                               std::to_string(k + 1) + " lies beyond 1e6 m: not a trim in a press (the scale?)");
      for (std::size_t d = 0; d < 2; ++d) {
        lo[d] = std::min(lo[d], p[k][d]);
        hi[d] = std::max(hi[d], p[k][d]);
      }
    }
  }
  // Two vertices within 1e-9 of the polygon's size of each other are one:
  // a side that short has no direction to cut along.
  const double close = 1e-9 * std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
  auto same = [&](const std::array<double, 2>& a, const std::array<double, 2>& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1]) <= close;
  };
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring& p = rings[r];
    const std::string which = dxf ? ": polyline " + std::to_string(r + 1) : std::string();
    if (p.size() > 1 && same(p.front(), p.back())) p.pop_back();
    if (p.size() < 3)
      throw ExportInputError(at + which + (dxf ? " has " : " holds ") + std::to_string(p.size()) +
                             " vertices: a polygon needs at least 3");
    const std::size_t n = p.size();
    double area = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (same(p[k], p[(k + 1) % n]))
        throw ExportInputError(at + (dxf ? which : std::string(":")) + " vertex " + std::to_string(k + 1) +
                               " is there twice in a row");
      area += cross2({0, 0}, p[k], p[(k + 1) % n]) / 2;
    }
    if (!(std::abs(area) > 0))
      throw ExportInputError(at + (dxf ? which : std::string(":")) + " the polygon has no area");
  }
  const std::optional<std::array<std::size_t, 4>> first = first_meeting_sides(rings);
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
  if (rings.empty()) return 1e300;  // a polygon moved in until nothing is left: everything outside
  double d2 = std::numeric_limits<double>::infinity();
  bool inside = false;
  for (const Ring& p : rings) {
    inside = inside != ring_contains(p, x, y);
    const std::size_t n = p.size();
    for (std::size_t k = 0, j = n - 1; k < n; j = k++) {
      const auto& a = p[j];
      const auto& b = p[k];
      const double ex = b[0] - a[0], ey = b[1] - a[1];
      const double t = std::clamp(((x - a[0]) * ex + (y - a[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
      const double dx = x - a[0] - t * ex, dy = y - a[1] - t * ey;
      d2 = std::min(d2, dx * dx + dy * dy);
    }
  }
  return inside ? -std::sqrt(d2) : std::sqrt(d2);
}

// The level of a point x (m) for one surface: the signed distance, at
// most 0 in the part.
double surface_level(const TrimSurface& t, const double* x) {
  const Vec r{x[0] - t.point[0], x[1] - t.point[1], x[2] - t.point[2]};
  switch (t.kind) {
    case TrimSurface::Kind::Plane:
      return -dot(r, t.direction);
    case TrimSurface::Kind::Cylinder: {
      const double a = dot(r, t.direction);
      const Vec off{r[0] - a * t.direction[0], r[1] - a * t.direction[1], r[2] - a * t.direction[2]};
      return norm(off) - t.radius;
    }
    case TrimSurface::Kind::Sphere:
      return norm(r) - t.radius;
    case TrimSurface::Kind::Polygon:
      return polygon_level(t.rings, x[0] * t.plan_u[0] + x[1] * t.plan_u[1] + x[2] * t.plan_u[2],
                           x[0] * t.plan_v[0] + x[1] * t.plan_v[1] + x[2] * t.plan_v[2]);
  }
  return 0;
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
    Vec n{0, 0, 1};
    t.rings = read_polygon(text.substr(colon + 1), what, n);
    // The plane's axes by DXF's arbitrary axis algorithm: x along (0, 1, 0)
    // x n, or (0, 0, 1) x n where n is not near z; y = n x x.
    Vec ax = std::abs(n[0]) < 1.0 / 64 && std::abs(n[1]) < 1.0 / 64 ? cross({0, 1, 0}, n) : cross({0, 0, 1}, n);
    const double l = norm(ax);
    ax = {ax[0] / l, ax[1] / l, ax[2] / l};
    t.plan_u = ax;
    t.plan_v = cross(n, ax);
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

std::array<double, 3> polygon_cut_direction(const TrimSurface& t) { return cross(t.plan_u, t.plan_v); }

double trim_level(const std::vector<TrimSurface>& trims, const double* x) {
  double level = -std::numeric_limits<double>::infinity();
  for (const TrimSurface& t : trims) level = std::max(level, surface_level(t, x));
  return level;
}

namespace {

// A polygon's ring as the trim takes it: its vertices, those between two
// sides along one line left out (such a side is one, as another trim
// along that line sees it), and whether it runs the other way round the
// part (the part lies on the left of a ring inside an even number of
// others run anticlockwise, one inside an odd number, a hole, clockwise).
struct TurnedRing {
  Ring vertices;
  bool reverse = false;
};

std::vector<TurnedRing> turned_rings(const std::vector<Ring>& rings) {
  std::vector<TurnedRing> out;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring p;
    const Ring& given = rings[r];
    for (std::size_t k = 0; k < given.size(); ++k) {
      const auto& a = given[(k + given.size() - 1) % given.size()];
      const auto& b = given[k];
      const auto& c = given[(k + 1) % given.size()];
      const double ab = std::hypot(b[0] - a[0], b[1] - a[1]), bc = std::hypot(c[0] - b[0], c[1] - b[1]);
      const bool straight = std::abs(cross2(a, b, c)) <= 1e-12 * ab * bc &&
                            (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1]) > 0;
      if (!straight && ab > 0) p.push_back(b);
    }
    if (p.size() < 3) p = given;
    int depth = 0;
    for (std::size_t q = 0; q < rings.size(); ++q)
      if (q != r && ring_contains(rings[q], p[0][0], p[0][1])) ++depth;
    double area = 0;
    for (std::size_t k = 0; k < p.size(); ++k) area += cross2({0, 0}, p[k], p[(k + 1) % p.size()]);
    out.push_back({p, (area > 0) != (depth % 2 == 0)});
  }
  return out;
}

// A polygon trim in plan view: its sides, each turned so that the part
// lies on its left (a ring inside an even number of others runs
// anticlockwise, one inside an odd number, a hole, clockwise), in a grid
// of cells over their extent that lists the sides reaching into each.
class PlanPolygon {
 public:
  struct Side {
    std::array<double, 2> a{}, b{};
    double length = 0;
  };

  explicit PlanPolygon(const std::vector<Ring>& rings) {
    lo_[0] = lo_[1] = std::numeric_limits<double>::infinity();
    hi_[0] = hi_[1] = -std::numeric_limits<double>::infinity();
    for (const TurnedRing& t : turned_rings(rings)) {
      const Ring& p = t.vertices;
      const bool reverse = t.reverse;
      for (std::size_t k = 0; k < p.size(); ++k) {
        Side s{p[k], p[(k + 1) % p.size()], 0};
        if (reverse) std::swap(s.a, s.b);
        s.length = std::hypot(s.b[0] - s.a[0], s.b[1] - s.a[1]);
        for (int d = 0; d < 2; ++d) {
          lo_[d] = std::min({lo_[d], s.a[static_cast<std::size_t>(d)], s.b[static_cast<std::size_t>(d)]});
          hi_[d] = std::max({hi_[d], s.a[static_cast<std::size_t>(d)], s.b[static_cast<std::size_t>(d)]});
        }
        sides.push_back(s);
      }
    }
    const int n = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(sides.size())))), 1, 1024);
    n_ = n;
    for (int d = 0; d < 2; ++d) cell_[d] = (hi_[d] - lo_[d]) / n;
    cells_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    for (std::size_t s = 0; s < sides.size(); ++s) {
      const Side& e = sides[s];
      const int c0 = index(0, std::min(e.a[0], e.b[0])), c1 = index(0, std::max(e.a[0], e.b[0]));
      const int r0 = index(1, std::min(e.a[1], e.b[1])), r1 = index(1, std::max(e.a[1], e.b[1]));
      for (int r = r0; r <= r1; ++r)
        for (int c = c0; c <= c1; ++c) cells_[static_cast<std::size_t>(r) * n_ + c].push_back(static_cast<int>(s));
    }
  }

  // Inside an odd number of rings: the crossings of a ray along +x,
  // through the cells of the point's row, each counted in the cell it
  // lies in.
  bool inside(double x, double y) const {
    if (!(x >= lo_[0] && x <= hi_[0] && y >= lo_[1] && y <= hi_[1])) return false;
    bool in = false;
    const int r = index(1, y);
    for (int c = index(0, x); c < n_; ++c)
      for (const int s : cells_[static_cast<std::size_t>(r) * n_ + c]) {
        const Side& e = sides[static_cast<std::size_t>(s)];
        if ((e.a[1] > y) == (e.b[1] > y)) continue;
        const double xc = std::clamp(e.a[0] + (y - e.a[1]) * (e.b[0] - e.a[0]) / (e.b[1] - e.a[1]),
                                     std::min(e.a[0], e.b[0]), std::max(e.a[0], e.b[0]));
        if (x < xc && index(0, xc) == c) in = !in;
      }
    return in;
  }

  // The sides reaching into the cells that the box meets, each once.
  void near(double x0, double x1, double y0, double y1, std::vector<int>& out) const {
    out.clear();
    if (x1 < lo_[0] || x0 > hi_[0] || y1 < lo_[1] || y0 > hi_[1]) return;
    for (int r = index(1, y0); r <= index(1, y1); ++r)
      for (int c = index(0, x0); c <= index(0, x1); ++c) {
        const auto& cell = cells_[static_cast<std::size_t>(r) * n_ + c];
        out.insert(out.end(), cell.begin(), cell.end());
      }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  // The signed distance of (x, y) to side s's line, negative on the
  // part's side (m), and how far along the side it lies from a, and back
  // from b (m; both at least 0 between the ends). Each from the side's
  // nearer end, or from the end it is measured from, so that a point
  // near an end keeps its digits however long the side.
  double level(int s, double x, double y) const {
    const Side& e = sides[static_cast<std::size_t>(s)];
    const bool from_a = std::hypot(x - e.a[0], y - e.a[1]) <= std::hypot(x - e.b[0], y - e.b[1]);
    const auto& o = from_a ? e.a : e.b;
    return -((e.b[0] - e.a[0]) * (y - o[1]) - (e.b[1] - e.a[1]) * (x - o[0])) / e.length;
  }
  double from_a(int s, double x, double y) const {
    const Side& e = sides[static_cast<std::size_t>(s)];
    return ((x - e.a[0]) * (e.b[0] - e.a[0]) + (y - e.a[1]) * (e.b[1] - e.a[1])) / e.length;
  }
  double from_b(int s, double x, double y) const {
    const Side& e = sides[static_cast<std::size_t>(s)];
    return ((e.b[0] - x) * (e.b[0] - e.a[0]) + (e.b[1] - y) * (e.b[1] - e.a[1])) / e.length;
  }

  std::vector<Side> sides;

 private:
  int index(int d, double v) const {
    const double c = std::floor((v - lo_[d]) / cell_[d]);
    return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(n_ - 1)));
  }
  double lo_[2]{}, hi_[2]{}, cell_[2]{};
  int n_ = 1;
  std::vector<std::vector<int>> cells_;
};

// A polygon's outline moved out by a margin m in its plane (in, m < 0).
// The region within |m| of the polygon (m > 0) is the polygon, a strip
// along each side (a rectangle of the side's length and |m| wide,
// outside it) and a sector about each vertex where the outline turns
// towards the polygon (an outer corner): a point within |m| of the
// polygon is nearest to a side between its ends or to such a vertex. Its
// outline is thus made of the strips' outer sides and the sectors' arcs;
// each arc is drawn as tangents to it, each over at most 2 degrees of it
// (a sector so drawn holds the whole sector, and no point of its outline
// is nearer to the vertex than |m|). At an inner corner the two moved
// sides end where they meet. Each of these lines is cut where it crosses
// another, and a piece is kept where it lies in none of the strips and
// sectors (and not in the polygon) and has none on its right: where the
// moved outline meets itself (a slot narrower than 2 |m|, a hole that
// closes), only its part at |m| from the polygon is left. Below 0 the
// region is the polygon less the strips and sectors inside it, the
// sectors about the inner corners. The pieces are joined into rings, the
// part on their left.
class MarginOutline {
 public:
  using P2 = std::array<double, 2>;

  MarginOutline(const std::vector<Ring>& rings, double m) : poly_(rings), m_(m), a_(std::abs(m)) {
    if (!(a_ <= kFar)) throw std::runtime_error("the margin " + g(m) + " m is beyond 1e6 m");
    double lo[2] = {kFar, kFar}, hi[2] = {-kFar, -kFar};
    for (const Ring& r : rings)
      for (const P2& p : r)
        for (std::size_t d = 0; d < 2; ++d) {
          if (!(std::abs(p[d]) <= kFar)) throw std::runtime_error("a vertex lies beyond 1e6 m");
          lo[d] = std::min(lo[d], p[d]);
          hi[d] = std::max(hi[d], p[d]);
        }
    size_ = std::hypot(hi[0] - lo[0], hi[1] - lo[1]) + 2 * a_;
    eps_ = 1e-10 * size_;
    for (const TurnedRing& t : turned_rings(rings)) {
      Ring chain = t.vertices;  // the part on its left
      if (t.reverse) std::reverse(chain.begin(), chain.end());
      add_ring(chain);
    }
  }

  // The rings of the moved outline; throws std::runtime_error where its
  // pieces do not join into rings that neither cross nor touch.
  std::vector<Ring> rings() {
    split();
    return join();
  }

  // The diagonal of the polygon's extent (m).
  double polygon_size() const { return size_ - 2 * a_; }

 private:
  struct Edge {
    P2 a, b;
    int part;  // the strip or sector it bounds
  };
  struct Part {
    // A strip: origin o, along d for len, across n (towards the margin)
    // for |m|. A sector: a convex polygon, anticlockwise.
    bool strip = true;
    P2 o{}, d{}, n{};
    double len = 0;
    std::vector<P2> fan;
    double lo[2]{}, hi[2]{};
  };

  void add_ring(const Ring& p) {
    const std::size_t n = p.size();
    std::vector<P2> d(n), out(n);  // each side's direction and outer normal
    std::vector<double> len(n), turn(n);
    for (std::size_t k = 0; k < n; ++k) {
      const P2& a = p[k];
      const P2& b = p[(k + 1) % n];
      len[k] = std::hypot(b[0] - a[0], b[1] - a[1]);
      d[k] = {(b[0] - a[0]) / len[k], (b[1] - a[1]) / len[k]};
      out[k] = {d[k][1], -d[k][0]};
    }
    // turn[k]: at the end of side k, towards side k + 1 (anticlockwise > 0).
    for (std::size_t k = 0; k < n; ++k) {
      const P2& u = d[k];
      const P2& w = d[(k + 1) % n];
      turn[k] = std::atan2(u[0] * w[1] - u[1] * w[0], u[0] * w[0] + u[1] * w[1]);
    }
    // At an inner corner (for this margin) the two moved sides meet at the
    // miter point, |m| tan(turn / 2) back along each from the corner: they
    // end there where both sides are more than twice that long (else they
    // run on to their ends and the pieces beyond the crossing fall inside
    // the other's strip). A miter short against the sides thus leaves no
    // sliver of a piece to judge.
    std::vector<char> miter(n, 0);
    std::vector<P2> at(n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t k1 = (k + 1) % n;
      if (m_ * turn[k] > 0 || turn[k] == 0) continue;
      const double back = a_ * std::tan(0.5 * std::abs(turn[k]));
      if (!(2 * back < len[k] && 2 * back < len[k1])) continue;
      const double c = 1 + out[k][0] * out[k1][0] + out[k][1] * out[k1][1];
      const P2& v = p[k1];
      miter[k] = 1;
      at[k] = {v[0] + m_ * (out[k][0] + out[k1][0]) / c, v[1] + m_ * (out[k][1] + out[k1][1]) / c};
    }
    const double sign = m_ > 0 ? 1.0 : -1.0;
    const double step = 2.0 * std::acos(-1.0) / 180.0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t k1 = (k + 1) % n, k0 = (k + n - 1) % n;
      const P2& ea = p[k];
      const P2& eb = p[k1];
      Part st;
      st.o = ea;
      st.d = d[k];
      st.n = {sign * out[k][0], sign * out[k][1]};
      st.len = len[k];
      const P2 ea_out{ea[0] + m_ * out[k][0], ea[1] + m_ * out[k][1]};
      const P2 eb_out{eb[0] + m_ * out[k][0], eb[1] + m_ * out[k][1]};
      box(st, {ea, eb, ea_out, eb_out});
      const P2 a = miter[k0] ? at[k0] : ea_out, b = miter[k] ? at[k] : eb_out;
      parts_.push_back(st);
      edges_.push_back({a, b, static_cast<int>(parts_.size() - 1)});
      // The corner at the side's end, towards the next side: an arc about it
      // where the outline turns towards the polygon (for this margin).
      if (!(m_ * turn[k] > 0)) continue;
      const int chords = std::max(1, static_cast<int>(std::ceil(std::abs(turn[k]) / step - 1e-9)));
      Part fan;
      fan.strip = false;
      std::vector<P2> q{b};
      const double reach = m_ / std::cos(0.5 * std::abs(turn[k]) / chords);  // the tangents' corners
      for (int j = 0; j < chords; ++j) {
        const double t = turn[k] * (j + 0.5) / chords, c = std::cos(t), sn = std::sin(t);
        const P2 r{c * out[k][0] - sn * out[k][1], sn * out[k][0] + c * out[k][1]};
        q.push_back({eb[0] + reach * r[0], eb[1] + reach * r[1]});
      }
      q.push_back({eb[0] + m_ * out[k1][0], eb[1] + m_ * out[k1][1]});
      fan.fan.push_back(eb);
      if (turn[k] > 0) {
        fan.fan.insert(fan.fan.end(), q.begin(), q.end());
      } else {
        fan.fan.insert(fan.fan.end(), q.rbegin(), q.rend());
      }
      box(fan, fan.fan);
      parts_.push_back(fan);
      for (std::size_t j = 0; j + 1 < q.size(); ++j)
        edges_.push_back({q[j], q[j + 1], static_cast<int>(parts_.size() - 1)});
    }
  }

  static void box(Part& p, const std::vector<P2>& pts) {
    p.lo[0] = p.lo[1] = std::numeric_limits<double>::infinity();
    p.hi[0] = p.hi[1] = -std::numeric_limits<double>::infinity();
    for (const P2& q : pts)
      for (std::size_t d = 0; d < 2; ++d) {
        p.lo[d] = std::min(p.lo[d], q[d]);
        p.hi[d] = std::max(p.hi[d], q[d]);
      }
  }

  // Whether q lies inside part p by more than eps.
  bool deep_inside(const Part& p, const P2& q) const {
    if (q[0] < p.lo[0] || q[0] > p.hi[0] || q[1] < p.lo[1] || q[1] > p.hi[1]) return false;
    if (p.strip) {
      const double u = (q[0] - p.o[0]) * p.d[0] + (q[1] - p.o[1]) * p.d[1];
      const double v = (q[0] - p.o[0]) * p.n[0] + (q[1] - p.o[1]) * p.n[1];
      return u > eps_ && u < p.len - eps_ && v > eps_ && v < a_ - eps_;
    }
    const std::size_t n = p.fan.size();
    for (std::size_t k = 0; k < n; ++k) {
      const P2& u = p.fan[k];
      const P2& w = p.fan[(k + 1) % n];
      const double l = std::hypot(w[0] - u[0], w[1] - u[1]);
      if (!(cross2(u, w, q) > eps_ * l)) return false;
    }
    return true;
  }

  // The cells of a grid over every edge and part, each listing the edges
  // and parts whose extent reaches into it.
  void grid() {
    lo_[0] = lo_[1] = std::numeric_limits<double>::infinity();
    hi_[0] = hi_[1] = -std::numeric_limits<double>::infinity();
    for (const Part& p : parts_)
      for (std::size_t d = 0; d < 2; ++d) {
        lo_[d] = std::min(lo_[d], p.lo[d]);
        hi_[d] = std::max(hi_[d], p.hi[d]);
      }
    n_ = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(edges_.size())))), 1, 1024);
    for (std::size_t d = 0; d < 2; ++d) cell_[d] = std::max((hi_[d] - lo_[d]) / n_, 1e-300);
    edge_cells_.assign(static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_), {});
    part_cells_.assign(edge_cells_.size(), {});
    for (std::size_t k = 0; k < edges_.size(); ++k) {
      const Edge& e = edges_[k];
      for_cells(std::min(e.a[0], e.b[0]) - eps_, std::max(e.a[0], e.b[0]) + eps_, std::min(e.a[1], e.b[1]) - eps_,
                std::max(e.a[1], e.b[1]) + eps_, [&](std::size_t c) { edge_cells_[c].push_back(static_cast<int>(k)); });
    }
    for (std::size_t k = 0; k < parts_.size(); ++k)
      for_cells(parts_[k].lo[0], parts_[k].hi[0], parts_[k].lo[1], parts_[k].hi[1],
                [&](std::size_t c) { part_cells_[c].push_back(static_cast<int>(k)); });
  }
  int index(std::size_t d, double v) const {
    const double c = std::floor((v - lo_[d]) / cell_[d]);
    return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(n_ - 1)));
  }
  template <class F>
  void for_cells(double x0, double x1, double y0, double y1, F&& f) const {
    for (int r = index(1, y0); r <= index(1, y1); ++r)
      for (int c = index(0, x0); c <= index(0, x1); ++c) f(static_cast<std::size_t>(r) * n_ + c);
  }

  // Each edge cut where another crosses it (or, along the same line,
  // where the other's ends lie on it), and its pieces kept where they lie
  // outside every part (and outside the polygon for m > 0, inside it for
  // m < 0).
  void split() {
    grid();
    std::vector<std::vector<double>> cuts(edges_.size());
    for (const auto& cell : edge_cells_)
      for (std::size_t i = 0; i < cell.size(); ++i)
        for (std::size_t j = i + 1; j < cell.size(); ++j) {
          const std::size_t p = static_cast<std::size_t>(std::min(cell[i], cell[j]));
          const std::size_t q = static_cast<std::size_t>(std::max(cell[i], cell[j]));
          crossing(p, q, cuts[p], cuts[q]);
        }
    for (std::size_t k = 0; k < edges_.size(); ++k) {
      const Edge& e = edges_[k];
      const double len = std::hypot(e.b[0] - e.a[0], e.b[1] - e.a[1]);
      auto& t = cuts[k];
      t.push_back(1.0);
      std::sort(t.begin(), t.end());
      double from = 0;
      P2 a = e.a;
      for (const double to : t) {
        if ((to - from) * len <= eps_ && to < 1.0) continue;  // one point with the cut before
        const P2 b = to >= 1.0 ? e.b : P2{e.a[0] + to * (e.b[0] - e.a[0]), e.a[1] + to * (e.b[1] - e.a[1])};
        // Judged at three points (one that lies on a line between two
        // parts, the polygon's side where the piece passes from a strip
        // into the polygon, says nothing), and beside each on the right,
        // which must lie outside the region: a piece along a line between
        // two parts (a strip's end) has the region on both sides. (Not
        // beside a piece so short that the points beside it lie near its
        // ends: a corner's tangents about a vertex with a margin near the
        // round-off.)
        const double l = std::hypot(b[0] - a[0], b[1] - a[1]);
        const P2 right{4 * eps_ * (b[1] - a[1]) / l, -4 * eps_ * (b[0] - a[0]) / l};
        bool keep = true;
        for (const double f : {0.5, 0.25, 0.75}) {
          const P2 q{a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])};
          keep = keep && kept(q, e.part) && (l <= 64 * eps_ || !in_region({q[0] + right[0], q[1] + right[1]}));
        }
        if (keep) pieces_.push_back({a, b, e.part});
        from = to;
        a = b;
      }
    }
  }

  void crossing(std::size_t p, std::size_t q, std::vector<double>& tp, std::vector<double>& tq) const {
    const Edge& e = edges_[p];
    const Edge& f = edges_[q];
    const P2 r{e.b[0] - e.a[0], e.b[1] - e.a[1]}, s{f.b[0] - f.a[0], f.b[1] - f.a[1]};
    const double lr = std::hypot(r[0], r[1]), ls = std::hypot(s[0], s[1]);
    if (std::max(e.a[0], e.b[0]) + eps_ < std::min(f.a[0], f.b[0]) ||
        std::max(f.a[0], f.b[0]) + eps_ < std::min(e.a[0], e.b[0]) ||
        std::max(e.a[1], e.b[1]) + eps_ < std::min(f.a[1], f.b[1]) ||
        std::max(f.a[1], f.b[1]) + eps_ < std::min(e.a[1], e.b[1]))
      return;
    auto add = [&](std::vector<double>& t, double v, double l) {
      if (v * l > eps_ && (1 - v) * l > eps_) t.push_back(v);
    };
    const double den = r[0] * s[1] - r[1] * s[0];
    const P2 w{f.a[0] - e.a[0], f.a[1] - e.a[1]};
    if (std::abs(den) > 1e-12 * lr * ls) {
      const double t = (w[0] * s[1] - w[1] * s[0]) / den, u = (w[0] * r[1] - w[1] * r[0]) / den;
      if (t * lr < -eps_ || (t - 1) * lr > eps_ || u * ls < -eps_ || (u - 1) * ls > eps_) return;
      add(tp, t, lr);
      add(tq, u, ls);
      return;
    }
    // Parallel: along one line, each cut where the other's ends lie on it.
    if (std::abs(w[0] * r[1] - w[1] * r[0]) > eps_ * lr) return;
    for (const P2& c : {f.a, f.b}) add(tp, ((c[0] - e.a[0]) * r[0] + (c[1] - e.a[1]) * r[1]) / (lr * lr), lr);
    for (const P2& c : {e.a, e.b}) add(tq, ((c[0] - f.a[0]) * s[0] + (c[1] - f.a[1]) * s[1]) / (ls * ls), ls);
  }

  // Whether q lies in the region (inside the polygon or deep inside a
  // part for m > 0; inside the polygon and no part for m < 0).
  bool in_region(const P2& q) const {
    bool deep = false;
    const auto& cell = part_cells_[static_cast<std::size_t>(index(1, q[1])) * n_ + index(0, q[0])];
    for (const int k : cell) deep = deep || deep_inside(parts_[static_cast<std::size_t>(k)], q);
    return m_ > 0 ? deep || poly_.inside(q[0], q[1]) : !deep && poly_.inside(q[0], q[1]);
  }

  bool kept(const P2& q, int own) const {
    if (poly_.inside(q[0], q[1]) != (m_ < 0)) return false;
    const auto& cell = part_cells_[static_cast<std::size_t>(index(1, q[1])) * n_ + index(0, q[0])];
    for (const int k : cell)
      if (k != own && deep_inside(parts_[static_cast<std::size_t>(k)], q)) return false;
    return true;
  }

  // The pieces joined end to start into rings: ends within 4 eps are one
  // point; a piece there twice is kept once, pieces both ways are dropped.
  std::vector<Ring> join() {
    std::vector<P2> points;
    std::unordered_map<long long, std::vector<int>> at;  // grid cells of 16 eps
    const double h = 16 * eps_;
    auto key = [&](long long i, long long j) { return i * 73856093LL ^ j * 19349663LL; };
    auto id = [&](const P2& p) {
      const long long i = static_cast<long long>(std::floor(p[0] / h));
      const long long j = static_cast<long long>(std::floor(p[1] / h));
      for (long long di = -1; di <= 1; ++di)
        for (long long dj = -1; dj <= 1; ++dj) {
          const auto f = at.find(key(i + di, j + dj));
          if (f == at.end()) continue;
          for (const int k : f->second) {
            const P2& q = points[static_cast<std::size_t>(k)];
            if (std::hypot(q[0] - p[0], q[1] - p[1]) <= 4 * eps_) return k;
          }
        }
      points.push_back(p);
      at[key(i, j)].push_back(static_cast<int>(points.size() - 1));
      return static_cast<int>(points.size() - 1);
    };
    std::set<std::pair<int, int>> links;
    for (const Edge& e : pieces_) {
      const int a = id(e.a), b = id(e.b);
      if (a == b) continue;
      if (links.erase({b, a})) continue;  // both ways: no outline there
      links.insert({a, b});
    }
    auto where = [&](int k) {
      const P2& q = points[static_cast<std::size_t>(k)];
      return "(" + g(q[0]) + ", " + g(q[1]) + ") m";
    };
    std::unordered_map<int, int> next;
    for (const auto& [a, b] : links)
      if (!next.emplace(a, b).second)
        throw std::runtime_error("the outline moved by the margin branches at " + where(a));
    std::vector<Ring> out;
    std::set<int> done;
    for (const auto& [a, b] : links) {
      if (done.count(a)) continue;
      Ring r;
      int k = a;
      while (!done.count(k)) {
        done.insert(k);
        r.push_back(points[static_cast<std::size_t>(k)]);
        const auto f = next.find(k);
        if (f == next.end()) throw std::runtime_error("the outline moved by the margin does not close at " + where(k));
        k = f->second;
      }
      if (k != a) throw std::runtime_error("the outline moved by the margin meets itself at " + where(k));
      // Vertices within 1e-9 of the size of each other are one.
      Ring q;
      for (const P2& p : r)
        if (q.empty() || std::hypot(p[0] - q.back()[0], p[1] - q.back()[1]) > 1e-9 * size_) q.push_back(p);
      while (q.size() > 1 && std::hypot(q[0][0] - q.back()[0], q[0][1] - q.back()[1]) <= 1e-9 * size_) q.pop_back();
      if (q.size() >= 3) out.push_back(std::move(q));
    }
    if (const auto meet = first_meeting_sides(out)) {
      const P2& p = out[(*meet)[0]][(*meet)[1]];
      throw std::runtime_error("the outline moved by the margin touches itself near (" + g(p[0]) + ", " + g(p[1]) +
                               ") m");
    }
    return out;
  }

  PlanPolygon poly_;
  double m_, a_;
  double size_ = 0, eps_ = 0;
  std::vector<Part> parts_;
  std::vector<Edge> edges_, pieces_;
  double lo_[2]{}, hi_[2]{}, cell_[2]{};
  int n_ = 1;
  std::vector<std::vector<int>> edge_cells_, part_cells_;
};

// The trims as a ply's pattern takes them: each plane, cylinder and
// sphere (and each polygon taken by its distance with a margin) as its
// level less the margin at every formed node, linear in each triangle;
// each polygon (its rings moved by the margin) as its sides in plan view,
// exact in each triangle, and whether each node lies inside it.
struct Trimming {
  // Levels within it of 0 are on the trim (m: 1e-10 of the formed ply's
  // size, far above the round-off of a level and far below any length
  // that matters): a point on two trims that coincide there (the same
  // plane twice, a plane along a polygon's side) is on both, not inside
  // one and outside the other by a rounding.
  double eps = 0;
  std::vector<std::vector<double>> linear;  // [trim][node], m
  std::vector<PlanPolygon> polygons;
  std::vector<std::vector<double>> plan;       // [polygon][2 node + 0, 1]: each node in the polygon's plane, m
  std::vector<std::vector<char>> node_inside;  // [polygon][node]
};

// combined: the trims as one level, the largest of their distances less
// the margin, linear in each triangle (a polygon's in its plane): corners
// where trims meet, and a polygon's, within about an element, but one
// level that changes sign where it does, whatever the trims' shapes.
Trimming make_trimming(const std::vector<double>& x, const std::vector<TrimSurface>& trims, double margin,
                       bool combined = false) {
  Trimming t;
  const long long n = static_cast<long long>(x.size() / 3);
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t k = 0; k < x.size(); ++k) {
    lo[k % 3] = std::min(lo[k % 3], x[k]);
    hi[k % 3] = std::max(hi[k % 3], x[k]);
  }
  t.eps = n > 0 ? 1e-10 * std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) : 0.0;
  // A level at every node; within eps of 0: 0 (a node on the trim to
  // round-off is on it).
  auto add_level = [&](auto&& level) {
    auto& l = t.linear.emplace_back(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static) if (n > 4096)
    for (long long i = 0; i < n; ++i) {
      const double f = level(&x[3 * i]);
      l[static_cast<std::size_t>(i)] = std::abs(f) <= t.eps ? 0.0 : f;
    }
    for (long long i = 0; i < n; ++i)
      if (!std::isfinite(l[static_cast<std::size_t>(i)]))
        throw std::runtime_error("the distance of node " + std::to_string(i) + " to the trim is not finite");
  };
  if (combined && !trims.empty()) {
    add_level([&](const double* q) {
      double l = -std::numeric_limits<double>::infinity();
      for (const TrimSurface& s : trims) l = std::max(l, surface_level(s, q) - (s.margin_in_rings ? 0.0 : margin));
      return l;
    });
    return t;
  }
  for (const TrimSurface& s : trims) {
    if (s.kind == TrimSurface::Kind::Polygon && (margin == 0 || s.margin_in_rings)) {
      const PlanPolygon& p = t.polygons.emplace_back(s.rings);
      auto& uv = t.plan.emplace_back(2 * static_cast<std::size_t>(n));
      auto& in = t.node_inside.emplace_back(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static) if (n > 4096)
      for (long long i = 0; i < n; ++i) {
        const double* q = &x[3 * i];
        const double u = q[0] * s.plan_u[0] + q[1] * s.plan_u[1] + q[2] * s.plan_u[2];
        const double v = q[0] * s.plan_v[0] + q[1] * s.plan_v[1] + q[2] * s.plan_v[2];
        uv[2 * static_cast<std::size_t>(i)] = u;
        uv[2 * static_cast<std::size_t>(i) + 1] = v;
        in[static_cast<std::size_t>(i)] = p.inside(u, v);
      }
      continue;
    }
    add_level([&](const double* q) { return surface_level(s, q) - margin; });
  }
  return t;
}

// A point of a triangle by its barycentric weights on the corners.
struct Weights {
  double w[3] = {0, 0, 0};
};

// A piece of the boundary of a triangle's part of the pattern, the
// pattern on its left: on the trim (a trim surface or a polygon's side)
// or along one of the triangle's edges; emitted when it belongs to the
// pattern's outline (not along an edge that another triangle shares).
struct Piece {
  Weights a, b;
  bool trim_a = false, trim_b = false, trim = false, emit = false;
};

// The part of one triangle inside every trim, as the pieces of its
// boundary: those of the triangle's edges inside the trims, and those of
// each trim's zero line (or polygon side) inside the triangle and the
// other trims. A plane's line and a polygon's sides are exact in the
// triangle, so that where two of them meet, the corner is too.
class TriangleCut {
 public:
  explicit TriangleCut(const Trimming& t) : t_(t) {}

  // The triangle's state: -1 outside the pattern, 1 inside it whole, 0 cut.
  int prepare(const int c[3]) {
    for (int k = 0; k < 3; ++k) c_[k] = c[k];
    lin_.clear();
    poly_.clear();
    sides_.clear();
    for (std::size_t j = 0; j < t_.linear.size(); ++j) {
      const auto& l = t_.linear[j];
      const double f0 = l[idx(0)], f1 = l[idx(1)], f2 = l[idx(2)];
      if (f0 > 0 && f1 > 0 && f2 > 0) return -1;
      if (f0 < 0 && f1 < 0 && f2 < 0) continue;
      lin_.push_back(static_cast<int>(j));
    }
    for (std::size_t p = 0; p < t_.polygons.size(); ++p) {
      const PlanPolygon& poly = t_.polygons[p];
      const auto& uv = t_.plan[p];
      double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
      for (int k = 0; k < 3; ++k)
        for (std::size_t d = 0; d < 2; ++d) {
          lo[d] = std::min(lo[d], uv[2 * idx(k) + d]);
          hi[d] = std::max(hi[d], uv[2 * idx(k) + d]);
        }
      const double grow = 10 * t_.eps;  // the sides within round-off of it too
      poly.near(lo[0] - grow, hi[0] + grow, lo[1] - grow, hi[1] + grow, near_);
      bool reached = false;
      for (const int s : near_) {
        SideAt sa{static_cast<int>(p), s, {}, {}, {}};
        auto snap = [&](double v) { return std::abs(v) <= t_.eps ? 0.0 : v; };
        for (int k = 0; k < 3; ++k) {  // a node on the side's line, or at its end, to round-off: on it
          const double u = uv[2 * idx(k)], v = uv[2 * idx(k) + 1];
          sa.f[k] = snap(poly.level(s, u, v));
          sa.sa[k] = snap(poly.from_a(s, u, v));
          sa.sb[k] = snap(poly.from_b(s, u, v));
        }
        if ((sa.f[0] > 0 && sa.f[1] > 0 && sa.f[2] > 0) || (sa.f[0] < 0 && sa.f[1] < 0 && sa.f[2] < 0)) continue;
        if ((sa.sa[0] < 0 && sa.sa[1] < 0 && sa.sa[2] < 0) || (sa.sb[0] < 0 && sa.sb[1] < 0 && sa.sb[2] < 0)) continue;
        sides_.push_back(sa);
        reached = true;
      }
      if (!reached) {  // no side reaches the triangle: inside or outside whole
        const auto& in = t_.node_inside[p];
        bool inside = in[idx(0)] != 0;
        if (in[idx(1)] != in[idx(0)] || in[idx(2)] != in[idx(0)]) {
          double cx = 0, cy = 0;
          for (int k = 0; k < 3; ++k) {
            cx += uv[2 * idx(k)] / 3;
            cy += uv[2 * idx(k) + 1] / 3;
          }
          inside = poly.inside(cx, cy);
        }
        if (!inside) return -1;
        continue;
      }
      poly_.push_back(static_cast<int>(p));
    }
    return lin_.empty() && poly_.empty() ? 1 : 0;
  }

  // Whether a point of the prepared triangle lies in the pattern, leaving
  // out one linear trim or one polygon (-1: none). A level at most `tol`
  // is inside: 0 for the triangle's edges (as the zero lines are found),
  // eps for a point on a trim (on another trim that coincides with it
  // there, it is inside that one too). Near a polygon's side (within
  // 10 eps, between its ends) the side's level decides, as it places the
  // side's line in the triangle; elsewhere the even-odd test in plan.
  bool kept(const Weights& w, int skip_linear, int skip_polygon, double tol) const {
    for (const int j : lin_) {
      if (j == skip_linear) continue;
      const auto& l = t_.linear[static_cast<std::size_t>(j)];
      if (w.w[0] * l[idx(0)] + w.w[1] * l[idx(1)] + w.w[2] * l[idx(2)] > tol) return false;
    }
    for (const int p : poly_) {
      if (p == skip_polygon) continue;
      double nearest = 10 * t_.eps, level = 0;
      bool near = false;
      for (const SideAt& sa : sides_) {
        if (sa.poly != p) continue;
        const double f = dot3(w, sa.f);
        if (std::abs(f) > nearest) continue;
        if (dot3(w, sa.sa) < -10 * t_.eps || dot3(w, sa.sb) < -10 * t_.eps) continue;
        nearest = std::abs(f);
        level = f;
        near = true;
      }
      if (near) {
        if (level > tol) return false;
        continue;
      }
      double px = 0, py = 0;
      for (int k = 0; k < 3; ++k) {
        px += w.w[k] * t_.plan[static_cast<std::size_t>(p)][2 * idx(k)];
        py += w.w[k] * t_.plan[static_cast<std::size_t>(p)][2 * idx(k) + 1];
      }
      if (!t_.polygons[static_cast<std::size_t>(p)].inside(px, py)) return false;
    }
    return true;
  }

  // The boundary pieces of the prepared triangle (state 0), and the share
  // of its area inside the pattern (by the pieces' closed path in the
  // barycentric plane). boundary[k]: whether the edge from corner k to
  // k + 1 is on the blank's edge.
  double pieces(const bool boundary[3], std::vector<Piece>& out) {
    out_ = &out;
    out.clear();
    // The triangle's edges, each taken from its smaller node, as the other
    // triangle that has it takes it too, then turned round as need be.
    for (int k = 0; k < 3; ++k) {
      const int i = k, j = (k + 1) % 3;
      const bool forward = c_[i] < c_[j];
      Weights a, b;
      a.w[forward ? i : j] = 1;
      b.w[forward ? j : i] = 1;
      const std::size_t first = out.size();
      along(a, b, -1, -1, -1, false, boundary[k]);
      if (forward) continue;
      std::reverse(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
      for (std::size_t q = first; q < out.size(); ++q) {
        std::swap(out[q].a, out[q].b);
        std::swap(out[q].trim_a, out[q].trim_b);
      }
    }
    // Each linear trim's zero line.
    for (const int j : lin_) {
      const auto& l = t_.linear[static_cast<std::size_t>(j)];
      const double g[3] = {l[idx(0)], l[idx(1)], l[idx(2)]};
      Weights a, b;
      if (zero_line(g, a, b)) along(a, b, j, -1, -1, true, true);
    }
    // Each polygon side's piece in the triangle: its line between the
    // side's ends.
    for (std::size_t s = 0; s < sides_.size(); ++s) {
      const SideAt& sa = sides_[s];
      Weights a, b;
      if (!zero_line(sa.f, a, b)) continue;
      // The part where it is at least 0 from a and from b, each from its
      // own end.
      double u0 = 0, u1 = 1;
      bool empty = false;
      for (const double* from : {sa.sa, sa.sb}) {
        const double ta = dot3(a, from), tb = dot3(b, from);
        if (ta < 0 && tb < 0) empty = true;
        else if (ta < 0) u0 = std::max(u0, ta / (ta - tb));
        else if (tb < 0) u1 = std::min(u1, ta / (ta - tb));
      }
      if (empty || !(u1 > u0)) continue;
      along(lerp(a, b, u0), lerp(a, b, u1), -1, static_cast<int>(s), sa.poly, true, true);
    }
    // Trims that coincide here give the same piece more than once: one is
    // kept; where it comes both ways (the trims' parts meet along it only)
    // none.
    auto same = [](const Weights& u, const Weights& v) {
      return std::abs(u.w[0] - v.w[0]) <= 1e-9 && std::abs(u.w[1] - v.w[1]) <= 1e-9 &&
             std::abs(u.w[2] - v.w[2]) <= 1e-9;
    };
    std::vector<char>& drop = drop_;
    drop.assign(out.size(), 0);
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!out[i].trim || drop[i]) continue;
      bool reversed = false;
      for (std::size_t j = i + 1; j < out.size(); ++j) {
        if (!out[j].trim || drop[j]) continue;
        if (same(out[i].a, out[j].a) && same(out[i].b, out[j].b)) {
          drop[j] = 1;
        } else if (same(out[i].a, out[j].b) && same(out[i].b, out[j].a)) {
          drop[j] = 1;
          reversed = true;
        }
      }
      if (reversed) drop[i] = 1;
    }
    std::size_t kept_pieces = 0;
    for (std::size_t i = 0; i < out.size(); ++i)
      if (!drop[i]) out[kept_pieces++] = out[i];
    out.resize(kept_pieces);
    double twice_area = 0;  // in the plane (w1, w2), where the triangle has 1/2
    for (const Piece& q : out) twice_area += q.a.w[1] * q.b.w[2] - q.a.w[2] * q.b.w[1];
    return std::clamp(twice_area, 0.0, 1.0);
  }

 private:
  struct SideAt {
    int poly = 0, side = 0;
    // The side's level, and how far along it from a and back from b, at
    // the corners (m).
    double f[3] = {0, 0, 0}, sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
  };

  std::size_t idx(int k) const { return static_cast<std::size_t>(c_[k]); }
  static double dot3(const Weights& w, const double* v) { return w.w[0] * v[0] + w.w[1] * v[1] + w.w[2] * v[2]; }
  // A level that goes from one side of 0 to the other (by more than tol
  // either way).
  static bool crosses(double fa, double fb, double tol) {
    return (fa < -tol && fb > tol) || (fa > tol && fb < -tol);
  }
  static Weights lerp(const Weights& a, const Weights& b, double u) {
    Weights w;
    for (int k = 0; k < 3; ++k) w.w[k] = a.w[k] + u * (b.w[k] - a.w[k]);
    return w;
  }

  // The zero line of the linear function with corner values g in the
  // triangle, directed with the negative side on its left: false where
  // it misses the triangle, touches it at a corner, covers it, or runs
  // along an edge with the triangle on its left (that edge is the
  // triangle's own: its pieces come from the edge). Crossings of edges
  // are placed from the edge's smaller node.
  bool zero_line(const double g[3], Weights& a, Weights& b) const {
    Weights p[3];
    bool node[3] = {false, false, false};
    int n = 0, corner[3] = {-1, -1, -1};
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (g[i] == 0) {
        p[n].w[i] = 1;
        node[n] = true;
        corner[n] = i;
        ++n;
      } else if ((g[i] < 0 && g[j] > 0) || (g[i] > 0 && g[j] < 0)) {
        if (c_[i] < c_[j]) {
          const double t = g[i] / (g[i] - g[j]);
          p[n].w[i] = 1 - t;
          p[n].w[j] = t;
        } else {
          const double t = g[j] / (g[j] - g[i]);
          p[n].w[j] = 1 - t;
          p[n].w[i] = t;
        }
        ++n;
      }
    }
    if (n != 2) return false;
    a = p[0];
    b = p[1];
    const double d1 = -(g[2] - g[0]), d2 = g[1] - g[0];
    if ((b.w[1] - a.w[1]) * d1 + (b.w[2] - a.w[2]) * d2 < 0) std::swap(a, b);
    if (node[0] && node[1]) {
      const int third = 3 - corner[0] - corner[1];
      if (g[third] < 0) return false;  // along an edge, the triangle (in the part) on its left
    }
    return true;
  }

  // The pieces of the segment a -> b inside every trim but its own
  // (own_linear, or own_side of own_polygon), split where it crosses
  // another trim's line or side. A triangle's edge is taken strictly, as
  // the zero lines cross it; a trim's piece with the tolerance eps (a
  // level within eps of 0 at both of its ends is on that trim along it).
  void along(const Weights& a, const Weights& b, int own_linear, int own_side, int own_polygon, bool trim,
             bool emit) {
    const double tol = trim ? t_.eps : 0.0;
    us_.assign({0.0, 1.0});
    for (const int j : lin_) {
      if (j == own_linear) continue;
      const auto& l = t_.linear[static_cast<std::size_t>(j)];
      const double g[3] = {l[idx(0)], l[idx(1)], l[idx(2)]};
      const double fa = dot3(a, g), fb = dot3(b, g);
      if (crosses(fa, fb, tol)) us_.push_back(fa / (fa - fb));
    }
    for (std::size_t s = 0; s < sides_.size(); ++s) {
      if (static_cast<int>(s) == own_side) continue;
      const SideAt& sa = sides_[s];
      const double fa = dot3(a, sa.f), fb = dot3(b, sa.f);
      if (!crosses(fa, fb, tol)) continue;
      const double u = fa / (fa - fb);
      const double from_a = dot3(a, sa.sa) + u * (dot3(b, sa.sa) - dot3(a, sa.sa));
      const double from_b = dot3(a, sa.sb) + u * (dot3(b, sa.sb) - dot3(a, sa.sb));
      if (from_a >= -t_.eps && from_b >= -t_.eps) us_.push_back(u);
    }
    std::sort(us_.begin(), us_.end());
    us_.erase(std::unique(us_.begin(), us_.end()), us_.end());
    // A run of kept parts is one piece along an edge; along a trim each
    // part is one, so that where another trim coincides with it over part
    // of it, the two give the same pieces there.
    double from = -1;  // the start of the kept run
    for (std::size_t k = 0; k + 1 < us_.size(); ++k) {
      const double ua = us_[k], ub = us_[k + 1];
      const bool in = kept(lerp(a, b, 0.5 * (ua + ub)), own_linear, own_polygon, tol);
      if (in && from < 0) from = ua;
      if ((!in || trim || k + 2 == us_.size()) && from >= 0) {
        const double to = in ? ub : ua;
        Piece q;
        q.a = lerp(a, b, from);
        q.b = lerp(a, b, to);
        q.trim_a = trim || from > 0;
        q.trim_b = trim || to < 1;
        q.trim = trim;
        q.emit = emit;
        out_->push_back(q);
        from = -1;
      }
    }
  }

  const Trimming& t_;
  int c_[3] = {0, 0, 0};
  std::vector<int> lin_, poly_, near_;
  std::vector<SideAt> sides_;
  std::vector<double> us_;
  std::vector<Piece>* out_ = nullptr;
  std::vector<char> drop_;
};

}  // namespace

namespace {

// An outline that does not close.
struct OpenOutline : std::runtime_error {
  using std::runtime_error::runtime_error;
};

CutPattern cut_with(const std::vector<double>& x0, const std::vector<double>& x, const std::vector<int>& tri,
                    const Trimming& trimming) {
  const std::size_t n = x0.size() / 3, m = tri.size() / 3;
  // How many triangles have each edge (smaller node first).
  std::unordered_map<std::uint64_t, int> uses;
  auto edge_key = [](int a, int b) {
    const int lo = std::min(a, b), hi = std::max(a, b);
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(lo)) << 32) | static_cast<std::uint32_t>(hi);
  };
  for (std::size_t e = 0; e < m; ++e)
    for (int k = 0; k < 3; ++k) ++uses[edge_key(tri[3 * e + k], tri[3 * e + (k + 1) % 3])];
  struct Segment {
    Vec b0, f0, b1, f1;  // the ends in the blank and formed
    bool on0 = false, on1 = false, trim = false;
  };
  std::vector<Segment> segments;  // the pattern on their left
  CutPattern p;
  TriangleCut cut(trimming);
  std::vector<Piece> pieces;
  for (std::size_t e = 0; e < m; ++e) {
    const int c[3] = {tri[3 * e], tri[3 * e + 1], tri[3 * e + 2]};
    auto place = [&](const Weights& w, const std::vector<double>& pos) {
      Vec q{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const Vec corner = at(pos, static_cast<std::size_t>(c[k]));
        for (int d = 0; d < 3; ++d) q[static_cast<std::size_t>(d)] += w.w[k] * corner[static_cast<std::size_t>(d)];
      }
      return q;
    };
    const double a0 = triangle_area(x0, c), a = triangle_area(x, c);
    p.blank_area += a0;
    const int state = cut.prepare(c);
    if (state < 0) continue;
    bool boundary[3];
    for (int k = 0; k < 3; ++k) boundary[k] = uses[edge_key(c[k], c[(k + 1) % 3])] == 1;
    if (state > 0) {
      p.kept_blank_area += a0;
      p.kept_formed_area += a;
      for (int k = 0; k < 3; ++k)
        if (boundary[k]) {
          Weights u, v;
          u.w[k] = 1;
          v.w[(k + 1) % 3] = 1;
          segments.push_back({place(u, x0), place(u, x), place(v, x0), place(v, x), false, false, false});
        }
      continue;
    }
    const double share = cut.pieces(boundary, pieces);
    p.kept_blank_area += share * a0;
    p.kept_formed_area += share * a;
    for (const Piece& q : pieces)
      if (q.emit)
        segments.push_back({place(q.a, x0), place(q.a, x), place(q.b, x0), place(q.b, x), q.trim_a, q.trim_b, q.trim});
  }
  // The segments' ends as points of the blank: ends within 1e-9 of the
  // blank's size of each other are one point (a corner where two trims
  // meet, or a polygon's vertex, is found in the triangle of each of its
  // lines, to round-off).
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], x0[3 * i + static_cast<std::size_t>(d)]);
      hi[d] = std::max(hi[d], x0[3 * i + static_cast<std::size_t>(d)]);
    }
  const double size = n ? std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) : 0.0;
  const double tol = size > 0 ? 1e-9 * size : 1e-300;
  struct Point {
    Vec blank, formed;
    bool on_trim;
  };
  std::vector<Point> points;
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  auto cell = [](long long i, long long j, long long k) {
    std::uint64_t h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(j) + 0x7F4A7C159E3779B9ULL + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k) + 0x94D049BB133111EBULL + (h << 6) + (h >> 2);
    return h;
  };
  auto point_of = [&](const Vec& b, const Vec& f, bool on) {
    long long g[3];
    for (int d = 0; d < 3; ++d)
      g[d] = static_cast<long long>(std::floor((b[static_cast<std::size_t>(d)] - lo[d]) / tol));
    for (long long i = g[0] - 1; i <= g[0] + 1; ++i)
      for (long long j = g[1] - 1; j <= g[1] + 1; ++j)
        for (long long k = g[2] - 1; k <= g[2] + 1; ++k) {
          const auto it = cells.find(cell(i, j, k));
          if (it == cells.end()) continue;
          for (const int id : it->second) {
            Point& q = points[static_cast<std::size_t>(id)];
            if (std::abs(q.blank[0] - b[0]) <= tol && std::abs(q.blank[1] - b[1]) <= tol &&
                std::abs(q.blank[2] - b[2]) <= tol) {
              q.on_trim = q.on_trim || on;
              return id;
            }
          }
        }
    points.push_back({b, f, on});
    cells[cell(g[0], g[1], g[2])].push_back(static_cast<int>(points.size() - 1));
    return static_cast<int>(points.size() - 1);
  };
  // Directed segments between points; one and its reverse cancel (a
  // trim line along an edge seen from both of its triangles), a second
  // alike is left out.
  std::vector<std::array<int, 2>> ends;
  std::vector<char> trim_segment;
  {
    std::unordered_map<std::uint64_t, std::size_t> open;
    std::vector<char> alive;
    auto key = [](int a, int b) {
      return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
    };
    std::vector<std::array<int, 2>> all;
    std::vector<char> all_trim;
    for (const Segment& s : segments) {
      const int a = point_of(s.b0, s.f0, s.on0), b = point_of(s.b1, s.f1, s.on1);
      if (a == b) continue;
      if (const auto it = open.find(key(b, a)); it != open.end()) {
        alive[it->second] = 0;
        open.erase(it);
        continue;
      }
      if (open.count(key(a, b))) continue;
      open[key(a, b)] = all.size();
      all.push_back({a, b});
      all_trim.push_back(s.trim ? 1 : 0);
      alive.push_back(1);
    }
    for (std::size_t s = 0; s < all.size(); ++s)
      if (alive[s]) {
        ends.push_back(all[s]);
        trim_segment.push_back(all_trim[s]);
      }
  }
  // The segments joined into closed outlines, in the order of their
  // triangles (where two outlines touch at a point, the first segment
  // not yet taken out of it).
  std::unordered_map<int, std::vector<int>> out_of;
  for (std::size_t s = 0; s < ends.size(); ++s) out_of[ends[s][0]].push_back(static_cast<int>(s));
  std::vector<char> taken(ends.size(), 0);
  for (std::size_t s0 = 0; s0 < ends.size(); ++s0) {
    if (taken[s0]) continue;
    std::vector<int> chain;
    int s = static_cast<int>(s0);
    const int start = ends[s0][0];
    while (true) {
      taken[static_cast<std::size_t>(s)] = 1;
      chain.push_back(s);
      const int next = ends[static_cast<std::size_t>(s)][1];
      if (next == start) break;
      int follow = -1;
      if (const auto it = out_of.find(next); it != out_of.end())
        for (const int t : it->second)
          if (!taken[static_cast<std::size_t>(t)]) {
            follow = t;
            break;
          }
      if (follow < 0) {
        const Vec& b = points[static_cast<std::size_t>(next)].blank;
        throw OpenOutline("the outline does not close at (" + g(b[0]) + ", " + g(b[1]) + ", " + g(b[2]) +
                          ") m of the blank");
      }
      s = follow;
    }
    if (chain.size() < 3) continue;  // a touch of the trim surface at a point or along an edge
    Outline o;
    for (const int k : chain) {
      const Point& a = points[static_cast<std::size_t>(ends[static_cast<std::size_t>(k)][0])];
      const Point& b = points[static_cast<std::size_t>(ends[static_cast<std::size_t>(k)][1])];
      o.points.push_back({a.blank, a.formed, a.on_trim});
      const double l0 = norm(sub(b.blank, a.blank));
      o.length_blank += l0;
      o.length_formed += norm(sub(b.formed, a.formed));
      if (trim_segment[static_cast<std::size_t>(k)]) o.trim_length_blank += l0;
    }
    p.outlines.push_back(std::move(o));
  }
  return p;
}

}  // namespace

std::vector<std::vector<std::array<double, 2>>> polygon_margin_rings(const TrimSurface& t, double margin) {
  if (t.kind != TrimSurface::Kind::Polygon) throw std::runtime_error("not a polygon trim");
  if (margin == 0) return t.rings;
  MarginOutline outline(t.rings, margin);
  try {
    return outline.rings();
  } catch (const std::runtime_error&) {
    // Moved sides that coincide exactly (a polygon on a grid moved by a
    // whole or half spacing): the margin 1e-8 of the polygon's size
    // larger, then smaller, parts them.
    const double nudge = 1e-8 * outline.polygon_size() * (margin > 0 ? 1 : -1);
    for (const double moved : {margin + nudge, margin - nudge}) {
      try {
        return MarginOutline(t.rings, moved).rings();
      } catch (const std::runtime_error&) {
      }
    }
    throw;
  }
}

namespace {

// The trims as cut with a margin: each polygon's rings moved by it
// (margin_in_rings) where they can be, otherwise the polygon is taken by
// its distance; why, for each polygon trim (empty where moved).
std::vector<TrimSurface> with_margin(const std::vector<TrimSurface>& trims, double margin,
                                     std::vector<std::string>* why) {
  std::vector<TrimSurface> out = trims;
  for (TrimSurface& t : out) {
    if (t.kind != TrimSurface::Kind::Polygon || margin == 0) continue;
    if (t.margin_in_rings) {  // moved already
      if (why) why->emplace_back();
      continue;
    }
    try {
      t.rings = polygon_margin_rings(t, margin);
      t.margin_in_rings = true;
      if (why) why->emplace_back();
    } catch (const std::runtime_error& e) {
      if (why) why->push_back(e.what());
    }
  }
  return out;
}

}  // namespace

CutPattern cut_pattern(const std::vector<double>& x0, const std::vector<double>& x, const std::vector<int>& tri,
                       const std::vector<TrimSurface>& given, double margin) {
  std::vector<std::string> moved;
  const std::vector<TrimSurface> trims = with_margin(given, margin, &moved);
  if (x.size() != x0.size()) throw std::runtime_error("the blank and the formed ply have other numbers of nodes");
  for (std::size_t k = 0; k < x0.size(); ++k)
    if (!std::isfinite(x0[k]) || !std::isfinite(x[k]))
      throw std::runtime_error("node " + std::to_string(k / 3) + " has a position that is not finite");
  std::string open;
  try {
    CutPattern p = cut_with(x0, x, tri, make_trimming(x, trims, margin));
    p.polygon_margin = moved;
    return p;
  } catch (const OpenOutline& e) {
    open = e.what();
  }
  try {  // where the exact cut does not close (a trim too thin or too tangent there for the doubles)
    CutPattern p = cut_with(x0, x, tri, make_trimming(x, trims, margin, true));
    p.fallback = open;
    p.polygon_margin = moved;
    return p;
  } catch (const OpenOutline& e) {
    throw std::runtime_error(std::string(e.what()) + " (triangles not alike oriented?)");
  }
}

std::vector<FibreMark> fibre_marks(const std::vector<double>& x0, const std::vector<double>& x,
                                   const std::vector<int>& tri, const std::vector<TrimSurface>& trims,
                                   const std::vector<double>& fibre, const std::array<double, 3>& e1,
                                   const std::array<double, 3>& e2, double spacing, double margin,
                                   bool combined) {
  const std::size_t m = tri.size() / 3;
  const Trimming trimming = make_trimming(x, with_margin(trims, margin, nullptr), margin, combined);
  TriangleCut cut(trimming);
  std::vector<FibreMark> marks;
  std::set<std::pair<long long, long long>> taken;  // grid points already marked
  for (std::size_t e = 0; e < m; ++e) {
    const int corners[3] = {tri[3 * e], tri[3 * e + 1], tri[3 * e + 2]};
    const int state = cut.prepare(corners);
    if (state < 0) continue;
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      const Vec p = at(x0, static_cast<std::size_t>(tri[3 * e + k]));
      u[k] = dot(p, e1);
      v[k] = dot(p, e2);
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
        if (state == 0 && !cut.kept(Weights{{b0, b1, b2}}, -1, -1, 0.0)) continue;  // outside the pattern
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
  for (int k = -3; k < 3; ++k) {
    const double p = std::pow(10.0, k);
    for (const double f : {1.0, 2.0, 5.0})
      if (std::abs(std::log(f * p / want)) < std::abs(std::log(best / want))) best = f * p;
  }
  return best;
}

// DXF (AutoCAD R12, ASCII) in mm ($INSUNITS 4): a number, the header
// with a comment and the layers (name and colour), a closed POLYLINE of
// points (mm) and a LINE.
std::string dxf_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return std::string(buf);
}

void dxf_begin(std::ostream& f, const std::string& comment,
               const std::vector<std::pair<std::string, int>>& layers) {
  f << "999\n" << comment << "\n"
    << "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1009\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n"
    << "0\nSECTION\n2\nTABLES\n0\nTABLE\n2\nLAYER\n70\n" << layers.size() << "\n";
  for (const auto& [name, colour] : layers)
    f << "0\nLAYER\n2\n" << name << "\n70\n0\n62\n" << colour << "\n6\nCONTINUOUS\n";
  f << "0\nENDTAB\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n";
}

template <class Points>
void dxf_polyline(std::ostream& f, const char* layer, const Points& points) {
  f << "0\nPOLYLINE\n8\n" << layer << "\n66\n1\n70\n1\n10\n0.0\n20\n0.0\n30\n0.0\n";
  for (const auto& [x, y] : points)
    f << "0\nVERTEX\n8\n" << layer << "\n10\n" << dxf_number(x) << "\n20\n" << dxf_number(y) << "\n30\n0.0\n";
  f << "0\nSEQEND\n8\n" << layer << "\n";
}

void dxf_line(std::ostream& f, const char* layer, double x0, double y0, double x1, double y1) {
  f << "0\nLINE\n8\n" << layer << "\n10\n" << dxf_number(x0) << "\n20\n" << dxf_number(y0) << "\n30\n0.0\n11\n"
    << dxf_number(x1) << "\n21\n" << dxf_number(y1) << "\n31\n0.0\n";
}

// A ply's DXF file: each outline as a closed POLYLINE, the blank's on
// layer BLANK, the pattern's on PATTERN, and the fibre marks as LINEs on
// layer FIBRE.
bool write_dxf(const std::filesystem::path& file, const BlankPly& ply) {
  std::ofstream f(file);
  if (!f) return false;
  const auto axes = plane_axes(ply.normal);
  dxf_begin(f, "thermostamp blank: ply '" + ply.name + "', mm", {{"BLANK", 8}, {"PATTERN", 1}, {"FIBRE", 5}});
  auto outline = [&](const Outline& o, const char* layer) {
    std::vector<std::pair<double, double>> mm;
    for (const OutlinePoint& q : o.points) mm.emplace_back(1000 * dot(q.blank, axes[0]), 1000 * dot(q.blank, axes[1]));
    dxf_polyline(f, layer, mm);
  };
  for (const Outline& o : ply.blank.outlines) outline(o, "BLANK");
  for (const Outline& o : ply.pattern.outlines) outline(o, "PATTERN");
  for (const FibreMark& k : ply.marks)
    dxf_line(f, "FIBRE", 1000 * dot(k.from, axes[0]), 1000 * dot(k.from, axes[1]), 1000 * dot(k.to, axes[0]),
             1000 * dot(k.to, axes[1]));
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

// The fibres of the modelled ply (the triangles before its mirror images:
// a mirrored ply's first half or quarter) in the blank's plane: their
// area-weighted mean direction, degrees from axes[0] in (-90, 90], and the
// largest difference of a triangle's direction from it (degrees).
std::pair<double, double> fibre_angle(const FramePly& d, const std::vector<double>& fibre,
                                      const std::array<Vec, 2>& axes) {
  const std::size_t m = (d.tri.size() / 3) >> d.mirrored.size();
  double c2 = 0, s2 = 0;
  std::vector<double> phis;
  for (std::size_t e = 0; e < m && 3 * e + 2 < fibre.size(); ++e) {
    const Vec f = at(fibre, e);
    const double u = dot(f, axes[0]), v = dot(f, axes[1]);
    if (u == 0 && v == 0) continue;
    const double phi = std::atan2(v, u), w = triangle_area(d.x0, &d.tri[3 * e]);
    c2 += w * std::cos(2 * phi);
    s2 += w * std::sin(2 * phi);
    phis.push_back(phi);
  }
  const double pi = std::acos(-1.0);
  auto wrap = [pi](double a) {  // into (-pi/2, pi/2]: a direction, not a sense
    a = std::remainder(a, pi);
    return a <= -pi / 2 ? a + pi : a;
  };
  const double mean = wrap(0.5 * std::atan2(s2, c2));
  double spread = 0;
  for (const double phi : phis) spread = std::max(spread, std::abs(wrap(phi - mean)));
  return {mean * 180 / pi, spread * 180 / pi};
}

// A layout on the roll (roll axes, mm): the roll's two edges over its
// first `length` m on layer ROLL, and on layer PATTERN each copy (the
// unit's rings in `pieces` patterns of as many rings each; a copy is one
// of them moved). Returns the patterns drawn, -1 where the file cannot be
// written.
int write_roll_dxf(const std::filesystem::path& file, const std::string& title, const std::vector<Ring2>& unit,
                   int pieces, const std::vector<RollCopy>& copies, double width, double length) {
  std::ofstream f(file);
  if (!f) return -1;
  dxf_begin(f, title, {{"ROLL", 8}, {"PATTERN", 1}});
  for (const double y : {0.0, width}) dxf_line(f, "ROLL", 0, 1000 * y, 1000 * length, 1000 * y);
  const std::size_t per = unit.size() / static_cast<std::size_t>(pieces);
  for (const RollCopy& c : copies)
    for (std::size_t r = c.piece * per; r < (c.piece + 1) * per; ++r) {
      std::vector<std::pair<double, double>> mm;
      for (const auto& v : unit[r]) mm.emplace_back(1000 * (v[0] + c.offset[0]), 1000 * (v[1] + c.offset[1]));
      dxf_polyline(f, "PATTERN", mm);
    }
  f << "0\nENDSEC\n0\nEOF\n";
  f.close();
  return f ? static_cast<int>(copies.size()) : -1;
}

// The copies of a nest's lanes (pieces patterns per unit) that lie wholly
// within the first `length` m of the roll.
std::vector<RollCopy> copies_within(const std::vector<Ring2>& unit, int pieces, const RollNest& n, double gap,
                                    double length) {
  const std::vector<std::array<double, 2>> extent = piece_extents(unit, pieces);
  const double tol = 1e-9 * (n.length + n.width);
  std::vector<RollCopy> copies;
  for (int j = 0; j < n.lanes; ++j) {
    const double shift = std::fmod(j * n.lane_shift, n.pitch), dy = n.origin[1] + j * n.lane_step;
    for (int i = -2;; ++i) {
      const double dx = n.origin[0] + i * n.pitch + shift;
      if (gap / 2 + i * n.pitch + shift > length) break;  // the unit starts beyond the length drawn
      for (int k = 0; k < pieces; ++k) {
        const auto& e = extent[static_cast<std::size_t>(k)];
        if (dx + e[0] < -tol || dx + e[1] > length + tol) continue;
        copies.push_back({k, {dx, dy}});
      }
    }
  }
  return copies;
}

}  // namespace

BlankResult blank_plies(const std::filesystem::path& dir, std::optional<double> time,
                        const std::filesystem::path& out, bool whole, const std::vector<TrimSurface>& trims,
                        double margin, std::optional<RollOptions> roll) {
  if (trims.empty()) throw ExportInputError("no --trim: give the surface the part is trimmed at");
  if (!(std::abs(margin) <= kFar)) throw ExportInputError("--margin " + g(margin) + ": beyond 1e6 (m)");
  if (roll && !(roll->width > 0 && roll->width <= kFar))
    throw ExportInputError("--roll " + g(roll->width) + ": a roll width above 0 and at most 1e6 (m)");
  if (roll && !(roll->gap >= 0 && roll->gap <= kFar))
    throw ExportInputError("--gap " + g(roll->gap) + ": a gap of at least 0 and at most 1e6 (m)");
  if (roll && !(roll->parts >= 0 && roll->parts <= 10000))
    throw ExportInputError("--parts " + std::to_string(roll->parts) + ": a number of parts from 1 to 10000");
  // Each polygon's outline moved by the margin (found once for every
  // ply): its rings and vertices, or why it is taken by its distance.
  std::vector<std::string> why;
  const std::vector<TrimSurface> cut = with_margin(trims, margin, &why);
  nlohmann::json margins = nlohmann::json::object();
  std::size_t k = 0;
  for (const TrimSurface& t : cut) {
    if (t.kind != TrimSurface::Kind::Polygon || margin == 0) continue;
    nlohmann::json j;
    if (t.margin_in_rings) {
      if (t.rings.empty())
        throw ExportInputError("--margin " + g(margin) + " moves the outline of '" + t.text +
                               "' in by half its width or more: nothing of it is left");
      std::size_t vertices = 0;
      for (const auto& r : t.rings) vertices += r.size();
      j = {{"method", "moved"}, {"rings", t.rings.size()}, {"vertices", vertices}, {"fallback", nullptr}};
    } else {
      j = {{"method", "distance"}, {"fallback", why[k]}};
    }
    margins[t.text] = j;
    ++k;
  }
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
  doc["polygon_cut_directions"] = nlohmann::json::object();  // each polygon trim's, by its text
  for (const TrimSurface& t : trims)
    if (t.kind == TrimSurface::Kind::Polygon) doc["polygon_cut_directions"][t.text] = polygon_cut_direction(t);
  doc["margin_m"] = margin;
  if (roll) doc["roll"] = {{"width_m", roll->width}, {"gap_m", roll->gap}, {"turn_90", roll->turn_90}};
  doc["polygon_margins"] = margins;
  doc["plies"] = nlohmann::json::object();
  // The fibre directions of the blank: the first frame's field.
  const FramePlies first = read_frame_plies(dir, std::nullopt, whole, true, true);
  for (const FramePly& d : frame.plies) {
    BlankPly ply;
    ply.name = d.name;
    ply.mirrored = d.mirrored;
    try {
      ply.pattern = cut_pattern(d.x0, d.x, d.tri, cut, margin);
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
      ply.marks = fibre_marks(d.x0, d.x, d.tri, cut, *fibre, axes[0], axes[1], ply.mark_spacing, margin,
                              !ply.pattern.fallback.empty());
    }
    if (roll && ply.flat && !ply.pattern.outlines.empty()) {
      const auto axes = plane_axes(ply.normal);
      PlyNest pn;
      if (fibre) {
        std::tie(pn.fibre_angle_deg, pn.fibre_spread_deg) = fibre_angle(d, *fibre, axes);
        pn.fibres_known = true;
      }
      const double a = pn.fibre_angle_deg * std::acos(-1.0) / 180, c = std::cos(a), sn = std::sin(a);
      std::vector<Ring2> rings;
      for (const Outline& o : ply.pattern.outlines) {
        Ring2 r;
        for (const OutlinePoint& q : o.points) {
          const double u = dot(q.blank, axes[0]), v = dot(q.blank, axes[1]);
          r.push_back({c * u + sn * v, -sn * u + c * v});
        }
        rings.push_back(std::move(r));
      }
      pn.layout = lay_on_roll(rings, roll->width, roll->gap, true, 1000, roll->turn_90);
      const RollNest& n = pn.layout.nest;
      pn.drawn_length = std::max(1.0, 3 * n.pitch + n.length + roll->gap);
      pn.dxf = out / (d.name + "_nest.dxf");
      const int pieces = pn.layout.pairs ? 2 : 1;
      const std::string title = "thermostamp blank: ply '" + d.name + "' nested on a roll " +
                                dxf_number(1000 * roll->width) + " mm wide, fibres along x, mm";
      pn.drawn_copies =
          write_roll_dxf(pn.dxf, title, pn.layout.unit, pieces,
                         copies_within(pn.layout.unit, pieces, n, roll->gap, pn.drawn_length), roll->width,
                         pn.drawn_length);
      if (pn.drawn_copies < 0) throw std::runtime_error("cannot write '" + pn.dxf.string() + "'");
      if (roll->parts > 0 && n.lanes > 0) {
        pn.batch = lay_batch(pn.layout, roll->gap, roll->parts);
        pn.batch_dxf = out / (d.name + "_parts.dxf");
        const std::string batch_title = "thermostamp blank: ply '" + d.name + "', " + std::to_string(roll->parts) +
                                        " patterns on a roll " + dxf_number(1000 * roll->width) +
                                        " mm wide, fibres along x, mm";
        if (write_roll_dxf(pn.batch_dxf, batch_title, pn.layout.unit, pieces, pn.batch->copies, roll->width,
                           pn.batch->length) < 0)
          throw std::runtime_error("cannot write '" + pn.batch_dxf.string() + "'");
      }
      ply.nest = pn;
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
    j["method"] = p.fallback.empty() ? "exact" : "distance";
    j["fallback"] = p.fallback.empty() ? nlohmann::json(nullptr) : nlohmann::json(p.fallback);
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
    if (roll) {
      if (ply.nest) {
        const PlyNest& pn = *ply.nest;
        const RollNest& n = pn.layout.nest;
        auto known = [&](double v) { return pn.fibres_known ? nlohmann::json(v) : nlohmann::json(nullptr); };
        j["nest"] = {{"roll_width_m", roll->width},
                     {"gap_m", roll->gap},
                     {"fibre_angle_deg", known(pn.fibre_angle_deg)},
                     {"fibre_spread_deg", known(pn.fibre_spread_deg)},
                     {"pattern_length_m", pn.layout.length},
                     {"pattern_width_m", pn.layout.width},
                     {"pattern_area_m2", pn.layout.area},
                     {"turned_90", pn.layout.turned_90},
                     {"pairs_turned_180", pn.layout.pairs},
                     {"turned_offset_m", pn.layout.pairs ? nlohmann::json(pn.layout.turned) : nlohmann::json(nullptr)},
                     {"unit_length_m", n.length},
                     {"unit_width_m", n.width},
                     {"pitch_m", n.pitch},
                     {"lane_step_m", n.lane_step},
                     {"lane_shift_m", n.lane_shift},
                     {"lanes", n.lanes},
                     {"roll_length_per_pattern_m",
                      n.lanes > 0 ? nlohmann::json(pn.layout.roll_per_pattern) : nlohmann::json(nullptr)},
                     {"alike_roll_length_per_pattern_m", pn.layout.single_roll_per_pattern > 0
                                                             ? nlohmann::json(pn.layout.single_roll_per_pattern)
                                                             : nlohmann::json(nullptr)},
                     {"utilisation", n.utilisation},
                     {"resolution_m", n.resolution},
                     {"dxf", pn.dxf.filename().string()},
                     {"drawn_length_m", pn.drawn_length},
                     {"drawn_copies", pn.drawn_copies}};
        if (roll->parts > 0 && !pn.batch) j["nest"]["parts"] = nullptr;  // no lane fits
        if (pn.batch)
          j["nest"]["parts"] = {{"count", roll->parts},
                                {"roll_length_m", pn.batch->length},
                                {"dxf", pn.batch_dxf.filename().string()}};
      } else {
        j["nest"] = nullptr;
        j["nest_left_out"] = ply.pattern.outlines.empty() ? "nothing of the ply lies inside the trim"
                                                           : "the blank is not flat";
      }
    }
    doc["plies"][d.name] = j;
    res.plies.push_back(std::move(ply));
  }
  if (roll) {
    double sum = 0, batch = 0;
    std::vector<std::string> why;
    for (const BlankPly& ply : res.plies) {
      if (ply.pattern.outlines.empty()) continue;  // nothing of it in the part
      if (!ply.nest)
        why.push_back("ply '" + ply.name + "' is not nested: its blank is not flat");
      else if (ply.nest->layout.nest.lanes == 0)
        why.push_back("ply '" + ply.name + "' does not fit on the roll");
      else {
        sum += ply.nest->layout.roll_per_pattern;
        if (ply.nest->batch) batch += ply.nest->batch->length;
      }
    }
    if (why.empty()) {
      res.roll_per_part = sum;
      if (roll->parts > 0) res.roll_for_parts = batch;
    }
    for (const std::string& w : why)
      res.roll_per_part_left_out += (res.roll_per_part_left_out.empty() ? "" : "; ") + w;
    doc["roll"]["roll_length_per_part_m"] = res.roll_per_part ? nlohmann::json(sum) : nlohmann::json(nullptr);
    if (!res.roll_per_part) doc["roll"]["roll_length_per_part_left_out"] = res.roll_per_part_left_out;
    if (roll->parts > 0) {
      doc["roll"]["parts"] = roll->parts;
      doc["roll"]["roll_length_for_parts_m"] =
          res.roll_for_parts ? nlohmann::json(*res.roll_for_parts) : nlohmann::json(nullptr);
    }
  }
  res.json = out / "blank.json";
  std::ofstream f(res.json);
  f << doc.dump(2) << "\n";
  f.close();
  if (!f) throw std::runtime_error("cannot write '" + res.json.string() + "'");
  return res;
}

}  // namespace ts
