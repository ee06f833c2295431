#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>
#include <set>

#include <thermostamp/sdk/math.hpp>

#include "mesh/shell_mesh.hpp"
#include "test_support.hpp"

namespace ts {
namespace {

void expect_valid(const ShellMesh& m) {
  // Neighbours are mutual and every triangle's normal points to +z.
  for (int e = 0; e < m.num_elements(); ++e) {
    const int* t = &m.triangles[3 * e];
    const auto a = sdk::load3(m.x.data(), t[0]), b = sdk::load3(m.x.data(), t[1]), c = sdk::load3(m.x.data(), t[2]);
    EXPECT_GT(sdk::cross(sdk::sub(b, a), sdk::sub(c, a))[2], 0.0);
    for (int k = 0; k < 3; ++k) {
      const int f = m.neighbours[3 * e + k];
      if (f < 0) continue;
      int back = 0;
      for (int q = 0; q < 3; ++q) back += m.neighbours[3 * f + q] == e;
      EXPECT_EQ(back, 1);
    }
  }
}

// A 0.3 x 0.2 rectangle of 6 x 4 cells: counts, total area, orientation,
// mutual neighbours and the 20 boundary edges.
void expect_rectangle(const ShellMesh& m, int nodes, int elements) {
  EXPECT_EQ(m.num_nodes(), nodes);
  EXPECT_EQ(m.num_elements(), elements);
  const auto a = node_areas(m);
  EXPECT_NEAR(std::accumulate(a.begin(), a.end(), 0.0), 0.06, 1e-15);
  expect_valid(m);
  int boundary_edges = 0;
  for (int n : m.neighbours) boundary_edges += n < 0;
  EXPECT_EQ(boundary_edges, 2 * (6 + 4));
}

TEST(Rectangle, AreaNeighboursOrientation) {
  expect_rectangle(rectangle_mesh({0, 0, 0.001}, {0.3, 0.2}, {6, 4}), 35, 48);
}

// The crossed pattern: four triangles per cell around a centre node, edges
// along x, y and both diagonals.
TEST(Rectangle, CrossedPattern) {
  const ShellMesh m = rectangle_mesh({0, 0, 0.001}, {0.3, 0.2}, {6, 4}, true);
  expect_rectangle(m, 35 + 24, 96);
  // Every triangle has its two inner edges along the diagonals of its cell.
  for (int e = 0; e < m.num_elements(); ++e) {
    const int c = m.triangles[3 * e + 2];  // the centre node
    EXPECT_GE(c, 35);
    for (int k = 0; k < 2; ++k) {
      const int v = m.triangles[3 * e + k];
      const double dx = m.x[3 * v] - m.x[3 * c], dy = m.x[3 * v + 1] - m.x[3 * c + 1];
      EXPECT_NEAR(std::abs(dx), 0.025, 1e-15);
      EXPECT_NEAR(std::abs(dy), 0.025, 1e-15);
    }
  }
}

// The thickness at constant volume under affine maps of a ply: a
// triangle's area scales by the determinant of the map's in-plane part, so
// every triangle of a mesh with irregular nodes has h0 / det, for stretches
// along and across, in-plane shear and rigid rotations (180 degrees
// included) carried out in 3D. Round-off only: 1e-13 relative.
TEST(Thickness, ConstantVolumeUnderAffineMaps) {
  ShellMesh m = rectangle_mesh({0.01, -0.02, 0.003}, {0.12, 0.08}, {7, 5});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jiggle(-0.004, 0.004);
  for (std::size_t i = 0; i < m.x.size(); i += 3) {  // irregular triangles, still in the plane z = 0.003
    m.x[i] += jiggle(rng);
    m.x[i + 1] += jiggle(rng);
  }
  const std::vector<double> area0 = element_areas(m);
  const double h0 = 4.5e-4;
  std::vector<double> h(m.num_elements());
  constant_volume_thickness(m, area0, m.x.data(), h0, h.data());
  for (const double v : h) EXPECT_EQ(v, h0);
  // Rotation about the unit axis u by angle a (Rodrigues).
  auto rotation = [](sdk::Vec3 u, double a) {
    const double c = std::cos(a), s = std::sin(a);
    std::array<std::array<double, 3>, 3> R{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R[i][j] = (i == j ? c : 0.0) + (1 - c) * u[i] * u[j];
    R[0][1] -= s * u[2];
    R[0][2] += s * u[1];
    R[1][0] += s * u[2];
    R[1][2] -= s * u[0];
    R[2][0] -= s * u[1];
    R[2][1] += s * u[0];
    return R;
  };
  struct Case {
    double fxx, fxy, fyx, fyy;  // the in-plane map
    sdk::Vec3 axis;
    double angle;
  };
  const sdk::Vec3 tilted = sdk::normalized({0.3, -0.5, 0.8});
  for (const Case& c : {Case{1.2, 0, 0, 1, {0, 0, 1}, 0}, Case{1, 0, 0, 0.7, {0, 0, 1}, 0},
                        Case{1, 0.4, 0, 1, {0, 0, 1}, 0},                          // simple shear: area kept
                        Case{1, std::sin(0.5), 0, std::cos(0.5), {0, 0, 1}, 0},  // trellis: both families keep length
                        Case{1.1, 0.2, -0.3, 0.9, tilted, 2.1}, Case{1, 0, 0, 1, {1, 0, 0}, M_PI},
                        Case{0.8, -0.1, 0.25, 1.3, {0, 1, 0}, M_PI}, Case{1, 0, 0, 1, tilted, 0.5 * M_PI}}) {
    const auto R = rotation(c.axis, c.angle);
    std::vector<double> x(m.x.size());
    for (std::size_t i = 0; i < m.x.size(); i += 3) {
      const double p[3] = {c.fxx * m.x[i] + c.fxy * m.x[i + 1], c.fyx * m.x[i] + c.fyy * m.x[i + 1], m.x[i + 2]};
      for (int d = 0; d < 3; ++d) x[i + d] = R[d][0] * p[0] + R[d][1] * p[1] + R[d][2] * p[2] + 0.05 * (d + 1);
    }
    constant_volume_thickness(m, area0, x.data(), h0, h.data());
    const double want = h0 / (c.fxx * c.fyy - c.fxy * c.fyx);
    for (int e = 0; e < m.num_elements(); ++e)
      ASSERT_NEAR(h[e], want, 1e-13 * want) << "map " << c.fxx << " " << c.fxy << " " << c.fyx << " " << c.fyy
                                            << ", rotation " << c.angle << ", element " << e;
  }
  // A triangle collapsed (a corner on another) has no thickness to give.
  std::vector<double> x = m.x;
  const int* t = &m.triangles[0];
  for (int d = 0; d < 3; ++d) x[3 * t[2] + d] = x[3 * t[0] + d];
  constant_volume_thickness(m, area0, x.data(), h0, h.data());
  EXPECT_TRUE(std::isnan(h[0]));
}

TEST(Gmsh, ReadsVersions22And41Alike) {
  const auto dir = test::temp_dir("gmsh");
  {
    std::ofstream f(dir / "a.msh");
    f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n9 0.5 0.5 0\n$EndNodes\n"
         "$Elements\n6\n1 15 2 0 1 1\n2 1 2 0 1 1 2\n3 2 2 0 1 1 2 9\n4 2 2 0 1 2 3 9\n5 2 2 0 1 3 4 9\n6 2 2 0 1 9 1 4\n"
         "$EndElements\n";
  }
  {
    // Same mesh in 4.1, with one triangle given clockwise (reoriented on read).
    std::ofstream f(dir / "b.msh");
    f << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n2 5 1 9\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
         "2 1 0 1\n9\n0.5 0.5 0\n$EndNodes\n$Elements\n2 5 1 5\n1 1 1 1\n1 1 2\n2 1 2 4\n2 1 2 9\n3 2 3 9\n4 3 4 9\n5 9 4 1\n"
         "$EndElements\n";
  }
  const ShellMesh a = read_gmsh(dir / "a.msh");
  const ShellMesh b = read_gmsh(dir / "b.msh");
  EXPECT_EQ(a.num_nodes(), 5);
  EXPECT_EQ(a.num_elements(), 4);
  EXPECT_EQ(b.num_elements(), 4);
  expect_valid(a);
  expect_valid(b);
  const auto aa = node_areas(a), ab = node_areas(b);
  EXPECT_NEAR(std::accumulate(aa.begin(), aa.end(), 0.0), 1.0, 1e-14);
  EXPECT_NEAR(std::accumulate(ab.begin(), ab.end(), 0.0), 1.0, 1e-14);
  // Both keep the files' tags of the triangles and of the nodes they use
  // (the point element and the line are left out), in either order.
  for (const bool reorder : {false, true}) {
    const ShellMesh ra = read_gmsh(dir / "a.msh", reorder), rb = read_gmsh(dir / "b.msh", reorder);
    using Tags = std::set<long long>;
    EXPECT_EQ(Tags(ra.element_tags.begin(), ra.element_tags.end()), (Tags{3, 4, 5, 6})) << reorder;
    EXPECT_EQ(Tags(rb.element_tags.begin(), rb.element_tags.end()), (Tags{2, 3, 4, 5})) << reorder;
    EXPECT_EQ(Tags(ra.node_tags.begin(), ra.node_tags.end()), (Tags{1, 2, 3, 4, 9})) << reorder;
    EXPECT_EQ(Tags(rb.node_tags.begin(), rb.node_tags.end()), (Tags{1, 2, 3, 4, 9})) << reorder;
    for (const ShellMesh* m : {&ra, &rb})  // the centre node, tag 9, at (0.5, 0.5)
      for (int i = 0; i < m->num_nodes(); ++i)
        if (m->node_tags[i] == 9) {
          EXPECT_EQ(m->x[3 * i] + m->x[3 * i + 1], 1.0);
        }
  }
}

// The largest distance in index between the two nodes of an edge (beside
// element_bandwidth, between neighbouring elements): how far apart in
// memory the element loops reach.
int node_bandwidth(const ShellMesh& m) {
  int w = 0;
  for (int e = 0; e < m.num_elements(); ++e)
    for (int k = 0; k < 3; ++k) w = std::max(w, std::abs(m.triangles[3 * e + k] - m.triangles[3 * e + (k + 1) % 3]));
  return w;
}

// A 40 x 30 rectangle's 2400 triangles written in a shuffled order, as mesh
// generators leave them, and read back. Without `reorder`: the file's order
// (neighbours up to the whole mesh apart). With it: every triangle keeps its
// tag's corners (by their node tags) and orientation, neighbours stay
// mutual, and neighbouring elements and the nodes of an edge lie within a
// few rows of cells of each other: at most twice as far apart as in the
// rectangle generator's row order, whose neighbours are up to a row of 2 x
// 40 triangles apart (bound 160, against about 2400 in the shuffled file).
TEST(Gmsh, ReorderBringsNeighboursTogether) {
  const auto dir = test::temp_dir("gmsh_reorder");
  const ShellMesh rect = rectangle_mesh({0, 0, 0}, {0.4, 0.3}, {40, 30});
  test::write_shuffled_gmsh(dir / "shuffled.msh", rect, 7);
  const ShellMesh as_is = read_gmsh(dir / "shuffled.msh");
  const ShellMesh sorted = read_gmsh(dir / "shuffled.msh", true);
  const int ne = rect.num_elements();
  for (const ShellMesh* m : {&as_is, &sorted}) {
    ASSERT_EQ(m->num_elements(), ne);
    ASSERT_EQ(m->num_nodes(), rect.num_nodes());
    ASSERT_EQ(m->element_tags.size(), static_cast<std::size_t>(ne));
    ASSERT_EQ(m->node_tags.size(), static_cast<std::size_t>(rect.num_nodes()));
    expect_valid(*m);
    std::vector<int> seen(ne, 0);
    for (int e = 0; e < ne; ++e) {
      const long long orig = m->element_tags[e] - test::shuffled_element_tag(0);
      ASSERT_TRUE(orig >= 0 && orig < ne) << e;
      ++seen[orig];
      // The same corners in the same turning order (the rectangle's are +z).
      std::array<long long, 3> got, want;
      for (int k = 0; k < 3; ++k) {
        got[k] = m->node_tags[m->triangles[3 * e + k]];
        want[k] = test::shuffled_node_tag(rect.triangles[3 * orig + k]);
      }
      std::rotate(got.begin(), std::min_element(got.begin(), got.end()), got.end());
      std::rotate(want.begin(), std::min_element(want.begin(), want.end()), want.end());
      EXPECT_EQ(got, want) << e;
      for (int k = 0; k < 3; ++k)  // each node at its tag's position
        for (int d = 0; d < 3; ++d)
          EXPECT_EQ(m->x[3 * m->triangles[3 * e + k] + d],
                    rect.x[3 * ((m->node_tags[m->triangles[3 * e + k]] - 7) / 3) + d]);
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), ne);
  }
  // Without reorder the file's order.
  std::vector<long long> file_order(ne);
  {
    std::vector<int> order(ne);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937(7));
    for (int e = 0; e < ne; ++e) file_order[e] = test::shuffled_element_tag(order[e]);
  }
  EXPECT_EQ(as_is.element_tags, file_order);
  const int bound = 2 * (2 * 40);
  std::printf("element / node bandwidth: rectangle generator %d / %d, shuffled file %d / %d, reordered %d / %d\n",
              element_bandwidth(rect), node_bandwidth(rect), element_bandwidth(as_is), node_bandwidth(as_is),
              element_bandwidth(sorted), node_bandwidth(sorted));
  EXPECT_GT(element_bandwidth(as_is), ne / 2);
  EXPECT_LE(element_bandwidth(sorted), bound);
  EXPECT_LE(node_bandwidth(sorted), bound);
  // The same order every time.
  const ShellMesh again = read_gmsh(dir / "shuffled.msh", true);
  EXPECT_EQ(again.triangles, sorted.triangles);
  EXPECT_EQ(again.element_tags, sorted.element_tags);
  EXPECT_EQ(again.node_tags, sorted.node_tags);
}

// Two pieces apart: each takes a contiguous range of the order, and every
// element is placed once.
TEST(Gmsh, ReorderTakesEachPieceInTurn) {
  const auto dir = test::temp_dir("gmsh_reorder_pieces");
  ShellMesh two = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {5, 5});
  const ShellMesh b = rectangle_mesh({1, 0, 0}, {0.1, 0.1}, {4, 6});
  const int n0 = two.num_nodes(), e0 = two.num_elements();
  two.x.insert(two.x.end(), b.x.begin(), b.x.end());
  for (const int t : b.triangles) two.triangles.push_back(t + n0);
  test::write_shuffled_gmsh(dir / "two.msh", two, 3);
  const ShellMesh m = read_gmsh(dir / "two.msh", true);
  ASSERT_EQ(m.num_elements(), two.num_elements());
  expect_valid(m);
  int changes = 0;
  for (int e = 1; e < m.num_elements(); ++e)
    changes += (m.element_tags[e] - 100 < e0) != (m.element_tags[e - 1] - 100 < e0);
  EXPECT_EQ(changes, 1);
}

