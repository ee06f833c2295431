// The cut pattern of a formed ply (thermostamp blank): the region of the
// blank that a map carries inside a trim surface.
#include <gtest/gtest.h>

#include <array>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "io/blank.hpp"
#include "io/export.hpp"
#include "mesh/shell_mesh.hpp"

namespace ts {
namespace {

using V3 = std::array<double, 3>;

// The message parse_trim refuses text with ("accepted" where it takes it).
std::string refused(const std::string& text) {
  try {
    parse_trim(text);
  } catch (const ExportInputError& e) {
    return e.what();
  }
  return "accepted";
}

// The signed area of an outline about +z (shoelace).
double signed_area_z(const Outline& o) {
  double a = 0;
  for (std::size_t k = 0; k < o.points.size(); ++k) {
    const V3& p = o.points[k].blank;
    const V3& q = o.points[(k + 1) % o.points.size()].blank;
    a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
  }
  return a;
}

// The part of a convex polygon (x, y) where a x + b y + c >= 0
// (Sutherland-Hodgman), independent of any mesh.
std::vector<std::array<double, 2>> clip(const std::vector<std::array<double, 2>>& poly, double a, double b, double c) {
  std::vector<std::array<double, 2>> out;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const auto& p = poly[k];
    const auto& q = poly[(k + 1) % poly.size()];
    const double fp = a * p[0] + b * p[1] + c, fq = a * q[0] + b * q[1] + c;
    if (fp >= 0) out.push_back(p);
    if ((fp >= 0) != (fq >= 0)) {
      const double t = fp / (fp - fq);
      out.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
    }
  }
  return out;
}
double area(const std::vector<std::array<double, 2>>& poly) {
  double a = 0;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const auto& p = poly[k];
    const auto& q = poly[(k + 1) % poly.size()];
    a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
  }
  return a;
}

// A closed polygon's perimeter, and the length of its sides that lie on
// one of the lines a x + b y + d = 0 (within 1e-12).
std::pair<double, double> perimeter_and_on(const std::vector<std::array<double, 2>>& poly,
                                           const std::vector<std::array<double, 3>>& lines) {
  double perimeter = 0, on = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& u = poly[i];
    const auto& w = poly[(i + 1) % poly.size()];
    const double l = std::hypot(w[0] - u[0], w[1] - u[1]);
    perimeter += l;
    for (const auto& ln : lines)
      if (std::abs(ln[0] * u[0] + ln[1] * u[1] + ln[2]) < 1e-12 &&
          std::abs(ln[0] * w[0] + ln[1] * w[1] + ln[2]) < 1e-12) {
        on += l;
        break;
      }
  }
  return {perimeter, on};
}

