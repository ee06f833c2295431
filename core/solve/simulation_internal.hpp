#pragma once
// The parts of Simulation that its source files share (solve/simulation.cpp:
// set-up and the steps; solve/run.cpp: the time loop, checkpoints and
// restarts; solve/run_output.cpp: frames, probes, time series, summary and
// log). Not installed: the kernel's own view of its state.
#include <array>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <thermostamp/sdk/memory.hpp>
#include <thermostamp/sdk/plugin.hpp>

#include "io/results_writer.hpp"
#include "solve/crystallisation.hpp"
#include "solve/conductivity.hpp"
#include "solve/heat_capacity.hpp"
#include "solve/simulation.hpp"

namespace ts {

struct MechPart {
  std::unique_ptr<sdk::ElementKernel> element;
  std::vector<const sdk::MaterialLaw*> membrane;
  const sdk::MaterialLaw* in_plane_bending = nullptr;  // the material's in_plane_bending, or null
  std::vector<double> curvature;
  std::vector<double> strain;  // Green-Lagrange membrane strain, 3 per element (ElementFields::strain)
  // The field membrane_stability: the long-term stiffness q (N/m) per
  // element (stability.hpp), where the frames show it.
  std::vector<double> stability, stability_tol;
  std::vector<double> load;  // applied nodal forces at full value (N), 3 per node
  sdk::large_vector<double> f_con;  // contact forces (N)
  std::vector<double> k_contact;     // contact stiffness bound (N/m)
  // The arrays every step streams through: on huge pages where the system
  // offers them (sdk/memory.hpp).
  sdk::large_vector<double> v, f_int, elem_sqrt_scale, node_temperature;
  // The faces' temperatures the contact handlers see (ContactForceInput::
  // face_temperature): bottom and top per node, degC.
  std::vector<double> face_temperature;
  bool scaled = false;  // some elem_sqrt_scale is not 1 (else the elements get no step factors)
  std::vector<double> mass, mass_node_physical, elem_dt, elem_scale, stress;
  // Half of the next step's internal, external, damping and contact works,
  // known at this step (see integrate_body).
  double pending_work[4] = {0, 0, 0, 0};
  // With solvers.mechanics.damping_direction "normal": each node's
  // unit normal (from the sum of its triangles' (x1 - x0) x (x2 - x0) at
  // t^n) and the part of its velocity v^{n-1/2} along it, per dof, which
  // the damping acts on.
  std::vector<double> node_normal, normal_velocity;
  // ... and each node's triangles (CSR: node_tri[node_tri_start[i] ..
  // node_tri_start[i + 1]) in ascending order), with each triangle's
  // (x1 - x0) x (x2 - x0).
  std::vector<int> node_tri_start, node_tri;
  std::vector<double> tri_cross;
  // Per element block, reused every step.
  std::vector<int> block_fail;
  std::vector<std::string> block_error;
  // Element blocks: the partition follows the element count only, never the
  // thread count, so the results are the same for any number of threads.
  int block_size = 0, blocks = 0;
  int passes = 1;  // the element's passes over the blocks per force evaluation
  // In the one-thread order (Simulation::one_thread_order): the blocks
  // whose values between passes may be needed at once
  // (ElementForceInput::pass_window), 0 for no bound below the block count.
  int pass_window = 0;
  std::vector<double> block_dt;
  // The bending's own stable steps (mass scaling included): per block from
  // the last evaluation with bending, and their smallest.
  std::vector<double> block_bdt;
  double bend_dt = std::numeric_limits<double>::infinity();
  // Node forces of each block, added by the element into the block's own
  // slots (ElementForceInput::patch_slot): the local nodes of block b are entries
  // block_node_start[b] .. block_node_start[b + 1] of block_node (ascending
  // global ids); slot_local holds each element slot's local index (-1: no
  // node). A node of one block only is written to f_int by that block; a
  // node shared by several blocks is summed after them, in block order:
  // the forces of shared node s from its blocks are entries shared_start[s]
  // .. shared_start[s + 1] of block_force (3 values each), and local slot l
  // writes entry shared_entry[l] (-1 for a node of one block only).
  std::vector<int> block_node_start, block_node, shared_node, shared_start, shared_entry;
  sdk::large_vector<int> slot_local;
  std::vector<double> block_force;
  std::vector<char> fixed;          // 3 per node
  std::vector<int> edge_condition;  // 3 per element (sdk::kEdgeFree / kEdgeClamped)
  std::vector<int> constraint_of;   // 3 per node: index of the constraint holding the dof, -1 if none
  std::vector<double> prescribed;   // 3 per node: velocity where fixed (0 for fix / symmetry)
  // Per dof, for the integration's vector pass: mass (negated where held or
  // driven) and gravity force; the held or driven dofs in ascending order.
  sdk::large_vector<double> mass3, gravity3;
  std::vector<int> fixed_dofs;
  bool external = false;  // gravity or applied loads act on the part
  double mass_physical = 0, mass_added = 0;
  double mass_added_contact = 0;  // the part of mass_added that the contact springs asked for
};

struct PartState {
  const PartDef* def = nullptr;
  ShellMesh mesh;
  std::vector<double> x0, fibre, area, normals, displacement, shear_angle, contact_status;
  // Per node, Pa: the largest contact pressure on its faces at the last
  // contact force evaluation (only where a field or probe asks for it).
  std::vector<double> contact_pressure;
  sdk::large_vector<double> x;  // positions (m), on huge pages where offered (sdk/memory.hpp)
  int nz = 1;
  std::vector<double> T, cap, mean, top, bottom;
  // A specific heat that depends on the temperature (empty: constant), and
  // the temperatures before the thermal step under way (solve/heat_capacity.hpp).
  HeatCapacityTable cp;
  std::vector<double> T_step;
  // A conductivity that depends on the temperature (empty: constant) and
  // its values at the temperatures of the step's start, 3 per value
  // (solve/conductivity.hpp).
  ConductivityTable kt;
  std::vector<double> k_field;
  // The matrix's crystallisation (solve/crystallisation.hpp; empty: none):
  // per value, the Nakamura integral theta (-1 after a melting: the
  // integral of X, taken when the value next crystallises) and the
  // relative crystallinity X; per node, X's mean through the thickness (for the frames); and the
  // specific heat the latent heat is given with where c is constant (J/(kg K)).
  CrystallisationKinetics kin;
  std::vector<double> theta, X, X_mean;
  double c_latent = 0;
  std::vector<double> h_bottom, t_bottom, h_top, t_top;
  // Per node, W/(m^2 K): the conductance of each face at the last thermal
  // step (tool contact, convection and radiation, ply/ply links per unit
  // area), for the field and probe quantity `conductance`.
  std::vector<double> conductance_bottom, conductance_top;
  // Per node, m: the gap from the ply's face to the nearest of its tools
  // (Simulation::update_tool_gap), for the field and probe quantity `tool_gap`.
  std::vector<double> tool_gap;
  // Per element, m: the thickness at constant volume (the job's thickness
  // times the element's initial area over its area; Simulation::
  // update_element_fields), for the field and probe quantity `thickness`;
  // area0 the initial areas (both empty unless asked for).
  std::vector<double> thickness, area0;
  // Per node, s: the first time a value of the node, and every value, was
  // below output.temperature_threshold (NaN: not yet), for the field
  // `below_threshold_from` (empty unless asked for).
  std::vector<double> below_from, all_below_from;
  // degC: the initial temperature (with initial temperatures from a results
  // file, their mean by heat capacity), for the laws probed at set-up.
  double t0 = 20.0;
};

namespace detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A number as the messages give it (%g with prec digits).
inline std::string fmt_g(double v, int prec = 6) {
  std::ostringstream s;
  s << std::setprecision(prec) << v;
  return s.str();
}

// A vector as the messages give it: "(x, y, z)", 4 digits each.
inline std::string fmt_vec3(double x, double y, double z) {
  return "(" + fmt_g(x, 4) + ", " + fmt_g(y, 4) + ", " + fmt_g(z, 4) + ")";
}

// The mean through the thickness h of a node's nz values (linear between
// them), or its one value.
inline double thickness_mean(const double* v, int nz, double h) {
  if (nz == 1) return v[0];
  const double e = h / (nz - 1);
  double s = 0;
  for (int k = 0; k < nz; ++k) s += (k == 0 || k == nz - 1 ? 0.5 * e : e) * v[k];
  return s / h;
}

// Progress on the terminal (a line rewritten in place) or, in a log or a
// batch queue's output, a line at every tenth of the run.
struct Progress {
  bool tty = false, quiet = false;
  double t_end = 1;
  Clock::time_point start = Clock::now(), last = start;
  int last_decile = -1;
  void update(double t, long long steps, bool force = false);
};

}  // namespace detail

