// Rigid tool surfaces against their closed-form distances, and tool motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <random>

#include <thermostamp/sdk/math.hpp>

#include "job/errors.hpp"
#include "solve/tools.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

struct Answer {
  double d;
  std::array<double, 3> n;
};

Answer ask(const RigidTool& t, std::array<double, 3> p, double cutoff = 1.0) {
  Answer a;
  t.query(1, p.data(), cutoff, &a.d, a.n.data());
  return a;
}

ToolDef punch_def(double R) {
  ToolDef d;
  d.name = "punch";
  d.pointer = "/tools/0";
  d.surface.type = "revolved";
  ProfileSegment cap;  // the hemisphere, pole to equator (outside on the left: above)
  cap.arc = true;
  cap.a = {0, R};
  cap.b = {R, 0};
  cap.centre = {0, 0};
  ProfileSegment side;  // the cylinder below it
  side.a = {R, 0};
  side.b = {R, -0.1};
  d.surface.profile = {cap, side};
  return d;
}

// An ASCII STL file of the triangles (their corners in the order given,
// 17 digits), and a mesh tool named "die" of it.
ToolDef stl_die(const std::filesystem::path& file, const std::vector<std::array<sdk::Vec3, 3>>& tris,
                const std::string& pointer) {
  std::ofstream s(file);
  s.precision(17);
  s << "solid die\n";
  for (const auto& t : tris) {
    s << " facet normal 0 0 0\n  outer loop\n";
    for (const sdk::Vec3& v : t) s << "   vertex " << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid die\n";
  ToolDef def;
  def.name = "die";
  def.pointer = pointer;
  def.surface.type = "mesh";
  def.surface.file = file;
  return def;
}

}  // namespace

// A revolved quarter circle + line is a hemisphere on a cylinder: the
// distance above the equator is |p| - R with the radial normal, below it
// r - R. Tolerance 1e-12 m (exact geometry, round-off only).
TEST(Tools, RevolvedHemisphereMatchesTheSphere) {
  const double R = 0.0375;
  const ToolDef def = punch_def(R);
  const RigidTool t(def);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (int k = 0; k < 200; ++k) {
    const std::array<double, 3> p = {u(rng), u(rng), std::abs(u(rng))};
    const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    const Answer a = ask(t, p);
    EXPECT_NEAR(a.d, len - R, 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.n[i], p[i] / len, 1e-9);
  }
  const Answer side = ask(t, {0.05, 0.0, -0.03});
  EXPECT_NEAR(side.d, 0.05 - R, 1e-12);
  EXPECT_NEAR(side.n[0], 1.0, 1e-12);
  const Answer inside = ask(t, {0.0, 0.01, -0.02});
  EXPECT_NEAR(inside.d, 0.01 - R, 1e-12);  // inside the cylinder: negative
}

// A die: flat top z = 0 for r >= a + f, an entry fillet of radius f, and the
// wall r = a below it (outside = above the top and inside the opening).
TEST(Tools, RevolvedDieWithFillet) {
  const double a = 0.04, f = 0.005;
  ToolDef d;
  d.name = "die";
  d.pointer = "/tools/1";
  d.surface.type = "revolved";
  ProfileSegment wall, fillet, top;
  wall.a = {a, -0.05};
  wall.b = {a, -f};
  fillet.arc = true;
  fillet.a = {a, -f};
  fillet.b = {a + f, 0};
  fillet.centre = {a + f, -f};
  top.a = {a + f, 0};
  top.b = {0.2, 0};
  d.surface.profile = {wall, fillet, top};
  const RigidTool t(d);
  Answer x = ask(t, {0.0, 0.1, 0.002});  // above the flat top
  EXPECT_NEAR(x.d, 0.002, 1e-12);
  EXPECT_NEAR(x.n[2], 1.0, 1e-12);
  x = ask(t, {0.03, 0.0, -0.02});  // in the opening, next to the wall
  EXPECT_NEAR(x.d, a - 0.03, 1e-12);
  EXPECT_NEAR(x.n[0], -1.0, 1e-12);
  // Over the fillet at 45 degrees, 1 mm out: distance 1 mm, normal along the diagonal.
  const double c = std::sqrt(0.5);
  const std::array<double, 3> p = {0.0, a + f - (f + 0.001) * c, -f + (f + 0.001) * c};
  x = ask(t, p);
  EXPECT_NEAR(x.d, 0.001, 1e-12);
  EXPECT_NEAR(x.n[1], -c, 1e-9);
  EXPECT_NEAR(x.n[2], c, 1e-9);
  x = ask(t, {0.0, 0.1, -0.001});  // under the top surface, inside the die
  EXPECT_NEAR(x.d, -0.001, 1e-12);
}