// The distance of (x, y) to a closed polygon's sides (m).
double to_sides(const std::vector<std::array<double, 2>>& poly, double x, double y) {
  double d = 1e300;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const auto& u = poly[k];
    const auto& w = poly[(k + 1) % poly.size()];
    const double ex = w[0] - u[0], ey = w[1] - u[1];
    const double t = std::clamp(((x - u[0]) * ex + (y - u[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
    d = std::min(d, std::hypot(x - u[0] - t * ex, y - u[1] - t * ey));
  }
  return d;
}
// The distance of (x, y) to a polygon's nearest vertex (m).
double to_vertices(const std::vector<std::array<double, 2>>& poly, double x, double y) {
  double d = 1e300;
  for (const auto& v : poly) d = std::min(d, std::hypot(x - v[0], y - v[1]));
  return d;
}

// A rectangle's mesh with its inner nodes moved at random by up to
// `amplitude` in x and y (those on its sides along them only), for
// irregular triangles with straight sides.
ShellMesh irregular_rectangle(double x0, double y0, double sx, double sy, int nx, int ny, double amplitude,
                              unsigned seed) {
  ShellMesh m = rectangle_mesh({x0, y0, 0.0}, {sx, sy}, {nx, ny});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jiggle(-amplitude, amplitude);
  const double eps = 1e-12;
  for (std::size_t i = 0; i < m.x.size(); i += 3) {
    const bool on_x = std::abs(m.x[i] - x0) < eps || std::abs(m.x[i] - x0 - sx) < eps;
    const bool on_y = std::abs(m.x[i + 1] - y0) < eps || std::abs(m.x[i + 1] - y0 - sy) < eps;
    if (!on_x) m.x[i] += jiggle(rng);
    if (!on_y) m.x[i + 1] += jiggle(rng);
  }
  return m;
}

// A rigid motion of the plan tests: turned by 30 degrees about z, moved
// by (0.3, -0.2, 0.05) m; of a point in plan and of a mesh's nodes.
std::array<double, 2> turned_and_moved(const std::array<double, 2>& v) {
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  return {c * v[0] - s * v[1] + 0.3, s * v[0] + c * v[1] - 0.2};
}
std::vector<double> turned_and_moved(const std::vector<double>& x0) {
  std::vector<double> x = x0;
  for (std::size_t i = 0; i < x.size(); i += 3) {
    const auto p = turned_and_moved(std::array<double, 2>{x0[i], x0[i + 1]});
    x[i] = p[0];
    x[i + 1] = p[1];
    x[i + 2] = x0[i + 2] + 0.05;
  }
  return x;
}

TEST(Blank, TrimSurfacesAreReadOrRefusedWithWhatIsWrong) {
  const TrimSurface p = parse_trim("plane:0,0,-0.005,0,0,-2");
  EXPECT_EQ(p.kind, TrimSurface::Kind::Plane);
  EXPECT_EQ(p.direction, (V3{0, 0, -1}));
  const double below[3] = {0.3, -0.2, -0.007}, above[3] = {0, 0, -0.004};
  EXPECT_DOUBLE_EQ(trim_level({p}, below), -0.002);
  EXPECT_DOUBLE_EQ(trim_level({p}, above), 0.001);
  const TrimSurface c = parse_trim("cylinder:0.01,0,0,0,0,3,0.08");
  const double r[3] = {0.01 + 0.06, 0.08, 5.0};  // 0.1 from the axis
  EXPECT_NEAR(trim_level({c}, r), 0.02, 1e-15);
  const TrimSurface s = parse_trim("sphere:0,0,0.1,0.05");
  const double o[3] = {0, 0.03, 0.14};
  EXPECT_NEAR(trim_level({s}, o), 0.0, 1e-15);
  // Inside both: the larger level (r: 0.02 off the cylinder, 5.005 above the plane).
  EXPECT_NEAR(trim_level({c, p}, r), 5.005, 1e-15);
  EXPECT_NEAR(trim_level({c, p}, above), 0.001, 1e-15);
  EXPECT_EQ(refused("cone:0,0,0,1"), "--trim 'cone:0,0,0,1': expected plane:X,Y,Z,NX,NY,NZ, cylinder:X,Y,Z,DX,DY,DZ,R, "
                                    "sphere:X,Y,Z,R (m) or polygon:FILE");
  EXPECT_EQ(refused("cylinder:0,0,0,0,0,1"),
            "--trim 'cylinder:0,0,0,0,0,1': a cylinder takes 7 numbers (a point on its axis, the axis's direction and "
            "the radius; m), found 6");
  EXPECT_EQ(refused("plane"), "--trim 'plane': a plane takes 6 numbers (a point and the normal, which points into "
                              "the part; m), found 0");
  EXPECT_EQ(refused("plane:0,0,x,0,0,1"), "--trim 'plane:0,0,x,0,0,1': 'x' is not a number");
  EXPECT_EQ(refused("plane:0,0,0,0,0,1,"), "--trim 'plane:0,0,0,0,0,1,': '' is not a number");
  EXPECT_EQ(refused("plane:0,0,0,0,0,0"), "--trim 'plane:0,0,0,0,0,0': the normal is zero");
  EXPECT_EQ(refused("cylinder:0,0,0,0,0,0,1"), "--trim 'cylinder:0,0,0,0,0,0,1': the axis's direction is zero");
  EXPECT_EQ(refused("sphere:0,0,0,-1"), "--trim 'sphere:0,0,0,-1': the radius must be above 0, found -1");
  EXPECT_EQ(refused("sphere:0,0,0,nan"), "--trim 'sphere:0,0,0,nan': 'nan' is not a number");
  EXPECT_EQ(refused("plane:0,0,1e300,0,0,1"), "--trim 'plane:0,0,1e300,0,0,1': 1e+300 is beyond 1e6 (m): not a trim "
                                              "in a press");
  // Control characters escaped: the message stays on one line.
  EXPECT_EQ(refused("plane:0,0,\r1,0,0,1\n"), "--trim 'plane:0,0,\\r1,0,0,1\\n': '1\\n' is not a number");
}

// An affine map x = A X + b of an irregular mesh of a rectangle carries
// the blank's part on one side of the plane A^T n . X = n . (q - b) to the
// side of the trim plane (q, n) that n points to: exactly, since the level
// is linear along every edge. The pattern is the rectangle clipped by that
// plane, its area, outline and trim line those of the clipped polygon.
TEST(Blank, AffineMapsCarryThePreimageOfATrimPlane) {
  const double x0 = 0.01, y0 = -0.02, sx = 0.12, sy = 0.08;
  const ShellMesh m = irregular_rectangle(x0, y0, sx, sy, 9, 6, 0.004, 11);
  const std::vector<std::array<double, 2>> rect = {{x0, y0}, {x0 + sx, y0}, {x0 + sx, y0 + sy}, {x0, y0 + sy}};
  struct Case {
    std::array<std::array<double, 3>, 3> A;
    V3 b, q, n;
  };
  const std::vector<Case> cases = {
      {{{{1.1, 0.0, 0.0}, {0.0, 0.95, 0.0}, {0.0, 0.0, 1.0}}}, {0.0, 0.0, 0.0}, {0.07, 0.0, 0.0}, {-1.0, 0.0, 0.0}},
      {{{{0.8, 0.3, 0.0}, {-0.2, 1.05, 0.0}, {0.4, 0.1, 1.0}}},
       {0.02, -0.01, 0.3},
       {0.05, 0.01, 0.31},
       {0.3, -1.0, 0.4}},
      {{{{0.0, -1.0, 0.0}, {0.6, 0.0, 0.0}, {0.8, 0.0, 1.0}}}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.039}, {0.2, 0.5, -1.0}},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    std::vector<double> x(m.x.size());
    for (std::size_t i = 0; i < m.x.size(); i += 3)
      for (int r = 0; r < 3; ++r)
        x[i + r] = c.A[r][0] * m.x[i] + c.A[r][1] * m.x[i + 1] + c.A[r][2] * m.x[i + 2] + c.b[r];
    const std::string text = "plane:" + std::to_string(c.q[0]) + "," + std::to_string(c.q[1]) + "," +
                             std::to_string(c.q[2]) + "," + std::to_string(c.n[0]) + "," + std::to_string(c.n[1]) +
                             "," + std::to_string(c.n[2]);
    const TrimSurface t = parse_trim(text);
    const CutPattern p = cut_pattern(m.x, x, m.triangles, {t});
    // The preimage: a X + b Y + d >= 0 kept (Z = 0 in the blank).
    const V3& n = t.direction;
    const double a = c.A[0][0] * n[0] + c.A[1][0] * n[1] + c.A[2][0] * n[2];
    const double bb = c.A[0][1] * n[0] + c.A[1][1] * n[1] + c.A[2][1] * n[2];
    double d = 0;
    for (int r = 0; r < 3; ++r) d += n[r] * (c.b[r] - t.point[r]);
    const auto kept = clip(rect, a, bb, d);
    ASSERT_EQ(p.outlines.size(), 1u) << "case " << k;
    const Outline& o = p.outlines[0];
    EXPECT_NEAR(p.blank_area, sx * sy, 1e-15) << "case " << k;
    EXPECT_NEAR(p.kept_blank_area, area(kept), 1e-15) << "case " << k;
    EXPECT_NEAR(signed_area_z(o), area(kept), 1e-15) << "case " << k << ": anticlockwise, round the whole pattern";
    // The area ratio of the map of the plane Z = 0: |A e1 x A e2|.
    const V3 a1{c.A[0][0], c.A[1][0], c.A[2][0]}, a2{c.A[0][1], c.A[1][1], c.A[2][1]};
    const double ratio = std::sqrt(std::pow(a1[1] * a2[2] - a1[2] * a2[1], 2) +
                                   std::pow(a1[2] * a2[0] - a1[0] * a2[2], 2) +
                                   std::pow(a1[0] * a2[1] - a1[1] * a2[0], 2));
    EXPECT_NEAR(p.kept_formed_area, ratio * area(kept), 1e-15) << "case " << k;
    const auto [perimeter, chord] = perimeter_and_on(kept, {{a, bb, d}});
    EXPECT_NEAR(o.length_blank, perimeter, 1e-14) << "case " << k;
    EXPECT_NEAR(o.trim_length_blank, chord, 1e-14) << "case " << k;
    EXPECT_GT(chord, 0.05) << "case " << k << ": the trim crosses the blank";
    int on_trim = 0;
    for (const OutlinePoint& q : o.points) {
      EXPECT_EQ(q.blank[2], 0.0);
      for (int r = 0; r < 3; ++r)
        EXPECT_NEAR(q.formed[r], c.A[r][0] * q.blank[0] + c.A[r][1] * q.blank[1] + c.b[r], 1e-15) << "case " << k;
      if (!q.on_trim) continue;
      ++on_trim;
      EXPECT_NEAR(a * q.blank[0] + bb * q.blank[1] + d, 0.0, 1e-16) << "case " << k;
      EXPECT_NEAR(trim_level({t}, q.formed.data()), 0.0, 1e-16) << "case " << k;
    }
    EXPECT_GE(on_trim, 7) << "case " << k;
    // With a margin: the trim line moved out (or in) by it on the formed
    // part, the pattern clipped by the plane moved as much in the preimage.
    for (const double margin : {0.004, -0.003}) {
      const CutPattern q = cut_pattern(m.x, x, m.triangles, {t}, margin);
      ASSERT_EQ(q.outlines.size(), 1u) << "case " << k;
      // n . (A X + b - q) >= -margin: a X + b Y + d + margin >= 0.
      EXPECT_NEAR(q.kept_blank_area, area(clip(rect, a, bb, d + margin)), 1e-15) << "case " << k << " " << margin;
      for (const OutlinePoint& o : q.outlines[0].points) {
        if (o.on_trim) {
          EXPECT_NEAR(trim_level({t}, o.formed.data()), margin, 1e-16) << "case " << k;
        }
      }
    }
  }
  // Without a trim, or with one the whole formed ply lies inside: the
  // blank's outline; with one it lies wholly outside of: nothing.
  const CutPattern all = cut_pattern(m.x, m.x, m.triangles, {});
  ASSERT_EQ(all.outlines.size(), 1u);
  EXPECT_EQ(all.outlines[0].points.size(), 2u * (9 + 6));
  EXPECT_NEAR(signed_area_z(all.outlines[0]), sx * sy, 1e-15);
  EXPECT_NEAR(all.outlines[0].length_blank, 2 * (sx + sy), 1e-15);
  EXPECT_EQ(all.outlines[0].trim_length_blank, 0.0);
  const CutPattern inside = cut_pattern(m.x, m.x, m.triangles, {parse_trim("plane:0,0,-1,0,0,1")});
  ASSERT_EQ(inside.outlines.size(), 1u);
  EXPECT_EQ(inside.kept_blank_area, inside.blank_area);
  const CutPattern none = cut_pattern(m.x, m.x, m.triangles, {parse_trim("plane:0,0,1,0,0,1")});
  EXPECT_TRUE(none.outlines.empty());
  EXPECT_EQ(none.kept_blank_area, 0.0);
  // A band: two planes, two outlines' worth of trim line in one outline.
  const CutPattern band =
      cut_pattern(m.x, m.x, m.triangles, {parse_trim("plane:0.05,0,0,1,0,0"), parse_trim("plane:0.1,0,0,-1,0,0")});
  ASSERT_EQ(band.outlines.size(), 1u);
  EXPECT_NEAR(band.kept_blank_area, 0.05 * sy, 1e-15);
  EXPECT_NEAR(band.outlines[0].trim_length_blank, 2 * sy, 1e-15);
  // A disc inside the blank: one outline, all of it on the trim line.
  const CutPattern disc = cut_pattern(m.x, m.x, m.triangles, {parse_trim("cylinder:0.07,0.02,0,0,0,1,0.025")});
  ASSERT_EQ(disc.outlines.size(), 1u);
  EXPECT_NEAR(signed_area_z(disc.outlines[0]), disc.kept_blank_area, 1e-13 * disc.kept_blank_area);
  EXPECT_EQ(disc.outlines[0].trim_length_blank, disc.outlines[0].length_blank);
  // (a polygon inside the circle: shorter, 1.4 % on these coarse cells)
  EXPECT_LT(disc.outlines[0].length_blank, 2 * M_PI * 0.025);
  EXPECT_GT(disc.outlines[0].length_blank, 0.97 * 2 * M_PI * 0.025);
  // Triangles of both orientations: refused.
  std::vector<int> mixed = m.triangles;
  std::swap(mixed[1], mixed[2]);
  EXPECT_THROW(cut_pattern(m.x, m.x, mixed, {}), std::runtime_error);
  std::vector<double> bad = m.x;
  bad[4] = std::nan("");
  EXPECT_THROW(cut_pattern(m.x, bad, m.triangles, {}), std::runtime_error);
}

// Where two trims meet inside a triangle, the pattern has the corner:
// each plane's line and each polygon side is cut by the others in the
// triangle, not averaged along its edges.
//  - Two planes on an affine map of an irregular mesh: the pattern is the
//    rectangle clipped by both preimage planes (clipped here, without the
//    mesh), the corner where they meet (68.0, 52.0 mm) among its points.
//  - 200 star-shaped polygons of 3 to 12 vertices in plan view, some
//    reaching out of a plate moved rigidly in plan, half of them with a
//    plane too: the area is the polygon clipped by the plate (and the
//    plane's preimage), each vertex inside is a point of the pattern,
//    every trim point lies on a side or the plane's line; fibre marks on
//    a 2 mm grid are those points of the grid inside that region.
//  - Trims along the mesh's lines and through its nodes, and a polygon's
//    vertex in the middle of an edge (a 1 m plate of 8 x 8 cells, every
//    coordinate a multiple of 1/16, exact in binary): the pattern closes,
//    with its area and corners exact.
TEST(Blank, CornersWhereTrimsMeetAreExact) {
  using P2 = std::array<double, 2>;
  auto distance_to = [](const std::vector<P2>& poly, const V3& q) { return to_sides(poly, q[0], q[1]); };
  auto nearest_point = [](const CutPattern& p, const P2& v) {
    double d = 1e300;
    for (const Outline& o : p.outlines)
      for (const OutlinePoint& q : o.points) d = std::min(d, std::hypot(q.blank[0] - v[0], q.blank[1] - v[1]));
    return d;
  };
  {
    const double x0 = 0.01, y0 = -0.02, sx = 0.12, sy = 0.08;
    const ShellMesh m = irregular_rectangle(x0, y0, sx, sy, 9, 6, 0.004, 11);
    const double A[3][3] = {{0.8, 0.3, 0.0}, {-0.2, 1.05, 0.0}, {0.4, 0.1, 1.0}}, b[3] = {0.02, -0.01, 0.3};
    std::vector<double> x(m.x.size());
    for (std::size_t i = 0; i < x.size(); i += 3)
      for (int r = 0; r < 3; ++r) x[i + r] = A[r][0] * m.x[i] + A[r][1] * m.x[i + 1] + A[r][2] * m.x[i + 2] + b[r];
    const std::vector<TrimSurface> trims = {parse_trim("plane:0.05,0.01,0.31,0.3,-1,0.4"),
                                            parse_trim("plane:0.09,0,0,-1,0,0")};
    std::vector<P2> kept = {{x0, y0}, {x0 + sx, y0}, {x0 + sx, y0 + sy}, {x0, y0 + sy}};
    std::vector<std::array<double, 3>> lines;  // a X + b Y + d >= 0 kept
    for (const TrimSurface& t : trims) {
      const V3& n = t.direction;
      double d = 0;
      for (int r = 0; r < 3; ++r) d += n[r] * (b[r] - t.point[r]);
      lines.push_back({A[0][0] * n[0] + A[1][0] * n[1] + A[2][0] * n[2],
                       A[0][1] * n[0] + A[1][1] * n[1] + A[2][1] * n[2], d});
      kept = clip(kept, lines.back()[0], lines.back()[1], d);
    }
    const double det = lines[0][0] * lines[1][1] - lines[0][1] * lines[1][0];
    const P2 corner = {(-lines[0][2] * lines[1][1] + lines[1][2] * lines[0][1]) / det,
                       (-lines[0][0] * lines[1][2] + lines[1][0] * lines[0][2]) / det};
    EXPECT_NEAR(corner[0], 0.0680131, 1e-7);
    EXPECT_NEAR(corner[1], 0.0519650, 1e-7);
    for (const bool swapped : {false, true}) {
      const CutPattern p =
          cut_pattern(m.x, x, m.triangles, swapped ? std::vector<TrimSurface>{trims[1], trims[0]} : trims);
      ASSERT_EQ(p.outlines.size(), 1u);
      EXPECT_NEAR(p.kept_blank_area, area(kept), 1e-15);
      EXPECT_NEAR(signed_area_z(p.outlines[0]), area(kept), 1e-15);
      EXPECT_LT(nearest_point(p, corner), 1e-15);
      const auto [perimeter, chords] = perimeter_and_on(kept, lines);
      EXPECT_NEAR(p.outlines[0].length_blank, perimeter, 1e-14);
      EXPECT_NEAR(p.outlines[0].trim_length_blank, chords, 1e-14);
      for (const OutlinePoint& q : p.outlines[0].points) {
        if (!q.on_trim) continue;
        double off = 1e300;
        for (const auto& ln : lines)
          off = std::min(off, std::abs(ln[0] * q.blank[0] + ln[1] * q.blank[1] + ln[2]) / std::hypot(ln[0], ln[1]));
        EXPECT_LT(off, 1e-16);
      }
    }
  }
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_corners";
  std::filesystem::create_directories(dir);
  {
    const double L = 0.1, turn = 0.7, c = std::cos(turn), s = std::sin(turn), bx = 0.3, by = -0.2;
    const ShellMesh m = irregular_rectangle(0, 0, L, L, 20, 20, 0.0015, 7);
    std::vector<double> x = m.x;  // turned about z and moved
    for (std::size_t i = 0; i < x.size(); i += 3) {
      x[i] = c * m.x[i] - s * m.x[i + 1] + bx;
      x[i + 1] = s * m.x[i] + c * m.x[i + 1] + by;
      x[i + 2] = m.x[i + 2] + 0.05;
    }
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int vertices_inside = 0, with_plane = 0, marks_checked = 0;
    for (int k = 0; k < 200; ++k) {
      const int n = 3 + k % 10;
      const P2 centre = {0.02 + 0.06 * u(rng), 0.02 + 0.06 * u(rng)};
      std::vector<P2> star;  // in the blank, round the centre: no two sides cross
      for (int i = 0; i < n; ++i) {
        const double a = 2 * M_PI * (i + 0.8 * u(rng)) / n, r = 0.01 + 0.05 * u(rng);
        star.push_back({centre[0] + r * std::cos(a), centre[1] + r * std::sin(a)});
      }
      {
        std::ofstream f(dir / "star.csv");
        f.precision(17);
        for (const P2& v : star) f << c * v[0] - s * v[1] + bx << "," << s * v[0] + c * v[1] + by << "\n";
      }
      std::vector<TrimSurface> trims = {parse_trim("polygon:" + (dir / "star.csv").string())};
      std::vector<P2> region = star;
      if (region.size() >= 3 && area(region) < 0) std::reverse(region.begin(), region.end());
      for (const auto& h : std::vector<std::array<double, 3>>{{1, 0, 0}, {-1, 0, L}, {0, 1, 0}, {0, -1, L}})
        region = clip(region, h[0], h[1], h[2]);
      std::array<double, 3> line{0, 0, 1};  // the plane's preimage, a X + b Y + d >= 0
      const bool plane = k % 2 == 1;
      if (plane) {  // a vertical plane through the star's centre, its normal in plan at random
        ++with_plane;
        const double a = 2 * M_PI * u(rng), nx = std::cos(a), ny = std::sin(a);
        const P2 q = {c * centre[0] - s * centre[1] + bx, s * centre[0] + c * centre[1] + by};
        std::ostringstream text;
        text.precision(17);
        text << "plane:" << q[0] << "," << q[1] << ",0," << nx << "," << ny << ",0";
        trims.push_back(parse_trim(text.str()));
        const V3& nn = trims.back().direction;
        line = {c * nn[0] + s * nn[1], -s * nn[0] + c * nn[1],
                nn[0] * (bx - trims.back().point[0]) + nn[1] * (by - trims.back().point[1])};
        region = clip(region, line[0], line[1], line[2]);
      }
      const CutPattern p = cut_pattern(m.x, x, m.triangles, trims);
      const double expected = region.size() >= 3 ? area(region) : 0.0;
      EXPECT_NEAR(p.kept_blank_area, expected, 1e-15) << k;
      EXPECT_NEAR(p.kept_formed_area, p.kept_blank_area, 1e-15) << k;
      double outlined = 0;
      for (const Outline& o : p.outlines) {
        outlined += signed_area_z(o);
        for (const OutlinePoint& q : o.points) {
          if (!q.on_trim) continue;
          const double off = std::min(distance_to(star, q.blank),
                                      plane ? std::abs(line[0] * q.blank[0] + line[1] * q.blank[1] + line[2]) /
                                                  std::hypot(line[0], line[1])
                                            : 1e300);
          EXPECT_LT(off, 1e-16) << k;
        }
      }
      EXPECT_NEAR(outlined, p.kept_blank_area, 1e-15) << k;
      for (const P2& v : star) {
        const double margin = std::min({v[0], L - v[0], v[1], L - v[1],
                                        plane ? (line[0] * v[0] + line[1] * v[1] + line[2]) /
                                                    std::hypot(line[0], line[1])
                                              : 1.0});
        if (margin < 1e-6) continue;
        ++vertices_inside;
        EXPECT_LT(nearest_point(p, v), 1e-16) << k << ": a vertex inside";
      }
      // Fibre marks: at the grid points inside the region (those farther
      // than 1e-9 m from its edge checked).
      if (k % 10 == 0) {
        const std::vector<double> fibre(m.triangles.size(), 1.0);
        const auto marks = fibre_marks(m.x, x, m.triangles, trims, fibre, {1, 0, 0}, {0, 1, 0}, 0.002);
        std::set<std::pair<long, long>> marked;
        for (const FibreMark& mk : marks)
          marked.emplace(std::lround((mk.from[0] + mk.to[0]) / 0.004), std::lround((mk.from[1] + mk.to[1]) / 0.004));
        auto inside_star = [&](double px, double py) {
          bool in = false;
          for (std::size_t a = 0, b = star.size() - 1; a < star.size(); b = a++)
            if ((star[a][1] > py) != (star[b][1] > py) &&
                px < star[a][0] + (py - star[a][1]) * (star[b][0] - star[a][0]) / (star[b][1] - star[a][1]))
              in = !in;
          return in;
        };
        for (long i = 0; i <= 50; ++i)
          for (long j = 0; j <= 50; ++j) {
            const double px = 0.002 * static_cast<double>(i), py = 0.002 * static_cast<double>(j);
            const double edge = std::min({distance_to(star, {px, py, 0}),
                                          plane ? std::abs(line[0] * px + line[1] * py + line[2]) /
                                                      std::hypot(line[0], line[1])
                                                : 1.0});
            if (edge < 1e-9) continue;
            const bool in = inside_star(px, py) && (!plane || line[0] * px + line[1] * py + line[2] > 0);
            EXPECT_EQ(marked.count({i, j}) == 1, in) << k << ": grid point " << i << ", " << j;
            ++marks_checked;
          }
      }
    }
    EXPECT_GT(vertices_inside, 800);
    EXPECT_EQ(with_plane, 100);
    EXPECT_GT(marks_checked, 50000);
  }
  {
    const ShellMesh m = rectangle_mesh({0, 0, 0}, {1.0, 1.0}, {8, 8});
    auto pattern = [&](const std::vector<P2>& poly, const std::vector<std::string>& planes) {
      {
        std::ofstream f(dir / "exact.csv");
        for (const P2& v : poly) f << v[0] << "," << v[1] << "\n";
      }
      std::vector<TrimSurface> trims = {parse_trim("polygon:" + (dir / "exact.csv").string())};
      for (const std::string& t : planes) trims.push_back(parse_trim(t));
      return cut_pattern(m.x, m.x, m.triangles, trims);
    };
    struct Case {
      std::vector<P2> poly;
      std::vector<std::string> planes;
      std::vector<P2> expected;  // the pattern, anticlockwise
    };
    const std::vector<P2> ell = {{0.125, 0.125}, {0.75, 0.125}, {0.75, 0.5}, {0.5, 0.5}, {0.5, 0.875}, {0.125, 0.875}};
    const std::vector<Case> cases = {
        {ell, {}, ell},  // along the mesh's lines, every vertex a node
        {ell,
         {"plane:0.25,0,0,1,0,0"},  // and a plane through a column of nodes
         {{0.25, 0.125}, {0.75, 0.125}, {0.75, 0.5}, {0.5, 0.5}, {0.5, 0.875}, {0.25, 0.875}}},
        {{{0.1875, 0.1875}, {0.5625, 0.1875}, {0.5625, 0.5}, {0.1875, 0.5}},  // a vertex mid-edge, a side along
         {},
         {{0.1875, 0.1875}, {0.5625, 0.1875}, {0.5625, 0.5}, {0.1875, 0.5}}},
        {{{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}},  // the blank's edge itself, and a diagonal plane
         {"plane:0.5,0.5,0,-1,-1,0"},
         {{0, 0}, {1, 0}, {0, 1}}},
    };
    for (std::size_t k = 0; k < cases.size(); ++k) {
      const Case& cs = cases[k];
      const CutPattern p = pattern(cs.poly, cs.planes);
      ASSERT_EQ(p.outlines.size(), 1u) << k;
      EXPECT_NEAR(p.kept_blank_area, area(cs.expected), 1e-15) << k;
      EXPECT_NEAR(signed_area_z(p.outlines[0]), area(cs.expected), 1e-15) << k;
      for (const P2& v : cs.expected) EXPECT_EQ(nearest_point(p, v), 0.0) << k << ": " << v[0] << ", " << v[1];
      for (const OutlinePoint& q : p.outlines[0].points) EXPECT_LT(distance_to(cs.expected, q.blank), 1e-16) << k;
    }
  }
  std::filesystem::remove_all(dir);
}

// Trims that coincide along a line: the same plane, cylinder or polygon
// twice, a plane along a polygon's side, two polygons sharing part of a
// side (one of them with a vertex along it), on an irregular plate of
// 100 mm (17 x 13 crossed cells) turned by 0.3 rad in plan and tilted.
// Each gives the pattern of the trims without the repeats, or the exact
// region where they overlap; where two parts meet along a line only,
// nothing.
TEST(Blank, CoincidentTrimsGiveTheirPatternOnce) {
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_coincident";
  std::filesystem::create_directories(dir);
  const ShellMesh m = irregular_rectangle(0, 0, 0.1, 0.1, 17, 13, 0.0008, 41);
  std::vector<double> x = m.x;
  const double c = std::cos(0.3), s = std::sin(0.3);
  for (std::size_t i = 0; i < x.size(); i += 3) {
    x[i] = c * m.x[i] - s * m.x[i + 1] + 0.01;
    x[i + 1] = s * m.x[i] + c * m.x[i + 1] - 0.02;
    x[i + 2] = 0.01 * m.x[i];
  }
  auto file = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return "polygon:" + (dir / name).string();
  };
  const std::string sq = file("sq.csv", "0.02,0.01\n0.06,0.01\n0.06,0.07\n0.02,0.07\n");
  const std::string beside = file("beside.csv", "0.06,0.03\n0.09,0.03\n0.09,0.05\n0.06,0.05\n");  // across x = 0.06
  const std::string part = file("part.csv", "0.01,0.02\n0.06,0.02\n0.06,0.05\n0.01,0.05\n");     // along x = 0.06
  auto pattern = [&](const std::vector<std::string>& texts) {
    std::vector<TrimSurface> trims;
    for (const std::string& t : texts) trims.push_back(parse_trim(t));
    return cut_pattern(m.x, x, m.triangles, trims);
  };
  auto expect_same = [&](const CutPattern& a, const CutPattern& b, const std::string& what) {
    EXPECT_NEAR(a.kept_blank_area, b.kept_blank_area, 1e-15) << what;
    EXPECT_NEAR(a.kept_formed_area, b.kept_formed_area, 1e-15) << what;
    ASSERT_EQ(a.outlines.size(), b.outlines.size()) << what;
    for (std::size_t o = 0; o < a.outlines.size(); ++o) {
      EXPECT_NEAR(a.outlines[o].length_blank, b.outlines[o].length_blank, 1e-14) << what;
      EXPECT_NEAR(a.outlines[o].trim_length_blank, b.outlines[o].trim_length_blank, 1e-14) << what;
    }
  };
  const std::string plane = "plane:0.03,0,0,1,0,0", cylinder = "cylinder:0.05,0.03,0,0,0,1,0.03";
  expect_same(pattern({plane, plane}), pattern({plane}), "a plane twice");
  expect_same(pattern({cylinder, cylinder}), pattern({cylinder}), "a cylinder twice");
  expect_same(pattern({sq, sq}), pattern({sq}), "a polygon twice");
  expect_same(pattern({sq, "plane:0.06,0,0,-1,0,0"}), pattern({sq}), "a plane along a side, the polygon inside it");
  expect_same(pattern({"plane:0.02,0,0,1,0,0", sq}), pattern({sq}), "a plane along the other side");
  const CutPattern one = pattern({sq});
  EXPECT_NEAR(one.kept_blank_area, 0.04 * 0.06, 1e-15);  // the plan's map is a turn: areas kept
  const CutPattern overlap = pattern({sq, part});
  ASSERT_EQ(overlap.outlines.size(), 1u);
  EXPECT_NEAR(overlap.kept_blank_area, 0.04 * 0.03, 1e-15);
  EXPECT_NEAR(overlap.outlines[0].length_blank, 2 * (0.04 + 0.03), 1e-14);
  expect_same(pattern({sq, part, "plane:0.06,0,0,-1,0,0"}), overlap, "two polygons and a plane along one line");
  // A vertex between two sides along one line: the same outline.
  const std::string kinked = file("kinked.csv", "0.01,0.02\n0.06,0.02\n0.06,0.035\n0.06,0.05\n0.01,0.05\n");
  expect_same(pattern({sq, kinked}), overlap, "a polygon with a vertex along the common line");
  for (const auto& texts : std::vector<std::vector<std::string>>{{sq, beside}, {sq, "plane:0.06,0,0,1,0,0"}}) {
    const CutPattern p = pattern(texts);
    EXPECT_TRUE(p.outlines.empty()) << texts[1];
    EXPECT_LT(p.kept_blank_area, 1e-18) << texts[1];
  }
  std::filesystem::remove_all(dir);
}

// Trims through the mesh's nodes and along its lines, where the levels at
// the nodes are zero but for round-off: 3 000 random cases of a plate of
// 100 mm on a regular grid (2 to 13 cells a side, crossed or not) turned
// at random in plan and moved, with 1 to 3 trims: planes through a node
// (or a cell's centre) along the grid's lines or diagonals, rectangles and
// triangles with their corners on nodes, given formed (so that the turn's
// rounding puts them off the nodes by 1e-17 m). The pattern's area
// against the plate clipped by the trims in the blank, here.
// THERMOSTAMP_BLANK_CASES and THERMOSTAMP_BLANK_SEED run other cases
// (scripts/fuzz_blank.py: many more).
TEST(Blank, TrimsThroughNodesAndAlongTheMeshLines) {
  using P2 = std::array<double, 2>;
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_aligned";
  std::filesystem::create_directories(dir);
  const char* count_env = std::getenv("THERMOSTAMP_BLANK_CASES");
  const char* seed_env = std::getenv("THERMOSTAMP_BLANK_SEED");
  const int total = count_env ? std::atoi(count_env) : 3000;
  std::mt19937 rng(seed_env ? static_cast<unsigned>(std::atoi(seed_env)) : 97u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cases = 0, cut = 0, empty = 0;
  for (int it = 0; it < total; ++it) {
    const int n = 2 + static_cast<int>(rng() % 12);
    const bool crossed = rng() % 2 == 0;
    const double L = 0.1, h = L / n;
    const ShellMesh m = rectangle_mesh({0, 0, 0}, {L, L}, {n, n}, crossed);
    const double turn = rng() % 4 == 0 ? 0.0 : 2 * M_PI * u(rng), c = std::cos(turn), s = std::sin(turn);
    const double tx = 0.3 * u(rng), ty = -0.2 * u(rng);
    std::vector<double> x = m.x;
    for (std::size_t i = 0; i < x.size(); i += 3) {
      x[i] = c * m.x[i] - s * m.x[i + 1] + tx;
      x[i + 1] = s * m.x[i] + c * m.x[i + 1] + ty;
      x[i + 2] = 0.02;
    }
    auto node = [&]() {
      double i = static_cast<double>(rng() % (n + 1)), j = static_cast<double>(rng() % (n + 1));
      if (crossed && rng() % 3 == 0 && i < n && j < n) {
        i += 0.5;
        j += 0.5;
      }
      return P2{i * h, j * h};
    };
    std::vector<TrimSurface> trims;
    std::vector<P2> region = {{0, 0}, {L, 0}, {L, L}, {0, L}};  // the reference, in the blank
    const int count = 1 + static_cast<int>(rng() % 3);
    for (int t = 0; t < count; ++t) {
      std::ostringstream text;
      text.precision(17);
      if (rng() % 2) {
        const P2 q = node();
        const double dirs[8][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
        const auto& d = dirs[rng() % 8];
        text << "plane:" << c * q[0] - s * q[1] + tx << "," << s * q[0] + c * q[1] + ty << ",0,"
             << c * d[0] - s * d[1] << "," << s * d[0] + c * d[1] << ",0";
        region = clip(region, d[0], d[1], -(d[0] * q[0] + d[1] * q[1]));
      } else {
        std::vector<P2> v;
        if (rng() % 2) {
          const P2 a = node(), b = node();
          if (a[0] == b[0] || a[1] == b[1]) {
            --t;
            continue;
          }
          const double x0 = std::min(a[0], b[0]), x1 = std::max(a[0], b[0]);
          const double y0 = std::min(a[1], b[1]), y1 = std::max(a[1], b[1]);
          v = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
        } else {
          v = {node(), node(), node()};
          if (std::abs(area(v)) < 1e-9) {
            --t;
            continue;
          }
          if (area(v) < 0) std::swap(v[1], v[2]);
        }
        const auto file = dir / ("p" + std::to_string(t) + ".csv");
        {
          std::ofstream f(file);
          f.precision(17);
          for (const P2& p : v) f << c * p[0] - s * p[1] + tx << "," << s * p[0] + c * p[1] + ty << "\n";
        }
        text << "polygon:" << file.string();
        for (std::size_t k = 0; k < v.size(); ++k) {
          const P2& a = v[k];
          const P2& b = v[(k + 1) % v.size()];
          region = clip(region, -(b[1] - a[1]), b[0] - a[0], (b[1] - a[1]) * a[0] - (b[0] - a[0]) * a[1]);
        }
      }
      trims.push_back(parse_trim(text.str()));
    }
    const double expected = region.size() >= 3 ? area(region) : 0.0;
    CutPattern p;
    ASSERT_NO_THROW(p = cut_pattern(m.x, x, m.triangles, trims)) << it;
    EXPECT_NEAR(p.kept_blank_area, expected, 1e-15) << it;
    double outlined = 0;
    for (const Outline& o : p.outlines) outlined += signed_area_z(o);
    EXPECT_NEAR(outlined, p.kept_blank_area, 1e-15) << it;
    ++cases;
    (expected > 1e-12 ? cut : empty) += 1;
  }
  EXPECT_EQ(cases, total);
  EXPECT_GT(cut, total / 3);
  EXPECT_GT(empty, total / 10);
  std::filesystem::remove_all(dir);
}

// A polygon across a vertical wall: a plate of 100 mm (20 x 20 cells, the
// nodes moved at random but for the wall's edges) formed into a step, its
// strip 40 < X < 60 mm stood up as a wall in the plane x = 40 mm (each of
// its triangles seen edge-on in plan view) and the rest beyond it moved
// back by 20 mm and up by as much. Trimmed by 100 star-shaped polygons in
// plan view, the pattern is exact: the polygon's area over the plan's 80
// x 100 mm, plus the wall's 20 mm times the length of the line x = 40 mm
// inside the polygon (computed here from the sides' crossings).
TEST(Blank, PolygonAcrossAVerticalWall) {
  using P2 = std::array<double, 2>;
  ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {20, 20});
  const std::size_t nodes = m.x.size() / 3;
  std::vector<int> column(nodes);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> jiggle(-0.001, 0.001);
  for (std::size_t i = 0; i < nodes; ++i) {
    column[i] = static_cast<int>(std::lround(m.x[3 * i] / 0.005));
    const int row = static_cast<int>(std::lround(m.x[3 * i + 1] / 0.005));
    if (column[i] != 0 && column[i] != 8 && column[i] != 12 && column[i] != 20) m.x[3 * i] += jiggle(rng);
    if (row != 0 && row != 20) m.x[3 * i + 1] += jiggle(rng);
  }
  double wall0 = 0, wall1 = 0;  // the wall's edges in the blank
  for (std::size_t i = 0; i < nodes; ++i) {
    if (column[i] == 8) wall0 = m.x[3 * i];
    if (column[i] == 12) wall1 = m.x[3 * i];
  }
  std::vector<double> x = m.x;
  for (std::size_t i = 0; i < nodes; ++i) {
    const double X = m.x[3 * i];
    if (column[i] > 8 && column[i] < 12) {
      x[3 * i] = wall0;
      x[3 * i + 2] = X - wall0;
    } else if (column[i] >= 12) {
      x[3 * i] = X - (wall1 - wall0);
      x[3 * i + 2] = wall1 - wall0;
    }
  }
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_wall";
  std::filesystem::create_directories(dir);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int crossing = 0;
  for (int k = 0; k < 100; ++k) {
    const int n = 3 + k % 10;
    const P2 centre = {0.02 + 0.04 * u(rng), 0.02 + 0.06 * u(rng)};
    std::vector<P2> star;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * (i + 0.8 * u(rng)) / n, r = 0.01 + 0.04 * u(rng);
      star.push_back({centre[0] + r * std::cos(a), centre[1] + r * std::sin(a)});
    }
    {
      std::ofstream f(dir / "star.csv");
      f.precision(17);
      for (const P2& v : star) f << v[0] << "," << v[1] << "\n";
    }
    const CutPattern p = cut_pattern(m.x, x, m.triangles, {parse_trim("polygon:" + (dir / "star.csv").string())});
    std::vector<P2> region = star;
    if (area(region) < 0) std::reverse(region.begin(), region.end());
    for (const auto& h : std::vector<std::array<double, 3>>{{1, 0, 0}, {-1, 0, 0.08}, {0, 1, 0}, {0, -1, 0.1}})
      region = clip(region, h[0], h[1], h[2]);
    std::vector<double> ys;  // where the sides cross x = wall0
    for (std::size_t i = 0; i < star.size(); ++i) {
      const P2& a = star[i];
      const P2& b = star[(i + 1) % star.size()];
      if ((a[0] > wall0) != (b[0] > wall0)) ys.push_back(a[1] + (wall0 - a[0]) * (b[1] - a[1]) / (b[0] - a[0]));
    }
    std::sort(ys.begin(), ys.end());
    double chord = 0;
    for (std::size_t i = 0; i + 1 < ys.size(); i += 2)
      chord += std::max(0.0, std::min(ys[i + 1], 0.1) - std::max(ys[i], 0.0));
    if (chord > 0) ++crossing;
    const double expected = (region.size() >= 3 ? area(region) : 0.0) + (wall1 - wall0) * chord;
    EXPECT_NEAR(p.kept_blank_area, expected, 2e-15) << k;
    double outlined = 0;
    for (const Outline& o : p.outlines) outlined += signed_area_z(o);
    EXPECT_NEAR(outlined, p.kept_blank_area, 2e-15) << k;
  }
  EXPECT_GT(crossing, 90);
  std::filesystem::remove_all(dir);
}

// A strip wrapped without stretch round a cylinder of radius R: x = (R
// sin(X/R), Y, R (1 - cos(X/R))). Trimmed at the plane z = z0 (the part
// below), the pattern is X <= X* = R acos(1 - z0/R), a straight line. The
// level is linear along each edge while z is not: with X* in the middle of
// a cell of length h, the trim line lies at X* - e, e = h^2 z''/(8 z') at
// X* to leading order (the chord's offset), falling as h^2.
TEST(Blank, StripWrappedRoundACylinderConvergesToItsArcLength) {
  const double R = 0.05, W = 0.03, z0 = 0.02;
  const double Xs = R * std::acos(1 - z0 / R);
  const double lead = std::cos(Xs / R) / (8 * R * std::sin(Xs / R));  // e / h^2
  double previous = 0, previous_h = 0;
  for (const int k : {4, 9, 19, 39}) {
    const double h = Xs / (k + 0.5);
    const int cells = 2 * k + 2;
    const ShellMesh m = rectangle_mesh({0, 0, 0}, {cells * h, W}, {cells, 6});
    std::vector<double> x(m.x.size());
    for (std::size_t i = 0; i < m.x.size(); i += 3) {
      x[i] = R * std::sin(m.x[i] / R);
      x[i + 1] = m.x[i + 1];
      x[i + 2] = R * (1 - std::cos(m.x[i] / R));
    }
    const CutPattern p = cut_pattern(m.x, x, m.triangles, {parse_trim("plane:0,0," + std::to_string(z0) + ",0,0,-1")});
    ASSERT_EQ(p.outlines.size(), 1u);
    double error = -1;
    for (const OutlinePoint& q : p.outlines[0].points) {
      if (!q.on_trim) continue;
      const double e = Xs - q.blank[0];
      if (error >= 0) {
        EXPECT_NEAR(e, error, 1e-15) << k << ": a straight trim line";
      }
      error = e;
      EXPECT_NEAR(q.formed[2], z0, 1e-15);
    }
    EXPECT_NEAR(error / (lead * h * h), 1.0, 0.002) << k;
    EXPECT_NEAR(p.kept_blank_area, W * (Xs - error), 1e-15) << k;
    EXPECT_NEAR(p.outlines[0].trim_length_blank, W, 1e-15);
    if (previous > 0) {
      EXPECT_NEAR(previous / error, std::pow(previous_h / h, 2), 0.002 * std::pow(previous_h / h, 2)) << k;
    }
    previous = error;
    previous_h = h;
  }
}

// A flat plate, not moved, trimmed by a cylinder and by a sphere that cut
// its plane in the same circle, r0 = 0.07 m. Each trim point lies inside
// the circle, by at most the chord's offset: the level, |x - c| - rho with
// rho the cylinder's radius or the distance to the sphere's centre, exceeds
// its linear interpolant along an edge of length h by at most
// h^2 / (8 (rho - h)), which is (rho / r0) times that in r. The pattern (a
// quarter disc) lacks at most that offset along the arc and the segments
// between the trim points inside it, s^3 / (12 r0) each for s <= h: pi h^2 / 24.
TEST(Blank, CylinderAndSphereTrimAFlatPlateAtTheirCircle) {
  const double r0 = 0.07, L = 0.1;
  const ShellMesh m = rectangle_mesh({0, 0, 0}, {L, L}, {40, 40}, true);
  const double h = max_edge_length(m);
  for (const auto& [text, rho] : {std::pair<std::string, double>{"cylinder:0,0,0.3,0,0,-2,0.07", 0.07},
                                  std::pair<std::string, double>{"sphere:0,0,0.024,0.074", 0.074}}) {
    const TrimSurface t = parse_trim(text);
    const CutPattern p = cut_pattern(m.x, m.x, m.triangles, {t});
    ASSERT_EQ(p.outlines.size(), 1u) << text;
    const double offset = rho / r0 * h * h / (8 * (rho - h));
    int on = 0;
    for (const OutlinePoint& q : p.outlines[0].points) {
      if (!q.on_trim) continue;
      ++on;
      const double r = std::hypot(q.blank[0], q.blank[1]);
      EXPECT_LE(r, r0 + 1e-15) << text;
      EXPECT_GE(r, r0 - offset) << text;
    }
    EXPECT_GT(on, 40) << text;
    const double quarter = M_PI * r0 * r0 / 4;
    EXPECT_LE(p.kept_blank_area, quarter) << text;
    EXPECT_GE(p.kept_blank_area, quarter - M_PI * r0 / 2 * offset - M_PI * h * h / 24) << text;
    EXPECT_NEAR(p.kept_formed_area, p.kept_blank_area, 1e-18) << text;
    EXPECT_NEAR(signed_area_z(p.outlines[0]), p.kept_blank_area, 1e-13 * quarter) << text;  // rounding
  }
}


// A trim line drawn in plan view (polygon:FILE): an L-shaped outline, its
// vertices off the mesh's lines, on a flat plate of 100 mm (40 x 40
// crossed cells) turned by 30 degrees about z and moved: the pattern is
// the outline taken back by that motion. Each side is a plane's line in
// every triangle (the signed distance to its line is linear on the
// formed mesh), and its ends are the outline's vertices, found inside
// their triangles: every point of the pattern lies on the outline to
// round-off, its 6 vertices among them, and the area is the outline's.
// Files that are not a polygon are refused with what is wrong.
TEST(Blank, PolygonDrawnInPlanViewTrimsAlongItsSides) {
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_polygon";
  std::filesystem::create_directories(dir);
  const std::vector<std::array<double, 2>> L = {{0.0113, 0.0127}, {0.0871, 0.0127}, {0.0871, 0.0413},
                                               {0.0437, 0.0413}, {0.0437, 0.0889}, {0.0113, 0.0889}};
  const double exact = 0.0758 * 0.0286 + 0.0324 * 0.0476;
  const ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {40, 40}, true);
  const std::vector<double> x = turned_and_moved(m.x);
  {
    std::ofstream f(dir / "outline.csv");
    f.precision(17);
    f << "x_m,y_m\n";
    for (const auto& v : L) f << turned_and_moved(v)[0] << ", " << turned_and_moved(v)[1] << "\n";
    f << turned_and_moved(L[0])[0] << "," << turned_and_moved(L[0])[1] << "\n";  // closed: dropped
  }
  const TrimSurface t = parse_trim("polygon:" + (dir / "outline.csv").string());
  ASSERT_EQ(t.rings.size(), 1u);
  ASSERT_EQ(t.rings[0].size(), 6u);
  const CutPattern p = cut_pattern(m.x, x, m.triangles, {t});
  ASSERT_EQ(p.outlines.size(), 1u);
  auto distance = [&](const V3& q) {  // to the outline's sides, and to its nearest vertex
    return std::pair<double, double>{to_sides(L, q[0], q[1]), to_vertices(L, q[0], q[1])};
  };
  int corners = 0;
  for (const OutlinePoint& q : p.outlines[0].points) {
    ASSERT_TRUE(q.on_trim);
    const auto [side, vertex] = distance(q.blank);
    EXPECT_LT(side, 1e-16) << q.blank[0] << " " << q.blank[1];
    if (vertex < 1e-16) ++corners;
  }
  EXPECT_EQ(corners, 6);
  EXPECT_GT(p.outlines[0].points.size(), 300u);
  // Areas: the round-off of sums over 3 200 triangles and 370 points.
  EXPECT_NEAR(p.kept_blank_area, exact, 1e-13 * exact);
  EXPECT_NEAR(p.kept_formed_area, p.kept_blank_area, 1e-13 * exact);
  EXPECT_NEAR(signed_area_z(p.outlines[0]), p.kept_blank_area, 1e-13 * exact);
  EXPECT_NEAR(p.outlines[0].trim_length_blank, 2 * (0.0758 + 0.0762), 1e-15);
  auto refused_file = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return refused("polygon:" + (dir / name).string());
  };
  const std::string at = "--trim 'polygon:" + dir.string() + "/";
  EXPECT_EQ(refused_file("two.csv", "0,0\n1,0\n"), at + "two.csv': '" + dir.string() + "/two.csv' holds 2 vertices: a "
                                                                                   "polygon needs at least 3");
  EXPECT_EQ(refused_file("bad.csv", "x,y\n0,0\n1,0\n1;1\x01\n"),
            at + "bad.csv': '" + dir.string() + "/bad.csv' row 4: expected x,y (m), found '1;1\\x01'");
  EXPECT_EQ(refused_file("three.csv", "0,0,0\n1,0,0\n1,1,0\n"),
            at + "three.csv': '" + dir.string() + "/three.csv' row 2: expected x,y (m), found '1,0,0'");
  EXPECT_EQ(refused_file("twice.csv", "0,0\n1,0\n1,0\n0,1\n"),
            at + "twice.csv': '" + dir.string() + "/twice.csv': vertex 2 is there twice in a row");
  EXPECT_EQ(refused_file("nearly.csv", "0,0\n1,0\n1,1e-12\n0,1\n"),  // within 1e-9 of the polygon's size
            at + "nearly.csv': '" + dir.string() + "/nearly.csv': vertex 2 is there twice in a row");
  EXPECT_EQ(refused_file("line.csv", "0,0\n1,1\n2,2\n"),
            at + "line.csv': '" + dir.string() + "/line.csv': the polygon has no area");
  EXPECT_EQ(refused_file("bowtie.csv", "0,0\n2,2\n2,0\n0,1\n"),
            at + "bowtie.csv': '" + dir.string() + "/bowtie.csv': the polygon crosses itself (sides 1 and 3)");
  EXPECT_EQ(refused_file("touch.csv", "# a side touching a vertex\n0,0\n2,0\n2,2\n1,0\n0,2\n"),
            at + "touch.csv': '" + dir.string() + "/touch.csv': the polygon crosses itself (sides 1 and 3)");
  // Random polygons, some crossing themselves: accepted exactly when no
  // two sides that are not neighbours share a point (every pair checked
  // here, by the signs of the triangles' areas).
  {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto orient = [](const std::array<double, 2>& o, const std::array<double, 2>& a, const std::array<double, 2>& b) {
      const double c = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
      return (c > 0) - (c < 0);
    };
    int accepted = 0, crossing = 0;
    for (int k = 0; k < 300; ++k) {
      const int n = 4 + k % 9;
      std::vector<std::array<double, 2>> v;
      const bool star = k % 2 == 0;  // half of them round a centre: no crossing
      for (int i = 0; i < n; ++i) {
        const double a = star ? 2 * M_PI * (i + 0.8 * u(rng)) / n : 0, r = 0.2 + 0.3 * u(rng);
        v.push_back(star ? std::array<double, 2>{0.5 + r * std::cos(a), 0.5 + r * std::sin(a)}
                         : std::array<double, 2>{u(rng), u(rng)});
      }
      bool meets = false;
      for (int i = 0; i < n && !meets; ++i)
        for (int j = i + 2; j < n && !meets; ++j) {
          if (i == 0 && j == n - 1) continue;
          const auto &a = v[i], &b = v[(i + 1) % n], &c = v[j], &d = v[(j + 1) % n];
          meets = orient(a, b, c) != orient(a, b, d) && orient(c, d, a) != orient(c, d, b);
        }
      std::ostringstream text;
      text.precision(17);
      for (const auto& p : v) text << p[0] << "," << p[1] << "\n";
      const std::string why = refused_file("random.csv", text.str());
      EXPECT_EQ(why == "accepted", !meets) << k << ": " << why;
      (meets ? crossing : accepted) += 1;
    }
    EXPECT_GT(accepted, 100);
    EXPECT_GT(crossing, 100);
  }
  std::filesystem::remove(dir / "none.csv");
  try {
    parse_trim("polygon:" + (dir / "none.csv").string());
    ADD_FAILURE() << "a missing file accepted";
  } catch (const ExportInputError& e) {
    EXPECT_EQ(std::string(e.what()), at + "none.csv': cannot read '" + dir.string() + "/none.csv'");
  }
  std::filesystem::remove_all(dir);
}


