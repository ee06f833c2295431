#include <gtest/gtest.h>

#include <fstream>
#include <numeric>

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

}  // namespace
}  // namespace ts
