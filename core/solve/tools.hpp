#pragma once
// Rigid tools: exact signed distance and outward normal of analytic
// surfaces (plane, sphere, profile of lines and arcs revolved about an axis)
// and of triangle meshes (Gmsh or STL), and their rigid translation
// (constant velocity, displacement table, or driven by a force).
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "job/job.hpp"

namespace ts {

class RigidTool {
 public:
  // Throws JobError (at the surface's pointer) when a mesh cannot be read.
  explicit RigidTool(const ToolDef& def);

  const ToolDef& def() const { return *def_; }
  // A triangulation of the surface in the tool's initial position, for the
  // results (3 coordinates per vertex, 3 vertices per triangle, outward
  // normals by the right-hand rule): a mesh tool's own triangles; a plane
  // as a square over the box [lo, hi] (the plies) and 20 % beyond it; a
  // sphere in 24 x 48 pieces; a revolved tool's profile (lines as one
  // segment, arcs in steps of at most 7.5 degrees) swept through 48 sectors.
  void display_mesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi, std::vector<double>& xyz,
                    std::vector<int>& tri) const;
  // A mesh tool's triangles, vertices, edge lengths and how its edges are
  // shared, in a line for `validate` and the log; empty for the others.
  std::string describe() const;
  // A mesh tool: the largest side of its box (m); 0 for the others.
  double mesh_span() const;
  // Signed distance (positive outside, where the outward normal points) and
  // outward unit normal of n points, in the tool's current position. Points
  // as far as `cutoff` or farther from a mesh surface get +infinity (with an
  // infinite cutoff every point gets its distance). Edges and the free ends
  // of a profile act as rounded (distance to the edge point).
  void query(std::size_t n, const double* points, double cutoff, double* distance, double* normal) const;
  static void query_fn(const void* self, std::size_t n, const double* points, double cutoff, double* distance,
                       double* normal) {
    static_cast<const RigidTool*>(self)->query(n, points, cutoff, distance, normal);
  }

  // A mesh tool's query for points asked again and again (a part's nodes,
  // step after step): `kept` holds a record of kKeptBytes per point, which
  // the caller keeps between calls (zero before the first call, 8-byte
  // aligned). A record lists the triangles near the point where it was
  // last searched; while the point stays near that place (in the tool's
  // frame) only those are tested. The same answers as query(), to the bit.
  static constexpr std::size_t kKeptBytes = 192;
  void query_kept(std::size_t n, const double* points, double cutoff, double* distance, double* normal,
                  void* kept) const;
  static void query_kept_fn(const void* self, std::size_t n, const double* points, double cutoff, double* distance,
                            double* normal, void* kept) {
    static_cast<const RigidTool*>(self)->query_kept(n, points, cutoff, distance, normal, kept);
  }
  bool is_mesh() const { return kind_ == Kind::Mesh; }
  // What a record holds: the number of triangles listed, -1 where more
  // than fit (the point's queries then search the tree), -2 where it has
  // no list yet.
  static int kept_listed(const void* record);

  // A revolved tool's query of one point p (already moved back by the
  // tool's displacement), point by point; query() gives the same bits with
  // vector passes over the points.
  void query_revolved(const double* p, double& d, double* n) const;

  // Rigid translation from the initial position (m) and velocity (m/s).
  const std::array<double, 3>& displacement() const { return u_; }
  const std::array<double, 3>& velocity() const { return v_; }
  bool force_controlled() const { return def_->motion.kind == MotionDef::Kind::Force; }
  // Advances the tool from t to t + dt. `reaction` is the force the plies
  // exert on the tool at t (used by force control); dt_avg is the central
  // difference interval of the velocity update.
  void advance(double t, double dt, double dt_avg, const std::array<double, 3>& reaction);
  // Prescribed displacement at time t (velocity and table motions).
  std::array<double, 3> prescribed(double t) const;
  // Checkpoints: the displacement and velocity (all the state a tool has).
  void set_motion_state(const std::array<double, 3>& u, const std::array<double, 3>& v) {
    u_ = u;
    v_ = v;
  }