// A trim line from CAD as a DXF file (mm, $INSUNITS 4): a slot, 50 x 30 mm
// between two half circles of 15 mm (a closed LWPOLYLINE with bulges),
// around a square hole of 20 x 10 mm (a closed POLYLINE of VERTEX
// entities); a LINE and an open polyline beside them are left out. On a
// flat plate of 100 mm (40 x 40 crossed cells): the arcs come in sides of
// 2 degrees (90 per half circle), a CIRCLE's in 180; the pattern is the slot less the hole,
// its area that of those polygons to round-off, the hole's outline
// clockwise; every point of the pattern lies on the polygons' sides.
// Units from $INSUNITS or from a scale after the file's name; a file that
// gives none, or holds no closed polyline, is refused.
TEST(Blank, PolygonFromADxfFileWithArcsAndAHole) {
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_dxf";
  std::filesystem::create_directories(dir);
  auto dxf = [&](const std::string& name, const std::string& header, const std::string& entities) {
    std::ofstream(dir / name) << "0\nSECTION\n2\nHEADER\n" << header << "0\nENDSEC\n0\nSECTION\n2\nENTITIES\n"
                              << entities << "0\nENDSEC\n0\nEOF\n";
    return (dir / name).string();
  };
  const std::string slot =
      "0\nLINE\n8\n0\n10\n0.0\n20\n0.0\n11\n100.0\n21\n100.0\n"
      "0\nLWPOLYLINE\n8\nTRIM\n90\n4\n70\n1\n10\n25.0\n20\n25.0\n10\n75.0\n20\n25.0\n42\n1.0\n10\n75.0\n20\n55.0\n"
      "10\n25.0\n20\n55.0\n42\n1.0\n"
      "0\nPOLYLINE\n8\nTRIM\n66\n1\n70\n1\n10\n0.0\n20\n0.0\n30\n0.0\n"
      "0\nVERTEX\n8\nTRIM\n10\n40.0\n20\n35.0\n30\n0.0\n0\nVERTEX\n8\nTRIM\n10\n60.0\n20\n35.0\n30\n0.0\n"
      "0\nVERTEX\n8\nTRIM\n10\n60.0\n20\n45.0\n30\n0.0\n0\nVERTEX\n8\nTRIM\n10\n40.0\n20\n45.0\n30\n0.0\n"
      "0\nSEQEND\n8\nTRIM\n"
      "0\nLWPOLYLINE\n8\n0\n90\n3\n70\n0\n10\n0.0\n20\n90.0\n10\n50.0\n20\n95.0\n10\n99.0\n20\n90.0\n";
  const std::string mm = dxf("slot.dxf", "9\n$ACADVER\n1\nAC1015\n9\n$INSUNITS\n70\n4\n", slot);
  const TrimSurface t = parse_trim("polygon:" + mm);
  ASSERT_EQ(t.rings.size(), 2u);
  EXPECT_EQ(t.rings[0].size(), 2u + 2 * 90);  // the corners, and 89 points inside each arc
  EXPECT_EQ(t.rings[1].size(), 4u);
  EXPECT_NEAR(t.rings[0][1][0], 0.075, 1e-15);
  const double r = 0.015, n = 90;
  const double tessellated = 0.05 * 0.03 + 2 * (n / 2) * r * r * std::sin(M_PI / n) - 0.02 * 0.01;
  const ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {40, 40}, true);
  const CutPattern p = cut_pattern(m.x, m.x, m.triangles, {t});
  ASSERT_EQ(p.outlines.size(), 2u);  // the slot, and the hole
  EXPECT_NEAR(signed_area_z(p.outlines[0]) + signed_area_z(p.outlines[1]), p.kept_blank_area, 1e-13 * tessellated);
  EXPECT_LT(std::min(signed_area_z(p.outlines[0]), signed_area_z(p.outlines[1])), 0.0) << "the hole runs clockwise";
  EXPECT_NEAR(p.kept_blank_area, tessellated, 1e-13 * tessellated);
  std::size_t points = 0;
  for (const Outline& o : p.outlines)
    for (const OutlinePoint& q : o.points) {
      double off = 1e300;
      for (const auto& ring : t.rings) off = std::min(off, to_sides(ring, q.blank[0], q.blank[1]));
      EXPECT_LT(off, 1e-16) << q.blank[0] << " " << q.blank[1];
      ++points;
    }
  EXPECT_GT(points, t.rings[0].size() + t.rings[1].size()) << "every vertex, and where sides cross the mesh's edges";
  // A CIRCLE (50, 40) mm, r 20 mm: a polygon of 180 sides of 2 degrees.
  {
    const TrimSurface c = parse_trim(
        "polygon:" + dxf("circle.dxf", "9\n$INSUNITS\n70\n4\n",
                         "0\nCIRCLE\n8\nTRIM\n10\n50.0\n20\n40.0\n30\n0.0\n40\n20.0\n0\nLINE\n8\n0\n10\n0.0\n20\n0.0\n"
                         "11\n1.0\n21\n1.0\n"));
    ASSERT_EQ(c.rings.size(), 1u);
    ASSERT_EQ(c.rings[0].size(), 180u);
    EXPECT_NEAR(c.rings[0][0][0], 0.07, 1e-15);
    EXPECT_NEAR(c.rings[0][90][0], 0.03, 1e-15);
    const CutPattern q = cut_pattern(m.x, m.x, m.triangles, {c});
    ASSERT_EQ(q.outlines.size(), 1u);
    const double gon = 90 * 0.02 * 0.02 * std::sin(2 * M_PI / 180);
    EXPECT_NEAR(q.kept_blank_area, gon, 1e-13 * gon);
    for (const OutlinePoint& o : q.outlines[0].points) EXPECT_LT(to_sides(c.rings[0], o.blank[0], o.blank[1]), 1e-16);
    EXPECT_EQ(refused("polygon:" + dxf("flat.dxf", "9\n$INSUNITS\n70\n4\n",
                                       "0\nCIRCLE\n8\nTRIM\n10\n50.0\n20\n40.0\n30\n0.0\n40\n0.0\n")),
              "--trim 'polygon:" + (dir / "flat.dxf").string() + "': '" + (dir / "flat.dxf").string() +
                  "' line 16: a CIRCLE without a radius above 0");
  }
  // Units: a scale after the name, inches from $INSUNITS 1, none.
  const std::string bare = dxf("bare.dxf", "", slot);
  const TrimSurface scaled = parse_trim("polygon:" + bare + ",0.001");
  EXPECT_EQ(scaled.rings, t.rings);
  const std::string inch = dxf("inch.dxf", "9\n$INSUNITS\n70\n1\n", slot);
  EXPECT_NEAR(parse_trim("polygon:" + inch).rings[0][1][0], 75 * 0.0254, 1e-15);
  EXPECT_EQ(refused("polygon:" + bare), "--trim 'polygon:" + bare + "': '" + bare +
                                            "' does not give its units (no $INSUNITS): give them after a comma, "
                                            "polygon:" + bare + ",0.001 for millimetres");
  EXPECT_EQ(refused("polygon:" + bare + ",1e6"), "--trim 'polygon:" + bare + ",1e6': '" + bare +
                                                   "': polyline 1 vertex 1 lies beyond 1e6 m: not a trim in a press "
                                                   "(the scale?)");
  EXPECT_EQ(refused("polygon:" + bare + ",-1"), "--trim 'polygon:" + bare + ",-1': the scale must be a number above "
                                                                              "0, found '-1'");
  const std::string open = dxf("open.dxf", "9\n$INSUNITS\n70\n4\n",
                               "0\nLWPOLYLINE\n8\n0\n90\n3\n70\n0\n10\n0.0\n20\n90.0\n10\n50.0\n20\n95.0\n"
                               "10\n99.0\n20\n90.0\n");
  EXPECT_EQ(refused("polygon:" + open), "--trim 'polygon:" + open + "': '" + open +
                                            "' holds no closed polyline (its 1 open one is not a trim line: close it "
                                            "in CAD)");
  const std::string crossing = dxf("crossing.dxf", "9\n$INSUNITS\n70\n4\n",
                                   slot + "0\nLWPOLYLINE\n8\n0\n90\n3\n70\n1\n10\n50.0\n20\n50.0\n10\n99.0\n20\n50.0\n"
                                          "10\n99.0\n20\n99.0\n");
  EXPECT_EQ(refused("polygon:" + crossing), "--trim 'polygon:" + crossing + "': '" + crossing +
                                                "': polylines 1 and 3 cross or touch");
  const std::string flag = dxf("flag.dxf", "9\n$INSUNITS\n70\n1e300\n", slot);
  EXPECT_EQ(refused("polygon:" + flag), "--trim 'polygon:" + flag + "': '" + flag +
                                            "' line 8: expected an integer, found '1e300'");
  std::filesystem::remove_all(dir);
}


