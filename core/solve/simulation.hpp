#pragma once
// A job turned into a runnable model: meshes, tools, plugins, state arrays,
// and the time loop. Construction validates everything a run needs (throws
// JobError); run() integrates and writes the output folder.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <thermostamp/sdk/plugin.hpp>

#include "io/checkpoint.hpp"
#include "io/results_writer.hpp"
#include "job/job.hpp"
#include "mesh/shell_mesh.hpp"
#include "plugins/registry.hpp"

namespace ts {

struct RunOptions {
  std::filesystem::path out_dir;
  int threads = 0;        // 0: OpenMP default
  bool quiet = false;
  bool write_files = true;
  bool flush_subnormals = true;  // subnormal numbers flushed to zero during the run (solve/subnormals.hpp)
  // Continue the run whose checkpoint this is (io/checkpoint.hpp; checked
  // with Simulation::check_restart) in out_dir, which holds that run's
  // output: its frames and time series up to the checkpoint are kept.
  const Checkpoint* restart = nullptr;
  // The file `restart` was read from, where it is a kept checkpoint
  // (DIR/checkpoints/..., `thermostamp run --restart-at`): once the run has
  // opened its output, it becomes DIR/checkpoint.bin and the kept
  // checkpoints after it are removed (they continued other frames).
  std::filesystem::path restart_kept;
  // Also write a checkpoint whenever this much wall time (s) has passed
  // since the run's start or its last checkpoint; 0: not by wall time.
  double checkpoint_wall_s = 0;
};

struct ProbeSample {
  int probe = 0;
  double time = 0;
  std::string quantity;
  std::vector<double> z;       // empty for scalars
  std::vector<double> values;  // one per z (or one)
};

struct EnergyAudit {
  double kinetic = 0, internal = 0, external = 0, damping = 0, balance_error = 0;
  double contact = 0;         // energy taken from the plies by contact forces (penalty storage + friction - tool work)
  double contact_stored = 0;  // elastic energy in the penalty springs, current
  double kinetic_half = 0;    // 1/2 m v^{n+1/2}^2 (never negative; the growth check uses it)
  std::vector<double> added_mass_percent;  // per part, from mass scaling
  std::vector<double> reactions;           // 3 per constraint: force the constraint applies to the plies (N), last step
  std::vector<double> tool_forces;         // 3 per tool: force of the plies on the tool (N), last step
  std::vector<double> tool_displacements;  // 3 per tool (m)
  std::vector<double> tool_heat;           // per tool: heat given to the plies (J)
  // per tool, with mechanics: the largest magnitude of the force of the
  // plies on the tool over the rows of tools.csv (N), and the time of that
  // row (s; the first such row)
  std::vector<double> tool_force_max, tool_force_max_at;
  // per gripper (in the order of the constraints): the largest magnitude of
  // its force on the plies over the rows of energy.csv (N) and the time of
  // that row (s; the first such row)
  std::vector<double> gripper_force_max, gripper_force_max_at;
};

// One line on a material's crystallisation kinetics (for the log and
// `thermostamp validate`), with the temperature at which it is half
// crystallised when cooled at 10 K/min.
std::string describe_crystallisation(const MaterialDef& m);

struct RunResult {
  bool ok = true;     // false: the run failed (error says why) or was interrupted
  int interrupted = 0;  // the signal that stopped the run early (see solve/interrupt.hpp), 0 if none
  std::string error;
  double wall_time_s = 0;  // s, of this run (a restarted run: of its continued part)
  // s, a restarted run: the wall time of the run up to its checkpoint (over
  // all its earlier parts); 0 for a run from the start.
  double wall_time_before_s = 0;
  // s, the time of the checkpoint the output folder holds after the run
  // (written by it, or the one it continued from); -1 where it holds none.
  double checkpoint_s = -1;
  // The process's peak resident memory at the end of the run (MB; 0 where
  // the system does not report it). Over the process's life: in a study,
  // the largest of the runs so far.
  double peak_memory_mb = 0;
  double simulated_time_s = 0;
  long long thermal_steps = 0;
  double thermal_dt = 0;
  double heat_in = 0, stored_change = 0, heat_balance_error = 0;
  std::vector<double> part_heat_change;  // per part: stored heat change (J)
  std::vector<double> part_link_heat;    // per part: heat received through ply/ply contact (J)
  // per part: heat received from the tools and from the heat exchanges (J)
  std::vector<double> part_tool_heat, part_exchange_heat;
  double heat_from_tools = 0, heat_from_exchanges = 0;  // J, over the parts
  // the heat by source was taken at the end-of-step face values in some
  // thermal step (a splitter that does not report its face values)
  bool heat_sources_at_step_end = false;
  std::vector<double> part_shear_min_deg, part_shear_max_deg;  // per part, mechanics only: shear angle range at the end
  // per part, mechanics only: the range of E11 (membrane strain along the initial fibre direction) at the end
  std::vector<double> part_fibre_strain_min, part_fibre_strain_max;
  // per part, mechanics only: the range of the thickness at constant volume (m) at the end
  std::vector<double> part_thickness_min_m, part_thickness_max_m;
  double temperature_min = 0, temperature_max = 0;  // over every value and every step
  // The plies' history (plies.csv): one row per sample, by part.
  struct PlySample {
    int part = 0;
    double time = 0;
    // with thermal:
    double min = 0, mean = 0, max = 0;  // degC; the mean weighted by heat capacity
    double fraction_below = 0;          // of the heat capacity below output.temperature_threshold (0 without one)
    // relative crystallinity, with a ply of a crystallising material (NaN
    // for a ply without)
    double crystallinity_min = std::numeric_limits<double>::quiet_NaN(),
           crystallinity_mean = std::numeric_limits<double>::quiet_NaN(),
           crystallinity_max = std::numeric_limits<double>::quiet_NaN();
    // with mechanics:
    double shear_min = 0, shear_max = 0;                // shear angle (degrees), over the elements
    double fibre_strain_min = 0, fibre_strain_max = 0;  // E11, over the elements
    double fraction_over_shear_limit = 0;  // of the initial area with |shear angle| > output.shear_angle_limit
    double fraction_unstable = 0;          // of the initial area where the long-term response is unstable
    double stability_min = 0;              // the smallest long-term stiffness q (N/m), over the elements
    double thickness_min = 0, thickness_max = 0;  // the thickness at constant volume (m), over the elements
    // with thermal: the heat received so far from the tools, the heat
    // exchanges and the other plies (J)
    double heat_from_tools = 0, heat_from_exchanges = 0, heat_from_plies = 0;
  };
  std::vector<PlySample> ply_history;  // a restarted run: those before its checkpoint too
  // per part, with output.temperature_threshold: the first time (s) a value
  // of the ply was below it (checked at every thermal step; -1: never)
  std::vector<double> part_below_threshold_from_s;
  // per part, with output.temperature_threshold: the first time (s) every
  // value of the ply was below it (checked at every thermal step; -1: never)
  std::vector<double> part_all_below_threshold_from_s;
  // per part, with output.shear_angle_limit: the first row (s) at which an
  // element of the ply was sheared beyond it (-1: never)
  std::vector<double> part_over_shear_limit_from_s;
  // per part, mechanics only: the first row (s) at which the long-term
  // response of an element of the ply was unstable (-1: never)
  std::vector<double> part_unstable_from_s;
  long long limited_node_steps = 0;  // bound-preserving corrections of the splitter
  std::vector<ProbeSample> probes;  // every sample (a restarted run: those before its checkpoint too)
  long long mechanical_steps = 0;
  double mechanical_dt = 0;  // last step
  // With bending_subcycles > 1: the evaluations that carried the bending,
  // and the most steps one of them stood for.
  long long bending_evaluations = 0;
  int bending_largest = 1;
  EnergyAudit energy;
};

struct PartState;
class RigidTool;
struct MechPart;



class Simulation {
 public:
  Simulation(const Job& job, PluginRegistry& registry);
  ~Simulation();
  RunResult run(const RunOptions& options);
  std::vector<std::string> plugins_loaded() const { return registry_.loaded_names(); }
  // The steps a run starts with (s): the mechanical one (dt_safety times the
  // stable step of the initial configuration, mass scaling included; 0
  // without mechanics) and the thermal one (0 without thermal). Before run().
  double initial_mechanical_step();
  double thermal_step() const { return thermal_dt_; }
  // One line per part meshed from a file (its counts, the file, its order
  // (mesh.reorder) and how far apart neighbouring triangles are) and per
  // meshed tool (RigidTool::describe()).
  std::vector<std::string> mesh_file_lines() const;
  // One line per tool that moves (with mechanics): its velocity, the first
  // and last rows of its displacement table, or its force, mass and damper.
  std::vector<std::string> tool_motion_lines() const;
  // A line per gripper: its nodes, spring and preload (validate, the log).
  std::vector<std::string> gripper_lines() const;
  // What the frames of results.h5 will take: their number and times, the
  // bytes of each and of all (before compression). mech_step: the
  // mechanical step at the start (s; 0 without mechanics), below which
  // output.interval gives a frame after every step.
  std::vector<std::string> output_lines(double mech_step) const;
  // The bytes of all the frames a run from the start writes, with what
  // results.h5 holds once (before compression); mech_step as above.
  double results_estimate(double mech_step) const;
  // The number of frames a run from the start writes at output.interval:
  // t = 0, each multiple of it and time.end (with the mechanics, at most
  // one a step).
  double frame_count() const;
  // frame_count(), or with the mechanics and output.interval below
  // mech_step, about one a step.
  double frames_expected(double mech_step) const;
  // results.h5's parts, the fields of a frame per part (with their
  // values) and the tools' surfaces (output.tool_surfaces; none without).
  std::vector<WriterPart> writer_parts() const;
  std::vector<std::vector<FrameField>> frame_fields() const;
  // The same for other output.fields (those of a checkpointed run).
  std::vector<std::vector<FrameField>> frame_fields(const std::vector<std::string>& names) const;
  std::vector<WriterTool> writer_tools() const;
  // Heat stored in the plies, J, relative to 0 degC (sum of capacity x temperature;
  // with a specific heat table, of mass x int_0^T c).
  double stored_heat() const;
  double stored_heat(int part) const;
  // Replaces the initial temperature of a part by one value per node
  // (uniform through the thickness), before run().
  void set_initial_temperature(int part, std::span<const double> per_node);
  int num_parts() const { return static_cast<int>(parts_.size()); }
  // Current temperature of a part (values_per_node per node, bottom to top).
  std::span<const double> temperature(int part) const;
  // Current relative crystallinity of a part, as temperature() (empty where
  // its material has no crystallisation kinetics).
  std::span<const double> crystallinity(int part) const;
  int values_per_node(int part) const;
  // Initial mid-surface coordinates of a part, 3 per node.
  std::span<const double> initial_coordinates(int part) const;
  // Throws JobError (one line) where a checkpoint cannot continue this job:
  // written by another job (time.end and the checkpoint settings aside), or
  // not before this job's time.end. Returns the time it was written at (s).
  double check_restart(const Checkpoint& c) const;

