#include "solve/tools.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/simd.hpp>

#include "io/fnv1a.hpp"
#include "job/errors.hpp"
#include "mesh/shell_mesh.hpp"

namespace ts {

using sdk::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Outward normal on an arc at a point c at distance `radius` from its
// centre: along the radius, towards the centre when the arc turns
// counter-clockwise (orient +1; walking counter-clockwise the left side is
// the centre's side), away from it otherwise.
std::array<double, 2> arc_normal(const ProfileSegment& s, const std::array<double, 2>& c, double orient,
                                 double radius) {
  const double f = -orient / radius;
  return {f * (c[0] - s.centre[0]), f * (c[1] - s.centre[1])};
}

// Turning sense of an arc: +1 counter-clockwise, -1 clockwise.
double arc_orient(const ProfileSegment& s) {
  return cross2(s.a[0] - s.centre[0], s.a[1] - s.centre[1], s.b[0] - s.centre[0], s.b[1] - s.centre[1]) > 0 ? 1.0
                                                                                                             : -1.0;
}

// Outward normal (left of the direction of travel) of a profile piece at a point c on it.
std::array<double, 2> piece_normal(const ProfileSegment& s, const std::array<double, 2>& c) {
  if (!s.arc) {
    const double dr = s.b[0] - s.a[0], dz = s.b[1] - s.a[1], l = std::sqrt(dr * dr + dz * dz);
    return {-dz / l, dr / l};
  }
  const double rx = c[0] - s.centre[0], rz = c[1] - s.centre[1];
  return arc_normal(s, c, arc_orient(s), std::sqrt(rx * rx + rz * rz));
}

// Revolved-tool queries as vector passes over a run of points, in
// structure-of-arrays buffers; the same operations in the same order as
// RigidTool::query_revolved (branches as selects), so the same bits.
// 1. The point in the axis frame: z along the axis, r from it, er the unit
//    radial direction (perp where r is zero). best = +inf, no piece yet.
TS_VECTOR_CLONES
void revolved_frame(std::size_t n, const double* __restrict x, const double* u, const double* o, const double* ax,
                    const double* perp, double* __restrict r, double* __restrict z, double* __restrict er,
                    double* __restrict best, double* __restrict c0, double* __restrict c1, double* __restrict piece,
                    double* __restrict end, std::size_t ld) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const double w0 = (x[3 * i] - u[0]) - o[0], w1 = (x[3 * i + 1] - u[1]) - o[1], w2 = (x[3 * i + 2] - u[2]) - o[2];
    const double zz = w0 * ax[0] + w1 * ax[1] + w2 * ax[2];
    const double h0 = w0 - ax[0] * zz, h1 = w1 - ax[1] * zz, h2 = w2 - ax[2] * zz;
    const double rr = std::sqrt(h0 * h0 + h1 * h1 + h2 * h2), inv = 1.0 / rr;
    const bool off = rr > 1e-300;
    r[i] = rr;
    z[i] = zz;
    er[i] = off ? h0 * inv : perp[0];
    er[ld + i] = off ? h1 * inv : perp[1];
    er[2 * ld + i] = off ? h2 * inv : perp[2];
    best[i] = kInf;
    c0[i] = 0;
    c1[i] = 0;
    piece[i] = -1;
    end[i] = -1;
  }
}

// Point i's closest point so far becomes (cx, cz) on piece k (at its end
// `at`: 0, 1, or -1 inside) where d2 is below the best squared distance.
[[gnu::always_inline]] inline void keep_closer(std::size_t i, double d2, double cx, double cz, double k, double at,
                                               double* __restrict best, double* __restrict c0,
                                               double* __restrict c1, double* __restrict piece,
                                               double* __restrict end) {
  const bool take = d2 < best[i];
  best[i] = take ? d2 : best[i];
  c0[i] = take ? cx : c0[i];
  c1[i] = take ? cz : c1[i];
  piece[i] = take ? k : piece[i];
  end[i] = take ? at : end[i];
}

// 2. One line piece (a, b) for every point: the closest point c on it,
//    taken where it is closer than the best so far.
TS_VECTOR_CLONES
void revolved_line(std::size_t n, const double* __restrict r, const double* __restrict z, double a0, double a1,
                   double b0, double b1, double inv_len2, double k, double* __restrict best, double* __restrict c0,
                   double* __restrict c1, double* __restrict piece, double* __restrict end) {
  const double dr = b0 - a0, dz = b1 - a1;
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const double t = ((r[i] - a0) * dr + (z[i] - a1) * dz) * inv_len2;
    const bool lo = t <= 0, hi = !lo && t >= 1;
    const double tt = lo ? 0.0 : hi ? 1.0 : t;
    const double cx = a0 + tt * dr, cz = a1 + tt * dz;
    const double d2 = (r[i] - cx) * (r[i] - cx) + (z[i] - cz) * (z[i] - cz);
    keep_closer(i, d2, cx, cz, k, lo ? 0.0 : hi ? 1.0 : -1.0, best, c0, c1, piece, end);
  }
}

// 2'. One arc piece (a to b about centre m, radius and turning sense).
TS_VECTOR_CLONES
void revolved_arc(std::size_t n, const double* __restrict r, const double* __restrict z, double a0, double a1,
                  double b0, double b1, double m0, double m1, double radius, double orient, double k,
                  double* __restrict best, double* __restrict c0, double* __restrict c1, double* __restrict piece,
                  double* __restrict end) {
  const double ax = a0 - m0, az = a1 - m1, bx = b0 - m0, bz = b1 - m1;
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const double qx = r[i] - m0, qz = z[i] - m1;
    const double ql2 = qx * qx + qz * qz;
    const bool inside = (ql2 > 0) & (orient * (ax * qz - az * qx) >= 0) & (orient * (qx * bz - qz * bx) >= 0);
    const double f = radius / std::sqrt(ql2);
    const double da2 = (r[i] - a0) * (r[i] - a0) + (z[i] - a1) * (z[i] - a1);
    const double db2 = (r[i] - b0) * (r[i] - b0) + (z[i] - b1) * (z[i] - b1);
    const bool at_a = da2 <= db2;
    const double cx = inside ? m0 + f * qx : at_a ? a0 : b0;
    const double cz = inside ? m1 + f * qz : at_a ? a1 : b1;
    const double d2 = (r[i] - cx) * (r[i] - cx) + (z[i] - cz) * (z[i] - cz);
    keep_closer(i, d2, cx, cz, k, inside ? -1.0 : at_a ? 0.0 : 1.0, best, c0, c1, piece, end);
  }
}

