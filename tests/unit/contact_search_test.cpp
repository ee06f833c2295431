// The ply/ply closest-point search of penalty_node_surface against a brute
// force over every triangle of the other ply.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
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
// The bucket grid of the contact searches: a box or cell beyond the range
// of doubles gives one cell (it gave a NaN cell count, a failed allocation),
// and a coordinate far outside the grid or NaN maps to a border cell
// without an int conversion out of range.
TEST(BucketGrid, NonFiniteBoxesAndFarPointsStayInTheGrid) {
  int n[3] = {0, 0, 0};
  const double inf = std::numeric_limits<double>::infinity();
  // hi - lo overflows in the first box
  for (const auto& hi : {sdk::Vec3{1e308, 1e308, 0}, sdk::Vec3{inf, 1, 1}, sdk::Vec3{std::nan(""), 1, 1}}) {
    const double cell = sdk::bucket_grid({-1e308, -1e308, 0}, hi, 1e-3, n);
    EXPECT_EQ(n[0] * n[1] * n[2], 1);
    EXPECT_EQ(cell, inf);
    EXPECT_EQ(sdk::bucket_index(1e300, -1e300, cell, n[0]), 0);
  }
  const double cell = sdk::bucket_grid({0, 0, 0}, {1, 1, 1}, 0.1, n);
  EXPECT_GT(n[0], 1);
  EXPECT_EQ(sdk::bucket_index(1e300, 0, cell, n[0]), n[0] - 1);
  EXPECT_EQ(sdk::bucket_index(-1e300, 0, cell, n[0]), 0);
  EXPECT_EQ(sdk::bucket_index(std::nan(""), 0, cell, n[0]), 0);
  EXPECT_EQ(sdk::bucket_index(0.55, 0, cell, n[0]), static_cast<int>(0.55 / cell));
}

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

// One call of a ply/ply handler's contact_forces() for parts (a, b) after a
// step dt, side 0 or 1 (one search direction) or -1 (both), the forces on
// each part's nodes added into fa and fb.
struct PlyForces {
  bool ok = false;
  double energy = 0;
  long long active = 0;
};
PlyForces ply_contact_forces(sdk::ContactHandler& h, std::span<const sdk::PartView> parts, double dt,
                             std::span<const std::span<const double>> velocity,
                             std::span<const std::span<const double>> node_area,
                             std::span<const std::span<const double>> mass, int side, std::vector<double>& fa,
                             std::vector<double>& fb) {
  std::vector<double> tool_force;
  const std::vector<std::span<double>> force = {fa, fb};
  sdk::ContactForceInput in;
  in.parts = parts;
  in.dt = dt;
  in.velocity = velocity;
  in.node_area = node_area;
  in.mass = mass;
  in.side = side;
  sdk::ContactForceOutput out;
  out.force = force;
  out.tool_force = tool_force;
  const bool ok = h.contact_forces(in, out).ok;
  return {ok, out.energy, out.active};
}