// A trim outline drawn in CAD in a plane other than plan view: a DXF
// polyline's extrusion direction n is the normal of the plane it is
// drawn in, its vertices in that plane's axes (DXF's arbitrary axis
// algorithm, here by hand: n = -y gives x and z; n = +x gives y and z;
// n = (0, -0.6, 0.8) gives (1, 0, 0) and (0, 0.8, 0.6)). The trim cuts
// along n. A plate of 100 mm (irregular triangles) formed into a plane
// tilted against the drawing's, x = X ax + Y ay + (0.3 X + 0.2 Y + 0.05)
// n: seen along n, each point lies at (X, Y), so the pattern is the L
// drawn, exactly. Polylines in two planes, or without a normal, are
// refused; a 3D POLYLINE is seen along z.
TEST(Blank, PolygonDrawnInAnotherPlaneCutsAlongItsNormal) {
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_plane";
  std::filesystem::create_directories(dir);
  const std::vector<std::array<double, 2>> L = {{11.3, 12.7}, {87.1, 12.7}, {87.1, 41.3},
                                               {43.7, 41.3}, {43.7, 88.9}, {11.3, 88.9}};  // mm
  const double exact = 0.0758 * 0.0286 + 0.0324 * 0.0476;
  std::vector<std::array<double, 2>> L_m;  // m
  for (const auto& v : L) L_m.push_back({v[0] / 1000, v[1] / 1000});
  auto lwpolyline = [&](const std::vector<std::array<double, 2>>& pts, const V3& n) {
    std::ostringstream e;
    e.precision(17);
    e << "0\nLWPOLYLINE\n8\nTRIM\n90\n" << pts.size() << "\n70\n1\n";
    for (const auto& v : pts) e << "10\n" << v[0] << "\n20\n" << v[1] << "\n";
    e << "210\n" << n[0] << "\n220\n" << n[1] << "\n230\n" << n[2] << "\n";
    return e.str();
  };
  auto dxf = [&](const std::string& name, const std::string& entities) {
    std::ofstream(dir / name) << "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n"
                              << entities << "0\nENDSEC\n0\nEOF\n";
    return (dir / name).string();
  };
  const ShellMesh m = irregular_rectangle(0, 0, 0.1, 0.1, 20, 20, 0.0015, 31);
  struct View {
    V3 n, ax, ay;
  };
  const std::vector<View> views = {{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                                   {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                                   {{0, -0.6, 0.8}, {1, 0, 0}, {0, 0.8, 0.6}}};
  for (std::size_t k = 0; k < views.size(); ++k) {
    const View& w = views[k];
    const TrimSurface t = parse_trim("polygon:" + dxf("view.dxf", lwpolyline(L, w.n)));
    for (int d = 0; d < 3; ++d) {
      EXPECT_NEAR(t.plan_u[d], w.ax[d], 1e-15) << k;
      EXPECT_NEAR(t.plan_v[d], w.ay[d], 1e-15) << k;
    }
    std::vector<double> x(m.x.size());
    for (std::size_t i = 0; i < x.size(); i += 3) {
      const double X = m.x[i], Y = m.x[i + 1], h = 0.3 * X + 0.2 * Y + 0.05;
      for (int d = 0; d < 3; ++d) x[i + d] = X * w.ax[d] + Y * w.ay[d] + h * w.n[d];
    }
    const CutPattern p = cut_pattern(m.x, x, m.triangles, {t});
    ASSERT_EQ(p.outlines.size(), 1u) << k;
    EXPECT_NEAR(p.kept_blank_area, exact, 1e-13 * exact) << k;
    EXPECT_NEAR(signed_area_z(p.outlines[0]), exact, 1e-13 * exact) << k;
    int corners = 0;
    for (const OutlinePoint& q : p.outlines[0].points) {
      EXPECT_LT(to_sides(L_m, q.blank[0], q.blank[1]), 1e-16) << k;
      if (to_vertices(L_m, q.blank[0], q.blank[1]) < 1e-16) ++corners;
    }
    EXPECT_EQ(corners, 6) << k;
  }
  // Plan view by default and along -z (x mirrored, as CAD draws it seen from below).
  EXPECT_EQ(parse_trim("polygon:" + dxf("z.dxf", lwpolyline(L, {0, 0, 1}))).plan_u, (V3{1, 0, 0}));
  const TrimSurface below = parse_trim("polygon:" + dxf("below.dxf", lwpolyline(L, {0, 0, -1})));
  EXPECT_EQ(below.plan_u, (V3{-1, 0, 0}));
  EXPECT_EQ(below.plan_v, (V3{0, 1, 0}));
  // A 3D POLYLINE (flag 8): its vertices' x and y, seen along z.
  {
    std::ostringstream e;
    e << "0\nPOLYLINE\n8\nTRIM\n66\n1\n70\n9\n10\n0.0\n20\n0.0\n30\n0.0\n";
    for (const auto& v : L)
      e << "0\nVERTEX\n8\nTRIM\n10\n" << v[0] << "\n20\n" << v[1] << "\n30\n" << v[0] / 3 << "\n70\n32\n";
    e << "0\nSEQEND\n8\nTRIM\n";
    const TrimSurface t = parse_trim("polygon:" + dxf("3d.dxf", e.str()));
    EXPECT_EQ(t.plan_u, (V3{1, 0, 0}));
    EXPECT_EQ(t.plan_v, (V3{0, 1, 0}));
    ASSERT_EQ(t.rings.size(), 1u);
    EXPECT_NEAR(t.rings[0][1][0], 0.0871, 1e-15);
  }
  const std::vector<std::array<double, 2>> hole = {{30, 20}, {35, 20}, {35, 25}};
  const std::string two = dxf("two.dxf", lwpolyline(L, {0, -1, 0}) + lwpolyline(hole, {0, 1, 0}));
  EXPECT_EQ(refused("polygon:" + two), "--trim 'polygon:" + two + "': '" + two +
                                           "': polyline 2 is drawn in another plane than polyline 1 (normal 0, 1, 0 "
                                           "against 0, -1, 0): draw a trim outline's polylines in one plane");
  const std::string none = dxf("none.dxf", lwpolyline(L, {0, 0, 0}));
  EXPECT_EQ(refused("polygon:" + none), "--trim 'polygon:" + none + "': '" + none +
                                            "': polyline 1 has no extrusion direction (the normal of its plane, codes "
                                            "210-230)");
  std::filesystem::remove_all(dir);
}

// Inside an odd number of rings (crossings of a ray along +x).
bool inside_rings(const std::vector<std::vector<std::array<double, 2>>>& rings, double x, double y) {
  bool in = false;
  for (const auto& p : rings)
    for (std::size_t k = 0, j = p.size() - 1; k < p.size(); j = k++)
      if ((p[j][1] > y) != (p[k][1] > y) &&
          x < p[j][0] + (y - p[j][1]) * (p[k][0] - p[j][0]) / (p[k][1] - p[j][1]))
        in = !in;
  return in;
}
double to_rings(const std::vector<std::vector<std::array<double, 2>>>& rings, double x, double y) {
  double d = 1e300;
  for (const auto& p : rings) d = std::min(d, to_sides(p, x, y));
  return d;
}
double area_of(const std::vector<std::vector<std::array<double, 2>>>& rings) {
  double a = 0;
  for (const auto& p : rings) a += std::abs(area(p));
  return a;
}
// The area of the sector of angle t (rad) about a vertex as drawn: its
// arc of radius r by tangents, each over at most 2 degrees of it (k kites
// of two right triangles with legs r and r tan(t / 2k)).
double drawn_sector(double t, double r) {
  const int k = static_cast<int>(std::ceil(t / (2 * M_PI / 180) - 1e-9));
  return k * r * r * std::tan(t / (2 * k));
}
// How much further from the vertex the tangents' corners lie than the arc.
const double kTangentReach = 1 / std::cos(M_PI / 180);

// --margin with a polygon: its outline moved by the margin in its plane,
// exact in its sides and inner corners, its outer corners drawn as
// tangents to the arc over at most 2 degrees each; the pattern is then
// cut exactly along it. References: the areas of the strips, corners and
// sectors for an L, in and out (Steiner's formula with the corners'
// overlaps); a slot narrower than twice the margin, closed; random
// polygons against the distance to the polygon, point by point (every
// grid point further than the tangents' offset from the moved line on the
// side the distance puts it).
TEST(Blank, PolygonMovedByAMarginIsItsOffsetOutline) {
  using Rings = std::vector<std::vector<std::array<double, 2>>>;
  auto polygon = [](const Rings& rings) {
    TrimSurface t;
    t.kind = TrimSurface::Kind::Polygon;
    t.rings = rings;
    t.text = "polygon";
    return t;
  };
  const std::vector<std::array<double, 2>> L = {{0.0113, 0.0127}, {0.0871, 0.0127}, {0.0871, 0.0413},
                                               {0.0437, 0.0413}, {0.0437, 0.0889}, {0.0113, 0.0889}};
  const double a_L = 0.0758 * 0.0286 + 0.0324 * 0.0476, p_L = 2 * (0.0758 + 0.0762);
  for (const double m : {0.004, -0.003}) {
    const Rings r = polygon_margin_rings(polygon({L}), m);
    ASSERT_EQ(r.size(), 1u) << m;
    const double a = std::abs(m);
    // Out: 5 outer corners rounded (90 degrees each), the inner one
    // where the sides meet (a square a x a counted twice); in: the 5
    // corners where the sides meet (a square each counted twice), the
    // inner corner rounded.
    const double exact = m > 0 ? a_L + p_L * a + 5 * drawn_sector(M_PI / 2, a) - a * a
                               : a_L - p_L * a + 5 * a * a - drawn_sector(M_PI / 2, a);
    EXPECT_NEAR(area_of(r), exact, 1e-16) << m;
    int at_margin = 0;  // every vertex and side at the margin or within the tangents' offset beyond it
    for (std::size_t k = 0; k < r[0].size(); ++k) {
      const auto& u = r[0][k];
      const auto& w = r[0][(k + 1) % r[0].size()];
      const double d = to_sides(L, u[0], u[1]), mid = to_sides(L, 0.5 * (u[0] + w[0]), 0.5 * (u[1] + w[1]));
      EXPECT_GE(d, a - 1e-16) << m << " vertex " << k;
      EXPECT_LE(d, a * kTangentReach + 1e-16) << m << " vertex " << k;
      EXPECT_GE(mid, a - 1e-16) << m << " side " << k;
      EXPECT_LE(mid, a * kTangentReach + 1e-16) << m << " side " << k;
      EXPECT_EQ(inside_rings({L}, u[0], u[1]), m < 0) << m << " vertex " << k;
      at_margin += std::abs(d - a) <= 1e-16;
    }
    // Each rounded corner: where the moved sides end (on the arc) and 45
    // tangents' corners; each sharp corner: one vertex.
    EXPECT_EQ(r[0].size(), m > 0 ? 5u * 47u + 1u : 5u + 47u) << m;
    EXPECT_EQ(at_margin, m > 0 ? 5 * 2 + 1 : 5 + 2) << m;
  }
  // A rectangle with a slot narrower than twice the margin: the slot is
  // filled, and above it the arcs about its two corners meet.
  {
    const double w = 0.008, m = 0.006;
    const std::vector<std::array<double, 2>> slotted = {{0, 0},     {0.1, 0},    {0.1, 0.05}, {0.054, 0.05},
                                                        {0.054, 0.02}, {0.046, 0.02}, {0.046, 0.05}, {0, 0.05}};
    const Rings r = polygon_margin_rings(polygon({slotted}), m);
    ASSERT_EQ(r.size(), 1u);
    const double c = w / 2;
    const double cusp = m * w - (c * std::sqrt(m * m - c * c) + m * m * std::asin(c / m));
    const double smooth = (0.1 + 2 * m) * (0.05 + 2 * m) - (4 - M_PI) * m * m - cusp;
    // The tangents add at most this much to the 6 arcs of 90 degrees.
    const double tangents = 6 * (drawn_sector(M_PI / 2, m) - M_PI / 4 * m * m);
    EXPECT_GE(area_of(r), smooth);
    EXPECT_LE(area_of(r), smooth + tangents);
    double lowest = 1;  // over the slot
    for (const auto& u : r[0]) {
      const double d = to_sides(slotted, u[0], u[1]);
      EXPECT_GE(d, m - 1e-16);
      EXPECT_LE(d, m * kTangentReach + 1e-16);
      if (std::abs(u[0] - 0.05) < c) lowest = std::min(lowest, u[1]);
    }
    EXPECT_GE(lowest, 0.05 + std::sqrt(m * m - c * c));
    EXPECT_LE(lowest, 0.05 + std::sqrt(m * m * kTangentReach * kTangentReach - c * c));
    // Moved in by more than half the slot's walls' width: two pieces.
    EXPECT_EQ(polygon_margin_rings(polygon({slotted}), -0.0201).size(), 2u);
    EXPECT_TRUE(polygon_margin_rings(polygon({slotted}), -0.03).empty());
  }
  // A step whose lower side, moved up, runs to the corner above along the
  // line between the upper side's strip and that corner's sector (inside
  // the region: left out, not taken as outline).
  {
    const std::vector<std::array<double, 2>> step = {{0, 0},       {0.03, 0},    {0.03, 0.01},
                                                     {0.01, 0.01}, {0.01, 0.02}, {0, 0.02}};
    const double m = 0.01;
    const Rings r = polygon_margin_rings(polygon({step}), m);
    ASSERT_EQ(r.size(), 1u);
    EXPECT_NEAR(area_of(r), 0.0004 + 0.1 * m + 5 * drawn_sector(M_PI / 2, m) - m * m, 1e-17);
  }
  // Margins near the round-off about inner corners of small turns (a
  // square with a dent): the moved sides end where they meet, not in
  // slivers beyond each other too short to judge. The area within what
  // joining the points within 1e-9 of the size allows (that times the
  // perimeter): the corners' tangents are shorter than that here.
  for (int k = 0; k < 200; ++k) {
    const double t = 0.001 + 0.05 * k / 200;  // the dent's depth (m)
    const std::vector<std::array<double, 2>> dart = {{0, 0}, {0.05, t}, {0.1, 0}, {0.1, 0.1}, {0, 0.1}};
    const double a = 0.01 - 0.05 * t, p = 0.3 + 2 * std::hypot(0.05, t);
    for (const double m : {1e-8, -1e-8, 3e-9, 1e-7}) {
      Rings r;
      ASSERT_NO_THROW(r = polygon_margin_rings(polygon({dart}), m)) << k << " " << m;
      EXPECT_NEAR(area_of(r), a + p * m + M_PI * m * m, 1e-9 * std::hypot(0.1, 0.1) * p) << k << " " << m;
    }
  }
  // Stars with their vertices on a 6.25 mm grid, moved by margins off
  // the grid: sides along the same lines and the moved sides of some
  // crossing others' where those pass from a strip into the polygon
  // (exactly half-way along a piece for some). Every outline is found.
  {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto orient = [](const std::array<double, 2>& o, const std::array<double, 2>& a, const std::array<double, 2>& b) {
      const double c = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
      return (c > 0) - (c < 0);
    };
    int moved = 0;
    for (int k = 0; k < 4000; ++k) {
      const int n = 3 + static_cast<int>(rng() % 58);
      const double g = 0.00625, rad = 0.02 + 0.05 * u(rng);
      std::vector<std::array<double, 2>> v;
      for (int i = 0; i < n; ++i) {
        const double t = 2 * M_PI * (i + 0.8 * u(rng)) / n, r = rad * (0.3 + 0.7 * u(rng));
        const std::array<double, 2> q{std::round(r * std::cos(t) / g) * g, std::round(r * std::sin(t) / g) * g};
        if (v.empty() || q != v.back()) v.push_back(q);
      }
      while (v.size() > 1 && v.front() == v.back()) v.pop_back();
      bool simple = v.size() >= 3 && std::abs(area(v)) > 0;
      for (std::size_t i = 0; i < v.size() && simple; ++i)
        for (std::size_t j = i + 1; j < v.size() && simple; ++j) {
          if (j == i + 1 || (i == 0 && j == v.size() - 1)) continue;
          const auto &a = v[i], &b = v[(i + 1) % v.size()], &c = v[j], &d = v[(j + 1) % v.size()];
          simple = !(orient(a, b, c) * orient(a, b, d) <= 0 && orient(c, d, a) * orient(c, d, b) <= 0);
        }
      for (std::size_t i = 0; i < v.size() && simple; ++i)  // no side folded back onto the one before
        simple = orient(v[i], v[(i + 1) % v.size()], v[(i + 2) % v.size()]) != 0 ||
                 (v[(i + 1) % v.size()][0] - v[i][0]) * (v[(i + 2) % v.size()][0] - v[(i + 1) % v.size()][0]) +
                         (v[(i + 1) % v.size()][1] - v[i][1]) * (v[(i + 2) % v.size()][1] - v[(i + 1) % v.size()][1]) >
                     0;
      if (!simple) continue;
      const double m = (k % 2 ? 1 : -1) * (1e-4 + 0.02 * u(rng));
      try {
        const Rings r = polygon_margin_rings(polygon({v}), m);
        ++moved;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "star " << k << ", margin " << m << ": " << e.what();
      }
    }
    EXPECT_GT(moved, 1000);
  }
  // Random polygons (stars with deep notches), with a hole in half of
  // them, moved out and in: every point of a grid over them lies inside
  // the moved outline exactly where its distance to the polygon says
  // (points within the tangents' offset beyond the margin left out).
  {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int checked = 0;
    for (int k = 0; k < 60; ++k) {
      const int n = 5 + k % 23;
      Rings rings(1);
      for (int i = 0; i < n; ++i) {
        const double t = 2 * M_PI * (i + 0.7 * u(rng)) / n, rad = 0.01 + 0.04 * u(rng);
        rings[0].push_back({rad * std::cos(t), rad * std::sin(t)});
      }
      if (k % 2) {  // a small hole round the centre, clockwise
        const double h = 0.003 + 0.004 * u(rng);
        rings.push_back({{-h, -h}, {-h, h}, {h, h}, {h, -h}});
        if (!inside_rings({rings[0]}, -h, -h) || !inside_rings({rings[0]}, h, h) ||
            !inside_rings({rings[0]}, -h, h) || !inside_rings({rings[0]}, h, -h) || to_sides(rings[0], 0, 0) < 2 * h)
          rings.pop_back();
      }
      const double m = (k % 3 == 0 ? -1 : 1) * (0.0005 + 0.01 * u(rng));
      Rings moved;
      try {
        moved = polygon_margin_rings(polygon(rings), m);
      } catch (const std::exception& e) {
        ADD_FAILURE() << "case " << k << ": " << e.what();
        continue;
      }
      const double band = std::abs(m) * (kTangentReach - 1) + 1e-12;
      const int g = 120;
      for (int i = 0; i <= g; ++i)
        for (int j = 0; j <= g; ++j) {
          const double x = -0.065 + 0.13 * i / g, y = -0.065 + 0.13 * j / g;
          const bool in = inside_rings(rings, x, y);
          const double d = in ? -to_rings(rings, x, y) : to_rings(rings, x, y);
          if (std::abs(d - m) <= band) continue;
          EXPECT_EQ(inside_rings(moved, x, y), d < m) << "case " << k << " at " << x << ", " << y << ": d " << d;
          ++checked;
        }
    }
    EXPECT_GT(checked, 500000);
  }
  // The pattern of a formed plate, turned and moved, cut with the margin:
  // exactly the moved outline carried back (the plate's map is rigid).
  {
    const ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {40, 40}, true);
    const std::vector<double> x = turned_and_moved(m.x);
    std::vector<std::array<double, 2>> formed;
    for (const auto& v : L) formed.push_back(turned_and_moved(v));
    for (const double margin : {0.004, -0.003}) {
      const Rings moved = polygon_margin_rings(polygon({formed}), margin);
      const CutPattern p = cut_pattern(m.x, x, m.triangles, {polygon({formed})}, margin);
      ASSERT_EQ(p.polygon_margin, std::vector<std::string>{""});
      ASSERT_EQ(p.outlines.size(), 1u);
      EXPECT_NEAR(p.kept_formed_area, area_of(moved), 1e-13 * area_of(moved)) << margin;
      EXPECT_NEAR(p.kept_blank_area, area_of(moved), 1e-13 * area_of(moved)) << margin;
      for (const OutlinePoint& q : p.outlines[0].points) EXPECT_LT(to_rings(moved, q.formed[0], q.formed[1]), 1e-16);
    }
    // Moved in until nothing is left: no pattern.
    const CutPattern none = cut_pattern(m.x, x, m.triangles, {polygon({formed})}, -0.02);
    EXPECT_TRUE(none.outlines.empty());
    EXPECT_EQ(none.kept_blank_area, 0.0);
  }
  // A C whose bars are moved in by exactly half their width: lines of no
  // width where the moved sides meet the polygon's own. The margin 1e-8
  // of the polygon's size larger parts them: the square of 10 mm left of
  // the slot, less that all round. Half the bars' width less a little:
  // the square and the bars' thin strips.
  {
    const std::vector<std::array<double, 2>> c = {{0, 0},       {0.1, 0},     {0.1, 0.02},  {0.05, 0.02},
                                                  {0.05, 0.03}, {0.1, 0.03},  {0.1, 0.05},  {0, 0.05}};
    const double nudge = 1e-8 * std::hypot(0.1, 0.05);
    const Rings square = polygon_margin_rings(polygon({c}), -0.02);
    ASSERT_EQ(square.size(), 1u);
    EXPECT_NEAR(area_of(square), (0.01 - 2 * nudge) * (0.01 - 2 * nudge), 1e-18);
    const ShellMesh plate = rectangle_mesh({-0.01, -0.01, 0}, {0.12, 0.07}, {24, 14}, true);
    for (const double m : {-0.02, -0.0199}) {
      const CutPattern p = cut_pattern(plate.x, plate.x, plate.triangles, {polygon({c})}, m);
      EXPECT_EQ(p.polygon_margin, std::vector<std::string>{""}) << m;
      EXPECT_NEAR(p.kept_blank_area, area_of(polygon_margin_rings(polygon({c}), m)), 1e-15) << m;
    }
  }
  // Where the moved outline cannot be found, the pattern comes from the
  // distance less the margin, and says why: a margin beyond 1e6 m keeps
  // the whole plate.
  {
    const ShellMesh plate = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {8, 8}, true);
    const CutPattern p = cut_pattern(plate.x, plate.x, plate.triangles, {polygon({L})}, 2e6);
    ASSERT_EQ(p.polygon_margin.size(), 1u);
    EXPECT_EQ(p.polygon_margin[0], "the margin 2e+06 m is beyond 1e6 m");
    EXPECT_NEAR(p.kept_blank_area, 0.01, 1e-15);
  }
}