// 3. Signed distance and outward normal from the closest point: the normal
//    of the profile there (the averaged one at a piece's end, the radial
//    one on an arc, the line's own), or the direction from the closest
//    point when the point is off the surface. Per piece k, tab holds
//    [is_arc, m0, m1, -orient / radius, n0, n1, end normals (4)].
TS_VECTOR_CLONES
void revolved_result(std::size_t n, const double* __restrict r, const double* __restrict z,
                     const double* __restrict er, std::size_t ld, const double* __restrict best,
                     const double* __restrict c0, const double* __restrict c1, const double* __restrict piece,
                     const double* __restrict end, const double* __restrict tab, const double* ax,
                     double* __restrict dist, double* __restrict nout) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const int k = piece[i] >= 0 ? static_cast<int>(piece[i]) : 0;
    const int e = end[i] >= 0 ? static_cast<int>(end[i]) : 0;
    const double* t = tab + 10 * k;
    const double arc0 = t[3] * (c0[i] - t[1]), arc1 = t[3] * (c1[i] - t[2]);
    const bool at_end = end[i] >= 0, arc = t[0] != 0;
    const double bn0 = at_end ? t[6 + 2 * e] : arc ? arc0 : t[4];
    const double bn1 = at_end ? t[7 + 2 * e] : arc ? arc1 : t[5];
    const double dr = r[i] - c0[i], dz = z[i] - c1[i];
    const double len = std::sqrt(best[i]);
    const double side = dr * bn0 + dz * bn1 >= 0 ? 1.0 : -1.0;
    dist[i] = side * len;
    const bool off = len > 1e-12;
    const double n0 = off ? side * dr / len : bn0, n1 = off ? side * dz / len : bn1;
    for (int d = 0; d < 3; ++d) nout[3 * i + d] = n0 * er[d * ld + i] + n1 * ax[d];
  }
}

struct RevolvedScratch {
  std::vector<double> r, z, er, best, c0, c1, piece, end;
};

// Triangle soup from an STL file (ASCII or binary).
void read_stl(const std::filesystem::path& file, const std::string& ptr, std::vector<double>& xyz, std::vector<int>& tri) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw JobError(ptr, "cannot open the tool mesh '" + file.string() + "'");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto add_vertex = [&](double x, double y, double z) {
    xyz.insert(xyz.end(), {x, y, z});
    tri.push_back(static_cast<int>(xyz.size() / 3 - 1));
  };
  if (data.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, 4);
    if (data.size() == 84 + 50ull * count) {  // binary
      for (std::uint32_t f = 0; f < count; ++f) {
        const char* rec = data.data() + 84 + 50ull * f + 12;
        for (int k = 0; k < 3; ++k) {
          float v[3];
          std::memcpy(v, rec + 12 * k, 12);
          add_vertex(v[0], v[1], v[2]);
        }
      }
      return;
    }
  }
  std::istringstream s(data);
  std::string word;
  if (!(s >> word) || word != "solid")
    throw JobError(ptr, "'" + file.string() + "' is neither an ASCII nor a binary STL file");
  while (s >> word) {
    if (word != "vertex") continue;
    double x, y, z;
    if (!(s >> x >> y >> z)) throw JobError(ptr, "'" + file.string() + "': unreadable vertex");
    add_vertex(x, y, z);
  }
  if (tri.size() % 3 != 0) throw JobError(ptr, "'" + file.string() + "': facets without three vertices");
}

}  // namespace