// A tool mesh (ASCII and binary STL of a square, Gmsh of the same) answers
// like the plane it is, and +infinity beyond the cutoff.
// query() answers a revolved tool in vector passes over the points; they
// must give the bits of the point-by-point query_revolved: profiles with
// lines and arcs turning both ways (the hemisphere scene's punch, die with
// its fillet, and holder ring with its edge radii), a moved tool, points on
// the axis, on piece ends and corners, inside and outside the arcs, and
// runs of every length from 1 to 300 (over the 256-point chunks).
TEST(Tools, RevolvedVectorPassesMatchPointByPoint) {
  auto seg = [](bool arc, std::array<double, 2> a, std::array<double, 2> b, std::array<double, 2> c = {0, 0}) {
    ProfileSegment g;
    g.arc = arc;
    g.a = a;
    g.b = b;
    g.centre = c;
    return g;
  };
  std::vector<ToolDef> defs(3);
  for (auto& d : defs) {
    d.name = "tool";
    d.pointer = "/tools/0";
    d.surface.type = "revolved";
  }
  defs[0].surface.profile = {seg(false, {0.075, 0.1}, {0.075, 0}), seg(true, {0.075, 0}, {0, -0.075}, {0, 0})};
  defs[0].surface.axis_origin = {0, 0, 0.076};
  defs[1].surface.profile = {seg(false, {0.08, -0.1}, {0.08, -0.0075}),
                             seg(true, {0.08, -0.0075}, {0.0875, 0}, {0.0875, -0.0075}),
                             seg(false, {0.0875, 0}, {0.3, 0})};
  defs[2].surface.profile = {seg(true, {0.155, 0.005}, {0.15, 0}, {0.15, 0.005}), seg(false, {0.15, 0}, {0.09, 0}),
                             seg(true, {0.09, 0}, {0.085, 0.005}, {0.09, 0.005})};
  defs[2].surface.axis_origin = {0, 0, 0.001};
  defs[2].surface.axis_direction = {0.1, -0.2, 1.0};  // a tilted axis
  defs[1].motion.kind = MotionDef::Kind::Velocity;
  defs[1].motion.velocity = {0.0, 0.0, 0.05};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  int compared = 0;
  for (const ToolDef& def : defs) {
    RigidTool t(def);
    t.advance(0.0, 0.1, 0.1, {0, 0, 0});  // moved: the queries subtract the displacement
    std::vector<double> pts;
    for (int k = 0; k < 2000; ++k) pts.insert(pts.end(), {u(rng), u(rng), 0.5 * u(rng)});
    for (const auto& g : def.surface.profile)  // piece ends and arc centres, on the axis plane y = 0
      for (const auto& q : {g.a, g.b, g.centre}) {
        const auto& o = def.surface.axis_origin;
        pts.insert(pts.end(), {o[0] + q[0] + t.displacement()[0], o[1] + t.displacement()[1],
                               o[2] + q[1] + t.displacement()[2]});
      }
    const auto& o = def.surface.axis_origin;  // a point on the axis (if it is z)
    pts.insert(pts.end(), {o[0] + t.displacement()[0], o[1] + t.displacement()[1], 0.03 + t.displacement()[2]});
    const std::size_t n = pts.size() / 3;
    for (const std::size_t len : {std::size_t{1}, std::size_t{3}, std::size_t{7}, std::size_t{300}, n}) {
      for (std::size_t b = 0; b + len <= n; b += len) {
        std::vector<double> d(len), nn(3 * len);
        t.query(len, &pts[3 * b], 1.0, d.data(), nn.data());
        for (std::size_t i = 0; i < len; ++i) {
          const double* x = &pts[3 * (b + i)];
          const double p[3] = {x[0] - t.displacement()[0], x[1] - t.displacement()[1], x[2] - t.displacement()[2]};
          double d1, n1[3];
          t.query_revolved(p, d1, n1);
          ASSERT_EQ(std::memcmp(&d1, &d[i], sizeof d1), 0) << "point " << b + i << ": " << d1 << " vs " << d[i];
          ASSERT_EQ(std::memcmp(n1, &nn[3 * i], sizeof n1), 0) << "point " << b + i;
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 29000);
}

TEST(Tools, MeshToolsAnswerLikeTheirPlane) {
  const auto dir = temp_dir("tool_mesh");
  {
    std::ofstream s(dir / "square.stl");
    s << "solid sq\n";
    for (const auto& tri : {std::array<double, 6>{0, 0, 1, 0, 1, 1}, std::array<double, 6>{0, 0, 1, 1, 0, 1}}) {
      s << " facet normal 0 0 1\n  outer loop\n";
      for (int k = 0; k < 3; ++k) s << "   vertex " << tri[2 * k] << ' ' << tri[2 * k + 1] << " 0.5\n";
      s << "  endloop\n endfacet\n";
    }
    s << "endsolid sq\n";
  }
  {
    std::ofstream s(dir / "square_bin.stl", std::ios::binary);
    char header[80] = {};
    s.write(header, 80);
    const std::uint32_t n = 2;
    s.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& tri : {std::array<float, 6>{0, 0, 1, 0, 1, 1}, std::array<float, 6>{0, 0, 1, 1, 0, 1}}) {
      const float normal[3] = {0, 0, 1};
      s.write(reinterpret_cast<const char*>(normal), 12);
      for (int k = 0; k < 3; ++k) {
        const float v[3] = {tri[2 * k], tri[2 * k + 1], 0.5f};
        s.write(reinterpret_cast<const char*>(v), 12);
      }
      const std::uint16_t attr = 0;
      s.write(reinterpret_cast<const char*>(&attr), 2);
    }
  }
  {
    std::ofstream s(dir / "square.msh");
    s << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0.5\n2 1 0 0.5\n3 1 1 0.5\n4 0 1 0.5\n$EndNodes\n"
      << "$Elements\n2\n1 2 0 1 2 3\n2 2 0 1 3 4\n$EndElements\n";
  }
  {
    // The same with a triangle of zero area (three corners on the
    // diagonal) and a node no triangle uses: the tool leaves the first out
    // (as from an STL file) and the second is not part of the surface.
    std::ofstream s(dir / "square_zero.msh");
    s << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0.5\n2 1 0 0.5\n3 1 1 0.5\n4 0 1 0.5\n"
      << "5 0.5 0.5 0.5\n6 5 5 5\n$EndNodes\n"
      << "$Elements\n3\n1 2 0 1 2 3\n2 2 0 1 5 3\n3 2 0 1 3 4\n$EndElements\n";
  }
  for (const char* name : {"square.stl", "square_bin.stl", "square.msh", "square_zero.msh"}) {
    ToolDef d;
    d.name = "m";
    d.pointer = "/tools/0";
    d.surface.type = "mesh";
    d.surface.file = dir / name;
    const RigidTool t(d);
    Answer a = ask(t, {0.3, 0.6, 0.52}, 0.1);
    EXPECT_NEAR(a.d, 0.02, 1e-7) << name;
    EXPECT_NEAR(a.n[2], 1.0, 1e-12) << name;
    a = ask(t, {0.7, 0.2, 0.49}, 0.1);
    EXPECT_NEAR(a.d, -0.01, 1e-7) << name;
    a = ask(t, {0.5, 0.5, 0.9}, 0.1);
    EXPECT_TRUE(std::isinf(a.d)) << name;
    EXPECT_NE(t.describe().find("2 triangles, 4 vertices"), std::string::npos) << t.describe();
    EXPECT_EQ(t.describe().find("1 triangle(s) of zero area") != std::string::npos,
              std::string(name) == "square_zero.msh")
        << t.describe();
  }
  {
    // A Gmsh tool faces where its triangles turn, as an STL one does: the
    // square turned clockwise (seen from +z) has its outside below.
    std::ofstream(dir / "square_down.msh")
        << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0.5\n2 1 0 0.5\n3 1 1 0.5\n4 0 1 0.5\n$EndNodes\n"
        << "$Elements\n2\n1 2 0 1 3 2\n2 2 0 1 4 3\n$EndElements\n";
    ToolDef d;
    d.name = "down";
    d.pointer = "/tools/0";
    d.surface.type = "mesh";
    d.surface.file = dir / "square_down.msh";
    const Answer a = ask(RigidTool(d), {0.3, 0.6, 0.52}, 0.1);
    EXPECT_NEAR(a.d, -0.02, 1e-12);
    EXPECT_NEAR(a.n[2], -1.0, 1e-12);
  }
  ToolDef bad;
  bad.pointer = "/tools/0";
  bad.surface.type = "mesh";
  bad.surface.file = dir / "nothing.stl";
  EXPECT_THROW(RigidTool{bad}, JobError);
}

// A meshed die as CAD exporters write one: its flat ring and its wall as
// long thin triangles from edge to edge (0.21 m and 0.09 m long), its
// fillet as fine ones (0.5 mm), over a quarter turn, in a shuffled order.
// Every answer must be the one of a search through every triangle (the
// closest, of equal distances the file's first; the same closest-point
// function, so the same bits), near the surface and far from it, with the
// contact's cutoff, a cutoff of 10 mm and none; and near the surface the
// distance must be the revolved die's within the facets' chord (1e-5 m).
TEST(Tools, MeshToolAnswersAsASearchOfEveryTriangle) {
  using sdk::Vec3;
  const double pi = std::acos(-1.0);
  // The die's profile (r, z) as the hemisphere scene has it.
  std::vector<std::array<double, 2>> prof = {{0.08, -0.1}, {0.08, -0.0075}};
  const int fillet = 24;  // 90 degrees of a 7.5 mm radius
  for (int k = 1; k <= fillet; ++k) {
    const double a = pi - 0.5 * pi * k / fillet;  // from the wall (r = 0.08) to the ring (z = 0)
    prof.push_back({0.0875 + 0.0075 * std::cos(a), -0.0075 + 0.0075 * std::sin(a)});
  }
  prof.back() = {0.0875, 0.0};
  prof.push_back({0.3, 0.0});
  const int sectors = 100;
  std::vector<std::array<Vec3, 3>> tris;
  auto at = [](std::array<double, 2> q, double t) { return Vec3{q[0] * std::cos(t), q[0] * std::sin(t), q[1]}; };
  for (std::size_t k = 0; k + 1 < prof.size(); ++k)
    for (int j = 0; j < sectors; ++j) {
      const double t0 = -0.05 + (0.5 * pi + 0.1) * j / sectors, t1 = -0.05 + (0.5 * pi + 0.1) * (j + 1) / sectors;
      // Outward normals, on the left of the profile's direction of travel:
      // (b - a) x (c - a) = z x theta = -r on the wall.
      const Vec3 a = at(prof[k], t0), b = at(prof[k + 1], t0), c = at(prof[k + 1], t1), d = at(prof[k], t1);
      tris.push_back({a, b, c});
      tris.push_back({a, c, d});
    }
  std::shuffle(tris.begin(), tris.end(), std::mt19937(5));
  const auto dir = temp_dir("tool_mesh_cad");
  const ToolDef def = stl_die(dir / "die.stl", tris, "/tools/1");
  const RigidTool tool(def);
  ToolDef rdef = def;
  rdef.surface.type = "revolved";
  for (const auto& [a, b] : {std::pair{prof[0], prof[1]}, std::pair{prof[prof.size() - 2], prof.back()}}) {
    ProfileSegment g;
    g.a = a;
    g.b = b;
    rdef.surface.profile.push_back(g);
  }
  rdef.surface.profile.insert(rdef.surface.profile.begin() + 1, ProfileSegment{});
  rdef.surface.profile[1].arc = true;
  rdef.surface.profile[1].a = prof[1];
  rdef.surface.profile[1].b = {0.0875, 0.0};
  rdef.surface.profile[1].centre = {0.0875, -0.0075};
  const RigidTool revolved(rdef);

  // Each triangle from its smallest corner (by x, y, z), in its turning
  // order; of equally close triangles the one whose corners come first.
  auto canon = tris;
  for (auto& t : canon) {
    int first = 0;
    for (int k = 1; k < 3; ++k)
      if (std::lexicographical_compare(t[k].begin(), t[k].end(), t[first].begin(), t[first].end())) first = k;
    t = {t[first], t[(first + 1) % 3], t[(first + 2) % 3]};
  }
  auto before = [&](std::size_t a, std::size_t b) {
    for (int k = 0; k < 3; ++k)
      if (canon[a][k] != canon[b][k]) return canon[a][k] < canon[b][k];
    return a < b;
  };
  auto every = [&](const Vec3& x, double cutoff, double& dist, Vec3& n) {
    double best = std::isfinite(cutoff) ? cutoff * cutoff : std::numeric_limits<double>::infinity();
    int be = -1;
    Vec3 bcp{};
    for (std::size_t e = 0; e < canon.size(); ++e) {
      const Vec3 cp = sdk::closest_point_on_triangle(x, canon[e][0], canon[e][1], canon[e][2]);
      const Vec3 dv = sdk::sub(x, cp);
      const double d2 = sdk::dot(dv, dv);
      if (d2 < best || (d2 == best && be >= 0 && before(e, static_cast<std::size_t>(be)))) {
        best = d2;
        be = static_cast<int>(e);
        bcp = cp;
      }
    }
    if (be < 0) {
      dist = std::numeric_limits<double>::infinity();
      return;
    }
    const auto& t = canon[static_cast<std::size_t>(be)];
    const Vec3 c = sdk::cross(sdk::sub(t[1], t[0]), sdk::sub(t[2], t[0]));
    const double l = sdk::norm(c);
    const Vec3 fn = {c[0] / l, c[1] / l, c[2] / l};
    const Vec3 dv = sdk::sub(x, bcp);
    const double len = std::sqrt(best);
    const double side = sdk::dot(dv, fn) >= 0 ? 1.0 : -1.0;
    dist = side * len;
    n = std::abs(sdk::dot(dv, fn)) < (1 - 1e-12) * len ? sdk::scale(dv, side / len) : fn;
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ang(0.0, 0.5 * pi), u(-1.0, 1.0);
  int near = 0, found = 0, beyond = 0;
  for (int k = 0; k < 3000; ++k) {
    // Near the surface (within 2 mm of a point of the profile), or anywhere over the die.
    const std::array<double, 2> q = prof[static_cast<std::size_t>(k) % prof.size()];
    const std::array<double, 2> on = k % 3 == 2 ? std::array<double, 2>{0.15 + 0.15 * u(rng), 0.05 * u(rng)}
                                                : std::array<double, 2>{q[0] + 0.002 * u(rng), q[1] + 0.002 * u(rng)};
    const Vec3 x = at(on, ang(rng));
    for (const double cutoff : {0.0015, 0.01, std::numeric_limits<double>::infinity()}) {
      Answer a = ask(tool, x, cutoff);
      double d;
      Vec3 n{};
      every(x, cutoff, d, n);
      ASSERT_EQ(std::memcmp(&a.d, &d, sizeof d), 0) << "point " << k << ", cutoff " << cutoff << ": " << a.d << " vs " << d;
      if (std::isinf(d)) {
        ++beyond;
        continue;
      }
      ++found;
      for (int j = 0; j < 3; ++j) ASSERT_EQ(std::memcmp(&a.n[j], &n[j], sizeof d), 0) << "point " << k;
      if (std::isfinite(cutoff) || std::abs(d) > 0.002) continue;
      ++near;
      EXPECT_NEAR(d, ask(revolved, x).d, 1e-5) << "point " << k;
    }
  }
  EXPECT_GT(near, 1000);
  EXPECT_GT(beyond, 500);
  EXPECT_GT(found, 5000);
}

namespace {

// A die's profile (r, z): a wall at r = 80 mm, a 7.5 mm fillet in 24
// facets, a flat ring to r = 120 mm (in two pieces where `split_ring`),
// and its triangles over a quarter turn in `sectors` sectors, ring after
// ring.
std::vector<std::array<double, 2>> die_profile(bool split_ring) {
  const double pi = std::acos(-1.0);
  std::vector<std::array<double, 2>> prof = {{0.08, -0.02}, {0.08, -0.0075}};
  for (int k = 1; k <= 24; ++k) {
    const double a = pi - 0.5 * pi * k / 24;
    prof.push_back({0.0875 + 0.0075 * std::cos(a), -0.0075 + 0.0075 * std::sin(a)});
  }
  prof.back() = {0.0875, 0.0};
  if (split_ring) prof.push_back({0.10, 0.0});
  prof.push_back({0.12, 0.0});
  return prof;
}

std::array<double, 3> on_die(std::array<double, 2> q, double t) { return {q[0] * std::cos(t), q[0] * std::sin(t), q[1]}; }

std::vector<std::array<sdk::Vec3, 3>> die_rows(const std::vector<std::array<double, 2>>& prof, int sectors) {
  const double pi = std::acos(-1.0);
  std::vector<std::array<sdk::Vec3, 3>> rows;
  for (std::size_t k = 0; k + 1 < prof.size(); ++k)
    for (int j = 0; j < sectors; ++j) {
      const double t0 = 0.5 * pi * j / sectors, t1 = 0.5 * pi * (j + 1) / sectors;
      const sdk::Vec3 a = on_die(prof[k], t0), b = on_die(prof[k + 1], t0), c = on_die(prof[k + 1], t1),
                      d = on_die(prof[k], t1);
      rows.push_back({a, b, c});
      rows.push_back({a, c, d});
    }
  return rows;
}

}  // namespace

// A mesh tool's answers depend on its triangles, not on the file: the
// die above (a fillet of 24 facets between a wall and a ring, 60 sectors)
// in rows, and shuffled with every triangle started from a random corner
// (the same turning order), give the same bits for points at its vertices
// and edge midpoints (equally close triangles all round: on the fillet
// their faces differ), 1 um from them inside and outside along a few
// directions, and for random points near it.
TEST(Tools, MeshToolAnswersDoNotDependOnTheFilesOrder) {
  using sdk::Vec3;
  const double pi = std::acos(-1.0);
  const auto prof = die_profile(false);
  const auto at = on_die;
  const std::vector<std::array<Vec3, 3>> rows = die_rows(prof, 60);
  auto shuffled = rows;
  std::mt19937 rng(11);
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  for (auto& t : shuffled) {
    const int r = static_cast<int>(rng() % 3);
    t = {t[r], t[(r + 1) % 3], t[(r + 2) % 3]};
  }
  const auto dir = temp_dir("tool_mesh_order");
  const ToolDef d1 = stl_die(dir / "rows.stl", rows, "/tools/0"), d2 = stl_die(dir / "shuffled.stl", shuffled, "/tools/0");
  const RigidTool a(d1), b(d2);
  std::vector<Vec3> points;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 dirs[] = {{0, 0, 1}, {0, 0, -1}, {0.6, 0, 0.8}, {-0.6, 0.48, 0.64}, {0.3, -0.4, -0.866}};
  for (const auto& t : rows)
    for (int k = 0; k < 3; ++k) {
      const Vec3 mid = sdk::scale(sdk::add(t[k], t[(k + 1) % 3]), 0.5);
      for (const Vec3& base : {t[k], mid}) {
        points.push_back(base);
        for (const Vec3& d : dirs) points.push_back(sdk::add(base, sdk::scale(d, 1e-6)));
      }
    }
  for (int k = 0; k < 5000; ++k) {
    const auto& q = prof[static_cast<std::size_t>(k) % prof.size()];
    points.push_back(at({q[0] + 0.002 * u(rng), q[1] + 0.002 * u(rng)}, 0.25 * pi * (1 + u(rng))));
  }
  std::size_t differ = 0;
  for (const double cutoff : {0.0015, std::numeric_limits<double>::infinity()}) {
    std::vector<double> da(points.size()), db(points.size()), na(3 * points.size()), nb(3 * points.size());
    a.query(points.size(), points[0].data(), cutoff, da.data(), na.data());
    b.query(points.size(), points[0].data(), cutoff, db.data(), nb.data());
    for (std::size_t i = 0; i < points.size(); ++i)
      if (std::memcmp(&da[i], &db[i], sizeof(double)) != 0 || std::memcmp(&na[3 * i], &nb[3 * i], 3 * sizeof(double)) != 0)
        ++differ;
  }
  EXPECT_EQ(differ, 0u) << "of " << 2 * points.size() << " answers";
}

// query_kept() answers a point from the triangles listed in its record
// while the point (in the tool's frame) stays near where the list was made:
// points walking in steps from 0.1 um to 0.6 mm over a die whose fillet is
// finer than the search's reach, with the tool moving and the cutoff
// changing half way (and to 0.1 pm, within the mesh's round-off margins,
// for the last steps), get the bits of the tree's answers at every step,
// from lists (most records) and from the tree (records whose list would
// not fit), near the surface, on both sides and beyond the cutoff.
TEST(Tools, KeptRecordsGiveTheTreesAnswers) {
  using sdk::Vec3;
  const double pi = std::acos(-1.0);
  const auto prof = die_profile(true);
  const auto at = on_die;
  const auto tris = die_rows(prof, 90);
  const auto dir = temp_dir("tool_mesh_kept");
  ToolDef def = stl_die(dir / "die.stl", tris, "/tools/0");
  RigidTool tool(def);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::size_t n = 3000;
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& q = prof[i % prof.size()];
    x[i] = at({q[0] + 0.003 * u(rng), q[1] + 0.003 * u(rng)}, 0.25 * pi * (1 + 0.9 * u(rng)));
  }
  std::vector<std::byte> kept(n * RigidTool::kKeptBytes, std::byte{0});
  std::vector<double> dk(n), dt(n), nk(3 * n), nt(3 * n);
  const double steps[] = {1e-7, 1e-5, 1e-4, 6e-4};
  std::size_t differ = 0, answers = 0, listed = 0, searched = 0, within = 0;
  for (int s = 0; s < 240; ++s) {
    const double cutoff = s < 120 ? 0.0015 : s < 230 ? 0.001 : 1e-13;  // the last: within the round-off margins
    tool.set_motion_state({0.0, 0.0, -2e-5 * s}, {0, 0, 0});
    tool.query_kept(n, x[0].data(), cutoff, dk.data(), nk.data(), kept.data());
    tool.query(n, x[0].data(), cutoff, dt.data(), nt.data());
    for (std::size_t i = 0; i < n; ++i) {
      ++answers;
      if (std::memcmp(&dk[i], &dt[i], sizeof(double)) != 0 || std::memcmp(&nk[3 * i], &nt[3 * i], 3 * sizeof(double)) != 0)
        ++differ;
      if (std::isfinite(dt[i])) ++within;
      const int c = RigidTool::kept_listed(&kept[i * RigidTool::kKeptBytes]);
      if (c >= 0) ++listed;
      if (c == -1) ++searched;
      const double h = steps[(i + static_cast<std::size_t>(s) / 40) % 4];
      x[i] = sdk::add(x[i], Vec3{h * u(rng), h * u(rng), h * u(rng)});
    }
  }
  EXPECT_EQ(differ, 0u) << "of " << answers << " answers";
  EXPECT_GT(within, answers / 4) << "answers within the cutoff";
  EXPECT_LT(within, answers * 3 / 4);
  EXPECT_GT(listed, answers / 2) << "answers from lists";
  EXPECT_GT(searched, answers / 100) << "answers from the tree (lists that would not fit)";
}

// Two triangles with a common edge must face the same side: walked the
// same way, one of them faces into the tool and the mesh is refused,
// naming both (counted from 1 in the file); `flip` turns all of them, so a
// consistent mesh stays consistent. describe() counts the edges.
// Three triangles, then the second one reversed; with and without `flip`.
// Then the same with two triangles of zero area ahead of them (a corner
// twice, three corners on a line), as CAD exports write now and then: they
// are left out and counted, the answers are the same, and the message
// still names the triangles by their place in the file.
TEST(Tools, MeshToolFacingBothWaysIsRefused) {
  const auto dir = temp_dir("tool_mesh_sides");
  auto write = [&](const std::string& name, bool second_reversed, bool zero_area) {
    std::ofstream s(dir / name);
    s << "solid sq\n";
    // Three triangles: the unit square at z = 0 and one more beyond the edge x = 1.
    std::vector<std::array<double, 6>> tris = {
        {0, 0, 1, 0, 1, 1}, second_reversed ? std::array<double, 6>{0, 0, 0, 1, 1, 1} : std::array<double, 6>{0, 0, 1, 1, 0, 1},
        {1, 0, 2, 0, 1, 1}};
    if (zero_area) tris.insert(tris.begin(), {{0, 0, 1, 1, 1, 1}, {0, 0, 0.5, 0.5, 1, 1}});
    for (const auto& t : tris) {
      s << " facet normal 0 0 1\n  outer loop\n";
      for (int k = 0; k < 3; ++k) s << "   vertex " << t[2 * k] << ' ' << t[2 * k + 1] << " 0\n";
      s << "  endloop\n endfacet\n";
    }
    s << "endsolid sq\n";
  };
  ToolDef d;
  d.name = "die";
  d.pointer = "/tools/2";
  d.surface.type = "mesh";
  for (const bool zero_area : {false, true}) {
    const std::string tag = zero_area ? "_zero" : "";
    write("good" + tag + ".stl", false, zero_area);
    write("bad" + tag + ".stl", true, zero_area);
    for (const bool flip : {false, true}) {
      d.surface.file = dir / ("good" + tag + ".stl");
      d.surface.flip = flip;
      const RigidTool t(d);
      EXPECT_NE(t.describe().find("tool 'die': 3 triangles, 5 vertices from"), std::string::npos) << t.describe();
      EXPECT_NE(t.describe().find("2 edges between two triangles (all facing the same side), 5 free, 0 shared by more"),
                std::string::npos)
          << t.describe();
      EXPECT_EQ(t.describe().find("2 triangle(s) of zero area in the file left out") != std::string::npos, zero_area)
          << t.describe();
      EXPECT_NEAR(ask(t, {0.6, 0.3, 0.1}).d, flip ? -0.1 : 0.1, 1e-12);
      d.surface.file = dir / ("bad" + tag + ".stl");
      try {
        const RigidTool bad(d);
        ADD_FAILURE() << "a mesh facing both ways was taken";
      } catch (const JobError& e) {
        EXPECT_EQ(e.pointer(), "/tools/2/surface/file");
        const std::string names = zero_area ? "its triangles 3 and 4" : "its triangles 1 and 2";
        EXPECT_NE(std::string(e.what()).find("faces both ways: " + names + " (counted from 1 in the file)"),
                  std::string::npos)
            << e.what();
      }
    }
  }
  ToolDef plane;
  plane.surface.type = "plane";
  EXPECT_EQ(RigidTool(plane).describe(), "");
}

// The surfaces the results draw: every vertex on the surface (1e-12 m:
// points computed on it), every triangle facing out (its normal against
// the outward direction worked out here from the geometry: +z for the
// plane, from the centre for the sphere, from the axis on the punch's
// cylinder and from the hemisphere's centre below it), and areas within
// 1 % of the exact ones (24 x 48 pieces of a sphere miss 0.3 % of it; 48
// sectors of a cylinder 0.29 %). The plane covers the given box and 20 %
// beyond; a mesh tool gives its own triangles. None moved by the tool's
// displacement.
TEST(Tools, DisplayMeshesLieOnTheSurfaceAndFaceOut) {
  using sdk::Vec3;
  const double pi = std::acos(-1.0);
  auto check = [&](const RigidTool& t, const std::function<Vec3(const Vec3&)>& outward, double area, const char* what) {
    std::vector<double> xyz;
    std::vector<int> tri;
    t.display_mesh({-0.05, -0.02, 0.0}, {0.05, 0.02, 0.001}, xyz, tri);
    ASSERT_FALSE(tri.empty()) << what;
    for (std::size_t i = 0; i < xyz.size() / 3; ++i) {
      const Vec3 p = {xyz[3 * i] + t.displacement()[0], xyz[3 * i + 1] + t.displacement()[1],
                      xyz[3 * i + 2] + t.displacement()[2]};
      EXPECT_NEAR(ask(t, p, std::numeric_limits<double>::infinity()).d, 0.0, 1e-12) << what << ", vertex " << i;
    }
    double sum = 0;
    for (std::size_t e = 0; e < tri.size() / 3; ++e) {
      const Vec3 a = sdk::load3(xyz.data(), tri[3 * e]), b = sdk::load3(xyz.data(), tri[3 * e + 1]),
                 c = sdk::load3(xyz.data(), tri[3 * e + 2]);
      const Vec3 n = sdk::cross(sdk::sub(b, a), sdk::sub(c, a));
      sum += 0.5 * sdk::norm(n);
      const Vec3 m = sdk::scale(sdk::add(sdk::add(a, b), c), 1.0 / 3.0);
      EXPECT_GT(sdk::dot(n, outward(m)), 0.0) << what << ", triangle " << e;
    }
    EXPECT_NEAR(sum, area, 0.01 * area) << what;
  };
  ToolDef plane;
  plane.name = "plane";
  plane.surface.type = "plane";
  plane.surface.point = {0, 0, 0.002};
  plane.surface.normal = {0, 0, 1};
  const double side = 2 * 0.6 * std::sqrt(0.1 * 0.1 + 0.04 * 0.04 + 0.001 * 0.001);
  check(RigidTool(plane), [](const Vec3&) { return Vec3{0, 0, 1}; }, side * side, "plane");
  ToolDef ball;
  ball.name = "ball";
  ball.surface.type = "sphere";
  ball.surface.centre = {0.01, 0.02, 0.03};
  ball.surface.radius = 0.05;
  check(RigidTool(ball), [&](const Vec3& m) { return sdk::sub(m, Vec3{0.01, 0.02, 0.03}); },
        4 * pi * 0.05 * 0.05, "sphere");
  ToolDef punch = punch_def(0.075);  // hemisphere (pole at z = R) on a cylinder down to z = -0.1
  punch.motion.kind = MotionDef::Kind::Velocity;
  punch.motion.velocity = {0, 0, -0.01};
  RigidTool moved(punch);
  moved.advance(0.0, 1.0, 1.0, {0, 0, 0});  // 10 mm down: the display stays where the tool started
  check(moved,
        [&](const Vec3& m) { return m[2] > 0 ? m : Vec3{m[0], m[1], 0.0}; },
        2 * pi * 0.075 * 0.075 + 2 * pi * 0.075 * 0.1, "revolved punch");
  const auto dir = temp_dir("tool_display");
  write_square_stl(dir / "square.stl", -0.01, 0.06, 0.0);
  ToolDef mesh;
  mesh.name = "mesh";
  mesh.surface.type = "mesh";
  mesh.surface.file = dir / "square.stl";
  check(RigidTool(mesh), [](const Vec3&) { return Vec3{0, 0, 1}; }, 0.07 * 0.07, "mesh");
}

// Cutting a display mesh at a symmetry plane. (a) A flat rectangle
// [-0.07, 0.13] x [-0.04, 0.11] at z = 0.02 in 10 x 6 cells with jittered
// inner vertices, cut at x = 0 and y = 0: the part kept is the rectangle
// [0, 0.13] x [0, 0.11] (area to 1e-12 relative, round-off), every vertex
// on its side exactly, every triangle still facing +z, no vertex twice;
// the other side of x = 0 holds the rest of the area. (b) A closed sphere
// (an icosahedron divided twice, 320 triangles), turned and moved so that
// the planes cross its triangles anywhere: after the cuts every edge is
// shared by two triangles, once in each direction, except those on a
// plane (open, once each); the areas of the two sides of x = 0 add up to
// the whole. (c) A vertex within the tolerance of the plane is put on it
// and its triangles kept.
TEST(Tools, CutDisplayMeshKeepsTheSideOfThePlies) {
  using sdk::Vec3;
  auto area = [](const std::vector<double>& xyz, const std::vector<int>& tri, double* nz_min = nullptr) {
    double sum = 0, nz = std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < tri.size() / 3; ++e) {
      const Vec3 a = sdk::load3(xyz.data(), tri[3 * e]), b = sdk::load3(xyz.data(), tri[3 * e + 1]),
                 c = sdk::load3(xyz.data(), tri[3 * e + 2]);
      const Vec3 n = sdk::cross(sdk::sub(b, a), sdk::sub(c, a));
      sum += 0.5 * sdk::norm(n);
      nz = std::min(nz, n[2] / sdk::norm(n));
    }
    if (nz_min) *nz_min = nz;
    return sum;
  };
  auto distinct = [](const std::vector<double>& xyz) {
    std::vector<std::array<double, 3>> v;
    for (std::size_t i = 0; i < xyz.size() / 3; ++i) v.push_back({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
    std::sort(v.begin(), v.end());
    return std::adjacent_find(v.begin(), v.end()) == v.end();
  };
  {  // (a)
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    const int nx = 10, ny = 6;
    std::vector<double> xyz;
    std::vector<int> tri;
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const bool inner = i > 0 && i < nx && j > 0 && j < ny;
        xyz.insert(xyz.end(), {-0.07 + 0.02 * (i + (inner ? jitter(rng) : 0.0)),
                               -0.04 + 0.025 * (j + (inner ? jitter(rng) : 0.0)), 0.02});
      }
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
        if ((i + j) % 2)
          tri.insert(tri.end(), {a, b, c, a, c, d});
        else
          tri.insert(tri.end(), {a, b, d, b, c, d});
      }
    ASSERT_NEAR(area(xyz, tri), 0.2 * 0.15, 1e-15);
    auto kept_xyz = xyz;
    auto kept_tri = tri;
    cut_display_mesh(kept_xyz, kept_tri, 0, 1.0, 1e-12);
    cut_display_mesh(kept_xyz, kept_tri, 1, 1.0, 1e-12);
    double nz = 0;
    EXPECT_NEAR(area(kept_xyz, kept_tri, &nz), 0.13 * 0.11, 1e-12 * 0.13 * 0.11);
    EXPECT_GT(nz, 1 - 1e-12) << "every triangle facing +z";
    for (std::size_t i = 0; i < kept_xyz.size() / 3; ++i) {
      ASSERT_GE(kept_xyz[3 * i], 0.0) << i;
      ASSERT_GE(kept_xyz[3 * i + 1], 0.0) << i;
    }
    EXPECT_TRUE(distinct(kept_xyz));
    auto rest_xyz = xyz;
    auto rest_tri = tri;
    cut_display_mesh(rest_xyz, rest_tri, 0, -1.0, 1e-12);
    EXPECT_NEAR(area(rest_xyz, rest_tri), 0.07 * 0.15, 1e-12 * 0.07 * 0.15);
    for (std::size_t i = 0; i < rest_xyz.size() / 3; ++i) ASSERT_LE(rest_xyz[3 * i], 0.0) << i;
  }
  {  // (b)
    const double g = (1 + std::sqrt(5.0)) / 2;
    std::vector<double> xyz = {-1, g, 0, 1, g, 0, -1, -g, 0, 1, -g, 0, 0, -1, g, 0, 1, g,
                               0, -1, -g, 0, 1, -g, g, 0, -1, g, 0, 1, -g, 0, -1, -g, 0, 1};
    std::vector<int> tri = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6,
                            7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int level = 0; level < 2; ++level) {  // each triangle into four, midpoints shared
      std::map<std::pair<int, int>, int> mid;
      auto at = [&](int a, int b) {
        const auto [it, fresh] = mid.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<int>(xyz.size() / 3));
        if (fresh)
          for (int d = 0; d < 3; ++d) xyz.push_back(0.5 * (xyz[3 * a + d] + xyz[3 * b + d]));
        return it->second;
      };
      std::vector<int> finer;
      for (std::size_t e = 0; e < tri.size(); e += 3) {
        const int a = tri[e], b = tri[e + 1], c = tri[e + 2], ab = at(a, b), bc = at(b, c), ca = at(c, a);
        finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
      }
      tri = std::move(finer);
    }
    ASSERT_EQ(tri.size(), 3u * 320u);
    const double c1 = std::cos(0.7), s1 = std::sin(0.7), c2 = std::cos(0.3), s2 = std::sin(0.3);
    for (std::size_t i = 0; i < xyz.size() / 3; ++i) {  // onto a sphere of 0.05 m, turned about z and x, moved
      Vec3 p = sdk::load3(xyz.data(), static_cast<int>(i));
      p = sdk::scale(p, 0.05 / sdk::norm(p));
      p = {c1 * p[0] - s1 * p[1], s1 * p[0] + c1 * p[1], p[2]};
      p = {p[0], c2 * p[1] - s2 * p[2], s2 * p[1] + c2 * p[2]};
      xyz[3 * i] = p[0] + 0.013;
      xyz[3 * i + 1] = p[1] - 0.007;
      xyz[3 * i + 2] = p[2];
    }
    const double whole = area(xyz, tri);
    auto kept_xyz = xyz;
    auto kept_tri = tri;
    cut_display_mesh(kept_xyz, kept_tri, 0, 1.0, 1e-12);
    cut_display_mesh(kept_xyz, kept_tri, 1, 1.0, 1e-12);
    EXPECT_TRUE(distinct(kept_xyz));
    std::map<std::pair<int, int>, int> used;  // directed edges
    for (std::size_t e = 0; e < kept_tri.size(); e += 3)
      for (int k = 0; k < 3; ++k) ++used[{kept_tri[e + k], kept_tri[e + (k + 1) % 3]}];
    int open = 0;
    for (const auto& [edge, count] : used) {
      ASSERT_EQ(count, 1) << "an edge used twice in one direction";
      const auto [a, b] = edge;
      const bool on_plane = (kept_xyz[3 * a] == 0 && kept_xyz[3 * b] == 0) ||
                            (kept_xyz[3 * a + 1] == 0 && kept_xyz[3 * b + 1] == 0);
      if (on_plane)
        ++open;
      else
        EXPECT_EQ(used.count({b, a}), 1u) << "edge " << a << "-" << b << " open off the planes";
    }
    EXPECT_GT(open, 20) << "the cuts run through triangles";
    auto a_xyz = xyz, b_xyz = xyz;
    auto a_tri = tri, b_tri = tri;
    cut_display_mesh(a_xyz, a_tri, 0, 1.0, 1e-12);
    cut_display_mesh(b_xyz, b_tri, 0, -1.0, 1e-12);
    EXPECT_NEAR(area(a_xyz, a_tri) + area(b_xyz, b_tri), whole, 1e-12 * whole);
    EXPECT_GT(area(a_xyz, a_tri), 0.5 * whole) << "the centre is on the kept side";
  }
  {  // (c)
    std::vector<double> xyz = {1e-13, 0, 0, 1, 0, 0, 1, 1, 0, -1e-13, 1, 0};
    std::vector<int> tri = {0, 1, 2, 0, 2, 3};
    cut_display_mesh(xyz, tri, 0, 1.0, 1e-9);
    EXPECT_EQ(tri, (std::vector<int>{0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(xyz[0], 0.0);
    EXPECT_EQ(xyz[9], 0.0);
  }
}

// Motion: a displacement table is interpolated linearly and held after its
// last row; the velocity over a step is the table's slope.
TEST(Tools, DisplacementTableAndVelocity) {
  ToolDef d = punch_def(0.01);
  d.motion.kind = MotionDef::Kind::Displacement;
  d.motion.table = {{0, 0, 0, 0}, {1, 0, 0, -0.05}, {2, 0, 0, -0.05}};
  RigidTool t(d);
  EXPECT_NEAR(t.prescribed(0.5)[2], -0.025, 1e-15);
  EXPECT_NEAR(t.prescribed(3.0)[2], -0.05, 1e-15);
  t.advance(0.25, 0.5, 0.5, {0, 0, 0});
  EXPECT_NEAR(t.displacement()[2], -0.0375, 1e-15);
  EXPECT_NEAR(t.velocity()[2], -0.05, 1e-12);
  // The surface moves with it: the pole is now at z = R - 0.0375.
  const Answer a = ask(t, {0, 0, 0.0});
  EXPECT_NEAR(a.d, 0.0375 - 0.01, 1e-12);
}

// A table whose first row is not zero places the tool there from the start:
// the tool of a CAD file in its closed position, opened by the first row,
// is answered at the open position before the first step (and, after it,
// where the table says, with the table's slope for its velocity).
TEST(Tools, DisplacementTableStartsAtItsFirstRow) {
  ToolDef d = punch_def(0.01);
  d.motion.kind = MotionDef::Kind::Displacement;
  d.motion.table = {{0, 0, 0, 0.02}, {1, 0, 0, 0}};
  RigidTool t(d);
  EXPECT_EQ(t.displacement()[2], 0.02);
  EXPECT_NEAR(ask(t, {0, 0, 0.05}).d, 0.05 - (0.02 + 0.01), 1e-15) << "the pole at z = 0.02 + R before any step";
  t.advance(0, 0.25, 0.25, {0, 0, 0});
  EXPECT_NEAR(t.displacement()[2], 0.015, 1e-15);
  EXPECT_NEAR(t.velocity()[2], -0.02, 1e-12);
  // A table that starts later holds its first row until then.
  d.motion.table = {{0.5, 0.01, 0, 0}, {1, 0, 0, 0}};
  RigidTool late(d);
  EXPECT_EQ(late.displacement()[0], 0.01);
  late.advance(0, 0.25, 0.25, {0, 0, 0});
  EXPECT_EQ(late.displacement()[0], 0.01);
  EXPECT_EQ(late.velocity()[0], 0.0);
}

}  // namespace ts::test
