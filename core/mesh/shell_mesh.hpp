#pragma once
// Triangulated mid-surface of a ply. Storage order as in sdk/math.hpp.
#include <array>
#include <filesystem>
#include <vector>

namespace ts {

struct ShellMesh {
  std::vector<double> x;          // 3 per node
  std::vector<int> triangles;     // 3 per element, counter-clockwise seen from the top face
  std::vector<int> neighbours;    // 3 per element, across the edge opposite node k, -1 if none

  int num_nodes() const { return static_cast<int>(x.size() / 3); }
  int num_elements() const { return static_cast<int>(triangles.size() / 3); }
};

// Rectangle [ox, ox+sx] x [oy, oy+sy] at height oz, nx x ny cells, two
// triangles per cell with alternating diagonals (no preferred direction).
ShellMesh rectangle_mesh(const std::array<double, 3>& origin, const std::array<double, 2>& size,
                         const std::array<int, 2>& divisions, bool crossed = false);

// Gmsh ASCII 2.2 or 4.1, triangles only (other elements are ignored).
// Throws std::runtime_error with the line number on malformed files.
ShellMesh read_gmsh(const std::filesystem::path& file);

// Orients all triangles consistently (normal of the first one kept, or +z
// for a mostly flat mesh) and fills the neighbour table. Throws if an edge
// is shared by more than two triangles.
void finalize_mesh(ShellMesh& mesh);

// Area of each triangle, m^2.
std::vector<double> element_areas(const ShellMesh& mesh);
// Lumped (one third of each adjacent triangle) area per node, m^2.
std::vector<double> node_areas(const ShellMesh& mesh);

double min_edge_length(const ShellMesh& mesh);
double max_edge_length(const ShellMesh& mesh);

}  // namespace ts
