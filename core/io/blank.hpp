#pragma once
// `thermostamp blank DIR --trim SURFACE`: the cut pattern of each ply. The
// part is trimmed on the formed ply (a plane, a cylinder, a sphere or an
// outline in plan view, in the run's coordinates); the pattern is the
// region of the blank, the ply as the run started, that the forming
// carries into the part: its outlines in the blank, the blank's area kept
// and the part's area, with marks along the fibres, as CSV, DXF (for a
// cutting table) and JSON.
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/nest.hpp"

namespace ts {

// A trim surface: the part lies on one side of it.
//   plane    "plane:X,Y,Z,NX,NY,NZ"        a point and the normal, which points into the part
//   cylinder "cylinder:X,Y,Z,DX,DY,DZ,R"   a point on the axis, the axis's direction and the radius; the part inside
//   sphere   "sphere:X,Y,Z,R"              the centre and the radius; the part inside
//   polygon  "polygon:FILE[,SCALE]"        a trim line drawn in a plane and cut along its
//                                          normal: a closed polygon in x and y from a CSV
//                                          file (a row "x,y" per vertex; plan view, seen
//                                          along z) or the closed polylines of a DXF file
//                                          (holes too: inside an odd number of them), in the
//                                          plane their extrusion direction gives (z for a
//                                          drawing in plan view); SCALE m per unit of the
//                                          file (CSV: 1; DXF: from its $INSUNITS); the part
//                                          inside
// Lengths in m.
struct TrimSurface {
  enum class Kind { Plane, Cylinder, Sphere, Polygon };
  Kind kind = Kind::Plane;
  std::array<double, 3> point{}, direction{};  // direction: unit
  double radius = 0;
  std::vector<std::vector<std::array<double, 2>>> rings;  // polygon: each ring's vertices (m)
  // polygon: the axes of its plane, unit and normal to each other; a
  // vertex (a, b) lies at a plan_u + b plan_v, and the polygon cuts along
  // plan_u x plan_v (x and y for a drawing in plan view, seen along z).
  std::array<double, 3> plan_u{1, 0, 0}, plan_v{0, 1, 0};
  // polygon: the rings are already moved by the margin the pattern is cut
  // with (polygon_margin_rings); the cut takes them as they are.
  bool margin_in_rings = false;
  std::string text;  // as given
};

// Throws ExportInputError ("--trim 'TEXT': what is wrong") for text that is
// no trim surface, numbers beyond 1e6 m, or a polygon file that cannot be
// read, holds no closed polygon, has a ring of fewer than 3 vertices, a
// vertex twice in a row, no area or sides that cross or touch, or a DXF
// file that does not give its units and no scale.
TrimSurface parse_trim(const std::string& text);

// The direction a polygon trim cuts along: plan_u x plan_v, (0, 0, 1)
// for a drawing in plan view.
std::array<double, 3> polygon_cut_direction(const TrimSurface& t);

// The level of a point x (m): at most 0 in the part, above 0 outside; the
// signed distance to the surface (a polygon's: in its plane, of the
// point's projection along its normal; for several surfaces, the part lying inside all of
// them, the largest).
double trim_level(const std::vector<TrimSurface>& trims, const double* x);

// A polygon trim's outline moved out by `margin` (m; in, below 0) in its
// plane: each side parallel to it at that distance, the outer corners
// rounded by arcs about the vertices (drawn as their tangents, each over
// at most 2 degrees of the arc: the line is nowhere nearer to the polygon
// than the margin, and at most 1.5e-4 of the margin further), the inner corners where the moved
// sides meet, and where the moved outline meets itself (a slot narrower
// than twice the margin, a hole that closes, a part narrower than twice
// a margin below 0) only its part at that distance from the polygon. The
// rings are those of the region within the margin of the polygon (its
// points outside within the margin of it taken too; below 0, its points
// within the margin of its outline left out), empty where a margin below
// 0 leaves nothing. Where moved sides coincide exactly (a polygon on a
// grid moved by a whole or half spacing, a bar moved in by half its
// width) the margin is taken 1e-8 of the polygon's size larger, or else
// smaller, which parts them. Throws std::runtime_error where the moved
// outline's pieces still do not join into rings that neither cross nor
// touch (saying where), and for a trim that is no polygon.
std::vector<std::vector<std::array<double, 2>>> polygon_margin_rings(const TrimSurface& t, double margin);

struct OutlinePoint {
  std::array<double, 3> blank{}, formed{};  // m
  bool on_trim = false;                     // on the trim line (else a node of the blank's edge)
};

// A closed outline of the pattern (the last point joins the first), the
// pattern on its left seen from the side the blank's triangles' normals
// point to: an outer outline runs anticlockwise, a hole's clockwise.
struct Outline {
  std::vector<OutlinePoint> points;
  double length_blank = 0, length_formed = 0;  // m, around
  double trim_length_blank = 0;                 // m: the part of it along the trim line
};

struct CutPattern {
  std::vector<Outline> outlines;
  double blank_area = 0;        // m^2, the whole blank
  double kept_blank_area = 0;   // m^2, the pattern in the blank
  double kept_formed_area = 0;  // m^2, the pattern formed: the trimmed part's area
  // Empty where each triangle was cut exactly; otherwise why not (where
  // the exact cut's outline did not close), and the pattern comes from
  // the trims' largest distance, linear in each triangle, as a curved
  // trim's does: corners within about an element.
  std::string fallback;
  // With a margin: for each polygon trim in order, empty where its
  // outline was moved by the margin (polygon_margin_rings) and cut
  // exactly; otherwise why not, and it was taken by its distance less the
  // margin, linear in each triangle.
  std::vector<std::string> polygon_margin;
};

// The pattern of one ply: x0 its positions in the blank, x formed (3 per
// node), tri its triangles (3 node indices each, alike oriented). In each
// triangle the part is cut by each trim in turn: a plane, cylinder or
// sphere by its level at the corners' formed positions, linear in the
// triangle (a crossing of an edge lies where the linear level is zero,
// at the same place of both positions); a polygon by each of its sides,
// the signed distance to the side's line in the polygon's plane (of the
// points projected along its normal), linear in the triangle, between the
// side's ends. A plane trim and a polygon are thus
// exact on the formed mesh, corners where two trims meet and a polygon's
// vertices included; a cylinder or a sphere is within the chord's error
// of the surface. Without trims the pattern is the whole blank (its
// outlines, its edges). Throws std::runtime_error for triangles that are
// not alike oriented (a boundary that does not close) or non-finite
// positions.
//
// margin (m): the trim line moved out by it on the formed part (the level
// less the margin), an allowance the pattern takes beyond the part's edge;
// below 0, in. A polygon's outline is moved by it in its plane
// (polygon_margin_rings) and cut exactly; where that cannot be done, the
// polygon is taken by its distance, linear in each triangle as a
// cylinder's (CutPattern::polygon_margin says which).
CutPattern cut_pattern(const std::vector<double>& x0, const std::vector<double>& x, const std::vector<int>& tri,
                       const std::vector<TrimSurface>& trims, double margin = 0);

// A fibre mark of a pattern: a short line along the fibres at a point of
// the pattern, in the blank (m), and its ends formed, by the map of the
// triangle its middle lies in (linear in the triangle).
struct FibreMark {
  std::array<double, 3> from{}, to{};
  std::array<double, 3> formed_from{}, formed_to{};
};

// Fibre marks at the points of a square grid of spacing `spacing` in the
// blank's plane (axes e1, e2, through the origin) that lie in the pattern
// (inside every trim as cut_pattern takes them), each along the fibre direction `fibre` (3 per triangle, as the
// frames' field fibre_direction) of the triangle it lies in, projected into
// the plane, 0.6 spacing long, centred on the point; a point on an edge
// goes to the first triangle that has it. combined: the trims as the
// pattern takes them where it falls back (CutPattern::fallback).
std::vector<FibreMark> fibre_marks(const std::vector<double>& x0, const std::vector<double>& x,
                                   const std::vector<int>& tri, const std::vector<TrimSurface>& trims,
                                   const std::vector<double>& fibre, const std::array<double, 3>& e1,
                                   const std::array<double, 3>& e2, double spacing, double margin = 0,
                                   bool combined = false);

// `blank --roll W [--gap G]`: each pattern laid on a roll W m wide, at
// least G m between copies.
struct RollOptions {
  double width = 0;      // m
  double gap = 0;        // m
  bool turn_90 = false;  // copies may also be turned by 90 degrees (a balanced woven roll's weft along it)
  int parts = 0;         // a batch of that many parts (lay_batch); 0: none
};

// A ply's pattern on the roll (lay_on_roll), turned in the blank's plane so
// that its fibres run along the roll.
struct PlyNest {
  RollLayout layout;
  // The fibres' direction in the blank's plane (its DXF axes), degrees from
  // its first axis, in (-90, 90]: the pattern is turned by minus it. The
  // area-weighted mean over the modelled ply's triangles (a mirrored ply's
  // first quarter or half); 0 without fibre_direction in the first frame.
  double fibre_angle_deg = 0;
  double fibre_spread_deg = 0;  // the largest difference of a triangle's fibres from it
  bool fibres_known = false;
  std::filesystem::path dxf;    // the layout: copies over a length of the roll
  double drawn_length = 0;      // m of roll in it
  int drawn_copies = 0;         // patterns drawn
  std::optional<RollBatch> batch;  // with RollOptions::parts, where a lane fits: the batch's patterns
  std::filesystem::path batch_dxf;  // and their layout
};

struct BlankPly {
  std::string name;
  std::filesystem::path csv, dxf;  // dxf empty where the blank is not flat
  std::vector<std::string> mirrored;
  CutPattern pattern;
  CutPattern blank;  // the whole blank's outlines (its edge), in the blank and formed
  bool flat = false;
  std::array<double, 3> normal{};  // the blank's plane's unit normal (flat)
  std::vector<FibreMark> marks;    // flat, with fibre_direction in the first frame
  double mark_spacing = 0;         // m
  std::optional<PlyNest> nest;     // with RollOptions, where the blank is flat and the pattern not empty
};

struct BlankResult {
  double time = 0;  // s, of the frame
  int frame = 0, frames = 0;
  std::filesystem::path json;
  std::vector<BlankPly> plies;
  // With a roll: m of roll per part, every ply's pattern once, each ply
  // cut in lanes of its own (the sum of the plies' roll per pattern; a ply
  // with nothing inside the trim takes none); none where a ply is not
  // nested or does not fit, and why.
  std::optional<double> roll_per_part;
  std::string roll_per_part_left_out;
  // With RollOptions::parts: m of roll for the batch, each ply's patterns
  // (a stretch of its own lanes, lay_batch) one after the other; none
  // where roll_per_part has none.
  std::optional<double> roll_for_parts;
};

// Writes, for each ply of the frame at `time` (as export_plies picks it;
// whole: mirrored at its symmetry planes), <out>/<ply>.csv (the points of
// the pattern's outlines and of the blank's edge, each in the blank and
// formed), <out>/<ply>.dxf where the blank is flat (the pattern and the
// blank's outline in its plane, in mm, and fibre marks where the first
// frame holds fibre_direction) and <out>/blank.json (areas,
// lengths, the edge's largest displacement in the blank's plane, the
// trims); with `roll`, also each flat ply's pattern nested on the roll
// (PlyNest; in blank.json and as <out>/<ply>_nest.dxf), and with
// RollOptions::parts the batch's (<out>/<ply>_parts.dxf). Throws ExportInputError for
// input that cannot give a pattern, std::runtime_error where the results
// cannot be read or the files written.
BlankResult blank_plies(const std::filesystem::path& dir, std::optional<double> time,
                        const std::filesystem::path& out, bool whole, const std::vector<TrimSurface>& trims,
                        double margin = 0, std::optional<RollOptions> roll = std::nullopt);

}  // namespace ts