RigidTool::RigidTool(const ToolDef& def) : def_(&def) {
  // A displacement table places the tool at its first row from the start
  // (a tool given in its closed position, as CAD draws it, and opened by
  // the table's first row).
  if (def.motion.kind == MotionDef::Kind::Displacement) u_ = prescribed(0.0);
  const SurfaceDef& s = def.surface;
  kind_ = s.type == "plane" ? Kind::Plane : s.type == "sphere" ? Kind::Sphere : s.type == "revolved" ? Kind::Revolved : Kind::Mesh;
  plane_normal_ = sdk::normalized({s.normal[0], s.normal[1], s.normal[2]});
  if (kind_ == Kind::Revolved) {
    axis_ = sdk::normalized({s.axis_direction[0], s.axis_direction[1], s.axis_direction[2]});
    const Vec3 trial = std::abs(axis_[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    perp_ = sdk::normalized(sdk::sub(trial, sdk::scale(axis_, sdk::dot(trial, axis_))));
    double scale = 0;
    for (const auto& g : s.profile) scale = std::max({scale, std::hypot(g.a[0], g.a[1]), std::hypot(g.b[0], g.b[1])});
    const double tol = 1e-9 * std::max(scale, 1e-3);
    pieces_.resize(s.profile.size());
    for (std::size_t i = 0; i < s.profile.size(); ++i) {
      const ProfileSegment& g = s.profile[i];
      if (!g.arc) {
        const double dr = g.b[0] - g.a[0], dz = g.b[1] - g.a[1];
        pieces_[i].inv_len2 = 1.0 / (dr * dr + dz * dz);
        pieces_[i].normal = piece_normal(g, g.a);
      } else {
        const double ax = g.a[0] - g.centre[0], az = g.a[1] - g.centre[1];
        pieces_[i].radius = std::sqrt(ax * ax + az * az);
        pieces_[i].orient = arc_orient(g);
      }
    }
    end_normals_.resize(s.profile.size());
    for (std::size_t i = 0; i < s.profile.size(); ++i) {
      for (int end = 0; end < 2; ++end) {
        const auto& q = end == 0 ? s.profile[i].a : s.profile[i].b;
        std::array<double, 2> n = piece_normal(s.profile[i], q);
        // Average with the pieces that share this end (corners of the profile).
        for (std::size_t j = 0; j < s.profile.size(); ++j) {
          if (j == i) continue;
          for (const auto& o : {s.profile[j].a, s.profile[j].b})
            if (std::hypot(o[0] - q[0], o[1] - q[1]) <= tol) {
              const auto m = piece_normal(s.profile[j], o);
              n[0] += m[0];
              n[1] += m[1];
            }
        }
        const double l = std::hypot(n[0], n[1]);
        if (l > 0) n = {n[0] / l, n[1] / l};
        end_normals_[i][2 * end] = n[0];
        end_normals_[i][2 * end + 1] = n[1];
      }
    }
    piece_table_.assign(10 * s.profile.size(), 0.0);
    for (std::size_t i = 0; i < s.profile.size(); ++i) {
      double* t = &piece_table_[10 * i];
      t[0] = s.profile[i].arc ? 1.0 : 0.0;
      t[1] = s.profile[i].centre[0];
      t[2] = s.profile[i].centre[1];
      t[3] = s.profile[i].arc ? -pieces_[i].orient / pieces_[i].radius : 0.0;
      t[4] = pieces_[i].normal[0];
      t[5] = pieces_[i].normal[1];
      for (int k = 0; k < 4; ++k) t[6 + k] = end_normals_[i][k];
    }
  } else if (kind_ == Kind::Mesh) {
    std::vector<double> xyz;
    std::vector<int> tri;
    const std::string ptr = def.pointer + "/surface/file";
    std::string ext = s.file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    try {
      if (ext == ".stl") {
        read_stl(s.file, ptr, xyz, tri);
        for (double& c : xyz) c *= s.scale;
      } else {
        ShellMesh m = read_mesh_triangles(s.file, s.scale);
        xyz = m.x;
        tri = m.triangles;
      }
    } catch (const JobError&) {
      throw;
    } catch (const std::exception& e) {
      throw JobError(ptr, "cannot read the tool mesh '" + s.file.string() + "': " + e.what());
    }
    if (tri.empty()) throw JobError(ptr, "the tool mesh '" + s.file.string() + "' has no triangles");
    // Triangles of zero area (two corners at one point, or three on a
    // line), which CAD exports write now and then, carry no surface: left
    // out (counted in describe()); messages keep the file's numbers.
    std::vector<int> kept, place;
    kept.reserve(tri.size());
    place.reserve(tri.size() / 3);
    mesh_info_ = {};
    for (std::size_t e = 0; e < tri.size() / 3; ++e) {
      if (zero_area(xyz, &tri[3 * e])) {
        ++mesh_info_.zero_area;
        continue;
      }
      kept.insert(kept.end(), {tri[3 * e], tri[3 * e + 1], tri[3 * e + 2]});
      place.push_back(static_cast<int>(e));
    }
    if (kept.empty()) throw JobError(ptr, "the tool mesh '" + s.file.string() + "' has no triangle of nonzero area");
    tri = std::move(kept);
    if (s.flip)
      for (std::size_t e = 0; e < tri.size(); e += 3) std::swap(tri[e + 1], tri[e + 2]);
    check_orientation(xyz, tri, place, ptr);
    build_mesh(xyz, tri);
  }
}

void RigidTool::check_orientation(const std::vector<double>& xyz, const std::vector<int>& tri,
                                  const std::vector<int>& place, const std::string& ptr) {
  // Corners at the same point are one vertex (an STL file repeats them).
  struct Hash {
    std::size_t operator()(const std::array<double, 3>& p) const {
      std::uint64_t h = kFnv1aOffset;
      for (const double c : p) {
        std::uint64_t b;
        std::memcpy(&b, &c, 8);
        fnv1a_mix(h, b);
      }
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<std::array<double, 3>, int, Hash> ids;
  std::vector<int> vid(tri.size());
  for (std::size_t k = 0; k < tri.size(); ++k) {
    const double* c = &xyz[3 * static_cast<std::size_t>(tri[k])];
    vid[k] = ids.try_emplace({c[0] + 0.0, c[1] + 0.0, c[2] + 0.0}, static_cast<int>(ids.size())).first->second;
  }
  // Each edge: the first triangle that has it, the way that one walks it,
  // and how many triangles have it. Two triangles on the same side of the
  // surface walk their common edge in opposite ways.
  struct Use {
    int triangle, count;
    bool forward;
  };
  std::unordered_map<std::uint64_t, Use> edges;
  edges.reserve(tri.size());
  mesh_info_.triangles = tri.size() / 3;
  mesh_info_.vertices = ids.size();
  for (std::size_t e = 0; e < tri.size() / 3; ++e)
    for (int k = 0; k < 3; ++k) {
      const int a = vid[3 * e + k], b = vid[3 * e + (k + 1) % 3];
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
      auto [it, fresh] = edges.try_emplace(key, Use{static_cast<int>(e), 1, a < b});
      if (fresh) continue;
      if (++it->second.count == 2 && it->second.forward == (a < b))
        throw JobError(ptr, "the tool mesh '" + def_->surface.file.string() + "' faces both ways: its triangles " +
                                std::to_string(place[it->second.triangle] + 1) + " and " + std::to_string(place[e] + 1) +
                                " (counted from 1 in the file) walk their common edge the same way, so one of them "
                                "faces into the tool; orient every triangle to the outside (counter-clockwise seen "
                                "from outside)");
    }
  for (const auto& [key, use] : edges)
    (use.count == 1 ? mesh_info_.open_edges : use.count == 2 ? mesh_info_.shared_edges : mesh_info_.other_edges)++;
  weld_xyz_.assign(3 * ids.size(), 0.0);
  for (const auto& [p, id] : ids)
    for (int d = 0; d < 3; ++d) weld_xyz_[3 * static_cast<std::size_t>(id) + d] = p[d];
  weld_tri_ = std::move(vid);
}

void RigidTool::display_mesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi, std::vector<double>& xyz,
                             std::vector<int>& tri) const {
  xyz.clear();
  tri.clear();
  if (kind_ == Kind::Mesh) {
    xyz = weld_xyz_;
    tri = weld_tri_;
    return;
  }
  const SurfaceDef& s = def_->surface;
  // A grid of rows x cols points (row-major) joined by two triangles per
  // cell, each turned to face the tool's outside at its centre; triangles
  // with two corners at one point (a pole, the axis) left out.
  auto grid = [&](int rows, int cols, const std::function<Vec3(int, int)>& at) {
    const int base = static_cast<int>(xyz.size() / 3);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < cols; ++j) {
        const Vec3 p = at(i, j);
        xyz.insert(xyz.end(), {p[0], p[1], p[2]});
      }
    auto add = [&](int a, int b, int c) {
      const Vec3 pa = sdk::load3(xyz.data(), a), pb = sdk::load3(xyz.data(), b), pc = sdk::load3(xyz.data(), c);
      const Vec3 n = sdk::cross(sdk::sub(pb, pa), sdk::sub(pc, pa));
      const double size = std::max({sdk::norm(sdk::sub(pb, pa)), sdk::norm(sdk::sub(pc, pa)), 1e-300});
      if (!(sdk::norm(n) > 1e-12 * size * size)) return;
      const Vec3 m = sdk::scale(sdk::add(sdk::add(pa, pb), pc), 1.0 / 3.0);
      // The outward normal there, in the initial position.
      double dist = 0, out[3] = {plane_normal_[0], plane_normal_[1], plane_normal_[2]};
      if (kind_ == Kind::Sphere)
        for (int d = 0; d < 3; ++d) out[d] = m[d] - s.centre[d];
      else if (kind_ == Kind::Revolved)
        query_revolved(m.data(), dist, out);
      if (sdk::dot(n, Vec3{out[0], out[1], out[2]}) >= 0)
        tri.insert(tri.end(), {a, b, c});
      else
        tri.insert(tri.end(), {a, c, b});
    };
    for (int i = 0; i + 1 < rows; ++i)
      for (int j = 0; j + 1 < cols; ++j) {
        const int a = base + i * cols + j, b = a + 1, c = a + cols + 1, d = a + cols;
        add(a, b, c);
        add(a, c, d);
      }
  };
  if (kind_ == Kind::Plane) {
    const Vec3 n = plane_normal_;
    const Vec3 trial = std::abs(n[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 u = sdk::normalized(sdk::sub(trial, sdk::scale(n, sdk::dot(trial, n))));
    const Vec3 v = sdk::cross(n, u);
    const Vec3 mid = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const Vec3 p0 = {s.point[0], s.point[1], s.point[2]};
    const Vec3 c = sdk::sub(mid, sdk::scale(n, sdk::dot(sdk::sub(mid, p0), n)));
    const double a = std::max(0.6 * sdk::norm(sdk::sub(Vec3{hi[0], hi[1], hi[2]}, Vec3{lo[0], lo[1], lo[2]})), 1e-3);
    grid(2, 2, [&](int i, int j) {
      return sdk::add(c, sdk::add(sdk::scale(u, (2 * j - 1) * a), sdk::scale(v, (2 * i - 1) * a)));
    });
  } else if (kind_ == Kind::Sphere) {
    const double pi = std::acos(-1.0);
    grid(25, 49, [&](int i, int j) {
      const double th = pi * i / 24, ph = 2 * pi * j / 48;
      return Vec3{s.centre[0] + s.radius * std::sin(th) * std::cos(ph), s.centre[1] + s.radius * std::sin(th) * std::sin(ph),
                  s.centre[2] + s.radius * std::cos(th)};
    });
  } else {  // revolved
    const double pi = std::acos(-1.0);
    const Vec3 e2 = sdk::cross(axis_, perp_);
    for (std::size_t k = 0; k < s.profile.size(); ++k) {
      const ProfileSegment& g = s.profile[k];
      std::vector<std::array<double, 2>> pts = {g.a};
      if (g.arc) {
        const double t0 = std::atan2(g.a[1] - g.centre[1], g.a[0] - g.centre[0]);
        double sweep = std::atan2(g.b[1] - g.centre[1], g.b[0] - g.centre[0]) - t0;
        if (pieces_[k].orient > 0 && sweep < 0) sweep += 2 * pi;
        if (pieces_[k].orient < 0 && sweep > 0) sweep -= 2 * pi;
        const int n = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / (pi / 24))));
        for (int i = 1; i < n; ++i)
          pts.push_back({g.centre[0] + pieces_[k].radius * std::cos(t0 + sweep * i / n),
                         g.centre[1] + pieces_[k].radius * std::sin(t0 + sweep * i / n)});
      }
      pts.push_back(g.b);
      grid(static_cast<int>(pts.size()), 49, [&](int i, int j) {
        const double ph = 2 * pi * (j % 48) / 48;
        const Vec3 radial = sdk::add(sdk::scale(perp_, std::cos(ph)), sdk::scale(e2, std::sin(ph)));
        return Vec3{s.axis_origin[0] + pts[i][0] * radial[0] + pts[i][1] * axis_[0],
                    s.axis_origin[1] + pts[i][0] * radial[1] + pts[i][1] * axis_[1],
                    s.axis_origin[2] + pts[i][0] * radial[2] + pts[i][1] * axis_[2]};
      });
    }
  }
}

void cut_display_mesh(std::vector<double>& xyz, std::vector<int>& tri, int axis, double sign, double tol) {
  const std::size_t nv = xyz.size() / 3;
  std::vector<double> sd(nv);
  std::vector<signed char> side(nv);  // +1 kept, 0 on the plane, -1 beyond
  for (std::size_t i = 0; i < nv; ++i) {
    sd[i] = sign * xyz[3 * i + axis];
    side[i] = sd[i] > tol ? 1 : sd[i] < -tol ? -1 : 0;
    if (side[i] == 0) {
      xyz[3 * i + axis] = 0.0;
      sd[i] = 0.0;
    }
  }
  std::map<std::pair<int, int>, int> cuts;  // edge (lower vertex, higher) -> its cut point
  auto cut = [&](int a, int b) {
    if (a > b) std::swap(a, b);  // the same bits from either triangle
    const auto [it, fresh] = cuts.try_emplace({a, b}, static_cast<int>(xyz.size() / 3));
    if (fresh) {
      const double t = sd[a] / (sd[a] - sd[b]);
      double p[3];
      for (int d = 0; d < 3; ++d) p[d] = xyz[3 * a + d] + t * (xyz[3 * b + d] - xyz[3 * a + d]);
      p[axis] = 0.0;
      xyz.insert(xyz.end(), {p[0], p[1], p[2]});
    }
    return it->second;
  };
  std::vector<int> out;
  out.reserve(tri.size());
  for (std::size_t e = 0; e + 2 < tri.size(); e += 3) {
    const int v[3] = {tri[e], tri[e + 1], tri[e + 2]};
    const bool any_in = side[v[0]] > 0 || side[v[1]] > 0 || side[v[2]] > 0;
    const bool any_out = side[v[0]] < 0 || side[v[1]] < 0 || side[v[2]] < 0;
    if (!any_out) {
      out.insert(out.end(), v, v + 3);
      continue;
    }
    if (!any_in) continue;
    int poly[4], n = 0;  // a triangle cut by a plane keeps 3 or 4 corners
    for (int k = 0; k < 3; ++k) {
      const int a = v[k], b = v[(k + 1) % 3];
      if (side[a] >= 0) poly[n++] = a;
      if (side[a] * side[b] < 0) poly[n++] = cut(a, b);
    }
    for (int k = 1; k + 1 < n; ++k) out.insert(out.end(), {poly[0], poly[k], poly[k + 1]});
  }
  // Only the vertices the kept triangles use, in their order.
  std::vector<int> renumber(xyz.size() / 3, -1);
  std::vector<double> kept;
  for (int& i : out) {
    if (renumber[i] < 0) {
      renumber[i] = static_cast<int>(kept.size() / 3);
      kept.insert(kept.end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
    }
    i = renumber[i];
  }
  xyz = std::move(kept);
  tri = std::move(out);
}

double RigidTool::mesh_span() const { return kind_ == Kind::Mesh ? box_span(weld_xyz_) : 0.0; }

std::string RigidTool::describe() const {
  if (kind_ != Kind::Mesh) return {};
  char scaled[64] = "";
  if (def_->surface.scale != 1.0) std::snprintf(scaled, sizeof scaled, " (its coordinates times %g)", def_->surface.scale);
  char line[1024];
  std::snprintf(line, sizeof line,
                "tool '%s': %zu triangles, %zu vertices from %s%s; edges %.3g to %.3g mm; %zu edges between two "
                "triangles (all facing the same side), %zu free, %zu shared by more than two",
                def_->name.c_str(), mesh_info_.triangles, mesh_info_.vertices, def_->surface.file.string().c_str(),
                scaled,
                1e3 * mesh_info_.shortest_edge, 1e3 * scale_, mesh_info_.shared_edges, mesh_info_.open_edges,
                mesh_info_.other_edges);
  std::string text = line;
  if (mesh_info_.zero_area > 0)
    text += "; " + std::to_string(mesh_info_.zero_area) + " triangle(s) of zero area in the file left out";
  return text;
}

// Triangle t's corners (3 vertex numbers into xyz) from the smallest (by
// x, then y, then z), in its turning order: its numbers do not depend on
// the corner the file starts it from.
static std::array<Vec3, 3> corners_from_smallest(const std::vector<double>& xyz, const int* t) {
  Vec3 w[3];
  for (int k = 0; k < 3; ++k) w[k] = sdk::load3(xyz.data(), t[k]);
  int first = 0;
  for (int k = 1; k < 3; ++k)
    if (std::lexicographical_compare(w[k].begin(), w[k].end(), w[first].begin(), w[first].end())) first = k;
  return {w[first], w[(first + 1) % 3], w[(first + 2) % 3]};
}

// Whether triangle t has zero area, its corners taken as build_mesh() takes
// them.
bool RigidTool::zero_area(const std::vector<double>& xyz, const int* t) {
  const auto v = corners_from_smallest(xyz, t);
  return !(sdk::norm(sdk::cross(sdk::sub(v[1], v[0]), sdk::sub(v[2], v[0]))) > 0);
}

void RigidTool::build_mesh(const std::vector<double>& xyz, const std::vector<int>& tri) {
  const std::size_t nt = tri.size() / 3;
  std::vector<double> vx(9 * nt), centre(3 * nt);
  double h = 0;
  for (std::size_t e = 0; e < nt; ++e) {
    // Corners from the smallest (by x, then y, then z), in the file's
    // turning order: a triangle's numbers do not depend on the corner the
    // file starts it from.
    const auto v = corners_from_smallest(xyz, &tri[3 * e]);
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) vx[9 * e + 3 * k + d] = v[k][d];
    for (int k = 0; k < 3; ++k) {
      const double l = sdk::norm(sdk::sub(v[k], v[(k + 1) % 3]));
      h = std::max(h, l);
      mesh_info_.shortest_edge = std::min(mesh_info_.shortest_edge, l);
    }
    for (int d = 0; d < 3; ++d) centre[3 * e + d] = (v[0][d] + v[1][d] + v[2][d]) / 3.0;
  }
  scale_ = std::max(h, 1e-9);
  double size = 0;
  for (const double c : vx) size = std::max(size, std::abs(c));
  tol_ = 1e-12 * (size + scale_);
  // The tree: each box split at the median of its triangles' centres along
  // the box's longest side (so at most log2(n) levels), down to leaves of
  // kLeaf triangles. The boxes bound the corners exactly.
  constexpr int kLeaf = 4;
  // Each triangle's rank among the triangles ordered by their corners
  // (from the smallest, as above): of equally close triangles a query takes
  // the lowest rank, so that the answers depend on the triangles, not on
  // the order of the file (equal triangles keep the file's order). The tree
  // is built from that order too.
  morig_.resize(nt);
  for (std::size_t e = 0; e < nt; ++e) morig_[e] = static_cast<int>(e);
  std::stable_sort(morig_.begin(), morig_.end(), [&](int p, int q) {
    return std::lexicographical_compare(&vx[9 * static_cast<std::size_t>(p)], &vx[9 * static_cast<std::size_t>(p) + 9],
                                        &vx[9 * static_cast<std::size_t>(q)], &vx[9 * static_cast<std::size_t>(q) + 9]);
  });
  std::vector<int> rank(nt);
  for (std::size_t i = 0; i < nt; ++i) rank[static_cast<std::size_t>(morig_[i])] = static_cast<int>(i);
  boxes_.clear();
  boxes_.reserve(2 * (nt / kLeaf + 1));
  auto bound = [&](int begin, int end, BoxNode& b) {
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = kInf;
      b.hi[d] = -kInf;
    }
    for (int q = begin; q < end; ++q)
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) {
          const double c = vx[9 * static_cast<std::size_t>(morig_[q]) + 3 * k + d];
          b.lo[d] = std::min(b.lo[d], c);
          b.hi[d] = std::max(b.hi[d], c);
        }
  };
  auto build = [&](auto&& self, int begin, int end) -> void {
    const std::size_t at = boxes_.size();
    boxes_.push_back({});
    bound(begin, end, boxes_[at]);
    if (end - begin <= kLeaf) {
      boxes_[at].first = begin;
      boxes_[at].count = end - begin;
      return;
    }
    // Along the axis on which the centres spread the most; equal
    // coordinates ordered by the other two, so that the halves stay apart
    // where triangles line up (a tool's wall, rows of a revolved surface),
    // whatever their order in the file.
    double clo[3] = {kInf, kInf, kInf}, chi[3] = {-kInf, -kInf, -kInf};
    for (int q = begin; q < end; ++q)
      for (int d = 0; d < 3; ++d) {
        clo[d] = std::min(clo[d], centre[3 * static_cast<std::size_t>(morig_[q]) + d]);
        chi[d] = std::max(chi[d], centre[3 * static_cast<std::size_t>(morig_[q]) + d]);
      }
    int axis = 0;
    for (int d = 1; d < 3; ++d)
      if (chi[d] - clo[d] > chi[axis] - clo[axis]) axis = d;
    const int mid = begin + (end - begin) / 2;
    std::nth_element(morig_.begin() + begin, morig_.begin() + mid, morig_.begin() + end, [&](int p, int q) {
      const double* cp = &centre[3 * static_cast<std::size_t>(p)];
      const double* cq = &centre[3 * static_cast<std::size_t>(q)];
      for (int k = 0; k < 3; ++k) {
        const int d = (axis + k) % 3;
        if (cp[d] != cq[d]) return cp[d] < cq[d];
      }
      return rank[static_cast<std::size_t>(p)] < rank[static_cast<std::size_t>(q)];
    });
    self(self, begin, mid);
    boxes_[at].first = static_cast<int>(boxes_.size());
    boxes_[at].count = 0;
    self(self, mid, end);
  };
  build(build, 0, static_cast<int>(nt));
  // The triangles in the order of the leaves, with their unit normal n and
  // the gradients g1, g2 of the barycentric weights w1, w2 of a point's
  // projection (w_k = (x - p0) . g_k, w0 = 1 - w1 - w2, g0 = -g1 - g2) and
  // 1 / |g_k|^2 of the three.
  mx_.resize(9 * nt);
  mn_.resize(kGeo * nt);
  mrank_.resize(nt);
  for (std::size_t q = 0; q < nt; ++q) mrank_[q] = rank[static_cast<std::size_t>(morig_[q])];
  for (std::size_t q = 0; q < nt; ++q) {
    const double* v = &vx[9 * static_cast<std::size_t>(morig_[q])];
    std::copy(v, v + 9, &mx_[9 * q]);
    const Vec3 p0{v[0], v[1], v[2]}, e1 = sdk::sub(Vec3{v[3], v[4], v[5]}, p0), e2 = sdk::sub(Vec3{v[6], v[7], v[8]}, p0);
    const Vec3 c = sdk::cross(e1, e2);
    const double l = sdk::norm(c);
    const Vec3 n = {c[0] / l, c[1] / l, c[2] / l};
    const Vec3 g1 = sdk::scale(sdk::cross(e2, n), 1.0 / l), g2 = sdk::scale(sdk::cross(n, e1), 1.0 / l);
    const Vec3 g0 = sdk::scale(sdk::add(g1, g2), -1.0);
    double* g = &mn_[kGeo * q];
    for (int d = 0; d < 3; ++d) {
      g[d] = n[d];
      g[3 + d] = g1[d];
      g[6 + d] = g2[d];
    }
    g[9] = 1.0 / sdk::dot(g0, g0);
    g[10] = 1.0 / sdk::dot(g1, g1);
    g[11] = 1.0 / sdk::dot(g2, g2);
  }
}

