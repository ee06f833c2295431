#pragma once
// Triangulated mid-surface of a ply. Storage order as in sdk/math.hpp.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace ts {

struct ShellMesh {
  std::vector<double> x;          // 3 per node
  std::vector<int> triangles;     // 3 per element, counter-clockwise seen from the top face
  std::vector<int> neighbours;    // 3 per element, across the edge opposite node k, -1 if none
  std::vector<long long> node_tags;     // read from a file: each node's tag there; else empty
  std::vector<long long> element_tags;  // read from a file: each triangle's element tag there; else empty

  int num_nodes() const { return static_cast<int>(x.size() / 3); }
  int num_elements() const { return static_cast<int>(triangles.size() / 3); }
};

// Rectangle [ox, ox+sx] x [oy, oy+sy] at height oz, nx x ny cells, two
// triangles per cell with alternating diagonals (no preferred direction).
ShellMesh rectangle_mesh(const std::array<double, 3>& origin, const std::array<double, 2>& size,
                         const std::array<int, 2>& divisions, bool crossed = false);

// A ply's or a tool's mesh file by its extension: Abaqus input (.inp, see
// read_abaqus_triangles), LS-DYNA keyword input (.k, .key, .dyn, see
// read_lsdyna_triangles) or Gmsh (any other), read as read_gmsh() reads
// Gmsh files.
ShellMesh read_mesh(const std::filesystem::path& file, bool reorder = false, double scale = 1.0);
ShellMesh read_mesh_triangles(const std::filesystem::path& file, double scale = 1.0);
bool is_abaqus_file(const std::filesystem::path& file);
// Abaqus input file (.inp): the 3-node triangles of one part (or of a file
// without *PART; nodes elsewhere, such as an assembly's reference points,
// are left out) and that part's nodes, in rectangular coordinates (z 0
// where left out), elements of 3-node triangle types (S3, S3R, S3RS, STRI3, DS3,
// M3D3, R3D3, SFM3D3, CPS3, CPE3, CAX3), node lists continued on the next
// line after a trailing comma; keywords and parameters in any case,
// comment lines (**) and the data of other keywords (sets, materials,
// steps) skipped. 2-node line elements are left out; any other element
// type (quadrilaterals, second-order elements, solids) is refused with its
// counts, as are triangles in more than one part, an *INSTANCE placed by a
// translation or rotation, *INCLUDE, INPUT= and generated nodes or
// elements (*NGEN, *ELGEN, ...) (std::runtime_error naming
// the file and line). Tags: the node and element numbers.
ShellMesh read_abaqus_triangles(const std::filesystem::path& file, double scale = 1.0);
// LS-DYNA keyword input (.k, .key, .dyn): *NODE and *ELEMENT_SHELL cards
// in the standard columns (integers 8 characters wide, reals 16), in
// 20-character columns (*KEYWORD LONG=Y, or a keyword ending in +), in
// those of a keyword ending in % (integers 10, reals 16) or
// comma-separated;
// triangles are shells whose N4 equals N3 or is blank; comment cards ($)
// and other keywords' cards skipped, reading ends at *END. 4-node shells
// and other element keywords are refused with their counts, as are shells
// of more than one part (PID) and *INCLUDE. Tags: NID and EID.
ShellMesh read_lsdyna_triangles(const std::filesystem::path& file, double scale = 1.0);
bool is_lsdyna_file(const std::filesystem::path& file);

// Gmsh ASCII 2.2 or 4.1: 3-node triangles; points and lines are left out,
// any other element is refused (std::runtime_error naming their counts).
// The coordinates are taken times `scale`.
// The nodes that the triangles use are numbered in the order in which the
// triangles first use them (others are dropped); with `reorder`, the
// triangles in locality_order and their nodes then numbered again so. Throws std::runtime_error with the line number
// on malformed files.
ShellMesh read_gmsh(const std::filesystem::path& file, bool reorder = false, double scale = 1.0);
// The file's nodes and triangles (with their tags) as read_gmsh() takes
// them, before it checks and orders them: nodes no triangle uses kept, no
// neighbours, triangles of zero area kept (a meshed tool leaves those out).
ShellMesh read_gmsh_triangles(const std::filesystem::path& file, double scale = 1.0);

// The largest side of the box around points (3 coordinates each); 0 for none.
double box_span(const std::vector<double>& xyz);

// Orients all triangles consistently (normal of the first one kept, or +z
// for a mostly flat mesh) and fills the neighbour table. Throws if an edge
// is shared by more than two triangles.
void finalize_mesh(ShellMesh& mesh);

// An order of the elements in which neighbours are close: reverse
// Cuthill-McKee on the elements' edge adjacency (each component from a
// pseudo-peripheral element, neighbours by increasing degree, ties by
// index). Depends on the connectivity alone, not on the positions.
std::vector<int> locality_order(const ShellMesh& mesh);
// Puts element order[i] at place i (triangles, neighbours, element tags);
// the nodes keep their numbers.
void reorder_elements(ShellMesh& mesh, const std::vector<int>& order);

// The largest difference in index between neighbouring elements.
int element_bandwidth(const ShellMesh& mesh);

// Tags as results.h5 and `thermostamp export` give them: those of the mesh
// file, else the number from 1.
long long node_tag(const ShellMesh& mesh, int n);
long long element_tag(const ShellMesh& mesh, int e);
// "element 12", or "element 12 (element 4711 of the mesh file)" for a mesh
// read from a file; so for nodes.
std::string element_label(const ShellMesh& mesh, int e);
std::string node_label(const ShellMesh& mesh, int n);

// Area of each triangle, m^2.
std::vector<double> element_areas(const ShellMesh& mesh);
// Lumped (one third of each adjacent triangle) area per node, m^2.
std::vector<double> node_areas(const ShellMesh& mesh);
// The thickness each triangle would have at constant volume (m): h0 times
// its area in `area0` over its area at the positions x (3 per node). A
// triangle that has collapsed to no area gets NaN.
void constant_volume_thickness(const ShellMesh& mesh, const std::vector<double>& area0, const double* x, double h0,
                               double* thickness);

double min_edge_length(const ShellMesh& mesh);
double max_edge_length(const ShellMesh& mesh);

}  // namespace ts