// The output.fields of the run that wrote a checkpoint (the job's default
// where it gives none).
std::vector<std::string> checkpoint_fields(const Checkpoint& c);

// One call of Simulation::run(): the loop's state (what a checkpoint keeps
// of it, run_io), the output files and the tables of the time series. The
// set-up opens the output (or, for a restart, checks and reopens it); the
// loops advance the model; finish() writes what is left and the summary.
struct Simulation::Run {
  Run(Simulation& sim, const RunOptions& opt, detail::Clock::time_point wall0, int threads, const char* subnormals);

  Simulation& sim;
  const Job& job;
  const RunOptions& opt;
  RunResult result;
  const detail::Clock::time_point wall0;
  const int threads;
  const char* subnormals;  // the mode of the subnormal numbers, in words

  // A restart: the loop's state as the checkpoint left it (read by
  // restore(), after the set-up), the frames it kept and the lengths of the
  // time series files then.
  std::optional<sdk::StateReader> resume;
  double resume_t = 0;     // s, the checkpoint's time
  double wall_before = 0;  // s, a restart: the wall time of the run up to its checkpoint (all its earlier parts)
  std::vector<double> frame_times;           // of the frames written (for checkpoints)
  std::uint64_t csv_size[4] = {0, 0, 0, 0};  // probes.csv, energy.csv, tools.csv, plies.csv