void RigidTool::query(std::size_t n, const double* points, double cutoff, double* distance, double* normal) const {
  if (kind_ == Kind::Revolved) {
    query_revolved_run(n, points, distance, normal);
    return;
  }
  const SurfaceDef& s = def_->surface;
  for (std::size_t i = 0; i < n; ++i) {
    const double p[3] = {points[3 * i] - u_[0], points[3 * i + 1] - u_[1], points[3 * i + 2] - u_[2]};
    double* nn = normal + 3 * i;
    if (kind_ == Kind::Plane) {
      const Vec3& u = plane_normal_;
      distance[i] = (p[0] - s.point[0]) * u[0] + (p[1] - s.point[1]) * u[1] + (p[2] - s.point[2]) * u[2];
      for (int d = 0; d < 3; ++d) nn[d] = u[d];
    } else if (kind_ == Kind::Sphere) {
      const Vec3 r = {p[0] - s.centre[0], p[1] - s.centre[1], p[2] - s.centre[2]};
      const double len = sdk::norm(r);
      const Vec3 u = len > 0 ? sdk::scale(r, 1.0 / len) : Vec3{0, 0, 1};
      distance[i] = len - s.radius;
      for (int d = 0; d < 3; ++d) nn[d] = u[d];
    } else {
      query_mesh(p, cutoff, distance[i], nn);
    }
  }
}