// One node (part 0) against a flat plate of two triangles (part 1: a 10 mm
// square split along its diagonal 0-2, node 1 on one side of it and node 3
// on the other), both plies 0.5 mm thick, through the handler's
// contact_forces() for the node's side of the pair. The plate is at rest;
// masses 1 g, areas 1 cm2, no damping.
class NodeOverPlate {
 public:
  static constexpr double kPenalty = 1e11, kArea = 1e-4;
  NodeOverPlate(const PluginRecord& r, int search_interval)
      : handler_(reinterpret_cast<sdk::ContactHandler* (*)()>(r.create)()) {
    b_.x = {0, 0, 0, 0.01, 0, 0, 0.01, 0.01, 0, 0, 0.01, 0};
    b_.triangles = {0, 1, 2, 0, 2, 3};
    b_.neighbours = {-1, 1, -1, -1, -1, 0};  // across the edge opposite node k
    a_.x = {0, 0, 0};
    const std::vector<sdk::PartView> parts = {test::part_view(a_, 0, 0.0005), test::part_view(b_, 1, 0.0005)};
    const sdk::ContactPair pair{{sdk::BodyRef::Type::Part, 0}, {sdk::BodyRef::Type::Part, 1}};
    ok_ = handler_
              ->configure(validate_params(json{{"penalty", kPenalty}, {"damping", 0.0},
                                               {"search_interval", search_interval}},
                                          "/c", r.descriptor),
                          pair, parts, {})
              .ok;
  }
  bool ok() const { return ok_; }
  // The forces on the node (3 values) and on the plate's nodes (12) with the
  // node at x, moving at v, after a step dt.
  bool step(const std::array<double, 3>& x, const std::array<double, 3>& v, double dt, std::array<double, 3>& fa,
            std::array<double, 12>& fb) {
    a_.x = {x[0], x[1], x[2]};
    const std::vector<sdk::PartView> parts = {test::part_view(a_, 0, 0.0005), test::part_view(b_, 1, 0.0005)};
    const std::vector<double> va(v.begin(), v.end()), vb(12, 0.0), area_a(1, kArea), area_b(4, kArea),
        ma(1, 1e-3), mb(4, 1e-3);
    const std::vector<std::span<const double>> vel = {va, vb}, areas = {area_a, area_b}, mass = {ma, mb};
    std::vector<double> f_a(3, 0.0), f_b(12, 0.0);
    // side 0: a's node against b's triangles
    if (!ply_contact_forces(*handler_, parts, dt, vel, areas, mass, 0, f_a, f_b).ok) return false;
    std::copy(f_a.begin(), f_a.end(), fa.begin());
    std::copy(f_b.begin(), f_b.end(), fb.begin());
    return true;
  }

 private:
  std::unique_ptr<sdk::ContactHandler> handler_;
  ShellMesh a_, b_;
  bool ok_ = false;
};

