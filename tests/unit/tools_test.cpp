// Rigid tool surfaces against their closed-form distances, and tool motion.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

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
  for (const char* name : {"square.stl", "square_bin.stl", "square.msh"}) {
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
  }
  ToolDef bad;
  bad.pointer = "/tools/0";
  bad.surface.type = "mesh";
  bad.surface.file = dir / "nothing.stl";
  EXPECT_THROW(RigidTool{bad}, JobError);
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

}  // namespace ts::test