void RigidTool::query_revolved_run(std::size_t n, const double* points, double* distance, double* normal) const {
  const SurfaceDef& s = def_->surface;
  constexpr std::size_t kChunk = 256;
  thread_local RevolvedScratch sc;
  if (sc.r.size() < kChunk) {
    for (auto* v : {&sc.r, &sc.z, &sc.best, &sc.c0, &sc.c1, &sc.piece, &sc.end}) v->resize(kChunk);
    sc.er.resize(3 * kChunk);
  }
  const double o[3] = {s.axis_origin[0], s.axis_origin[1], s.axis_origin[2]};
  for (std::size_t b = 0; b < n; b += kChunk) {
    const std::size_t m = std::min(kChunk, n - b);
    revolved_frame(m, points + 3 * b, u_.data(), o, axis_.data(), perp_.data(), sc.r.data(), sc.z.data(), sc.er.data(),
                   sc.best.data(), sc.c0.data(), sc.c1.data(), sc.piece.data(), sc.end.data(), kChunk);
    for (std::size_t k = 0; k < s.profile.size(); ++k) {
      const ProfileSegment& g = s.profile[k];
      if (!g.arc)
        revolved_line(m, sc.r.data(), sc.z.data(), g.a[0], g.a[1], g.b[0], g.b[1], pieces_[k].inv_len2,
                      static_cast<double>(k), sc.best.data(), sc.c0.data(), sc.c1.data(), sc.piece.data(),
                      sc.end.data());
      else
        revolved_arc(m, sc.r.data(), sc.z.data(), g.a[0], g.a[1], g.b[0], g.b[1], g.centre[0], g.centre[1],
                     pieces_[k].radius, pieces_[k].orient, static_cast<double>(k), sc.best.data(), sc.c0.data(),
                     sc.c1.data(), sc.piece.data(), sc.end.data());
    }
    revolved_result(m, sc.r.data(), sc.z.data(), sc.er.data(), kChunk, sc.best.data(), sc.c0.data(), sc.c1.data(),
                    sc.piece.data(), sc.end.data(), piece_table_.data(), axis_.data(), distance + b, normal + 3 * b);
  }
}

