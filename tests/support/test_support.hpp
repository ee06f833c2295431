#pragma once
// Helpers shared by the tests: build a job from JSON, run it in-process,
// read probe samples, run the command line.
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include <hdf5.h>

#include <thermostamp/sdk/views.hpp>

#include "job/job.hpp"
#include "mesh/shell_mesh.hpp"
#include "solve/simulation.hpp"

namespace ts::test {

// A view of a mesh as part `index`, at its mesh coordinates (x0 = x); the
// view refers to the mesh, which must outlive it. Callers set fibres,
// thermal data and other positions.
sdk::PartView part_view(const ShellMesh& mesh, int index = 0, double thickness = 0.0005);

// A thermal-only job for one or more flat plies; callers edit the JSON.
json ply_job(const std::string& splitter, int layers, double t_end, double interval);

struct JobRun {
  RunResult result;
  // Profile of probe `probe` at time t (nearest sample), bottom to top.
  const ProbeSample* sample(int probe, const std::string& quantity, double t) const;
};

// Two plies of ply_job's material (the lower on a die at 260 degC, h_c
// 1000 W/(m^2 K)), h_c between them, to 2 s; probes `lo` and `up` give
// their profiles every 0.5 s.
json two_ply_job(const std::string& splitter, int layers, double hc);

// Runs the job in-process (no files unless out is given).
JobRun run_json(const json& doc, int threads = 0, const std::filesystem::path& out = {});

// Dataset `name` of an open results file, its rows one after the other.
template <class T>
std::vector<T> read_dataset(hid_t file, const std::string& name) {
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(set);
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(space, dims, nullptr);
  std::vector<T> v(dims[0] * (H5Sget_simple_extent_ndims(space) > 1 ? dims[1] : 1));
  H5Dread(set, std::is_same_v<T, int> ? H5T_NATIVE_INT : H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Sclose(space);
  H5Dclose(set);
  return v;
}

// The number of frames in an open results file (-1 without a frames group).
inline int frame_count(hid_t file) {
  const hid_t frames = H5Gopen2(file, "frames", H5P_DEFAULT);
  if (frames < 0) return -1;
  hsize_t n = 0;
  H5Gget_num_objs(frames, &n);
  H5Gclose(frames);
  return static_cast<int>(n);
}

// Where the results.xdmf of output folder `dir` names what its results.h5
// does not hold: the first DataItem whose dataset is missing or whose
// dimensions differ from those it gives ("" when every one resolves, as
// ParaView needs), and "no DataItem" for an index that names none.
std::string xdmf_mismatch(const std::filesystem::path& dir);

struct CommandResult {
  int exit_code = -1;
  std::string out, err;
};
// A path quoted for the shell.
inline std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
// Runs the thermostamp executable with arguments (shell-quoted by the caller).
CommandResult thermostamp(const std::string& args);
// The same, with shell commands before it (e.g. "ulimit -f 100; exec").
CommandResult thermostamp_after(const std::string& before, const std::string& args);
std::filesystem::path binary_dir();
std::filesystem::path source_dir();

// The `mixture` of share/materials/pa66_cf_ud_mixture.json: PA66 melt and
// carbon fibres at a fibre volume fraction of 0.4.
json pa66_carbon_mixture();
std::filesystem::path temp_dir(const std::string& name);
// The cells of every line of a comma-separated file, header included (an
// empty cell between commas is kept, an empty last one is not).
std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& file);

// An STL file of the square [lo, hi]^2 in the plane z (two triangles,
// normal +z), for a meshed tool.
void write_square_stl(const std::filesystem::path& file, double lo, double hi, double z);

// An STL file of a revolved tool's `surface` (a job's, axis along z) over
// the quarter x, y >= 0 and 3 degrees either side: lines as one segment,
// arcs and the sectors around the axis in steps of at most `step_deg`;
// outward normals as the revolved tool's (left of the profile's direction).
void write_revolved_stl(const std::filesystem::path& file, const json& surface, double step_deg);

// The bias-extension specimen (230 x 115 mm, yarns at +-45 degrees, woven
// law of shear coefficients kBiasKsh), its left end held, its right end
// pulled along x at `speed` (y held), z held everywhere; `mesh` is the
// part's mesh entry. Callers add the output.
inline constexpr double kBiasKsh[3] = {18.5, 46.4, -21.3};  // N/m
json bias_job(const json& mesh, double speed, double t_end);

// A lattice of diamonds for a woven specimen with yarns at +-45 degrees
// to x: nodes at (i a, j a), a = width / ny, for i + j even (0 <= i <= nx,
// 0 <= j <= ny); each diamond split by its horizontal diagonal, half
// diamonds at the ends. The triangles' edges follow the yarns. Gmsh 2.2.
void write_yarn_lattice_gmsh(const std::filesystem::path& file, double width, int nx, int ny);

// The mesh as a Gmsh 2.2 file as mesh generators leave them: its triangles
// in an order shuffled by `seed` (0: in order), tagged 100 + their index in
// `mesh`, the nodes tagged 7 + 3 x their index, listed from the last.
void write_shuffled_gmsh(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed);
inline long long shuffled_node_tag(int node) { return 7 + 3LL * node; }
inline long long shuffled_element_tag(int element) { return 100 + element; }
// The same nodes and triangles, tags and order as write_shuffled_gmsh, as
// Abaqus writes an input file: a heading, comments, the mesh in a *Part
// (element type `type`, every 7th element's node list continued on a second
// line, keywords in mixed case), node and element sets, an assembly with
// an instance and a reference point outside the part, and a material.
void write_shuffled_abaqus(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed,
                           const std::string& type = "S3R");
// The same as an LS-DYNA keyword file, in the columns of `style`:
// "standard" (I8, E16: 10 significant digits), "long" (*KEYWORD LONG=Y:
// 20 characters, 14 digits), "i10" (keywords ending in %: I10, E16) or
// "free" (comma-separated, 17 digits); with a title, a part, its section,
// comment cards, every 5th triangle's N4 left blank (the others N4 = N3),
// and cards after *END. With `shell_option` (THICKNESS, BETA_OFFSET, ...)
// the shells as *ELEMENT_SHELL_<option>, each element with the cards the
// option adds (nodal thicknesses and an angle, an offset).
void write_shuffled_lsdyna(const std::filesystem::path& file, const ShellMesh& mesh, unsigned seed,
                           const std::string& style, const std::string& shell_option = "");

// A Gmsh 2.2 mesh of the parallelogram x = xi + s y, xi in [0, L], y in
// [0, W]: its slanted edges follow the level lines of cos(pi xi / L).
void write_parallelogram(const std::filesystem::path& file, double L, double W, double s, int nx, int ny);

// The nodal values T (n + 1 across a thickness h, bottom to top) at z in
// [-h/2, h/2], linear between nodes.
double profile_at(const std::vector<double>& T, double h, double z);
// Largest difference between two series of such profiles (one per sample
// time, any node counts) at 17 levels of the thickness h: a reference's
// own convergence.
double largest_difference(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                          double h);

// In-plane diffusion of a mode: runs job `j` (one ply, no probes, read
// from `dir`) from T0 = T_of(a cos(pi (x - slant y) / L)) (uniform through
// the thickness) and returns the decay rate (1/s) of the projection on
// that cosine of u_of(T), the mean through the thickness, over time.end.
// `result` receives the run's result.
double mode_decay_rate(const json& j, const std::filesystem::path& dir, double L, double slant, double a,
                       double (*T_of)(double), double (*u_of)(double), RunResult* result = nullptr);

// Plane wall, thickness L, insulated at x = 0, Robin (h, T_inf) at x = L,
// initially T0: T(x, t) from the eigen-series (lambda tan lambda = Bi).
double slab_robin_series(double x, double t, double L, double alpha, double Bi, double T0, double Tinf);
// The same wall's mean temperature over its thickness.
double slab_robin_mean(double t, double L, double alpha, double Bi, double T0, double Tinf);

// The heat flows (W/m^2) into the values T[0..n] of a slab of n cells of
// thickness e with linear elements and lumped capacities (the independent
// explicit references of the tests): conduction k between neighbours, an
// adiabatic bottom (value 0) and a Robin top (value n: h, to Ta).
void slab_heat_flows(const std::vector<double>& T, double k, double e, double h, double Ta, std::vector<double>& q);

}  // namespace ts::test