 private:
  // One call of run(): its loop, checkpoints and output (solve/simulation_internal.hpp).
  struct Run;
  void build_parts();
  void build_tools();
  // Where a run that goes unstable is fastest: the node of the plies with
  // the largest half-step speed, its part, position, initial position and
  // speed ("node 12 of part 'ply' at (x, y, z) m, ..."; empty without
  // mechanics).
  std::string fastest_node() const;
  void warn_plies_behind_tools() const;
  void warn_large_meshes() const;
  void refuse_impossible_plies() const;
  void warn_unlikely_units() const;
  void build_thermal();
  // A specific heat table (solve/heat_capacity.hpp) or crystallisation
  // kinetics (solve/crystallisation.hpp): the temperatures before a thermal
  // step, and the enthalpy correction and crystallisation after it; a
  // conductivity table (solve/conductivity.hpp): its values at the
  // temperatures before the step.
  void keep_step_temperatures();
  void finish_thermal_step(double dt);
  void build_probes();
  void build_mechanics();
  // One explicit step of every part; returns the step taken.
  double mechanics_step(double dt, double t, long long step, EnergyAudit& audit);
  double mechanics_stable_dt();
  void check_initial_step(int limiting_tool, double tool_stiffness) const;
  double with_contact_springs(double dt) const;
  // interleaved: called in the one-thread order (one_thread_order), which
  // the element learns through ElementForceInput::pass_window.
  void element_block(std::size_t part, int block, int pass, bool interleaved);
  double finish_elements();
  double forces_and_stable_dt(double t, double dt);
  void update_node_temperature();
  void check_law_ranges(double t);
  struct LawUse {
    const sdk::MaterialLaw* law = nullptr;
    std::string pointer, name;
    bool warned = false;
  };
  std::vector<LawUse> law_uses_;
  void update_element_fields();
  // The faces' conditions and the contact map for the thermal step ending
  // at t. With contact samples (sampled >= 0: the time since the last
  // sample, which this call takes at t), the conductance of each tool
  // contact and link is its mean over the samples of the step, weighted by
  // the time each stands for; without (sampled < 0), the map at t.
  void assemble_faces(double t, double sampled = -1);
  // A contact sample at t standing for the last w seconds (between two
  // thermal steps; assemble_faces takes the last one).
  void sample_contacts(double t, double w);
  // Every contact handler's thermal contacts at t, into out (cleared first).
  void thermal_contacts(double t, sdk::ThermalContactMap& out);
  // The far temperatures of the faces over the thermal step [t0, t1]:
  // tools whose temperature follows rows (their mean over the step, into
  // the tool views and the faces touching them), and the faces of heat
  // exchanges that follow ambient rows or radiate (not covered by a tool
  // contact; exchange_faces_): the ambient's mean over the step and the
  // conductance h + eps sigma (T^2 + Ta^2)(T + Ta) (kelvin) at the face's
  // present temperature. After every assemble_faces().
  void update_far_temperatures(double t0, double t1);
  // The faces' conductances (conductance_bottom / _top of the parts) from
  // the last assembled faces and ply/ply links.
  void update_face_conductance();
  // The parts' tool_gap: per node, the signed distance (m) from the ply's
  // mid-surface to the nearest surface of the tools it has contact pairs
  // with (of every tool where it has none), less half the thickness: the
  // gap between the face and the tool, negative where the face is inside
  // it; gaps beyond kToolGapLimit are shown as kToolGapLimit.
  void update_tool_gap();
  std::vector<int> gap_tools(int part) const;
  void tool_gaps(int part, std::size_t n, const double* x, double* gap) const;
  static constexpr double kToolGapLimit = 0.01;  // m
  bool want_tool_gap_ = false;  // the field `tool_gap` is written
  bool want_below_from_ = false;  // the field `below_threshold_from` is written
  bool want_thickness_ = false;   // the field or a probe quantity `thickness` is written
  // The initial temperatures of a part from a frame of an earlier run
  // (PartDef::initial_results); JobError where that cannot be done.
  void load_initial_temperature(PartState& st);
  bool want_conductance_ = false;  // the field `conductance` is written
  void check_field(double time, long long step);
  // The kernel's and the plugins' state between two steps, for checkpoints
  // (sections "kernel" and "plugin/..."; run() adds its loop's state).
  void save_state(Checkpoint& c);
  void load_state(const Checkpoint& c);
  template <class A>
  bool state_io(A& a);
  double seen_min_ = 0, seen_max_ = 0;
  std::vector<double> below_from_;  // per part: first time below output.temperature_threshold (s), -1: not yet
  std::vector<double> all_below_from_;  // per part: first time all of it was below the threshold (s), -1: not yet
  std::vector<double> over_from_;   // per part: first row beyond output.shear_angle_limit (s), -1: not yet
  std::vector<double> unstable_from_;  // per part: first row with a long-term unstable element (s), -1: not yet
  double last_mech_dt_ = 0;
  // Whether the element fields that only output frames show (stresses,
  // curvatures) are written after the force evaluation being done
  // (ElementForceInput::fields_due).
  bool fields_due_ = true;
  bool want_element_dt_ = false;  // the elements' own stable steps, for the mass scaling at set-up
  // A frame field or a probe asks for the contact pressure
  // (PartState::contact_pressure), and a frame or such a probe follows the
  // next contact force evaluation: only then do the handlers get arrays
  // for it (ContactForceOutput::pressure).
  bool want_pressure_ = false, pressure_due_ = true;
  std::vector<char> probe_pressure_;               // per probe: it records contact_pressure
  std::vector<std::vector<double>> pressure_sum_;  // per part, scratch of update_contact_fields()
  void update_contact_fields();
  // Raised whenever the node temperatures the elements see change
  // (ElementForceInput::temperature_version; 0 before the first).
  std::uint64_t temperature_version_ = 0;
  // The time of the positions whose forces are being formed (messages).
  double forces_t_ = 0;
  // Bending evaluated less often than the membrane (bending_subcycles):
  // the weight of the coming evaluation's bending forces, the evaluations
  // still to come without bending, how many carried it and the most steps
  // one stood for; the last smallest stable step (finish_elements).
  void choose_bending_weight();
  double bending_weight_ = 1.0;
  int bending_left_ = 0, bending_largest_ = 1;
  long long bending_evaluations_ = 0;
  double last_stable_ = 0;
  std::vector<double> part_sums_;  // per part: works, kinetic energies, reactions of the step (mechanics_step)
  std::vector<int> part_bad_;      // per part: first non-finite coordinate of the step, -1 if none