void RigidTool::query_revolved(const double* p, double& dist, double* nout) const {
  const SurfaceDef& s = def_->surface;
  const Vec3 w = {p[0] - s.axis_origin[0], p[1] - s.axis_origin[1], p[2] - s.axis_origin[2]};
  const double z = sdk::dot(w, axis_);
  const Vec3 rho = sdk::sub(w, sdk::scale(axis_, z));
  const double r = std::sqrt(sdk::dot(rho, rho));
  const Vec3 er = r > 1e-300 ? sdk::scale(rho, 1.0 / r) : perp_;
  double best = kInf;
  std::array<double, 2> bc{0, 0};
  int best_k = -1, best_end = -1;
  for (std::size_t k = 0; k < s.profile.size(); ++k) {
    const ProfileSegment& g = s.profile[k];
    const PieceConstants& pc = pieces_[k];
    std::array<double, 2> c;
    int end = -1;  // 0: at a, 1: at b, -1: inside
    if (!g.arc) {
      const double dr = g.b[0] - g.a[0], dz = g.b[1] - g.a[1];
      double t = ((r - g.a[0]) * dr + (z - g.a[1]) * dz) * pc.inv_len2;
      if (t <= 0) {
        t = 0;
        end = 0;
      } else if (t >= 1) {
        t = 1;
        end = 1;
      }
      c = {g.a[0] + t * dr, g.a[1] + t * dz};
    } else {
      const double ax = g.a[0] - g.centre[0], az = g.a[1] - g.centre[1];
      const double bx = g.b[0] - g.centre[0], bz = g.b[1] - g.centre[1];
      const double qx = r - g.centre[0], qz = z - g.centre[1];
      const double ql2 = qx * qx + qz * qz;
      const bool inside = ql2 > 0 && pc.orient * cross2(ax, az, qx, qz) >= 0 && pc.orient * cross2(qx, qz, bx, bz) >= 0;
      if (inside) {
        const double f = pc.radius / std::sqrt(ql2);
        c = {g.centre[0] + f * qx, g.centre[1] + f * qz};
      } else {
        const double da2 = (r - g.a[0]) * (r - g.a[0]) + (z - g.a[1]) * (z - g.a[1]);
        const double db2 = (r - g.b[0]) * (r - g.b[0]) + (z - g.b[1]) * (z - g.b[1]);
        end = da2 <= db2 ? 0 : 1;
        c = end == 0 ? g.a : g.b;
      }
    }
    const double d2 = (r - c[0]) * (r - c[0]) + (z - c[1]) * (z - c[1]);
    if (d2 < best) {
      best = d2;
      bc = c;
      best_k = static_cast<int>(k);
      best_end = end;
    }
  }
  const PieceConstants& pb = pieces_[best_k];
  const std::array<double, 2> bn =
      best_end >= 0             ? std::array<double, 2>{end_normals_[best_k][2 * best_end], end_normals_[best_k][2 * best_end + 1]}
      : s.profile[best_k].arc ? arc_normal(s.profile[best_k], bc, pb.orient, pb.radius)
                              : pb.normal;
  const double dr = r - bc[0], dz = z - bc[1];
  const double len = std::sqrt(best);
  const double side = dr * bn[0] + dz * bn[1] >= 0 ? 1.0 : -1.0;
  dist = side * len;
  std::array<double, 2> n2 = bn;
  if (len > 1e-12) n2 = {side * dr / len, side * dz / len};
  for (int d = 0; d < 3; ++d) nout[d] = n2[0] * er[d] + n2[1] * axis_[d];
}