// Where the exact cut's outline does not close, the pattern comes from
// the trims' largest distance, linear in each triangle, and says so: a
// circle drawn on the front plane (normal -y, r = 21.3 mm) touching the
// flat plate, seen edge-on, in one vertex at z = 1e-18 m (the 180-gon's
// lowest, off the plate by round-off): the exact cut finds the line of
// contact on some of the plate's edges and not on others. The pattern is
// that line, no area.
TEST(Blank, APatternTheExactCutCannotCloseComesFromTheDistance) {
  const auto dir = std::filesystem::temp_directory_path() / "thermostamp_blank_fallback";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "tangent.dxf");
    f << "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n6\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nCIRCLE\n8\nT\n10\n0.0437\n"
         "20\n0.0213\n30\n0\n40\n0.0213\n210\n0\n220\n-1\n230\n0\n0\nENDSEC\n0\nEOF\n";
  }
  const TrimSurface t = parse_trim("polygon:" + (dir / "tangent.dxf").string());
  for (const int n : {7, 13, 20}) {
    const ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {n, n});
    const CutPattern p = cut_pattern(m.x, m.x, m.triangles, {t});
    EXPECT_NE(p.fallback.find("the outline does not close at (0.0437, "), std::string::npos) << n << ": " << p.fallback;
    EXPECT_TRUE(p.outlines.empty()) << n;
    EXPECT_LT(p.kept_blank_area, 1e-18) << n;
    const std::vector<double> fibre(m.triangles.size(), 1.0);
    EXPECT_TRUE(fibre_marks(m.x, m.x, m.triangles, {t}, fibre, {1, 0, 0}, {0, 1, 0}, 0.01, 0, true).empty()) << n;
  }
  std::filesystem::remove_all(dir);
}