// search_interval k: from one full search to the next (every k-th call)
// each node keeps the triangle the last search found and takes the closest
// point on it. A node pressed 0.1 mm into a flat plate of two triangles
// (faces at +-h/2 of 0.5 mm plies) crosses their shared diagonal, 1 um per
// call, at the third call. Every step (k = 1) the plate's force moves to
// the other triangle's far node at that call; with k = 3 it stays on the
// diagonal's two nodes until the fourth call, the next search. There the
// node, s past the kept triangle's edge at the plane distance d, is
// sqrt(d^2 + s^2) from it (1e-9 of the penetration further at s = 0.5 um,
// d = 0.4 mm) and pushed along the line from the edge. Forces within 1e-12
// of those values; a search every step gives the exact plane forces.
TEST(PlyPlySearch, SearchIntervalKeepsTheTriangleUntilTheNextSearch) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const double s2 = std::sqrt(0.5), d = 0.0004, penalty = NodeOverPlate::kPenalty, area = NodeOverPlate::kArea;
  auto at = [&](int call) {  // 1.5 um on node 1's side of the diagonal at call 0, 1 um towards node 3 per call
    const double off = 1.5e-6 - 1e-6 * call;
    return std::array<double, 3>{0.005 + off * s2, 0.005 - off * s2, d};
  };
  std::vector<std::array<double, 3>> fa[2];    // node force, per call
  std::vector<std::array<double, 4>> fz_b[2];  // z force on b's four nodes, per call
  for (int run = 0; run < 2; ++run) {
    NodeOverPlate plate(r, run == 0 ? 1 : 3);
    ASSERT_TRUE(plate.ok());
    for (int call = 0; call < 6; ++call) {
      std::array<double, 3> f_a;
      std::array<double, 12> f_b;
      ASSERT_TRUE(plate.step(at(call), {0, 0, 0}, 1e-5, f_a, f_b));
      fa[run].push_back(f_a);
      fz_b[run].push_back({f_b[2], f_b[5], f_b[8], f_b[11]});
    }
  }
  // Half the penalty per direction; only the direction of a's node here.
  const double exact = 0.5 * penalty * area * (0.0005 - d);
  for (int call = 0; call < 6; ++call) {
    const bool beyond = at(call)[0] < 0.005;  // past the diagonal, over triangle 0-2-3
    const bool searched = call % 3 == 0;
    const double off = std::abs(1.5e-6 - 1e-6 * call);
    // Every step: the exact force, on the triangle under the node.
    EXPECT_NEAR(fa[0][call][2], exact, 1e-12 * exact) << "call " << call;
    EXPECT_EQ(fz_b[0][call][1] != 0.0, !beyond) << "call " << call;
    EXPECT_EQ(fz_b[0][call][3] != 0.0, beyond) << "call " << call;
    // Every third step: the triangle of the last search.
    const bool kept_beyond = at(call - call % 3)[0] < 0.005;
    EXPECT_EQ(fz_b[1][call][1] != 0.0, !kept_beyond && !beyond) << "call " << call;
    EXPECT_EQ(fz_b[1][call][3] != 0.0, kept_beyond && beyond) << "call " << call;
    // On the kept triangle's edge: at distance sqrt(d^2 + off^2), pushed
    // along the line from the edge, so its z share is d / distance.
    const double dist = beyond != kept_beyond ? std::sqrt(d * d + off * off) : d;
    const double expected = 0.5 * penalty * area * (0.0005 - dist) * d / dist;
    EXPECT_NEAR(fa[1][call][2], expected, 1e-12 * exact) << "call " << call;
    if (searched) {
      EXPECT_EQ(fa[1][call][2], fa[0][call][2]) << "call " << call;
    }
    double sum = 0;
    for (double f : fz_b[1][call]) sum += f;
    EXPECT_NEAR(sum, -fa[1][call][2], 1e-12 * exact) << "call " << call;  // momentum
  }
  // The crossing at the third call (index 2) is seen at the fourth with k = 3.
  EXPECT_EQ(fz_b[1][2][3], 0.0);
  EXPECT_GT(std::abs(fz_b[1][3][3]), 0.0);
  EXPECT_GT(std::abs(fz_b[0][2][3]), 0.0);
}

// A node going round the free edge of the other ply: the plate's edge x =
// 10 mm (triangle 0-1-2 has no neighbour there) acts as a rounded edge of
// radius h = 0.5 mm (the two plies' half-thicknesses). The node walks a half
// circle of radius 0.3 mm about it, from 80 degrees above the plate's plane
// to 100 degrees below it (under the plate), at y = 5 mm, at rest. Round
// the edge it is pushed away from the edge by the penalty force over h -
// 0.3 mm, the same at every angle, along the line from the edge; under the
// plate (beyond -90 degrees) away from its face, by the force over h less
// its distance from the plane: a conservative force, continuous where it
// passes from the edge to the face, so a node that goes round the edge and
// back gains no energy. Before 0.28.1 the node kept the side it
// came from: beyond the plate's plane it was pulled towards the edge with
// the force over h + 0.3 mm (a jump of 2.5 times the force, energy for free
// at every crossing). Required: the direction within 1e-9 and the
// magnitude within 1e-9 relative, at each of 37 angles, with search
// intervals 1 and 3.
TEST(PlyPlySearch, NodeGoesRoundAFreeEdge) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const double rho = 0.0003, h = 0.0005;
  const double exact = 0.5 * NodeOverPlate::kPenalty * NodeOverPlate::kArea * (h - rho);
  for (const int k : {1, 3}) {
    NodeOverPlate plate(r, k);
    ASSERT_TRUE(plate.ok());
    for (int step = 0; step <= 36; ++step) {
      const double theta = (80.0 - 5.0 * step) * std::numbers::pi / 180.0;
      const std::array<double, 3> radial = {std::cos(theta), 0.0, std::sin(theta)};
      const std::array<double, 3> x = {0.01 + rho * radial[0], 0.005, rho * radial[2]};
      std::array<double, 3> fa;
      std::array<double, 12> fb;
      ASSERT_TRUE(plate.step(x, {0, 0, 0}, 1e-5, fa, fb));
      const bool under = x[0] < 0.01;  // under the plate's face: pushed along -z
      const std::array<double, 3> expected =
          under ? std::array<double, 3>{0, 0, -0.5 * NodeOverPlate::kPenalty * NodeOverPlate::kArea * (h + x[2])}
                : std::array<double, 3>{exact * radial[0], 0, exact * radial[2]};
      for (int d = 0; d < 3; ++d)
        EXPECT_NEAR(fa[d], expected[d], 1e-9 * exact) << "k " << k << ", angle " << 80 - 5 * step << ", dof " << d;
    }
  }
}

