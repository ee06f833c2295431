#pragma once
// The validated content of a job file (format thermostamp-job/1).
#include <algorithm>
#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "job/json_reader.hpp"

namespace ts {

struct MaterialDef {
  std::string name;
  std::string pointer;
  // specific_heat: J/(kg K); with a table, its smallest value (the one the
  // thermal splitters advance with, see solve/heat_capacity.hpp).
  double density = 0, specific_heat = 0;
  // Rows [T (degC), c (J/(kg K))] of a specific heat that depends on the
  // temperature; empty for a constant one (a table of equal values too);
  // and the largest value (= specific_heat when constant).
  std::vector<std::array<double, 2>> specific_heat_table;
  double specific_heat_max = 0;
  // k11, k22, k33 (W/(m K)); with a table, its largest values.
  std::array<double, 3> conductivity{0, 0, 0};
  // Rows [T (degC), k11, k22, k33] of a conductivity that depends on the
  // temperature (linear between the rows, held beyond them); empty for a
  // constant one (a table of equal rows too).
  std::vector<std::array<double, 4>> conductivity_table;
  // The smallest and largest k33 of the table (W/(m K)), for the log.
  std::array<double, 2> k33_range() const {
    std::array<double, 2> r{conductivity[2], conductivity[2]};
    for (const auto& row : conductivity_table) {
      r[0] = std::min(r[0], row[3]);
      r[1] = std::max(r[1], row[3]);
    }
    return r;
  }
  bool has_thermal = false;
  // The fibre volume fraction when the thermal data above were formed from
  // `mixture` (matrix and fibre); negative when they were given.
  double mixture_fibre_fraction = -1;
  double mixture_matrix_mass_fraction = 0;  // (1 - V_f) rho_m / rho, with a mixture
  json membrane, bending, in_plane_bending;  // null when absent
  // The crystallisation kinetics of the matrix (Nakamura), see
  // solve/crystallisation.hpp; `present` false when the material has none.
  struct Crystallisation {
    bool present = false;
    std::string pointer;
    double latent_heat = 0;      // J/kg of ply, released from relative crystallinity 0 to 1
    // J/kg of matrix where the job gives it so (matrix_latent_heat, with a
    // mixture: latent_heat is then it times the matrix's mass fraction);
    // negative where the job gives latent_heat.
    double matrix_latent_heat = -1;
    double avrami_exponent = 3;  // n
    // The rate K(T) (1/s): rows [T (degC), K] (linear between them, held
    // beyond), or, with the rows empty, Ziabicki's Gaussian
    // K = k_max exp(-4 ln 2 (T - t_max)^2 / half_width^2).
    std::vector<std::array<double, 2>> rate_rows;
    double k_max = 0, t_max = 0, half_width = 0;
    double initial = 0;  // relative crystallinity at the start, in [0, 1] (1: as crystalline as it gets)
    // Melting on heating (empty: none): rows [T (degC), share of the
    // crystals still solid], temperatures increasing, the shares falling
    // from 1 at the first row to 0 at the last (linear between the rows,
    // held beyond them): the cumulative melting endotherm of a DSC heating
    // run. A value holds at most the share at its temperature.
    std::vector<std::array<double, 2>> melting_rows;
  } crystallisation;
};

struct MeshDef {
  enum class Kind { Rectangle, File } kind = Kind::Rectangle;
  std::array<double, 3> origin{0, 0, 0};
  std::array<double, 2> size{0, 0};
  std::array<int, 2> divisions{1, 1};
  bool crossed = false;  // rectangle: four triangles per cell around a centre node
  std::filesystem::path file;
  // file: the triangles taken so that neighbours are close in memory
  // (reverse Cuthill-McKee) and the nodes numbered in the order they first
  // use them; false: the file's order (its nodes numbered likewise).
  bool reorder = true;
  // file: the factor its coordinates are taken times (0.001 for a file in
  // millimetres).
  double scale = 1.0;
};

struct PartDef {
  std::string name, pointer;
  MeshDef mesh;
  double thickness = 0;
  int material = -1;
  std::array<double, 3> fibre_direction{1, 0, 0};
  std::string element;
  double initial_temperature = 20.0;
  // The initial temperatures from a frame of an earlier run's results.h5
  // (empty: the constant above): its file, part (empty: this part's name)
  // and time (< 0: its last frame).
  std::filesystem::path initial_results;
  std::string initial_results_part;
  double initial_results_time = -1;
  int thickness_layers = 8;
  bool flip = false;  // reverse the mesh orientation: the ply's top face looks the other way
};

// One piece of a revolved profile in the (r, z) half-plane: a line from
// `a` to `b`, or an arc (less than 180 degrees) from `a` to `b` about `centre`.
struct ProfileSegment {
  bool arc = false;
  std::array<double, 2> a{0, 0}, b{0, 0}, centre{0, 0};
};

struct SurfaceDef {
  std::string type;  // plane, sphere, revolved, mesh
  std::array<double, 3> point{0, 0, 0}, normal{0, 0, 1}, centre{0, 0, 0};
  double radius = 0;
  std::array<double, 3> axis_origin{0, 0, 0}, axis_direction{0, 0, 1};  // revolved
  std::vector<ProfileSegment> profile;                                   // revolved
  std::filesystem::path file;                                            // mesh
  bool flip = false;                                                     // mesh: reverse the normals
  double scale = 1.0;                                                    // mesh: factor on the file's coordinates
};

// The value of rows [t, x, y, z] (times increasing, at least one row) at
// time t: linear between the rows, held before the first and after the last.
std::array<double, 3> rows_at(const std::vector<std::array<double, 4>>& rows, double t);

struct MotionDef {
  enum class Kind { Fixed, Velocity, Displacement, Force } kind = Kind::Fixed;
  std::array<double, 3> velocity{0, 0, 0};
  std::vector<std::array<double, 4>> table;  // t, dx, dy, dz
  // A force-controlled tool: the force (N), constant, or with force_table
  // the first row's that is not zero (its direction, along which the tool
  // moves; every row lies along it).
  std::array<double, 3> force{0, 0, 0};
  // Force over time: rows [t (s), fx, fy, fz (N)], times increasing; linear
  // between rows, held before the first and after the last. Empty: constant.
  std::vector<std::array<double, 4>> force_table;
  double mass = 0, damping = 0;
  // The force at time t (N): force, or force_table's there.
  std::array<double, 3> force_at(double t) const;
  // The displacement at time t (m) of a Velocity or Displacement motion
  // from where it starts (zero for the others).
  std::array<double, 3> prescribed(double t) const;
};

struct ToolDef {
  std::string name, pointer;
  SurfaceDef surface;
  MotionDef motion;
  double temperature = 20.0;  // constant, or the table's first value
  // Temperature over time: rows [t (s), T (degC)], times increasing; linear
  // between rows, held before the first and after the last. Empty: constant.
  std::vector<std::array<double, 2>> temperature_table;
  // The mean temperature over [t0, t1] (degC); at t0 where t1 <= t0.
  double temperature_over(double t0, double t1) const;
};

// The mean over [t0, t1] of a piecewise-linear curve of rows [t, value]
// (times increasing; held before the first row and after the last): the
// exact integral, kinks inside the interval included; its value at t0
// where t1 <= t0.
double rows_mean(const std::vector<std::array<double, 2>>& rows, double t0, double t1);

struct BodyDef {
  bool is_tool = false;
  int index = -1;
};

struct ContactDef {
  std::string pointer, handler;
  BodyDef first, second;
  json params;  // everything but type / handler / between, validated by the handler's descriptor
};

struct RegionDef {
  enum class Kind { All, Circle, Box } kind = Kind::All;
  std::array<double, 2> centre{0, 0};
  double radius = 0;
  std::array<double, 2> lo{0, 0}, hi{0, 0};
  bool contains(double x, double y) const;
};

struct HeatExchangeDef {
  std::string pointer;
  std::vector<int> parts;
  bool top = false, bottom = false;
  double h = 0, ambient = 0;  // ambient: constant, or the table's first value
  std::vector<std::array<double, 2>> ambient_table;  // rows [t (s), T (degC)]; empty: constant
  double emissivity = 0;  // radiation to the ambient, eps sigma (T^4 - T_amb^4) in kelvin
  double ambient_over(double t0, double t1) const {
    return ambient_table.empty() ? ambient : rows_mean(ambient_table, t0, t1);
  }
  RegionDef region;
};

struct ProbeDef {
  std::string name, pointer;
  int part = -1;
  std::array<double, 3> at{0, 0, 0};
  std::vector<std::string> quantities;
  double interval = 0;  // 0: every thermal step
};

struct ThermalSolverDef {
  std::string pointer = "/solvers/thermal";
  std::string splitter;
  json params;  // validated by the splitter's descriptor
  int subcycle = 0;
  double dt = 0;  // 0: automatic
  // With the mechanics: contact samples per thermal step, whose
  // conductances are averaged over the step (1: the contact map of the
  // step's end only).
  int contact_samples = 8;
};

struct MechanicsDef {
  double dt_safety = 0.8;
  double target_dt = 0;      // mass scaling to this step (0: none)
  double mass_factor = 1.0;  // uniform mass scaling factor
  double damping = 0;        // mass-proportional damping coefficient, 1/s
  bool damping_normal = false;  // the damping acts on the velocity along each node's normal only
  std::array<double, 3> gravity{0, 0, 0};
  double energy_tolerance = 0.05;  // relative energy balance error that stops the run
  // How elements and contact share the threads: "auto" (timed), "beside"
  // (contact on the first thread beside the element blocks), "in_turn" or
  // "by_part" (each ply's elements and contact on a thread of its own).
  std::string contact_schedule = "auto";
  // At most how many steps one evaluation of the bending carries (1: the
  // bending every step); fewer where the bending's stable step demands it.
  int bending_subcycles = 1;
};

struct ConstraintDef {
  enum class Type { Symmetry, Fix, Velocity, Force, Gripper } type = Type::Fix;
  std::string pointer;
  std::string name;  // gripper: its name in messages and summary.json
  std::vector<int> parts;
  int plane = 0;  // symmetry: 0 x, 1 y, 2 z
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
  std::array<bool, 3> dofs{false, false, false};
  std::array<double, 3> velocity{0, 0, 0};
  std::array<double, 3> force{0, 0, 0};  // force: total over the nodes in the box (N)
  double ramp = 0;                       // force, gripper's preload: linear ramp time from zero (s)
  // gripper: a spring from the anchor (m) to the centre of the nodes in the
  // box (their mean position weighted by their mass), which pulls them
  // with the force preload + stiffness (d - d0), d the spring's length and
  // d0 its length at t = 0, shared among them by their mass; never
  // pushing where tension_only. The anchor moves by `anchor_motion`
  // (Fixed, Velocity or Displacement).
  std::array<double, 3> anchor{0, 0, 0};
  double stiffness = 0;  // N/m
  double preload = 0;    // N
  bool tension_only = true;
  // gripper: the gripped nodes move as one rigid body instead of each
  // following the ply: translating only (a clamp's jaws that neither deform
  // nor turn, `"jaws": "rigid"`), or also turning (`"swivelling"`, with
  // `rigid` true as well).
  bool rigid = false;
  bool swivelling = false;
  double release = std::numeric_limits<double>::infinity();  // s: from then on the gripper holds no more
  MotionDef anchor_motion;
};

struct OutputDef {
  double interval = 0;
  double checkpoint_interval = 0;  // s of simulated time between checkpoints, 0: only when interrupted
  bool checkpoint_at_end = true;    // a checkpoint at time.end too (from which a later time.end extends the run)
  bool keep_checkpoints = false;    // every checkpoint also kept as DIR/checkpoints/checkpoint_<t>.bin
  double series_interval = 0;       // s between the rows of energy.csv, tools.csv and plies.csv, 0: time.end / 500
  // Per part (empty: none asked for). degC: plies.csv and the summary give
  // each ply's share below it and the times its coldest and its hottest
  // value first went below it. One number for every ply, or by material.
  std::vector<double> temperature_threshold;
  // Per part (empty: none). Degrees (0 to 90, mechanics): plies.csv and the
  // summary give each ply's share of its area sheared beyond it and the
  // first row at which some element was. One number, or by material.
  std::vector<double> shear_angle_limit;
  int compression = 0;              // gzip level of results.h5's datasets (with shuffle), 0: none
  bool tool_surfaces = true;        // the tools' surfaces in results.h5 / results.xdmf
  bool tool_surfaces_whole = false;  // ... whole, not cut at the plies' symmetry planes
  std::vector<std::string> fields;
  std::vector<ProbeDef> probes;
  // The fields of a job that names none.
  static std::vector<std::string> default_fields() { return {"temperature"}; }
};

struct Job {
  std::string name;
  std::filesystem::path file, base_dir;
  json document;         // after --set overrides
  json document_as_run;  // the same with its file paths made absolute (job.json of the output folder)
  double t_end = 0;
  std::vector<MaterialDef> materials;
  std::vector<PartDef> parts;
  std::vector<ToolDef> tools;
  std::vector<ContactDef> contacts;
  std::vector<HeatExchangeDef> heat_exchanges;
  std::vector<ConstraintDef> constraints;
  bool mechanics = false;
  MechanicsDef mechanics_settings;
  std::optional<ThermalSolverDef> thermal;
  OutputDef output;
  std::vector<std::filesystem::path> plugin_paths;
};

// Reads a job file; throws JobError. `sets` are "path=value" overrides.
json read_job_document(const std::filesystem::path& file);
void apply_set(json& doc, const std::string& assignment);
void apply_set_value(json& doc, const std::string& path, const json& value);
Job parse_job(const json& doc, const std::filesystem::path& file);
// One line on the thermal data a material formed from `mixture` (its fibre
// volume fraction, density, specific heat and conductivity, or their
// ranges over the rows); empty for a material without one.
std::string describe_mixture(const MaterialDef& m);
// The material card a material of the job took its values from (absolute),
// empty for a material without "card".
std::filesystem::path material_card_file(const Job& job, const MaterialDef& m);
// `e` with the material card named where its pointer is a value that a
// material took from its card; `e` itself otherwise.
JobError with_material_card(const Job& job, const JobError& e);
Job load_job(const std::filesystem::path& file, const std::vector<std::string>& sets);

inline const std::vector<std::string>& known_fields() {
  static const std::vector<std::string> f = {"temperature", "temperature_mean", "temperature_top",
                                             "temperature_bottom", "displacement", "velocity", "shear_angle",
                                             "fibre_direction", "contact_status", "contact_pressure",
                                             "membrane_stress", "curvature", "membrane_strain", "conductance",
                                             "tool_gap", "below_threshold_from", "crystallinity",
                                             "membrane_stability", "thickness"};
  return f;
}
inline const std::vector<std::string>& known_probe_quantities() {
  static const std::vector<std::string> q = {"temperature_profile", "temperature_mean", "displacement_x",
                                             "displacement_y", "displacement_z", "shear_angle",
                                             "contact_pressure", "fibre_strain", "conductance", "tool_gap",
                                             "crystallinity_profile", "thickness"};
  return q;
}

}  // namespace ts
