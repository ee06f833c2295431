#pragma once
// `thermostamp export DIR`: the plies of one frame of an output folder as
// Gmsh meshes (format 2.2, ASCII), one file per ply: the mid-surface at its
// positions of that frame, with the frame's node and element fields as
// $NodeData and $ElementData. A formed ply thus goes to a structural model
// (its fibre directions and shear angles per element) or, as a mesh file,
// into another job.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ts {

// What cannot be exported as asked (no results file, no frame near the
// time asked): the command's input is wrong.
struct ExportInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ExportedPly {
  std::string name;
  std::filesystem::path file;
  int nodes = 0, triangles = 0;
  std::vector<std::string> node_data, element_data;  // the fields written
  std::vector<std::string> mirrored;                  // whole: the planes mirrored at ("x", "y", "z")
  // Abaqus: the element set's name, and the fields the orientations, the
  // initial temperatures and the nodal thicknesses were written from (""
  // for none)
  std::string elset, orientation_from, temperature_from, thickness_from;
};

// Gmsh 2.2 ASCII (<ply>.msh, every field), or Abaqus input (<ply>.inp: the
// mesh as S3 shells in an element set named after the ply, each element's
// material orientation from the frame's fibre direction as a distribution
// and an *ORIENTATION, each node's mean temperature as *INITIAL
// CONDITIONS, type=TEMPERATURE, and each node's thickness at constant
// volume, the mean of its elements' weighted by their areas, as *NODAL
// THICKNESS), or the same for CalculiX (<ply>.inp,
// its distribution without the default line that Abaqus asks for first:
// CalculiX 2.20 gives that line's directions to every element).
enum class ExportFormat { Gmsh, Abaqus, CalculiX };

// How a field's values change in the mirror image of a ply across a plane
// normal to axis d: kept (scalars), the d-th component negated (vectors:
// displacement, velocity), the fibre direction's mirror image, turned
// end for end where the ply's fibre direction in the job points away from
// its own mirror image (a direction is a line: a fibre along x mirrored at
// x = 0 stays along +x, as a run of the mirrored ply gives it), the value
// negated (the shear angle: the mirror image R of the material frame
// (a, n x a) is (Ra, -R(n x a)), or (-Ra, R(n x a)) turned end for end), the
// third component negated (the 12 component of a membrane stress, strain
// or curvature given as [11, 22, 12] in that frame). None for a field the
// export does not know.
enum class MirrorRule { Keep, Vector, Fibre, Negate, Negate12 };
std::optional<MirrorRule> mirror_rule(const std::string& field);

// A field of a frame: its values and how many per node or element.
struct PlyField {
  std::string name;
  bool cells = false;
  int components = 1;
  MirrorRule rule = MirrorRule::Keep;
  std::vector<double> v;
};

// A ply of a frame: its positions at the frame (x) and in the first frame
// (x0: the mesh the run started from), triangles by node index, the
// numbers of the mesh file and, when asked, the frame's fields of the ply.
struct FramePly {
  std::string name;
  std::vector<double> x, x0;
  std::vector<int> tri;
  std::vector<long long> node_tag, element_tag;
  std::vector<PlyField> fields;
  std::vector<std::string> mirrored;  // whole: the planes mirrored at ("x", "y", "z")
};

struct FramePlies {
  std::filesystem::path h5;  // the results file
  std::string group;         // the frame's group in it ("frames/000004")
  double time = 0;           // s
  int frame = 0, frames = 0;
  std::vector<FramePly> plies;
};

// The plies of the frame at `time` (the last frame without one; otherwise
// the frame nearest to it, the time lying between the first and the last
// frame's), with their fields when `fields`, each mirrored whole at its
// symmetry planes when `whole` (see export_gmsh). Throws ExportInputError
// for a folder without results.h5 or frames, or a time outside the
// frames'; std::runtime_error where the file cannot be read.
// first: the first frame instead (time is then not looked at).
FramePlies read_frame_plies(const std::filesystem::path& dir, std::optional<double> time, bool whole, bool fields,
                            bool first = false);

// Creates the folder a command writes into (and its parents); throws
// ExportInputError naming it and the system's reason where it cannot (as
// `run` refuses its --out).
void create_output_folder(const std::filesystem::path& out);

struct ExportResult {
  double time = 0;  // s, of the frame exported
  int frame = 0;    // its index (0 the first)
  int frames = 0;   // frames in the file
  std::vector<ExportedPly> plies;
};

// Writes <out>/<ply>.msh for every ply of the frame at `time` (the last
// frame without one; otherwise the frame nearest to it, the time lying
// between the first and the last frame's). Throws ExportInputError for a
// folder without results.h5 or frames, or a time outside the frames';
// std::runtime_error where the file cannot be read or the output written.
//
// whole: a ply held by `symmetry` constraints (read from the folder's
// job_as_run.json) is written whole: mirrored at each of its planes in
// turn (x, then y, then z), the nodes on a plane (within 1e-6 of the
// longest edge in the first frame, as the run found them) shared by both
// halves, the mirror images' triangles turned to keep the normals' side,
// the fields changed by mirror_rule. The mirror images' nodes and
// triangles are numbered from those of the half they mirror plus the
// smallest power of 10 at least as large as that half's largest number.
ExportResult export_gmsh(const std::filesystem::path& dir, std::optional<double> time,
                         const std::filesystem::path& out, bool whole = false);
// The same in either format.
ExportResult export_plies(const std::filesystem::path& dir, std::optional<double> time,
                          const std::filesystem::path& out, bool whole, ExportFormat format);
// An Abaqus name for a ply: letters, digits and underscores, upper case,
// starting with a letter (P_ put before one that does not).
std::string abaqus_name(const std::string& ply);

}  // namespace ts