 private:
  void query_revolved_run(std::size_t n, const double* points, double* distance, double* normal) const;
  void query_mesh(const double* p, double cutoff, double& d, double* n) const;
  // The closest triangle so far of a search (q < 0: none), its squared
  // distance and closest point, and the reach of the search, squared.
  struct Closest {
    double best = 0, limit2 = 0;
    int q = -1;
    std::array<double, 3> cp{};
  };
  void test_triangle(const double* p, int q, Closest& c) const;
  double closest_on(const double* p, int q, std::array<double, 3>& cp) const;
  // Walks the tree's boxes within sqrt(limit2) of p, the nearer child
  // first, and hands each leaf to `leaf`, which may shrink limit2.
  template <class Leaf>
  void descend(const double* p, const double& limit2, Leaf&& leaf) const;
  // The triangles whose distance from p may be at most `radius` (by the
  // search's lower bounds), nearest first, into out[0 .. max), and a lower
  // bound of each one's distance from p into near: their number, or -1
  // where more than max are.
  int mesh_near(const double* p, double radius, std::int32_t* out, float* near, int max) const;
  // The closest of the listed triangles nearer than the cutoff, from a
  // point at most `moved` from where the list was made: what query_mesh()
  // answers where the list holds every triangle it could take.
  void query_listed(const double* p, double cutoff, const std::int32_t* list, const float* near, int count,
                    double moved, double& d, double* n) const;
  // The signed distance and outward normal from the closest point cp of
  // triangle q (squared distance d2; q < 0: none within the cutoff).
  void mesh_answer(const double* p, int q, double d2, const std::array<double, 3>& cp, double& d, double* n) const;
  void build_mesh(const std::vector<double>& xyz, const std::vector<int>& tri);
  // Throws JobError (at ptr) when two triangles with a common edge face
  // opposite sides, naming them by their place in the file (place[e]:
  // triangle e's, from 0); counts the edges for describe().
  void check_orientation(const std::vector<double>& xyz, const std::vector<int>& tri, const std::vector<int>& place,
                         const std::string& ptr);
  static bool zero_area(const std::vector<double>& xyz, const int* t);

  const ToolDef* def_;
  enum class Kind { Plane, Sphere, Revolved, Mesh } kind_ = Kind::Plane;  // from def_->surface.type, once
  std::array<double, 3> plane_normal_{0, 0, 1};                           // unit
  std::array<double, 3> u_{0, 0, 0}, v_{0, 0, 0};
  // revolved: unit axis, a unit vector normal to it, per-segment normals at the ends
  std::array<double, 3> axis_{0, 0, 1}, perp_{1, 0, 0};
  // Per profile piece: a line's 1 / length^2 and outward normal, an arc's
  // radius and turning sense (+1 counter-clockwise).
  struct PieceConstants {
    double inv_len2 = 0, radius = 0, orient = 1;
    std::array<double, 2> normal{0, 0};
  };
  std::vector<PieceConstants> pieces_;
  std::vector<std::array<double, 4>> end_normals_;  // (nr, nz) at a, (nr, nz) at b: averaged at shared ends
  // Per piece, for the vector passes: is_arc, centre (2), -orient / radius,
  // line normal (2), end normals (4).
  std::vector<double> piece_table_;
  // mesh: triangles in the initial position, in the order of the leaves of
  // a tree of bounding boxes (each inner box holds its two children; a
  // leaf a few triangles), so that a query visits only boxes within its
  // reach and reads the triangles it tests from consecutive memory,
  // whatever the sizes and the order of the file's triangles.
  struct BoxNode {
    double lo[3], hi[3];
    int first;  // leaf: first triangle; inner: the second child (the first follows the node)
    int count;  // leaf: number of triangles; inner: 0
  };
  std::vector<double> mx_;     // 9 per triangle
  static constexpr int kGeo = 12;
  std::vector<double> mn_;     // kGeo per triangle: unit normal, barycentric gradients g1, g2, 1 / |g_k|^2
  std::vector<int> morig_;     // each triangle's index in the file
  std::vector<int> mrank_;     // its rank by its corners (ties go to the lowest)
  std::vector<BoxNode> boxes_;  // depth first, root at 0
  double scale_ = 1;           // the longest edge
  double tol_ = 0;             // round-off margin of the search's bounds (m)
  std::vector<double> weld_xyz_;  // a mesh tool's vertices (corners at one point merged) and
  std::vector<int> weld_tri_;     // triangles, as read (flip applied)
  struct MeshInfo {
    std::size_t triangles = 0, vertices = 0, shared_edges = 0, open_edges = 0, other_edges = 0;
    std::size_t zero_area = 0;  // triangles of zero area in the file, left out
    double shortest_edge = std::numeric_limits<double>::infinity();
  } mesh_info_;
};

// Keeps the part of a display mesh (3 coordinates per vertex, 3 vertices
// per triangle) on the side sign * x[axis] >= 0 of the plane x[axis] = 0:
// vertices within tol of the plane are put on it, triangles across it are
// cut along it (a cut point shared by the triangles on both sides of its
// edge), triangles beyond it dropped, and the vertices no longer used
// removed. The triangles keep their orientation.
void cut_display_mesh(std::vector<double>& xyz, std::vector<int>& tri, int axis, double sign, double tol);

}  // namespace ts