// Fibre marks: on a flat plate 120 x 80 mm (irregular triangles, fibres at
// 30 degrees in its first half and 120 degrees in the other, as a field
// per triangle), trimmed to 13.3 < x < 101.7 mm, with a grid of 10 mm: a
// mark at every grid point inside the trim, the blank's edges included
// (9 x 9 of them), 6 mm long, centred on it, along the fibres of its
// triangle; their ends formed by an affine map are the map's images of
// them.
TEST(Blank, FibreMarksFollowTheFibresOfTheirTriangles) {
  const ShellMesh m = irregular_rectangle(0, 0, 0.12, 0.08, 12, 8, 0.0025, 5);
  const std::size_t tris = m.triangles.size() / 3;
  std::vector<double> fibre(3 * tris);
  auto centre_x = [&](std::size_t e) {
    double c = 0;
    for (int k = 0; k < 3; ++k) c += m.x[3 * static_cast<std::size_t>(m.triangles[3 * e + k])] / 3;
    return c;
  };
  for (std::size_t e = 0; e < tris; ++e) {
    const double a = (centre_x(e) < 0.06 ? 30.0 : 120.0) * M_PI / 180;
    fibre[3 * e] = std::cos(a);
    fibre[3 * e + 1] = std::sin(a);
  }
  const std::vector<TrimSurface> trims = {parse_trim("plane:0.0133,0,0,1,0,0"), parse_trim("plane:0.1017,0,0,-1,0,0")};
  // Formed: a stretch, a shear and a turn out of the plane, x = A X + b
  // (the trims' planes x = const are kept by it: A's first row is (1, 0, 0)).
  std::vector<double> x(m.x.size());
  const double A[3][3] = {{1.0, 0.0, 0.0}, {0.2, 1.1, 0.0}, {0.0, 0.3, 1.0}}, b[3] = {0.0, 0.01, 0.02};
  for (std::size_t i = 0; i < x.size(); i += 3)
    for (int r = 0; r < 3; ++r) x[i + r] = A[r][0] * m.x[i] + A[r][1] * m.x[i + 1] + A[r][2] * m.x[i + 2] + b[r];
  const auto marks = fibre_marks(m.x, x, m.triangles, trims, fibre, {1, 0, 0}, {0, 1, 0}, 0.01);
  ASSERT_EQ(marks.size(), 9u * 9u);  // x = 20 ... 100 mm, y = 0 ... 80 mm
  std::set<std::pair<long, long>> at;
  for (const FibreMark& k : marks) {
    const double cx = (k.from[0] + k.to[0]) / 2, cy = (k.from[1] + k.to[1]) / 2;
    const long i = std::lround(cx / 0.01), j = std::lround(cy / 0.01);
    EXPECT_NEAR(cx, 0.01 * static_cast<double>(i), 1e-15);
    EXPECT_NEAR(cy, 0.01 * static_cast<double>(j), 1e-15);
    at.emplace(i, j);
    EXPECT_NEAR(std::hypot(k.to[0] - k.from[0], k.to[1] - k.from[1]), 0.006, 1e-15);
    EXPECT_EQ(k.from[2], 0.0);
    for (int r = 0; r < 3; ++r) {  // the ends formed: by the affine map
      EXPECT_NEAR(k.formed_from[r], A[r][0] * k.from[0] + A[r][1] * k.from[1] + b[r], 1e-15);
      EXPECT_NEAR(k.formed_to[r], A[r][0] * k.to[0] + A[r][1] * k.to[1] + b[r], 1e-15);
    }
    // The triangle the point lies in: its fibres.
    int found = -1;
    for (std::size_t e = 0; e < tris && found < 0; ++e) {
      double u[3], v[3];
      for (int q = 0; q < 3; ++q) {
        u[q] = m.x[3 * static_cast<std::size_t>(m.triangles[3 * e + q])];
        v[q] = m.x[3 * static_cast<std::size_t>(m.triangles[3 * e + q]) + 1];
      }
      const double det = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
      const double b1 = ((cx - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (cy - v[0])) / det;
      const double b2 = ((u[1] - u[0]) * (cy - v[0]) - (cx - u[0]) * (v[1] - v[0])) / det;
      if (b1 >= -1e-12 && b2 >= -1e-12 && 1 - b1 - b2 >= -1e-12) found = static_cast<int>(e);
    }
    ASSERT_GE(found, 0);
    const double cross = (k.to[0] - k.from[0]) * fibre[3 * static_cast<std::size_t>(found) + 1] -
                         (k.to[1] - k.from[1]) * fibre[3 * static_cast<std::size_t>(found)];
    EXPECT_NEAR(cross, 0.0, 1e-15) << "along the fibres of triangle " << found;
  }
  EXPECT_EQ(at.size(), marks.size()) << "one mark a point";
  EXPECT_EQ(at.begin()->first, 2);
  EXPECT_EQ(at.rbegin()->first, 10);
}

}  // namespace
}  // namespace ts