namespace {

// Squared distance from x to a box, a lower bound of the distance to
// anything inside it.
double box_distance2(const double* x, const double* lo, const double* hi) {
  double s = 0;
  for (int d = 0; d < 3; ++d) {
    const double g = std::max({lo[d] - x[d], 0.0, x[d] - hi[d]});
    s += g * g;
  }
  return s;
}

}  // namespace

namespace {

// The lower bound of triangle q's squared distance from x that the searches
// skip it by: the distance to its plane, and beyond the line of edge k
// (w_k < 0) the projection is at least -w_k / |g_k| away from the triangle.
inline double triangle_bound2(const double* x, const double* v, const double* g) {
  const double rx = x[0] - v[0], ry = x[1] - v[1], rz = x[2] - v[2];
  const double plane = rx * g[0] + ry * g[1] + rz * g[2];
  const double w1 = rx * g[3] + ry * g[4] + rz * g[5], w2 = rx * g[6] + ry * g[7] + rz * g[8];
  const double w0 = 1.0 - w1 - w2;
  const double out = std::max({w0 < 0 ? w0 * w0 * g[9] : 0.0, w1 < 0 ? w1 * w1 * g[10] : 0.0,
                               w2 < 0 ? w2 * w2 * g[11] : 0.0});
  return plane * plane + out;
}

// What a record of RigidTool::query_kept holds: where its list was made (in
// the tool's initial position), for which cutoff (0: no list yet), the
// triangles near that place (-1: more than fit, the tree is searched),
// nearest first, and a lower bound of each one's distance from that place.
struct KeptRecord {
  static constexpr int kMax = static_cast<int>((RigidTool::kKeptBytes - 4 * sizeof(double) - sizeof(std::int32_t)) /
                                               (sizeof(std::int32_t) + sizeof(float)));
  double x[3];
  double cutoff;
  std::int32_t count;
  std::int32_t tri[kMax];
  float near[kMax];
};
static_assert(sizeof(KeptRecord) <= RigidTool::kKeptBytes);

}  // namespace

// The closest point cp of triangle q to p, and its squared distance.
inline double RigidTool::closest_on(const double* p, int q, Vec3& cp) const {
  const double* v = &mx_[9 * static_cast<std::size_t>(q)];
  const Vec3 x = {p[0], p[1], p[2]};
  cp = sdk::closest_point_on_triangle(x, {v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]});
  const Vec3 dv = sdk::sub(x, cp);
  return sdk::dot(dv, dv);
}

// Keeps triangle q if it is closer than the best so far, or as close with a
// lower rank; the search's reach (limit2) follows the best.
inline void RigidTool::test_triangle(const double* p, int q, Closest& c) const {
  if (triangle_bound2(p, &mx_[9 * static_cast<std::size_t>(q)], &mn_[kGeo * static_cast<std::size_t>(q)]) > c.limit2)
    return;
  Vec3 cp;
  const double d2 = closest_on(p, q, cp);
  if (d2 < c.best || (d2 == c.best && c.q >= 0 && mrank_[q] < mrank_[c.q])) {
    c.best = d2;
    c.q = q;
    c.cp = cp;
    const double reach = std::sqrt(d2) + tol_;
    c.limit2 = reach * reach;
  }
}

template <class Leaf>
void RigidTool::descend(const double* p, const double& limit2, Leaf&& leaf) const {
  int stack[128];
  int top = 0;
  if (!boxes_.empty() && !(box_distance2(p, boxes_[0].lo, boxes_[0].hi) > limit2)) stack[top++] = 0;
  while (top > 0) {
    const BoxNode& b = boxes_[stack[--top]];
    if (b.count == 0) {
      const int c1 = static_cast<int>(&b - boxes_.data()) + 1, c2 = b.first;
      const double d1 = box_distance2(p, boxes_[c1].lo, boxes_[c1].hi);
      const double d2 = box_distance2(p, boxes_[c2].lo, boxes_[c2].hi);
      const bool f1 = d1 > limit2, f2 = d2 > limit2;
      if (d1 <= d2) {  // the nearer child on top of the stack
        if (!f2) stack[top++] = c2;
        if (!f1) stack[top++] = c1;
      } else {
        if (!f1) stack[top++] = c1;
        if (!f2) stack[top++] = c2;
      }
      continue;
    }
    if (box_distance2(p, b.lo, b.hi) > limit2) continue;  // the reach shrank since this box was stacked
    leaf(b);
  }
}

void RigidTool::query_mesh(const double* p, double cutoff, double& dist, double* nout) const {
  // The closest triangle nearer than the cutoff: of equal distances the
  // lowest rank. Boxes and triangles whose lower bound (the distance to
  // the box, to the triangle's plane) is farther than the best so far are
  // skipped, with a margin of 1e-12 of the mesh's size for the round-off of
  // the two distances, so that nothing the comparison below would take is
  // skipped; the nearer child first.
  Closest c;
  c.best = std::isfinite(cutoff) ? cutoff * cutoff : kInf;
  c.limit2 = std::isfinite(cutoff) ? (cutoff + tol_) * (cutoff + tol_) : kInf;
  descend(p, c.limit2, [&](const BoxNode& b) {
    for (int q = b.first; q < b.first + b.count; ++q) test_triangle(p, q, c);
  });
  mesh_answer(p, c.q, c.best, c.cp, dist, nout);
}