// Surface elements other than 3-node triangles are refused, with their
// counts by type (a mixed mesh would otherwise lose them and leave holes);
// points and lines (borders, corners) are left out as before.
TEST(Gmsh, ElementsOtherThanTrianglesAreRefused) {
  const auto dir = test::temp_dir("gmsh_quads");
  // 2.2: a triangle, two quadrangles, a line and a point.
  std::ofstream(dir / "mixed.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 1 1 0\n"
                                      "4 0 1 0\n5 2 0 0\n6 2 1 0\n$EndNodes\n$Elements\n5\n1 15 2 0 1 1\n2 1 2 0 1 1 2\n"
                                      "3 2 2 0 1 1 2 4\n4 3 2 0 1 2 5 6 3\n5 3 2 0 1 4 2 3 4\n$EndElements\n";
  // 4.1: a block of two 6-node triangles.
  std::ofstream(dir / "second.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 6 1 6\n2 1 0 6\n1\n2\n3\n4\n5\n6\n"
                                       "0 0 0\n1 0 0\n0 1 0\n0.5 0 0\n0.5 0.5 0\n0 0.5 0\n$EndNodes\n$Elements\n1 2 1 2\n"
                                       "2 1 9 2\n1 1 2 3 4 5 6\n2 1 2 3 4 5 6\n$EndElements\n";
  const std::pair<const char*, const char*> cases[] = {
      {"mixed.msh", ": 2 4-node quadrangles (element type 3): only 3-node triangles are taken"},
      {"second.msh", ": 2 6-node triangles (element type 9): only 3-node triangles are taken"}};
  for (const auto& [name, text] : cases) {
    try {
      read_gmsh(dir / name);
      ADD_FAILURE() << name << " was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(name) + text), std::string::npos) << e.what();
    }
  }
}

TEST(Gmsh, MalformedFileNamesTheLine) {
  const auto dir = test::temp_dir("gmsh_bad");
  std::ofstream(dir / "c.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0\n";
  try {
    read_gmsh(dir / "c.msh");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("c.msh:6"), std::string::npos) << e.what();
  }
}

// Writes each case's text to dir/bad<k><ext> (k from 1) and expects
// read_mesh to refuse it with a message holding the case's message.
void expect_refused(const std::filesystem::path& dir, const std::vector<std::pair<std::string, std::string>>& cases,
                    const std::string& ext) {
  int k = 0;
  for (const auto& [text, message] : cases) {
    const std::string name = "bad" + std::to_string(++k) + ext;
    std::ofstream(dir / name) << text;
    try {
      read_mesh(dir / name);
      ADD_FAILURE() << name << " was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// An Abaqus input file as Abaqus/CAE writes one (a part, sets, an
// assembly with a reference point outside the part, a material; node
// lists continued on a second line) gives the mesh the same nodes and
// triangles give as a Gmsh file: the same coordinates, corners, tags and
// neighbours, bit for bit, in the file's order and reordered, and scaled.
TEST(Abaqus, ReadsTheMeshGmshReads) {
  const auto dir = test::temp_dir("abaqus");
  const ShellMesh m = rectangle_mesh({0.01, -0.02, 0.003}, {0.12, 0.08}, {9, 6}, true);
  test::write_shuffled_gmsh(dir / "ply.msh", m, 5);
  test::write_shuffled_abaqus(dir / "ply.inp", m, 5);
  test::write_shuffled_abaqus(dir / "PLY_M3D3.INP", m, 5, "M3D3");
  EXPECT_TRUE(is_abaqus_file(dir / "PLY_M3D3.INP"));
  EXPECT_FALSE(is_abaqus_file(dir / "ply.msh"));
  for (const bool reorder : {false, true})
    for (const double scale : {1.0, 0.001}) {
      const ShellMesh g = read_mesh(dir / "ply.msh", reorder, scale);
      for (const char* name : {"ply.inp", "PLY_M3D3.INP"}) {
        const ShellMesh a = read_mesh(dir / name, reorder, scale);
        EXPECT_EQ(a.num_elements(), m.num_elements()) << name;
        EXPECT_EQ(a.x, g.x) << name << reorder << scale;
        EXPECT_EQ(a.triangles, g.triangles) << name << reorder << scale;
        EXPECT_EQ(a.neighbours, g.neighbours) << name << reorder << scale;
        EXPECT_EQ(a.node_tags, g.node_tags) << name << reorder << scale;
        EXPECT_EQ(a.element_tags, g.element_tags) << name << reorder << scale;
      }
    }
  // The reference point (node 1 of the assembly) is not one of the mesh's.
  const ShellMesh t = read_mesh_triangles(dir / "ply.inp");
  EXPECT_EQ(t.num_nodes(), m.num_nodes());
  EXPECT_LT(box_span(t.x), 0.2);
}

// What the reader cannot take is refused with the file, and the line where
// there is one: quadrilaterals and second-order elements (counted by type),
// triangles in two parts, an instance placed by a translation, included
// files, other coordinate systems, a node given twice, an unknown node, a
// malformed number, no triangles, generated elements.
TEST(Abaqus, RefusesWhatItCannotRead) {
  const auto dir = test::temp_dir("abaqus_bad");
  const std::string nodes = "*Node\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {nodes + "*Element, type=S3\n1, 1, 2, 3\n*Element, type=S4R\n2, 1, 2, 3, 4\n3, 1, 2, 3, 4\n"
               "*Element, type=STRI65\n4, 1, 2, 3, 1, 2, 3\n*Element, type=B31\n5, 1, 2\n",
       "bad1.inp: 2 S4R, 1 STRI65 elements: only 3-node triangles are taken"},
      {"*Part, name=A\n" + nodes + "*Element, type=S3\n1, 1, 2, 3\n*End Part\n*Part, name=B\n" + nodes +
           "*Element, type=R3D3\n1, 1, 3, 4\n*End Part\n",
       "bad2.inp: triangles in 2 parts (A, B): give each ply and each tool a file of its own"},
      {"*Part, name=A\n" + nodes + "*Element, type=S3\n1, 1, 2, 3\n*End Part\n*Assembly, name=X\n"
           "*Instance, name=A-1, part=A\n0.1, 0., 0.\n*End Instance\n",
       "bad3.inp:12: an *INSTANCE placed by a translation or rotation"},
      {"*INCLUDE, INPUT=mesh.inp\n", "bad4.inp:1: *INCLUDE: included files are not read"},
      {"*Node, system=C\n1, 1, 0, 0\n", "bad5.inp:1: *NODE with SYSTEM=C: only rectangular coordinates"},
      {nodes + "2, 5, 5, 5\n", "bad6.inp:6: node 2 given twice"},
      {nodes + "*Element, type=S3\n1, 1, 2, 3\n2, 1, 3,\n 9\n", "bad7.inp:8: element 2 refers to unknown node 9"},
      {"*Node\n1, 0, zero, 0\n", "bad8.inp:2: expected y, found 'zero'"},
      {nodes + "*Element, type=S3\n1, 1, 2\n", "bad9.inp:7: element 1 of type S3 has 2 nodes, expected 3"},
      {nodes, "bad10.inp: no 3-node triangles"},
      {nodes + "*Element, type=S3\n1, 1, 2, 3\n*ELGEN, elset=ALL\n1, 10, 1, 1\n",
       "bad11.inp:8: *ELGEN: generated nodes and elements are not read"}};
  expect_refused(dir, cases, ".inp");
}

// An LS-DYNA keyword file in each of its column styles, and free format,
// also with the shells as *ELEMENT_SHELL_THICKNESS, _BETA_OFFSET, _MCID and
// _THICKNESS_OFFSET (their extra cards skipped, a comment card among them),
// gives the mesh of the same nodes and triangles in a Gmsh file: the same
// corners, tags and neighbours, in the file's order and reordered, the
// positions to the digits each style holds (10 in the standard 16-column
// reals, 14 in 20 columns, all 17 comma-separated).
TEST(LsDyna, ReadsTheMeshGmshReads) {
  const auto dir = test::temp_dir("lsdyna");
  const ShellMesh m = rectangle_mesh({0.01, -0.02, 0.003}, {0.12, 0.08}, {9, 6}, true);
  test::write_shuffled_gmsh(dir / "ply.msh", m, 5);
  // The styles, and options of *ELEMENT_SHELL whose cards carry no mesh.
  const std::vector<std::pair<std::string, std::string>> files = {
      {"standard", ""},          {"long", ""},         {"i10", ""},           {"free", ""},
      {"standard", "THICKNESS"}, {"long", "BETA_OFFSET"}, {"i10", "MCID"}, {"free", "THICKNESS_OFFSET"}};
  for (const auto& [style, option] : files)
    test::write_shuffled_lsdyna(dir / ("ply_" + style + option + ".k"), m, 5, style, option);
  EXPECT_TRUE(is_lsdyna_file(dir / "A.KEY"));
  EXPECT_TRUE(is_lsdyna_file(dir / "a.dyn"));
  EXPECT_FALSE(is_lsdyna_file(dir / "a.inp"));
  for (const bool reorder : {false, true}) {
    const ShellMesh g = read_mesh(dir / "ply.msh", reorder);
    for (const auto& [style, option] : files) {
      const ShellMesh k = read_mesh(dir / ("ply_" + style + option + ".k"), reorder);
      EXPECT_EQ(k.triangles, g.triangles) << style << reorder;
      EXPECT_EQ(k.neighbours, g.neighbours) << style << reorder;
      EXPECT_EQ(k.node_tags, g.node_tags) << style << reorder;
      EXPECT_EQ(k.element_tags, g.element_tags) << style << reorder;
      ASSERT_EQ(k.x.size(), g.x.size());
      const double tol = style == "free" ? 0.0 : style == "long" ? 1e-13 : 1e-9;
      for (std::size_t i = 0; i < g.x.size(); ++i)
        EXPECT_NEAR(k.x[i], g.x[i], tol * 0.13) << style << " " << i;
    }
  }
  const ShellMesh mm = read_mesh(dir / "ply_free.k", false, 0.001), metres = read_mesh(dir / "ply_free.k");
  for (std::size_t i = 0; i < mm.x.size(); ++i) EXPECT_EQ(mm.x[i], metres.x[i] * 0.001);
}

// What the LS-DYNA reader refuses, with the file and the line where there
// is one.
TEST(LsDyna, RefusesWhatItCannotRead) {
  const auto dir = test::temp_dir("lsdyna_bad");
  const std::string nodes = "*NODE\n1,0,0,0\n2,1,0,0\n3,1,1,0\n4,0,1,0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {nodes + "*ELEMENT_SHELL\n1,1,1,2,3,3\n2,1,1,2,3,4\n3,1,1,2,3,4\n*ELEMENT_SOLID\n4,1,1,2,3,4,1,2,3,4\n",
       "bad1.k: 2 4-node shells (*ELEMENT_SHELL with N4 other than N3), 1 cards of *ELEMENT_SOLID: only 3-node "
       "shells are taken"},
      {nodes + "*ELEMENT_SHELL\n1,1,1,2,3,3\n2,2,1,3,4,4\n", "bad2.k: shells of 2 parts (PID 1, 2)"},
      {"*INCLUDE\nmesh.k\n", "bad3.k:1: *INCLUDE: included files are not read"},
      {nodes + "3,5,5,5\n", "bad4.k:6: node 3 given twice"},
      {nodes + "*ELEMENT_SHELL\n1,1,1,2,3,3\n2,1,1,3,9,9\n", "bad5.k:8: element 2 refers to unknown node 9"},
      {"*NODE\n       1            zero             0.0             0.0\n", "bad6.k:2: expected x, found 'zero'"},
      {nodes + "*ELEMENT_SHELL\n1,1,1,2\n", "bad7.k:7: element 1 has fewer than 3 nodes"},
      {nodes, "bad8.k: no 3-node shells"},
      {nodes + "*ELEMENT_SHELL_THICKNESS\n1,1,1,2,3,3\n0.5,0.5,0.5,0.5\n2,1,1,3,4,4\n*END\n",
       "bad9.k:10: *ELEMENT_SHELL_THICKNESS: the last element has 1 of its 2 cards"},
      {nodes + "*ELEMENT_SHELL_BETA_OFFSET\n1,1,1,2,3,3\n,,,,30\n",
       "bad10.k:8: *ELEMENT_SHELL_BETA_OFFSET: the last element has 2 of its 3 cards"},
      {nodes + "*ELEMENT_SHELL\n1,1,1,2,3,3\n*ELEMENT_SHELL_COMPOSITE\n2,1,1,3,4,4\n1,0.5,0\n",
       "bad11.k: 2 cards of *ELEMENT_SHELL_COMPOSITE: only 3-node shells are taken"}};
  expect_refused(dir, cases, ".k");
}

}  // namespace
}  // namespace ts
