#pragma once
// results.h5 + results.xdmf: fields per frame, readable in ParaView as a time
// series. Each frame is flushed to disk as soon as it is written and the
// XDMF index is rewritten (past 100 frames at most once a second, and when
// the writer closes), so a run that fails keeps every frame so far.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace ts {

struct WriterPart {
  std::string name;
  int num_nodes = 0, num_elements = 0;
  const std::vector<int>* triangles = nullptr;
  double thickness = 0;
  int nz = 1;  // through-thickness values per node
  bool layers = true;  // write the extruded through-thickness mesh
  // Each node's and triangle's tag in the mesh file, or its number from 1
  // (results.h5's /parts/<ply>/node_tags and element_tags).
  std::vector<long long> node_tags, element_tags;
};

// A tool's surface as the results show it: its triangulation in the
// initial position (results.h5's /tools/<name>/nodes and triangles) and,
// for a tool that moves, its nodes at each frame (/frames/<k>/<name>/nodes).
struct WriterTool {
  std::string name;
  std::vector<double> nodes;  // 3 per vertex (m)
  std::vector<int> triangles;
  bool moves = false;
};

// The units of a frame's dataset (a field, "nodes" or "layer_nodes"), as
// its attribute "units" gives them: "degC", "m", "m/s", "deg", "Pa", "N/m",
// "1/m", or "1" for dimensionless values.
std::string field_units(const std::string& name);
// Whether a frame's dataset of this field holds a value per element
// (ElementFields: shear angle, fibre direction, membrane stress and strain,
// curvature) rather than per node.
bool field_on_elements(const std::string& name);
// The units of a series' column (the energy, tool and ply tables), as the
// series' attribute "units" lists them beside "columns".
std::string series_column_units(const std::string& column);

struct FrameField {
  std::string name;
  const double* data = nullptr;
  int components = 1;            // 1 scalar, 3 vector
  bool on_cells = false;         // element data instead of node data
  bool on_layers = false;        // extruded through-thickness mesh
};

// The bytes of the values results.h5 holds (before compression, without
// HDF5's own structures and the time series written at the end): those
// written once (the plies' triangles, node and element tags and
// through-thickness wedges, the tools' surfaces) and those of each frame
// (the plies' positions, through-thickness positions and fields, the
// moving tools' positions), for these parts, fields per part and tools.
struct ResultsBytes {
  double once = 0, per_frame = 0;
};
ResultsBytes results_bytes(const std::vector<WriterPart>& parts, const std::vector<std::vector<FrameField>>& fields,
                           const std::vector<WriterTool>& tools);

class ResultsWriter {
 public:
  // compression: the gzip level (1-9, with the shuffle filter) of the
  // datasets of at least 256 values, 0 for none.
  ResultsWriter(const std::filesystem::path& dir, std::vector<WriterPart> parts, int compression = 0);
  // A restarted run (io/checkpoint.hpp): opens the results.h5 of the run in
  // dir, keeps its first frames (their times given, every frame with the
  // fields of `fields`: names and kinds, those of the run that wrote them),
  // removes the frames after them, adds the through-thickness mesh of the
  // parts whose frames to come need it where the file lacks it, and
  // rewrites results.xdmf. Throws std::runtime_error when the file is not
  // there or holds fewer frames.
  ResultsWriter(const std::filesystem::path& dir, std::vector<WriterPart> parts, const std::vector<double>& kept_times,
                const std::vector<std::vector<FrameField>>& fields, int compression = 0);
  ~ResultsWriter();
  ResultsWriter(const ResultsWriter&) = delete;
  ResultsWriter& operator=(const ResultsWriter&) = delete;

  // The tools' surfaces, once, before the first frame written (a restarted
  // run: again, replacing those of the file; its kept frames show the tools
  // where they hold them).
  void set_tools(std::vector<WriterTool> tools);
  // Geometry of one part for this frame: mid-surface nodes and node normals
  // (for the extruded through-thickness mesh); the displacement of each
  // tool of set_tools() (m; none without tools).
  void write_frame(double time, const std::vector<const double*>& x, const std::vector<const double*>& normals,
                   const std::vector<std::vector<FrameField>>& fields,
                   const std::vector<std::array<double, 3>>& tool_displacements = {});
  int frames() const { return static_cast<int>(times_.size()); }
  // A table of time series (rows x columns, row-major) under /series/<name>
  // with its column names; replaces an earlier one of the same name.
  void write_series(const std::string& name, const std::vector<std::string>& columns, const std::vector<double>& rows);

 private:
  void write_xdmf() const;
  void check_compression() const;  // throws std::runtime_error where the library lacks the filters
  // Runs `write` (HDF5 calls that throw std::runtime_error where one fails)
  // and flushes the file. Where that fails (a full disk), closes what the
  // write left open and throws "cannot write results.h5 (what): why"; every
  // later write then throws the same without touching the file.
  template <class F>
  void guard(const std::string& what, F&& write);
  std::string failed_;  // the first write that failed, or empty
  std::filesystem::path dir_;
  std::vector<WriterPart> parts_;
  int compression_ = 0;
  long long file_ = -1;
  std::vector<double> times_;
  std::vector<std::vector<std::vector<FrameField>>> frame_fields_;  // names/kinds only
  std::vector<WriterTool> tools_;
  bool xdmf_behind_ = false;       // frames written since results.xdmf was
  double xdmf_written_at_ = -1e300;  // steady clock (s) of its last writing
  // Per frame, per tool: whether the frame holds the tool's nodes (a moving
  // tool; frames of a run without tool surfaces do not).
  std::vector<std::vector<char>> frame_tools_;
};

}  // namespace ts
