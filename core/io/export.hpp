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
};

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
ExportResult export_gmsh(const std::filesystem::path& dir, std::optional<double> time,
                         const std::filesystem::path& out);

}  // namespace ts