// search_interval is a most: the next full search comes sooner where the
// plies' fastest nodes could close half the gap of a node that the last
// search found out of reach. A node 2 mm above a plate (0.5 mm plies:
// touching below 0.5 mm, out of reach beyond 1.005 mm) falls at 5 m/s,
// 50 um per step of 10 us. With k = 64 and the searches every 64th step
// only, it would be 1.2 mm below the plate at the next search and never
// pushed back; the bound takes a search every floor(0.5 x 0.505 mm / 50 um)
// = 5 steps, which finds the plate at 1.0 mm (step 20), so the node feels
// the plate from the step it touches it (31, 0.45 mm), with the forces of
// a search every step.
TEST(PlyPlySearch, SearchIntervalShortensForFastPlies) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const double speed = 5.0, dt = 1e-5;
  const int calls = 40;
  std::vector<double> fz[2];
  for (int run = 0; run < 2; ++run) {
    NodeOverPlate plate(r, run == 0 ? 1 : 64);
    ASSERT_TRUE(plate.ok());
    for (int call = 0; call < calls; ++call) {
      std::array<double, 3> f_a;
      std::array<double, 12> f_b;
      ASSERT_TRUE(plate.step({0.007, 0.002, 0.002 - speed * dt * call}, {0, 0, -speed}, dt, f_a, f_b));
      fz[run].push_back(f_a[2]);
    }
  }
  int first = -1;
  for (int call = 0; call < calls; ++call) {
    if (first < 0 && fz[0][call] != 0.0) first = call;
    EXPECT_EQ(fz[1][call], fz[0][call]) << "call " << call;
  }
  EXPECT_EQ(first, 31);  // 0.45 mm above the plate's mid-surface
  EXPECT_GT(fz[1][calls - 1], 0.0);
}

