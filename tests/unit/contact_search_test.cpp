// The ply/ply closest-point search of penalty_node_surface against a brute
// force over every triangle of the other ply.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include <thermostamp/sdk/math.hpp>

#include "mesh/shell_mesh.hpp"
#include "plugins/registry.hpp"
#include "test_support.hpp"

namespace ts {
namespace {

// A creased, curved surface: a ridge along x = 0.031 (slope 0.2 on either
// side, so that nodes over it find an edge or a vertex, not a face) on a
// cylinder of radius 0.05 m along x.
double surface(double x, double y) { return -0.2 * std::abs(x - 0.031) - y * y / 0.1; }

ShellMesh ply_mesh(const std::array<double, 3>& origin, const std::array<double, 2>& size, std::array<int, 2> div,
                   bool crossed, double offset_amplitude) {
  ShellMesh m = rectangle_mesh(origin, size, div, crossed);
  for (int i = 0; i < m.num_nodes(); ++i) {
    double* p = &m.x[3 * i];
    p[0] += 0.0011 * std::sin(7.0 * i);
    p[1] += 0.0009 * std::cos(5.0 * i);
    // Distance to the other ply varying over the ply and crossing zero, so
    // nodes lie on both sides, within and beyond reach.
    p[2] = surface(p[0], p[1]) + offset_amplitude * std::sin(97.0 * p[0]) * std::cos(61.0 * p[1]);
  }
  return m;
}

// The heat links of ply a's nodes on ply b (0.5 mm plies) from a
// penalty_node_surface handler configured with the given gap tolerance.
sdk::ThermalContactMap ply_links(const PluginRecord& r, const ShellMesh& a, const ShellMesh& b, double gap_tolerance) {
  std::unique_ptr<sdk::ContactHandler> handler(reinterpret_cast<sdk::ContactHandler* (*)()>(r.create)());
  const std::vector<sdk::PartView> parts = {test::part_view(a, 0, 0.0005), test::part_view(b, 1, 0.0005)};
  sdk::ThermalContactMap map;
  EXPECT_TRUE(handler
                  ->configure(validate_params(json{{"conductance", 1000.0}, {"gap_tolerance", gap_tolerance}}, "/c",
                                              r.descriptor),
                              sdk::ContactPair{{sdk::BodyRef::Type::Part, 0}, {sdk::BodyRef::Type::Part, 1}}, parts,
                              {})
                  .ok);
  const std::vector<double> area_a(a.num_nodes(), 1e-4), area_b(b.num_nodes(), 1e-4);
  const std::vector<std::span<const double>> area = {area_a, area_b};
  EXPECT_TRUE(handler->thermal_contacts(parts, {}, area, map).ok);
  return map;
}

// Every node of ply a within reach of ply b (mid-surface distance at most
// h + gap_tolerance) gets a heat link, and the link's target point on b is
// a closest point of b: its distance equals the brute-force minimum over all
// of b's triangles within 1e-12 m (round-off is about 1e-18 m here; a
// search that skips the closest triangle misses by 1e-6 m or more). Nodes
// beyond reach get no link.
TEST(PlyPlySearch, TargetsAreTheClosestPointsOfTheOtherPly) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const ShellMesh b = ply_mesh({0, 0, 0}, {0.06, 0.06}, {6, 6}, true, 0.0);
  // The second ply: its own mesh, or the same cells with its nodes right
  // over b's (as in a stack of plies: several triangles tie), up to 5 mm
  // away, on both sides; with a gap tolerance of 2 mm, and of 30 mm (every
  // triangle of b is then a candidate of every node: more than the search
  // keeps between its two sweeps).
  for (const auto& [same_cells, gap_tolerance] : {std::pair{false, 0.002}, std::pair{true, 0.002}, std::pair{false, 0.03}}) {
    const double reach = 0.0005 + gap_tolerance;
    const ShellMesh a = same_cells ? ply_mesh({0, 0, 0}, {0.06, 0.06}, {6, 6}, true, 0.005)
                                   : ply_mesh({0.004, 0.007, 0}, {0.05, 0.05}, {7, 5}, false, 0.005);
    const sdk::ThermalContactMap map = ply_links(r, a, b, gap_tolerance);
    std::vector<int> link(a.num_nodes(), -1);
    for (std::size_t l = 0; l < map.links.size(); ++l) link[map.links[l].node_a] = static_cast<int>(l);
    int within = 0, beyond = 0;
    double worst = 0;
    for (int i = 0; i < a.num_nodes(); ++i) {
      const sdk::Vec3 x = sdk::load3(a.x.data(), i);
      double best = INFINITY;
      for (int e = 0; e < b.num_elements(); ++e) {
        const int* t = &b.triangles[3 * e];
        const sdk::Vec3 cp = sdk::closest_point_on_triangle(x, sdk::load3(b.x.data(), t[0]),
                                                            sdk::load3(b.x.data(), t[1]), sdk::load3(b.x.data(), t[2]));
        best = std::min(best, sdk::norm(sdk::sub(x, cp)));
      }
      if (std::abs(best - reach) < 1e-9) continue;  // at the border of reach: either answer
      if (best > reach) {
        ++beyond;
        EXPECT_LT(link[i], 0) << "node " << i << " at " << best << " m";
        continue;
      }
      ++within;
      ASSERT_GE(link[i], 0) << "node " << i << " at " << best << " m";
      const sdk::HeatLink& l = map.links[link[i]];
      sdk::Vec3 target = {0, 0, 0};
      for (int j = 0; j < 3; ++j) {
        EXPECT_GE(l.w_b[j], -1e-12);
        target = sdk::add(target, sdk::scale(sdk::load3(b.x.data(), l.nodes_b[j]), l.w_b[j]));
      }
      EXPECT_NEAR(l.w_b[0] + l.w_b[1] + l.w_b[2], 1.0, 1e-12);
      const double d = sdk::norm(sdk::sub(x, target));
      worst = std::max(worst, std::abs(d - best));
      EXPECT_NEAR(d, best, 1e-12) << "node " << i;
    }
    std::printf("%s, reach %g m: %d nodes within reach, %d beyond; largest distance error %.2e m\n",
                same_cells ? "nodes over nodes" : "other mesh", reach, within, beyond, worst);
    EXPECT_GT(within, a.num_nodes() / 4);
    if (gap_tolerance < 0.01) {
      EXPECT_GT(beyond, a.num_nodes() / 10);
    }
  }
}

// The closest point of a lone triangle (no neighbour to find an edge from
// the other side), acute, right-angled and obtuse: points all around it,
// beyond one edge's line or two, in its plane and off it, every one within
// reach. Each target must be the brute-force closest point (distance
// within 1e-12 m, the target point within 1e-12 m of it) with weights that
// rebuild it: a search that takes the wrong one of two edges sharing a
// node, or a wrong end of an edge, misses by millimetres.
TEST(PlyPlySearch, LoneTriangleTargetsAreItsClosestPoints) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const std::vector<std::array<double, 9>> shapes = {
      {0, 0, 0, 0.010, 0.001, 0.001, 0.004, 0.008, -0.002},   // acute
      {0, 0, 0, 0.010, 0, 0, 0, 0.010, 0},                     // right angle at node 0
      {0, 0, 0, 0.012, 0, 0.002, 0.001, 0.002, 0.001},         // obtuse at node 2
  };
  int checked = 0;
  for (const auto& shape : shapes) {
    ShellMesh b;
    b.x.assign(shape.begin(), shape.end());
    b.triangles = {0, 1, 2};
    b.neighbours = {-1, -1, -1};
    ShellMesh a;  // points on a grid around the triangle, at several heights
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 21; ++j)
        for (int i = 0; i < 21; ++i)
          a.x.insert(a.x.end(), {-0.006 + 0.0012 * i + 1e-5 * j, -0.006 + 0.0010 * j, -0.002 + 0.002 * k});
    const sdk::ThermalContactMap map = ply_links(r, a, b, 0.05);  // every point is within reach
    ASSERT_EQ(static_cast<int>(map.links.size()), a.num_nodes());
    for (const sdk::HeatLink& l : map.links) {
      const sdk::Vec3 x = sdk::load3(a.x.data(), l.node_a);
      const sdk::Vec3 cp = sdk::closest_point_on_triangle(x, sdk::load3(b.x.data(), 0), sdk::load3(b.x.data(), 1),
                                                          sdk::load3(b.x.data(), 2));
      sdk::Vec3 target = {0, 0, 0};
      for (int j = 0; j < 3; ++j) {
        EXPECT_GE(l.w_b[j], -1e-12);
        target = sdk::add(target, sdk::scale(sdk::load3(b.x.data(), l.nodes_b[j]), l.w_b[j]));
      }
      EXPECT_NEAR(l.w_b[0] + l.w_b[1] + l.w_b[2], 1.0, 1e-12);
      EXPECT_NEAR(sdk::norm(sdk::sub(x, target)), sdk::norm(sdk::sub(x, cp)), 1e-12) << "node " << l.node_a;
      EXPECT_LT(sdk::norm(sdk::sub(target, cp)), 1e-12) << "node " << l.node_a;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3 * 3 * 21 * 21);
}

}  // namespace
}  // namespace ts