  const Job& job_;
  PluginRegistry& registry_;
  std::vector<std::unique_ptr<PartState>> parts_;
  std::vector<std::unique_ptr<RigidTool>> tools_;
  std::vector<double> tool_force_;  // 3 per tool: force of the plies on the tool (N), current
  std::vector<double> tool_heat_;   // per tool: heat given to the plies (J), cumulative
  std::vector<double> link_heat_;   // per part: net heat received through ply/ply contact (J), cumulative
  // Per part, cumulative (J): the heat received from the heat exchanges
  // and from the tools.
  std::vector<double> part_exchange_heat_, part_tool_heat_;
  std::vector<std::vector<char>> face_kind_;  // accumulate_face_heat's marks, per part 2 per node
  std::vector<double> block_sums_;            // accumulate_face_heat's sums per block of nodes
  std::vector<double> step_exchange_;         // accumulate_face_heat's exchange per part over the step
  bool face_values_missing_ = false;          // a thermal step's splitter gave no face values
  enum { kTimeElements, kTimeContact, kTimeThermal, kTimeIntegrate, kTimeOutput, kTimeCount };
  double timing_[kTimeCount] = {0, 0, 0, 0, 0};  // wall time per phase of the mechanics loop (s)
  // How forces_and_stable_dt shares out elements and contact (see there):
  // the way chosen, the calls left in the current trial of the ways, the
  // calls so far and at the next trial, the calls made each way, and each
  // way's time and calls in the trial's current round and its best mean
  // time per call over the trial's rounds.
  enum Way { kInTurn, kBeside, kByPart, kWays };
  struct ForceSchedule {
    int way = kInTurn;
    int trial_left = 0;
    long long calls = 0, next_trial = 0;
    long long way_calls[kWays] = {0, 0, 0};
    double time[kWays] = {0, 0, 0};
    long long count[kWays] = {0, 0, 0};
    double best[kWays] = {0, 0, 0};
    int pending_way = -1;  // a trial's call whose time runs until the next call starts
    std::chrono::steady_clock::time_point pending_start;
    // element_passes: the element blocks of each pass in order, (part,
    // block), and per pass the next block to claim and the blocks done.
    std::vector<std::vector<std::pair<int, int>>> work;
    // The evaluations of a step on one thread in their order
    // (one_thread_order): pass `pass` of block `block` of part `part`.
    struct Step {
      int part = 0, block = 0, pass = 0;
    };
    std::vector<Step> one_thread;
    struct alignas(64) Counter {
      std::atomic<int> value{0};
    };
    std::unique_ptr<Counter[]> claimed, done;
    // by_part: the thread that owns each part (its element blocks, the
    // contact tasks that move its nodes, its integration), for `team` threads.
    std::vector<int> part_thread;
    int team = 0;
  } schedule_;
  double contact_energy_ = 0;       // penalty energy stored, current
  struct Load {
    double ramp = 0;                            // s
    std::vector<std::pair<int, int>> nodes;     // (part, node) in the box
    std::array<double, 3> per_node{0, 0, 0};    // N, at full value
  };
  std::vector<Load> loads_;                     // `force` entries of the constraints
  // `gripper` entries of the constraints: a spring from an anchor to the
  // centre of the gripped nodes, whose force they share by their mass.
  struct Gripper {
    int constraint = 0;                         // index in job.constraints
    std::vector<std::pair<int, int>> nodes;     // (part, node) in the box
    std::vector<double> share;                  // each node's share of the force (its mass over theirs)
    double mass = 0;                            // kg, of the gripped nodes (physical)
    double length0 = 0;                         // m, the spring's length at t = 0
    // At the last step: the force on the plies (N), the spring's tension
    // (N) and extension (m), the gripped nodes' centre (m).
    std::array<double, 3> force{0, 0, 0}, centre{0, 0, 0};
    double tension = 0, extension = 0;
    // Rigid jaws: the directions in which a gripped node is held (by a
    // symmetry plane or a `fix`), which hold the whole jaw, and the
    // constraint that holds it in each (-1: free).
    std::array<int, 3> held_by{-1, -1, -1};
    std::vector<std::vector<int>> part_nodes;  // rigid jaws: per part, its gripped nodes
    // Swivelling jaws: the symmetry planes (by normal) that a gripped node
    // lies on, which allow the jaw only to turn about their normals; the
    // first gripped node held otherwise (part, node; -1: none), about
    // which the jaw turns; the jaws' size (m); the origin at t (m).
    std::array<bool, 3> on_symmetry{false, false, false};
    int pin_part = -1, pin_node = -1;
    double size = 0;
    std::array<double, 3> origin{0, 0, 0};
  };
  std::vector<Gripper> grippers_;
  bool rigid_jaws_ = false;       // a gripper has rigid (or swivelling) jaws
  bool swivelling_jaws_ = false;  // a gripper has swivelling jaws
  std::vector<double> jaw_solution_;  // per thread and gripper: a swivelling jaw's (V, phi) this step
  std::vector<double> jaw_sums_;  // per part and gripper: its share of a rigid jaw's sums (kJawSums)
  static constexpr std::size_t kJawSums = 72;  // swivelling: moments, p, C (swivel_jaw_sums); rigid: the first 6
  // Each gripper's force on the plies at t, added to the parts' loads.
  void apply_grippers(double t);
  // Rigid jaws at t: part p's share of each jaw's momentum and mass; then
  // to its gripped nodes' loads the forces that give them the jaw's
  // velocity, and the held directions' supports to its reactions.
  void rigid_jaw_sums(int p, double t, double dt_avg);
  void tie_rigid_jaws(int p, int slot, double t, double dt, double dt_avg, double* reactions);
  // Swivelling jaws: part p's share of the sums; each jaw's (V, phi) from
  // every part's (into the thread's slot of jaw_solution_); the ties.
  void swivel_jaw_sums(const Gripper& g, const MechPart& m, const double* x, const std::vector<int>& nodes,
                       double dt_avg, bool normal_damping, bool contact, double* sums) const;
  void solve_swivelling_jaw(const Gripper& g, std::size_t gi, double dt, double* solution) const;
  void solve_swivelling_jaws(int slot, double t, double dt);
  void tie_swivelling_jaw(const Gripper& g, const double* solution, int p, double dt, double dt_avg,
                          double* reactions);
  std::string jaw_words(const Gripper& g) const;
  double contact_dt_ = std::numeric_limits<double>::infinity();  // contact bound of the stable step
  double tool_dt_ = std::numeric_limits<double>::infinity();     // force-controlled tools' bound
  long long contact_active_ = 0;
  // The contact forces as tasks: a pair, or one side of a ply/ply pair
  // whose handler splits it (ContactHandler::sides). A task adds its forces
  // on the part whose nodes it moves (its owner) into that part's f_con, and
  // those on the pair's other part into an array of its own, which the other
  // part's integration adds in task order: the same sums in the same order
  // whichever thread runs which task.
  struct ContactTask {
    int contact = 0, side = -1;
    int owner = 0, other = -1;     // parts (-1: a tool)
    std::vector<double> cross;     // 3 per node of `other`
    std::vector<double> cross_status;    // per node of `other` (isothermal runs)
    // What the handler adds to the contact pressure of `owner` and `other`
    // (where PartState::contact_pressure is written).
    std::vector<double> own_pressure, cross_pressure;
    std::vector<double> tool_force;      // 3 per tool
    std::vector<std::span<double>> force, status, pressure;  // per part, the views given to the handler
    double energy = 0;
    long long active = 0;
    std::exception_ptr error;
    // by_part, where `other` is integrated on another thread than the one
    // running the task: the task reads `other`'s positions and velocities
    // from that part's exchange copies (views, vel), and hands its forces
    // on `other` over through cross_out, written with streaming stores
    // (published: cross_out holds this step's forces, else cross does).
    std::vector<sdk::PartView> views;
    std::vector<std::span<const double>> vel;
    std::vector<double> cross_out;
    bool published = false;
  };
  std::vector<ContactTask> contact_tasks_;
  // Per part read by a contact task of another part's thread: copies of its
  // positions and velocities that its own thread writes with streaming
  // stores at the start of each by_part force phase, so that the other
  // core reads them from memory and this part's own lines stay in its
  // core's cache (a store to a line another core has read waits for that
  // core; docs/benchmarks.md). `round` says which phase the copies are of.
  struct Exchange {
    std::vector<double> x, v;
    alignas(64) std::atomic<long long> round{0};
  };
  std::vector<std::unique_ptr<Exchange>> exchange_;  // per part, null where no task reads it
  long long exchange_round_ = 0;
  bool crosses_threads(const ContactTask& task, int team) const;
  std::vector<std::vector<int>> cross_into_;  // per part: the tasks whose `cross` it receives, in order
  void build_contact_tasks();
  void start_part_contact(int part);
  void run_contact_task(ContactTask& task, double t, double dt);
  void merge_part_contact(int part);
  void compute_contact_forces(double t, double dt);
  void finish_contact_forces();
  struct BesideContact {  // the contact forces at (t, dt) beside the element blocks
    double t = 0, dt = 0;
    bool by_part = false;          // every thread its parts' tasks, else all on the first thread
    double seconds = 0;            // out: the contact's own wall time (the longest of the threads')
    std::exception_ptr error;      // out: what it threw
  };
  void element_passes(BesideContact* contact);
  void part_threads(int team);
  void one_thread_order(int passes);
  int thread_of_part(int part, int team) const;
  struct ContactSpans {  // per part views handed to the contact handlers every step
    std::vector<std::span<const double>> vel, areas, mass, temp;
  } contact_spans_;
  // A report for the splitter's step, with room for the face values.
  sdk::ThermalStepReport thermal_report();
  // The heat through the faces and links over the thermal step just taken,
  // by tool, by part and by source (tools, heat exchanges, links).
  void accumulate_face_heat(double dt, const sdk::ThermalStepReport& rep);
  std::vector<std::vector<double>> face_values_;  // per part, 2 per node: the step's face values (report)
  std::vector<std::span<double>> face_value_spans_;
  std::vector<sdk::PartView> part_views_;
  std::vector<sdk::ToolView> tool_views_;
  std::unique_ptr<sdk::ThermalSplitter> splitter_;
  std::vector<std::unique_ptr<MechPart>> mech_;
  std::vector<std::unique_ptr<sdk::MaterialLaw>> laws_;
  std::vector<std::unique_ptr<sdk::ContactHandler>> contacts_;
  sdk::ThermalContactMap contact_map_;
  // The contact samples of the thermal step under way: each tool contact
  // and link found, in the order first found, its conductance the sum of
  // conductance x the time its samples stand for (the geometry of a link:
  // its last sample's); `time` the time they stand for in all; `touched`
  // and `link_touched`, per tool contact and link of `map`, the time its
  // samples stand for.
  struct ContactSums {
    sdk::ThermalContactMap map;
    std::vector<double> touched, link_touched;
    double time = 0;
    std::unordered_map<std::uint64_t, std::size_t> tool_at, link_at;  // key -> index into map
  } contact_sums_;
  sdk::ThermalContactMap contact_sample_;  // one sample (reused)
  sdk::ThermalContactMap contact_last_;    // the last sample (from the start: the map at t = 0)
  void index_contact_sums();               // contact_sums_'s keys, from its map
  struct ExchangeFace {
    int part = 0, node = 0, face = 0, exchange = 0;  // exchange: index into job_.heat_exchanges
    double scale = 1;  // the share of the face no other ply covers over the step
  };
  std::vector<ExchangeFace> exchange_faces_;  // from assemble_faces
  // Per tool contact and per link of contact_map_: the share of the
  // thermal step its samples found it in contact (1 without samples).
  std::vector<double> contact_touch_, link_touch_;
  // A face whose condition mixes several sources over the thermal step:
  // more than one tool, or a tool for part of the step and its heat
  // exchange for the rest (`free`, the share of the step no tool touched
  // it). Its tool contacts are mixed_contacts_[begin .. end) (indices into
  // contact_map_.tool_contacts); exchange: the index into
  // job_.heat_exchanges of an exchange that radiates or follows ambient
  // rows (renewed at every step), else -1 and the face's constant exchange
  // in h_ex (0 for none, and times the share no other ply covers) and
  // t_ex; scale: that share, for a renewed exchange. The face takes
  // h = sum h_c + free h_ex and the far temperature
  // (sum h_c T_tool + free h_ex T_ambient) / h.
  struct MixedFace {
    int part = 0, node = 0, face = 0, exchange = -1, begin = 0, end = 0;
    double free = 0, h_ex = 0, t_ex = 0, scale = 1;
  };
  std::vector<MixedFace> mixed_faces_;  // from assemble_faces
  std::vector<int> mixed_contacts_;
  // A mixed face's conductance and far temperature, its exchange's
  // conductance being h_ex (W/(m^2 K)) to the ambient t_ex (degC).
  void mix_face(const MixedFace& m, double h_ex, double t_ex);
  std::vector<sdk::FaceConditions> faces_;
  // Per part: its values of a conductivity table at the step's start, or
  // empty (sdk::ThermalStepInput::conductivity); none when no ply has a table.
  std::vector<std::span<const double>> conductivity_;
  std::vector<int> probe_node_;
  std::vector<std::vector<int>> probe_elements_;  // elements around each probe's node
  double thermal_stable_dt_ = 0, thermal_accurate_dt_ = 0, thermal_dt_ = 0;
};

}  // namespace ts