// The full searches prune the candidates that distance bounds show to be
// farther than each node's target of a recent search (prune_search, the
// default). Ply a (15 x 11 nodes, its distance to the creased, curved ply b
// varying over it and crossing b's mid-surface) and ply b both move every
// call: a drift of 6 um per call and a wave of 3 um per call across them
// (so that the bounds are formed again every few calls and the candidate
// lists are rebuilt), 300 calls of both sides of the pair. With and
// without pruning the forces on every node, the energy and the number of
// nodes in contact must be the same bits at every call: the bounds may
// skip only triangles farther than the target. (Bounds that leave out the
// motions since the reference make 156 of the 300 calls differ; leaving
// out only one motion term is not caught here, where the bound has room to
// spare: the next test catches each.)
TEST(PlyPlySearch, PrunedSearchFindsTheTargetsOfTheFullSearch) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  const ShellMesh b0 = ply_mesh({0, 0, 0}, {0.06, 0.06}, {8, 8}, true, 0.0);
  const ShellMesh a0 = ply_mesh({0.004, 0.007, 0}, {0.05, 0.05}, {14, 10}, false, 0.0009);
  ShellMesh a = a0, b = b0;
  const sdk::ContactPair pair{{sdk::BodyRef::Type::Part, 0}, {sdk::BodyRef::Type::Part, 1}};
  std::unique_ptr<sdk::ContactHandler> h[2];
  for (const int k : {0, 1}) {
    h[k].reset(reinterpret_cast<sdk::ContactHandler* (*)()>(r.create)());
    const std::vector<sdk::PartView> parts = {test::part_view(a, 0, 0.0005), test::part_view(b, 1, 0.0005)};
    ASSERT_TRUE(h[k]->configure(validate_params(json{{"penalty", 1e10}, {"friction", 0.2}, {"prune_search", k == 0}},
                                                "/c", r.descriptor),
                                pair, parts, {})
                    .ok);
  }
  const std::vector<double> area_a(a.num_nodes(), 1e-5), area_b(b.num_nodes(), 1e-5), ma(a.num_nodes(), 1e-3),
      mb(b.num_nodes(), 1e-3);
  std::vector<double> va(3 * a.num_nodes(), 0.0), vb(3 * b.num_nodes(), 0.0);
  const double dt = 1e-4;
  long long active = 0;
  int differ = 0;
  for (int call = 0; call < 300; ++call) {
    for (int i = 0; i < a.num_nodes(); ++i) {
      const double* p0 = &a0.x[3 * i];
      double* p = &a.x[3 * i];
      const double wave = 3e-6 * call * std::sin(0.05 * call + 300.0 * p0[0]);
      p[0] = p0[0] + 6e-6 * call;
      p[1] = p0[1] + wave;
      p[2] = p0[2] + 0.5 * wave;
    }
    for (int i = 0; i < b.num_nodes(); ++i) {
      const double* p0 = &b0.x[3 * i];
      double* p = &b.x[3 * i];
      p[0] = p0[0] - 2e-6 * call;
      p[2] = p0[2] + 2e-6 * call * std::cos(0.03 * call + 200.0 * p0[1]);
    }
    const std::vector<sdk::PartView> parts = {test::part_view(a, 0, 0.0005), test::part_view(b, 1, 0.0005)};
    const std::vector<std::span<const double>> vel = {va, vb}, areas = {area_a, area_b}, mass = {ma, mb};
    std::vector<double> f[2][2];
    double energy[2];
    long long act[2];
    for (const int k : {0, 1}) {
      f[k][0].assign(3 * a.num_nodes(), 0.0);
      f[k][1].assign(3 * b.num_nodes(), 0.0);
      const PlyForces out = ply_contact_forces(*h[k], parts, dt, vel, areas, mass, -1, f[k][0], f[k][1]);  // both sides
      ASSERT_TRUE(out.ok);
      energy[k] = out.energy;
      act[k] = out.active;
    }
    const bool same = f[0][0] == f[1][0] && f[0][1] == f[1][1] && energy[0] == energy[1] && act[0] == act[1];
    differ += !same;
    EXPECT_TRUE(same) << "call " << call;
    active += act[0];
  }
  std::printf("300 calls, %lld node contacts in all, %d calls differ\n", active, differ);
  EXPECT_GT(active, 300LL * a.num_nodes() / 10);  // many nodes in contact throughout
}