  // Output (run_output.cpp).
  std::unique_ptr<ResultsWriter> writer;
  double frame_bytes = 0;  // the values of a frame in results.h5 (results_bytes)
  std::ofstream probes_csv, energy_csv, tools_csv, plies_csv;
  std::vector<double> energy_rows;  // the energy.csv table, also written to results.h5
  std::vector<double> tool_rows;    // the tools.csv table (wide), also written to results.h5
  std::vector<double> ply_rows;     // the plies.csv table (wide), also written to results.h5
  std::vector<std::string> energy_cols, tool_cols, ply_fields, ply_cols;
  std::size_t ply_per = 0;  // values per ply in a row of ply_rows
  bool threshold = false, shear_limit = false;  // output.temperature_threshold / shear_angle_limit given
  bool ply_series = false;                      // plies.csv is written (thermal or mechanics)
  bool crystallising = false;                   // some ply's material crystallises (the thermal solver on)
  // The elements' shear angles, strains and thicknesses at constant volume
  // at a row, and their initial areas (the weights of the share beyond the
  // limit), per mechanics part.
  std::vector<std::vector<double>> row_shear, row_strain, row_thickness, elem_area;
  // The elements' long-term stiffness q at a row, its tolerance and the
  // angle of the worst direction (stability.hpp), per mechanics part.
  std::vector<std::vector<double>> row_q, row_tol, row_theta;
  // At the end: each ply's share beyond the shear limit, and (with the
  // thermal solver) its coldest, mean and hottest value and share below the
  // threshold (ply_temperature).
  std::vector<double> over_end;
  // At the end: each ply's share of its area whose long-term response is
  // unstable, and the smallest q (N/m), per mechanics part.
  std::vector<double> unstable_end, stability_min_end;
  // At the end: each ply's thinnest and thickest element at constant volume (m).
  std::vector<std::array<double, 2>> thickness_end;
  std::vector<std::array<double, 4>> ply_end;