void RigidTool::query_listed(const double* p, double cutoff, const std::int32_t* list, const float* near, int count,
                             double moved, double& dist, double* nout) const {
  Closest c;
  c.best = cutoff * cutoff;
  c.limit2 = (cutoff + tol_) * (cutoff + tol_);
  for (int k = 0; k < count; ++k) {
    // This triangle and the ones after it are at least near[k] - moved away.
    const double lower = static_cast<double>(near[k]) - moved;
    if (lower > 0 && lower * lower > c.limit2) break;
    test_triangle(p, list[k], c);
  }
  mesh_answer(p, c.q, c.best, c.cp, dist, nout);
}

void RigidTool::mesh_answer(const double* p, int best_q, double best, const Vec3& best_cp, double& dist,
                            double* nout) const {
  if (best_q < 0) {
    dist = kInf;
    nout[0] = nout[1] = 0;
    nout[2] = 1;
    return;
  }
  const Vec3 x = {p[0], p[1], p[2]};
  const Vec3 fn = sdk::load3(&mn_[kGeo * static_cast<std::size_t>(best_q)], 0);
  const Vec3 dv = sdk::sub(x, best_cp);
  const double len = std::sqrt(best);
  const double side = sdk::dot(dv, fn) >= 0 ? 1.0 : -1.0;
  dist = side * len;
  // Inside a triangle the direction is its normal; off an edge or a vertex
  // the direction from the closest point (folds act as rounded).
  const Vec3 n = len > 1e-12 * scale_ && std::abs(sdk::dot(dv, fn)) < (1 - 1e-12) * len ? sdk::scale(dv, side / len) : fn;
  for (int d = 0; d < 3; ++d) nout[d] = n[d];
}

int RigidTool::mesh_near(const double* p, double radius, std::int32_t* out, float* near, int max) const {
  const double limit2 = radius * radius;
  int count = 0;
  bool full = false;
  descend(p, limit2, [&](const BoxNode& b) {
    for (int q = b.first; q < b.first + b.count && !full; ++q) {
      if (triangle_bound2(p, &mx_[9 * static_cast<std::size_t>(q)], &mn_[kGeo * static_cast<std::size_t>(q)]) >
          limit2)
        continue;
      if (count == max)
        full = true;
      else
        out[count++] = q;
    }
  });
  if (full) return -1;
  // Nearest first, each with its distance less the round-off margin,
  // rounded down to a float: a query from a point that has moved by m
  // since stops at the first triangle at least m beyond its best so far.
  for (int k = 0; k < count; ++k) {
    Vec3 cp;
    const double d = std::sqrt(closest_on(p, out[k], cp)) - 2 * tol_;
    float f = static_cast<float>(std::max(d, 0.0));
    if (static_cast<double>(f) > d) f = std::nextafter(f, 0.0f);
    near[k] = f;
  }
  for (int k = 1; k < count; ++k)
    for (int m = k; m > 0 && near[m] < near[m - 1]; --m) {
      std::swap(near[m], near[m - 1]);
      std::swap(out[m], out[m - 1]);
    }
  return count;
}

int RigidTool::kept_listed(const void* record) {
  const auto* r = static_cast<const KeptRecord*>(record);
  return r->cutoff > 0 ? r->count : -2;
}

void RigidTool::query_kept(std::size_t n, const double* points, double cutoff, double* distance, double* normal,
                           void* kept) const {
  // A cutoff within the round-off margins of the mesh leaves no room for
  // a list: the tree answers.
  if (kind_ != Kind::Mesh || !(0.125 * cutoff > 4 * tol_) || !std::isfinite(cutoff)) {
    query(n, points, cutoff, distance, normal);
    return;
  }
  // A record's list holds every triangle within cutoff + skin (+ margins)
  // of the place x_r where it was made. While the point p stays within
  // skin - 2 tol of x_r, a triangle not listed is farther than cutoff +
  // tol from p: the closest of the listed ones within the cutoff is the
  // closest of all. The tools only translate, so the place is kept in the
  // tool's initial position, where the tool's motion moves the point.
  const double skin = 0.125 * cutoff;
  const double stay = skin - 2 * tol_;
  const double radius = cutoff + skin + 2 * tol_;
  auto* rec = static_cast<KeptRecord*>(kept);
  for (std::size_t i = 0; i < n; ++i) {
    const double p[3] = {points[3 * i] - u_[0], points[3 * i + 1] - u_[1], points[3 * i + 2] - u_[2]};
    KeptRecord& r = rec[i];
    const double dx = p[0] - r.x[0], dy = p[1] - r.x[1], dz = p[2] - r.x[2];
    double moved2 = dx * dx + dy * dy + dz * dz;
    if (!(r.cutoff == cutoff && moved2 <= stay * stay)) {
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
        query_mesh(p, cutoff, distance[i], normal + 3 * i);
        continue;
      }
      for (int d = 0; d < 3; ++d) r.x[d] = p[d];
      r.cutoff = cutoff;
      r.count = mesh_near(p, radius, r.tri, r.near, KeptRecord::kMax);
      moved2 = 0;
    }
    if (r.count < 0)
      query_mesh(p, cutoff, distance[i], normal + 3 * i);
    else
      query_listed(p, cutoff, r.tri, r.near, r.count, std::sqrt(moved2) * (1 + 1e-12) + 2 * tol_, distance[i],
                   normal + 3 * i);
  }
}

std::array<double, 3> RigidTool::prescribed(double t) const {
  const MotionDef& m = def_->motion;
  if (m.kind == MotionDef::Kind::Velocity || m.kind == MotionDef::Kind::Displacement) return m.prescribed(t);
  return u_;
}

void RigidTool::advance(double t, double dt, double dt_avg, const std::array<double, 3>& reaction) {
  const MotionDef& m = def_->motion;
  if (m.kind == MotionDef::Kind::Fixed) return;
  if (m.kind == MotionDef::Kind::Force) {
    // Translation along the force: M a = F + dir . R - c v, F the force at
    // t along dir (the direction of the force, or of its rows' first that
    // is not zero).
    const Vec3 dir = sdk::normalized({m.force[0], m.force[1], m.force[2]});
    const auto f = m.force_at(t);
    const double F = m.force_table.empty() ? sdk::norm({f[0], f[1], f[2]}) : sdk::dot(dir, {f[0], f[1], f[2]});
    double v = sdk::dot(v_, dir);
    v += dt_avg * (F + sdk::dot(dir, {reaction[0], reaction[1], reaction[2]}) - m.damping * v) / m.mass;
    for (int d = 0; d < 3; ++d) {
      v_[d] = v * dir[d];
      u_[d] += dt * v_[d];
    }
    return;
  }
  const auto a = prescribed(t), b = prescribed(t + dt);
  for (int d = 0; d < 3; ++d) {
    v_[d] = (b[d] - a[d]) / dt;
    u_[d] = b[d];
  }
}

}  // namespace ts