// The pruned search skips a candidate when its distance at the reference,
// less the motions since, exceeds the reference target's distance plus
// those motions; each motion term is needed. A node lies between the two
// layers of a folded ply (a 10 mm square of two triangles at z = 0 and the
// same square at z = H, facing it), 0.4 mm above the lower layer: its
// reference target. Then one thing moves 0.04 mm (within the 5 % of the
// 1.005 mm reach that the bounds serve) so that the upper layer becomes the
// closer one, with the upper layer's bound between the target's distance
// plus one motion term and plus all of them: the node moves up (H 0.86 mm:
// 0.44 mm to the lower, 0.42 mm to the upper), the upper layer moves down
// (H 0.83 mm: 0.39 mm against 0.40 mm), the lower layer moves down (H
// 0.83 mm: 0.43 mm against 0.44 mm). Without the node's motion, the
// candidate's or the target's, the pruned search would skip the upper
// layer and keep the lower one.
TEST(PlyPlySearch, PrunedSearchAllowsForTheMotionsOfTheNodeTheCandidateAndTheTarget) {
  PluginRegistry registry;
  const auto& r = registry.require(sdk::PluginKind::Contact, "penalty_node_surface", "/handler");
  struct Case {
    const char* what;
    double height, node_dz, upper_dz, lower_dz;
  };
  const double z0 = 0.4e-3, move = 0.04e-3;
  for (const Case& c : {Case{"the node moves up", 0.86e-3, move, 0, 0},
                        Case{"the upper layer moves down", 0.83e-3, 0, -move, 0},
                        Case{"the lower layer moves down", 0.83e-3, 0, 0, -move}}) {
    SCOPED_TRACE(c.what);
    ShellMesh a, b;
    const double s = 0.01, h = c.height;
    b.x = {0, 0, 0, s, 0, 0, s, s, 0, 0, s, 0, 0, 0, h, s, 0, h, s, s, h, 0, s, h};
    b.triangles = {0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6};  // the upper layer faces down
    b.neighbours = {-1, 1, -1, -1, -1, 0, -1, -1, 3, -1, 2, -1};  // across the edge opposite node k
    a.x = {0.003, 0.007, z0};
    std::unique_ptr<sdk::ContactHandler> hd[2];
    const sdk::ContactPair pair{{sdk::BodyRef::Type::Part, 0}, {sdk::BodyRef::Type::Part, 1}};
    for (const int k : {0, 1}) {
      hd[k].reset(reinterpret_cast<sdk::ContactHandler* (*)()>(r.create)());
      const std::vector<sdk::PartView> parts = {test::part_view(a, 0, 0.0005), test::part_view(b, 1, 0.0005)};
      ASSERT_TRUE(hd[k]->configure(validate_params(json{{"penalty", 1e10}, {"damping", 0.0}, {"prune_search", k == 0}},
                                                   "/c", r.descriptor),
                                   pair, parts, {})
                      .ok);
    }
    const std::vector<double> va(3, 0.0), vb(24, 0.0), area_a(1, 1e-5), area_b(8, 1e-5), ma(1, 1e-3), mb(8, 1e-3);
    const std::vector<std::span<const double>> vel = {va, vb}, areas = {area_a, area_b}, mass = {ma, mb};
    for (int call = 0; call < 2; ++call) {
      if (call == 1) {  // the motion
        a.x[2] += c.node_dz;
        for (int n = 0; n < 4; ++n) b.x[3 * n + 2] += c.lower_dz;
        for (int n = 4; n < 8; ++n) b.x[3 * n + 2] += c.upper_dz;
      }
      const std::vector<sdk::PartView> parts = {test::part_view(a, 0, 0.0005), test::part_view(b, 1, 0.0005)};
      std::vector<double> fa[2], fb[2];
      for (const int k : {0, 1}) {
        fa[k].assign(3, 0.0);
        fb[k].assign(24, 0.0);
        ASSERT_TRUE(ply_contact_forces(*hd[k], parts, 1e-6, vel, areas, mass, 0, fa[k], fb[k]).ok);  // the node's side
      }
      EXPECT_EQ(fa[0], fa[1]) << "call " << call;
      EXPECT_EQ(fb[0], fb[1]) << "call " << call;
      // The node's target: the lower layer at the reference, the upper one after the motion.
      double lower = 0, upper = 0;
      for (int n = 0; n < 4; ++n) lower += std::abs(fb[1][3 * n + 2]);
      for (int n = 4; n < 8; ++n) upper += std::abs(fb[1][3 * n + 2]);
      EXPECT_GT(call == 0 ? lower : upper, 0.0) << "call " << call;
      EXPECT_EQ(call == 0 ? upper : lower, 0.0) << "call " << call;
    }
  }
}

}  // namespace
}  // namespace ts