  // The loop.
  const double t_end, interval;
  const double eps_t;  // a billionth of the thermal step (or of the frame interval without thermal)
  double t = 0;
  long long steps = 0;  // thermal steps
  double stored0 = 0;
  std::vector<double> stored0_part;
  double heat_in = 0;
  int substeps_max = 1;
  long long limited_total = 0;
  std::vector<double> next_probe;
  long long frame_index = 1;
  detail::Progress progress;
  std::vector<std::span<double>> Tspans;
  sdk::ThermalStepInput in;
  EnergyAudit audit;
  long long mech_steps = 0;
  double mech_dt = 0;
  std::string failure;
  int stop_signal = 0;  // the signal of a stop request, once the loop has seen it
  double frame_t = 0;   // time of the last frame written
  // The mechanics loop's own state (explicit dynamics; the thermal
  // splitter advances over the time elapsed since its last step, at the
  // first mechanical step at or after each multiple of the thermal step,
  // or every `subcycle` mechanical steps where the job sets it).
  double t_thermal = 0;
  double t_sampled = 0;  // the last contact sample (solvers.thermal.contact_samples), or thermal step
  long long since_thermal = 0;
  int subcycle = 0;
  double stable = 0;
  double next_sample = 0, audit_scale = 0, supplied_max = 0;
  const double series_iv;  // s between the rows of energy.csv, tools.csv and plies.csv
  // What a failed audit blames: an unstable step, or a start with loaded
  // contact springs, whose release at once the audit cannot follow.
  std::string unstable = "the run is unstable (step too large?)";
  // Checkpoints: the run's state after a step (the loop's, the kernel's,
  // the plugins'), with the frames and the time series so far.
  const double checkpoint_iv;
  double next_checkpoint = std::numeric_limits<double>::infinity();
  double restarted_from = -1;  // s, a restart's checkpoint time
  double checkpoint_at = -1;   // s, the time of the output folder's checkpoint (written or continued from)
  detail::Clock::time_point last_checkpoint_wall;
  // The end checkpoint (output.checkpoint_at_end): the state before the
  // first step that depends on time.end (the mechanical steps that land on
  // it, a thermal step cut short by it), or the end state where none did.
  // A later time.end continues from it as a run to that end would have.
  bool landing_saved = false;

  // run.cpp
  void read_checkpoint();  // a restart: the checkpoint's run section, checked against the output folder
  // A restart: the loop's and the model's state from the checkpoint (before
  // the output is opened: a checkpoint that does not fit is refused with
  // the folder as it was), and what it changed, into restore_log.
  void restore();
  void log_restore() const;  // restore_log into the log, after the run's first lines
  std::vector<std::string> restore_log;
  void start();            // a new run: the first frame, rows and probe samples
  void mechanics_loop();
  void thermal_loop();
  void finish_interrupted();  // a stopped run: the state reached, as a last frame, rows and samples
  bool checkpoint_due(int stop_seen) const;
  bool thermal_due(double next_dt) const;  // a thermal step at t, the next mechanical step being next_dt
  void save_checkpoint(const char* what = "");
  void end_checkpoint(const char* what);
  template <class A>
  bool probes_io(A& a);
  template <class A>
  bool run_io(A& a);

  // run_output.cpp
  void open_output();  // results.h5, job_as_run.json and the time series files, with their columns
  void open_series(std::ofstream& out, const char* name, int k, const std::string& header);
  void log_start() const;
  void update_derived();
  void write_frame(double time);
  void sample_probes(double time, std::size_t only = static_cast<std::size_t>(-1));
  void sample_tools(double time);
  void sample_plies(double time);
  void sample_energy();
  std::array<double, 9> ply_mechanics(std::size_t p, double time);
  std::optional<double> threshold_of(std::size_t p) const;
  std::pair<double, double> quasi_static() const;
  void finish();  // the tables into results.h5, the result, summary.json and the log's last lines
  // Writes summary.json; false where it could not be written (its reason in `why`).
  bool write_summary(std::string& why) const;
  // Throws RunError naming the first time series file that could not be
  // written (a full disk), after flushing them.
  void check_series_files();
  // Throws RunError where the output folder's device has too little space
  // left for the frame about to be written at `time` and what the run
  // writes after it (a frame written half way can leave results.h5
  // unreadable; stopped before it, the file holds every frame so far).
  void check_space(double time) const;
  // Logs what the frames will take (Simulation::output_lines) and warns
  // where that is more than the output folder's device has free. Not for
  // a restart.
  void announce_output(double mech_step) const;
  void log_end() const;
};

}  // namespace ts
