// thermostamp: the command line. See docs/user-guide.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <boost/dll/runtime_symbol_info.hpp>

#include "commands.hpp"
#include "io/blank.hpp"
#include "io/compare.hpp"
#include "io/export.hpp"
#include "io/logging.hpp"
#include "job/job.hpp"
#include "plugins/describe.hpp"
#include "plugins/registry.hpp"
#include "plugins/schema.hpp"
#include "solve/interrupt.hpp"
#include "solve/simulation.hpp"
#include "version.hpp"

namespace {

constexpr const char* kUsage = R"(usage:
  thermostamp run JOB.json [--out DIR] [--threads N] [--set PATH=VALUE ...] [--quiet] [--keep-subnormals]
                  [--restart | --restart-at T] [--checkpoint-minutes M]
  thermostamp validate JOB.json [--set PATH=VALUE ...]
  thermostamp plugins [--json | --markdown]
  thermostamp schema                 # JSON Schema of job files, from the plugins found
  thermostamp study STUDY.json [--out DIR] [--threads N] [--quiet] [--keep-subnormals]
                  [--restart] [--checkpoint-minutes M]
  thermostamp report DIR [--against OTHER]   # PNG figures into DIR/figures (with OTHER: both runs on the same axes)
  thermostamp compare DIR_A DIR_B [--json] [--rtol R] [--from T]   # how far two runs' results are apart
  thermostamp export DIR [--time T] [--out FOLDER] [--whole] [--format gmsh|abaqus|calculix]   # each ply as a mesh
  thermostamp blank DIR --trim SURFACE [--trim SURFACE ...] [--margin M] [--time T] [--out FOLDER] [--whole]
                  [--roll W [--gap G] [--turn-90] [--parts N]]
                  # cut patterns
  thermostamp --version
)";

// What --help adds to the usage: the options and the exit statuses.
constexpr const char* kDetails = R"(
--keep-subnormals: keep numbers below 2.2e-308 as the processor's slow
subnormals instead of flushing them to zero during the run (the default)
--restart: continue the run from the checkpoint in its output folder
(checkpoint.bin, written when a run is interrupted, every
output.checkpoint_interval, every --checkpoint-minutes and at the end), with
the same job and --set values but for time.end, output.interval,
output.series_interval and output.fields: a later time.end extends a finished
run as a run to it would have gone on, other intervals write the frames and
rows after the checkpoint closer or further apart, other fields are those of
the frames after it; the frames and time series up to the checkpoint are
kept; with study: continue the study in its output folder
(study_state.json), its completed runs not run again, a stopped one from its
checkpoint; the study file may have other variants (new and changed ones
run, dropped ones are left out of study.csv)
--restart-at T: the same from the last checkpoint at or before T s (give or
take T / 1000) that the run kept (output.keep_checkpoints:
DIR/checkpoints/); the frames, rows and kept checkpoints after it are
replaced
--checkpoint-minutes M: also write a checkpoint after every M minutes of
wall time (against machines that go down without a signal)

compare: the largest differences of the probe samples, frame fields and
histories at the same times and the summaries' figures that differ; exit
status 0 when every value compared is equal (with --rtol R: when each
quantity's largest difference is at most R times its largest value in A),
1 otherwise; --from T: only the samples, frames and rows at T s and later
(an extended run against the run to its end: from its restarted_from_s)

export: writes FOLDER/<ply>.msh (default DIR/export) for each ply of the
last frame (with --time T: the frame nearest to T), Gmsh 2.2 ASCII: the
mid-surface at that frame's positions, the frame's node fields as $NodeData
and its element fields (shear angle, fibre direction, stresses, strains,
curvatures) as $ElementData; a mesh file a job can read; --whole: a ply
of a model reduced by symmetry planes mirrored into the whole ply;
--format abaqus: FOLDER/<ply>.inp instead, Abaqus input: the mid-surface
as S3 shells in an element set named after the ply, each element's
fibre direction as an *ORIENTATION (from a distribution), each node's
mean temperature as *INITIAL CONDITIONS and, where the frame has the field
thickness, each node's thickness as *NODAL THICKNESS, for a structural
model; a mesh
file a job can read too; --format calculix: the same for CalculiX (its
distribution of orientations without Abaqus's default line)

blank: the cut pattern of each ply of the last frame (--time T: the frame
nearest to T): the region of the blank (the ply as the run started) that
the forming carries into the part, which lies inside every --trim surface,
given on the formed part in m: plane:X,Y,Z,NX,NY,NZ (a point, and the
normal, which points into the part), cylinder:X,Y,Z,DX,DY,DZ,R (inside; a
point on the axis, its direction, the radius), sphere:X,Y,Z,R (inside) or
polygon:FILE[,SCALE] (inside a trim line, cut along the normal of the
plane it is drawn in: a CSV file, a row x,y per vertex, in plan view, or
the closed polylines of a DXF file, in the plane of their extrusion
direction; SCALE m per unit, for a DXF file from its $INSUNITS);
writes FOLDER/<ply>.csv (default DIR/blank: the pattern's outlines, each
point in the blank and formed), FOLDER/<ply>.dxf where the blank is flat
(the pattern and the blank's outline in its plane, mm) and
FOLDER/blank.json (areas, lengths); --margin M: the trim line moved out by
M m on the formed part (an allowance; below 0, in); --whole: mirrored as
with export; --roll W: also lays each flat pattern on a roll W m wide with
its fibres along the roll, copies in lanes at least G m apart (--gap,
default 0), all alike or in pairs with one turned by 180 degrees where
that saves roll: the lanes, the roll's length per pattern and the share
of the roll used, in blank.json and FOLDER/<ply>_nest.dxf (the layout, mm),
and the roll per part (every ply once, each in lanes of its own);
--turn-90: copies may also be turned by 90 degrees, the weft along the roll
(for a balanced woven roll; a UD tape's fibres would run across it);
--parts N: also the roll a batch of N parts takes (each ply's N patterns on
the shortest stretch of its lanes, one ply after the other), in blank.json
and FOLDER/<ply>_parts.dxf (the batch's patterns, mm)

exit status: 0 success, 2 invalid input (nothing was run), 3 the run failed,
130 / 143 interrupted by SIGINT / SIGTERM (stopped at the end of a step, with a
last frame, a checkpoint and summary.json; a second signal ends it at once)
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Args {
  std::string command;
  std::vector<std::string> positional;
  std::vector<std::string> sets;
  std::string out;
  int threads = 0;
  bool quiet = false, json = false, markdown = false, keep_subnormals = false, restart = false;
  double checkpoint_minutes = 0;
  std::optional<double> restart_at;  // run: continue from the last kept checkpoint at or before it (s)
  double rtol = -1;  // compare: the relative tolerance (-1: exact)
  std::string against;  // report: the other run's folder
  double from = -std::numeric_limits<double>::infinity();  // compare: the first time compared (s)
  std::optional<double> time;  // export: the frame's time (s; the last frame without it)
  bool whole = false;          // export: mirrored at the symmetry planes
  ts::ExportFormat format = ts::ExportFormat::Gmsh;  // export: --format
  std::vector<std::string> trims;    // blank: the --trim surfaces, as written
  double margin = 0;                 // blank: --margin (m)
  std::optional<double> roll;        // blank: --roll, the roll's width (m)
  std::optional<double> gap;         // blank: --gap between copies on the roll (m)
  bool turn_90 = false;              // blank: --turn-90, copies on the roll may be turned by 90 degrees
  int parts = 0;                     // blank: --parts, a batch of that many parts (0: none)
  std::vector<std::string> options;  // the options given, as written (--set once)
};

// The options each command takes; any other is a usage error.
const std::map<std::string, std::vector<std::string>>& command_options() {
  static const std::map<std::string, std::vector<std::string>> m = {
      {"run",
       {"--out", "--threads", "--set", "--quiet", "--keep-subnormals", "--restart", "--restart-at",
        "--checkpoint-minutes"}},
      {"validate", {"--set"}},
      {"plugins", {"--json", "--markdown"}},
      {"schema", {}},
      {"study", {"--out", "--threads", "--quiet", "--keep-subnormals", "--restart", "--checkpoint-minutes"}},
      {"report", {"--against"}},
      {"compare", {"--json", "--rtol", "--from"}},
      {"export", {"--time", "--out", "--whole", "--format"}},
      {"blank", {"--trim", "--margin", "--time", "--out", "--whole", "--roll", "--gap", "--turn-90", "--parts"}}};
  return m;
}

// The finite number t of option opt, above 0 (or at least 0 with
// zero_allowed); otherwise a usage error saying that opt expects `what`.
double finite_number(const std::string& opt, const std::string& t, bool zero_allowed, const std::string& what) {
  try {
    std::size_t used = 0;
    const double v = std::stod(t, &used);
    if (used != t.size() || !std::isfinite(v) || !(zero_allowed ? v >= 0 : v > 0)) throw std::invalid_argument(t);
    return v;
  } catch (const std::exception&) {
    throw UsageError(opt + " expects " + what + ", found '" + t + "'");
  }
}

Args parse(int argc, char** argv) {
  Args a;
  std::vector<std::string> v(argv + 1, argv + argc);
  if (v.empty()) throw UsageError("no command given");
  a.command = v[0];
  for (std::size_t i = 1; i < v.size(); ++i) {
    const std::string& s = v[i];
    auto value = [&](const std::string& opt) {
      if (i + 1 >= v.size()) throw UsageError(opt + " needs a value");
      return v[++i];
    };
    if (s == "--set") {
      a.sets.push_back(value(s));
    } else if (s.rfind("--set=", 0) == 0) {
      a.sets.push_back(s.substr(6));
    } else if (s == "--out") {
      a.out = value(s);
    } else if (s == "--threads") {
      const std::string t = value(s);
      try {
        std::size_t used = 0;
        a.threads = std::stoi(t, &used);
        if (used != t.size() || a.threads < 1) throw std::invalid_argument(t);
      } catch (const std::exception&) {
        throw UsageError("--threads expects a positive integer, found '" + t + "'");
      }
    } else if (s == "--against") {
      a.against = value(s);
    } else if (s == "--from") {
      a.from = finite_number(s, value(s), true, "a time of at least 0");
    } else if (s == "--time") {
      a.time = finite_number(s, value(s), true, "a time of at least 0");
    } else if (s == "--rtol") {
      a.rtol = finite_number(s, value(s), true, "a number of at least 0");
    } else if (s == "--checkpoint-minutes") {
      a.checkpoint_minutes = finite_number(s, value(s), false, "a positive number");
    } else if (s == "--quiet") {
      a.quiet = true;
    } else if (s == "--restart") {
      a.restart = true;
    } else if (s == "--restart-at") {
      a.restart_at = finite_number(s, value(s), true, "a time of at least 0");
      a.restart = true;
    } else if (s == "--trim") {
      a.trims.push_back(value(s));
    } else if (s == "--margin") {
      const std::string t = value(s);
      try {
        std::size_t used = 0;
        a.margin = std::stod(t, &used);
        if (used != t.size() || !std::isfinite(a.margin)) throw std::invalid_argument(t);
      } catch (const std::exception&) {
        throw UsageError("--margin expects a length in m, found '" + t + "'");
      }
    } else if (s == "--roll") {
      a.roll = finite_number(s, value(s), false, "a roll width in m, above 0");
    } else if (s == "--gap") {
      a.gap = finite_number(s, value(s), true, "a gap in m, at least 0");
    } else if (s == "--turn-90") {
      a.turn_90 = true;
    } else if (s == "--parts") {
      const std::string t = value(s);
      try {
        std::size_t used = 0;
        a.parts = std::stoi(t, &used);
        if (used != t.size() || a.parts < 1 || a.parts > 10000) throw std::invalid_argument(t);
      } catch (const std::exception&) {
        throw UsageError("--parts expects a number of parts from 1 to 10000, found '" + t + "'");
      }
    } else if (s == "--whole") {
      a.whole = true;
    } else if (s == "--format") {
      const std::string f = value(s);
      if (f == "gmsh") a.format = ts::ExportFormat::Gmsh;
      else if (f == "abaqus") a.format = ts::ExportFormat::Abaqus;
      else if (f == "calculix") a.format = ts::ExportFormat::CalculiX;
      else throw UsageError("--format expects gmsh, abaqus or calculix, found '" + f + "'");
    } else if (s == "--keep-subnormals") {
      a.keep_subnormals = true;
    } else if (s == "--json") {
      a.json = true;
    } else if (s == "--markdown") {
      a.markdown = true;
    } else if (s.rfind("--", 0) == 0) {
      // The nearest option of the command (of any command where it is unknown).
      std::vector<std::string> known;
      for (const auto& [c, opts] : command_options())
        if (c == a.command || !command_options().count(a.command)) known.insert(known.end(), opts.begin(), opts.end());
      const std::string dym = ts::did_you_mean(s, known);
      throw UsageError("unknown option '" + s + "'" + (dym.empty() ? "" : "; " + dym));
    } else {
      a.positional.push_back(s);
      continue;
    }
    a.options.push_back(s.rfind("--set=", 0) == 0 ? "--set" : s);
  }
  if (const auto it = command_options().find(a.command); it != command_options().end()) {
    for (const auto& o : a.options)
      if (std::find(it->second.begin(), it->second.end(), o) == it->second.end())
        throw UsageError(o + " does not apply to '" + a.command + "'" +
                         (it->second.empty() ? std::string(", which takes no option")
                                             : "; its options: " + ts::join(it->second)));
  }
  return a;
}

int cmd_run(const Args& a, bool validate_only) {
  if (a.positional.size() != 1) throw UsageError("expected one job file");
  // From here a signal asks for a stop: during the setup (which can take a
  // while for a large mesh) the run then stops after its first step.
  if (!validate_only) ts::install_stop_handlers();
  ts::log_to_terminal(a.quiet);
  if (!validate_only) ts::log_hold();  // the set-up's lines go to log.txt too
  const ts::Job job = ts::load_job(a.positional[0], a.sets);
  ts::PluginRegistry registry;
  ts::Simulation sim(job, registry);
  if (validate_only) {
    std::cout << "job '" << job.name << "' is valid: " << job.parts.size() << " part(s), " << job.tools.size()
              << " tool(s), " << job.contacts.size() + job.heat_exchanges.size() << " interaction(s); plugins: "
              << ts::join(sim.plugins_loaded()) << "\n";
    // What the run will take, from its first steps (the mechanical step
    // changes as the plies deform and touch).
    auto rounded = [](double n) {  // three significant digits
      const double r = n >= 100 ? std::pow(10.0, std::floor(std::log10(n)) - 2) : 1.0;
      return std::round(n / r) * r;
    };
    char line[512];
    const double dm = sim.initial_mechanical_step();
    if (dm > 0) {
      std::snprintf(line, sizeof line, "mechanical step %.4g s at the start: about %.0f steps to t = %.4g s\n", dm,
                    rounded(job.t_end / dm), job.t_end);
      std::cout << line;
    }
    for (const std::string& l : sim.mesh_file_lines()) std::cout << l << "\n";
    for (const std::string& l : sim.tool_motion_lines()) std::cout << l << "\n";
    for (const std::string& l : sim.gripper_lines()) std::cout << l << "\n";
    for (const auto& m : job.materials)
      if (const auto card = ts::material_card_file(job, m); !card.empty())
        std::cout << "material '" << m.name << "': from the material card " << card.string() << "\n";
    for (const auto& m : job.materials)
      if (const auto mix = ts::describe_mixture(m); !mix.empty())
        std::cout << "material '" << m.name << "': " << mix << "\n";
    if (const double dt = sim.thermal_step(); dt > 0) {
      // With the mechanics a thermal step ends at a mechanical step.
      if (dm > 0 && dt < dm)
        std::snprintf(line, sizeof line, "thermal step %.4g s: one every mechanical step (its own %.4g s is shorter)\n",
                      dm, dt);
      else
        std::snprintf(line, sizeof line, "thermal step %.4g s: about %.0f steps\n", dt, rounded(job.t_end / dt));
      std::cout << line;
      if (const int n = job.thermal->contact_samples; dm > 0 && n > 1) {
        std::snprintf(line, sizeof line, "contact samples: %d a thermal step, every %.3g s\n", n, dt / n);
        std::cout << line;
      }
      for (const auto& m : job.materials) {
        if (m.crystallisation.present)
          std::cout << "material '" << m.name << "': " << ts::describe_crystallisation(m) << "\n";
        if (const auto& k = m.conductivity_table; !k.empty()) {
          std::snprintf(line, sizeof line,
                        "material '%s': conductivity from %zu rows, %g to %g degC, k33 %g to %g W/(m K) (steps with "
                        "the largest: %g, %g, %g)\n",
                        m.name.c_str(), k.size(), k.front()[0], k.back()[0], m.k33_range()[0], m.k33_range()[1],
                        m.conductivity[0], m.conductivity[1], m.conductivity[2]);
          std::cout << line;
        }
        if (m.specific_heat_table.empty()) continue;
        std::snprintf(line, sizeof line,
                      "material '%s': specific heat from %zu rows, %g to %g degC, %g to %g J/(kg K) (steps with %g)\n",
                      m.name.c_str(), m.specific_heat_table.size(), m.specific_heat_table.front()[0],
                      m.specific_heat_table.back()[0], m.specific_heat, m.specific_heat_max, m.specific_heat);
        std::cout << line;
      }
    }
    for (const std::string& l : sim.output_lines(dm)) std::cout << l << "\n";
    return 0;
  }
  ts::RunOptions opt;
  opt.out_dir = a.out.empty() ? std::filesystem::path("results") / job.name : std::filesystem::path(a.out);
  opt.threads = a.threads;
  opt.quiet = a.quiet;
  opt.flush_subnormals = !a.keep_subnormals;
  opt.checkpoint_wall_s = 60 * a.checkpoint_minutes;
  // --restart: the run continues from the checkpoint in its output folder
  // (checked before anything runs: a checkpoint of another job is refused).
  std::optional<ts::Checkpoint> checkpoint;
  double restart_t = 0;
  std::filesystem::path restart_file = opt.out_dir / ts::kCheckpointFile;
  if (a.restart_at) {
    // The last kept checkpoint at or before that time, give or take a
    // thousandth of it: a periodic checkpoint falls on the first step at or
    // after its multiple of output.checkpoint_interval (2.00000107 s for 2 s).
    const auto kept = ts::kept_checkpoints(opt.out_dir);
    auto g = [](double v) {  // as the kept checkpoints' names give their times
      char text[32];
      std::snprintf(text, sizeof text, "%.9g", v);
      return std::string(text);
    };
    const std::string what = "--restart-at " + g(*a.restart_at) + ": ";
    if (kept.empty())
      throw ts::JobError("", what + "no kept checkpoints in " + (opt.out_dir / ts::kKeptCheckpointFolder).string() +
                                 " (a run keeps every checkpoint it writes with output.keep_checkpoints: true)");
    const ts::KeptCheckpoint* pick = nullptr;
    for (const auto& k : kept)
      if (k.t <= *a.restart_at * (1 + 1e-3)) pick = &k;
    if (!pick) {
      std::string times;
      for (const auto& k : kept) times += (times.empty() ? "" : ", ") + g(k.t);
      throw ts::JobError("", what + "no kept checkpoint at or before it in " +
                                 (opt.out_dir / ts::kKeptCheckpointFolder).string() + " (kept at t = " + times + " s)");
    }
    restart_file = pick->file;
    opt.restart_kept = pick->file;
  }
  if (a.restart) {
    try {
      checkpoint = ts::read_checkpoint(restart_file);
    } catch (const std::exception& e) {
      throw ts::JobError("", std::string(a.restart_at ? "--restart-at: " : "--restart: ") + e.what());
    }
    restart_t = sim.check_restart(*checkpoint);
    opt.restart = &*checkpoint;
  }
  ts::cli::make_output_folder(opt.out_dir);
  ts::log_to_file(opt.out_dir / "log.txt", a.restart);
  if (a.restart)
    ts::logger("job")->info("restart from {} (t = {:.6g} s)", restart_file.string(), restart_t);
  ts::logger("job")->info("thermostamp {} running {} -> {}", ts::kVersion, job.file.string(), opt.out_dir.string());
  for (const auto& s : a.sets) ts::logger("job")->info("override: {}", s);
  const ts::RunResult r = sim.run(opt);
  ts::log_close_file();
  if (r.interrupted) {
    std::cerr << r.error << ": " << opt.out_dir.string() << "\n";
    return 128 + r.interrupted;
  }
  if (!r.ok) {
    std::cerr << "error: run failed: " << r.error << "\n(frames and probes up to the failure are in "
              << opt.out_dir.string() << ")\n";
    // A closer look: the same job from the checkpoint, with closer frames.
    if (r.checkpoint_s >= 0)
      std::cerr << "(its checkpoint at t = " << r.checkpoint_s
                << " s remains: the same command with --restart --set output.interval=... runs on from it with "
                   "closer frames)\n";
    return 3;
  }
  if (!a.quiet) std::cout << "results: " << opt.out_dir.string() << "\n";
  return 0;
}

int cmd_plugins(const Args& a) {
  ts::PluginRegistry registry;
  registry.load_all();
  const auto all = registry.all();
  if (a.json) {
    ts::json out = ts::json::array();
    for (const auto* r : all) out.push_back(ts::descriptor_json(*r));
    std::cout << out.dump(2) << "\n";
  } else if (a.markdown) {
    std::cout << ts::reference_markdown(all);
  } else {
    if (all.empty()) std::cout << "no plugin found\n";
    for (const auto* r : all) std::cout << ts::descriptor_text(*r) << "\n";
    std::cout << "searched: ";
    std::vector<std::string> dirs;
    for (const auto& d : registry.search_dirs()) dirs.push_back(d.string());
    std::cout << ts::join(dirs) << "\n";
  }
  for (const auto& e : registry.load_errors()) std::cerr << "warning: " << e << "\n";
  return 0;
}

// `thermostamp blank DIR --trim SURFACE ...`: the cut pattern of each ply.
int cmd_blank(const Args& a) {
  if (a.positional.size() != 1) throw UsageError("expected one output folder");
  if (a.trims.empty()) throw UsageError("blank needs a --trim surface");
  if (a.gap && !a.roll)
    throw UsageError("--gap is the gap between patterns on a roll: give the roll's width with --roll");
  if (a.turn_90 && !a.roll)
    throw UsageError("--turn-90 lets patterns on a roll be turned by 90 degrees: give the roll's width with --roll");
  if (a.parts > 0 && !a.roll)
    throw UsageError("--parts gives the roll a batch of parts takes: give the roll's width with --roll");
  std::optional<ts::RollOptions> roll;
  if (a.roll) roll = ts::RollOptions{*a.roll, a.gap.value_or(0.0), a.turn_90, a.parts};
  const std::filesystem::path dir = a.positional[0];
  ts::BlankResult r;
  std::vector<ts::TrimSurface> trims;
  try {
    for (const auto& t : a.trims) trims.push_back(ts::parse_trim(t));
    r = ts::blank_plies(dir, a.time, a.out.empty() ? dir / "blank" : std::filesystem::path(a.out), a.whole, trims,
                        a.margin, roll);
  } catch (const std::exception& e) {  // 2: no pattern as asked; 3: a file that cannot be read or written
    std::cerr << "error: blank: " << e.what() << "\n";
    return dynamic_cast<const ts::ExportInputError*>(&e) ? 2 : 3;
  }
  char line[600];
  for (const auto& t : trims) {  // an outline drawn in another plane than plan view: which way it cuts
    const std::array<double, 3> n = ts::polygon_cut_direction(t);
    if (t.kind != ts::TrimSurface::Kind::Polygon || (n[0] == 0 && n[1] == 0)) continue;
    std::snprintf(line, sizeof line, "(%.6g, %.6g, %.6g)", n[0], n[1], n[2]);
    std::cout << "trim '" << t.text << "': cut along " << line
              << ", the normal of the plane its outline is drawn in\n";
  }
  if (!r.plies.empty()) {  // a polygon whose outline moved by the margin could not be found
    const auto& why = r.plies.front().pattern.polygon_margin;
    std::size_t k = 0;
    for (const auto& t : trims) {
      if (t.kind != ts::TrimSurface::Kind::Polygon || a.margin == 0) continue;
      if (k < why.size() && !why[k].empty())
        std::cerr << "warning: trim '" << t.text << "': " << why[k]
                  << "; the polygon is taken by its distance less the margin, linear in each triangle (corners "
                     "within about an element)\n";
      ++k;
    }
  }
  char moved[64];
  std::snprintf(moved, sizeof moved, "%s by %g mm", a.margin > 0 ? "out" : "in", std::abs(1000 * a.margin));
  const std::string margin_text = moved;
  for (const auto& p : r.plies) {
    const auto& c = p.pattern;
    std::size_t trimmed = 0;
    double cut = 0;
    for (const auto& o : c.outlines) {
      trimmed += o.trim_length_blank > 0 ? 1 : 0;
      cut += o.trim_length_blank;
    }
    std::snprintf(line, sizeof line,
                  "ply '%s' at t = %.6g s (frames/%06d of results.h5, %d frames)%s: %zu outline%s, %.4g %% of the "
                  "blank's %.6g m^2 (%.6g m^2 formed), trim line %.6g m in the blank",
                  p.name.c_str(), r.time, r.frame, r.frames,
                  (p.mirrored.empty() ? std::string() : ", mirrored at " + ts::join(p.mirrored, " = 0, ") + " = 0")
                      .append(a.margin == 0 ? std::string() : ", the trim line moved " + margin_text)
                      .c_str(),
                  c.outlines.size(), c.outlines.size() == 1 ? "" : "s",
                  c.blank_area > 0 ? 100 * c.kept_blank_area / c.blank_area : 0.0, c.blank_area, c.kept_formed_area,
                  cut);
    std::cout << p.csv.string() << ": " << line;
    if (c.outlines.empty()) std::cout << "; nothing of the ply lies inside the trim";
    else if (trimmed == 0) std::cout << "; the trim does not cross the ply: the whole blank";
    std::cout << (p.flat ? "; " + p.dxf.string() : std::string("; no DXF: the blank is not flat"));
    if (!p.marks.empty())
      std::snprintf(line, sizeof line, " with %zu fibre marks every %g mm", p.marks.size(), 1000 * p.mark_spacing);
    else if (p.flat && !c.outlines.empty())
      std::snprintf(line, sizeof line, " without fibre marks (the frames hold no fibre_direction)");
    else
      line[0] = '\0';
    std::cout << line << "\n";
    if (p.nest) {
      const ts::RollNest& n = p.nest->layout.nest;
      const bool pairs = p.nest->layout.pairs;
      // The pattern is turned by minus the fibres' angle (0 where unknown)
      // and, with turned_90, by 90 degrees more.
      const bool quarter = p.nest->layout.turned_90;
      const double turn = (quarter ? 90.0 : 0.0) - p.nest->fibre_angle_deg;
      std::string fibres = !p.nest->fibres_known ? (quarter ? "the blank's y" : "the blank's x")
                           : quarter              ? "the weft"
                                                  : "fibres";
      fibres += " along it";
      char turned[64];
      std::snprintf(turned, sizeof turned, " (the pattern turned by %.4g deg)", turn);
      if (std::abs(turn) > 1e-9) fibres += turned;
      if (!p.nest->fibres_known) fibres += " (the frames hold no fibre_direction)";
      if (n.lanes > 0)
        std::snprintf(line, sizeof line,
                      "  on a roll %g mm wide, %s, %g mm apart: %d lane%s%s, a %s every %.4g mm along each, %.4g "
                      "mm of roll per pattern, %.1f %% of the roll used",
                      1000 * *a.roll, fibres.c_str(), 1000 * a.gap.value_or(0.0), n.lanes, n.lanes == 1 ? "" : "s",
                      pairs ? " of pairs (a copy and one turned by 180 deg)" : "", pairs ? "pair" : "pattern",
                      1000 * n.pitch, 1000 * p.nest->layout.roll_per_pattern, 100 * n.utilisation);
      else
        std::snprintf(line, sizeof line,
                      "  on a roll %g mm wide, %s, %g mm apart: the pattern, %.4g mm across the roll with the gap, "
                      "does not fit",
                      1000 * *a.roll, fibres.c_str(), 1000 * a.gap.value_or(0.0),
                      1000 * (p.nest->layout.width + a.gap.value_or(0.0)));
      std::cout << line;
      if (pairs || quarter) {
        const char* as = quarter ? "not turned by 90 deg, all alike" : "all alike";
        std::snprintf(line, sizeof line, " (%s: %.4g mm)", as, 1000 * p.nest->layout.single_roll_per_pattern);
        std::cout << (p.nest->layout.single_roll_per_pattern > 0 ? std::string(line)
                                                                  : " (" + std::string(as) + ": none fits)");
      }
      std::cout << "; " << p.nest->dxf.string() << "\n";
      if (const auto& b = p.nest->batch) {
        std::snprintf(line, sizeof line,
                      "  %d pattern%s: %.4g m of the roll (%d x %.4g mm = %.4g m at the lanes' rate); ", a.parts,
                      a.parts == 1 ? "" : "s", b->length, a.parts, 1000 * p.nest->layout.roll_per_pattern,
                      a.parts * p.nest->layout.roll_per_pattern);
        std::cout << line << p.nest->batch_dxf.string() << "\n";
      }
    } else if (roll) {
      std::cout << "  not nested: "
                << (c.outlines.empty() ? "nothing of the ply lies inside the trim" : "the blank is not flat")
                << "\n";
    }
    if (!c.fallback.empty())
      std::cerr << "warning: ply '" << p.name << "': the exact cut's outline did not close (" << c.fallback
                << "): its pattern comes from the trims' largest distance, linear in each triangle (corners within "
                   "about an element)\n";
  }
  if (a.roll) {
    if (r.roll_per_part)
      std::snprintf(line, sizeof line,
                    "per part: %.4g mm of the roll, every ply's pattern once, each ply in lanes of its own",
                    1000 * *r.roll_per_part);
    else
      std::snprintf(line, sizeof line, "per part: no figure, %s", r.roll_per_part_left_out.c_str());
    std::cout << line << "\n";
    if (a.parts > 0) {
      if (r.roll_for_parts)
        std::snprintf(line, sizeof line,
                      "for %d part%s: %.4g m of the roll, each ply's patterns on a stretch of its own lanes, one ply "
                      "after the other",
                      a.parts, a.parts == 1 ? "" : "s", *r.roll_for_parts);
      else
        std::snprintf(line, sizeof line, "for %d part%s: no figure, %s", a.parts, a.parts == 1 ? "" : "s",
                      r.roll_per_part_left_out.c_str());
      std::cout << line << "\n";
    }
  }
  std::cout << r.json.string() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc >= 2 && (std::string(argv[1]) == "--version" || std::string(argv[1]) == "version")) {
      std::cout << "thermostamp " << ts::kVersion << " (plugin SDK " << ts::sdk::kSdkVersion << ", ABI "
                << ts::sdk::kAbiVersion << ")\n";
      return 0;
    }
    if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h" ||
                      std::string(argv[1]) == "help")) {
      std::cout << kUsage << kDetails;
      return 0;
    }
    const Args a = parse(argc, argv);
    if (a.command == "run") return cmd_run(a, false);
    if (a.command == "validate") return cmd_run(a, true);
    if (a.command == "plugins") return cmd_plugins(a);
    if (a.command == "schema") {
      ts::PluginRegistry registry;
      registry.load_all();
      std::cout << ts::job_schema(registry.all()).dump(2) << "\n";
      return 0;
    }
    if (a.command == "study") {
      if (a.positional.size() != 1) throw UsageError("expected one study file");
      ts::log_to_terminal(a.quiet);
      return ts::cli::run_study(a.positional[0], a.out, a.threads, a.quiet, !a.keep_subnormals, a.restart,
                                60 * a.checkpoint_minutes);
    }
    if (a.command == "compare") {
      if (a.positional.size() != 2) throw UsageError("expected two output folders");
      ts::Comparison c;
      try {
        c = ts::compare_outputs(a.positional[0], a.positional[1], a.from);
      } catch (const std::exception& e) {
        std::cerr << "error: compare: " << e.what() << "\n";
        return 2;
      }
      const bool pass = a.rtol >= 0 ? c.within(a.rtol) : c.identical;
      if (a.json) {
        ts::json j = c.to_json();
        if (a.rtol >= 0) j["within_rtol"] = {{"rtol", a.rtol}, {"within", pass}};
        std::cout << j.dump(2) << "\n";
      } else {
        std::cout << c.to_text(a.positional[0], a.positional[1]);
        if (a.rtol >= 0)
          std::cout << (pass ? "within" : "not within") << " --rtol " << a.rtol
                    << (c.matched ? "" : " (the folders do not hold the same quantities and times)") << "\n";
      }
      return pass ? 0 : 1;
    }
    if (a.command == "report") {
      if (a.positional.size() != 1) throw UsageError("expected one output folder");
      return ts::cli::run_report(a.positional[0], a.against);
    }
    if (a.command == "export") {
      if (a.positional.size() != 1) throw UsageError("expected one output folder");
      const std::filesystem::path dir = a.positional[0];
      ts::ExportResult r;
      try {
        r = ts::export_plies(dir, a.time, a.out.empty() ? dir / "export" : std::filesystem::path(a.out), a.whole,
                             a.format);
      } catch (const std::exception& e) {  // 2: nothing to export as asked; 3: a file that cannot be read
        std::cerr << "error: export: " << e.what() << "\n";
        return dynamic_cast<const ts::ExportInputError*>(&e) ? 2 : 3;
      }
      char at[120];
      std::snprintf(at, sizeof at, "t = %.6g s (frames/%06d of results.h5, %d frames)", r.time, r.frame, r.frames);
      for (const auto& p : r.plies) {
        std::cout << p.file.string() << ": ply '" << p.name << "' at " << at << ", "
                  << (p.mirrored.empty() ? std::string() : "mirrored at " + ts::join(p.mirrored, " = 0, ") + " = 0, ")
                  << p.nodes << " nodes, " << p.triangles << " triangles";
        if (a.format != ts::ExportFormat::Gmsh)
          std::cout << " in element set " << p.elset << "; orientations: "
                    << (p.orientation_from.empty() ? std::string("none (no fibre_direction in the frame)")
                                                   : "from " + p.orientation_from + " (" + p.elset + "_ORIENTATION)")
                    << "; initial temperatures: "
                    << (p.temperature_from.empty() ? std::string("none (no temperature in the frame)")
                                                   : "from " + p.temperature_from)
                    << "; nodal thicknesses: "
                    << (p.thickness_from.empty() ? std::string("none (no thickness in the frame)")
                                                 : "from " + p.thickness_from)
                    << "\n";
        else
          std::cout << "; node data: " << (p.node_data.empty() ? std::string("none") : ts::join(p.node_data))
                    << "; element data: "
                    << (p.element_data.empty() ? std::string("none") : ts::join(p.element_data)) << "\n";
      }
      return 0;
    }
    if (a.command == "blank") return cmd_blank(a);
    std::vector<std::string> commands;
    for (const auto& c : command_options()) commands.push_back(c.first);
    const std::string dym = ts::did_you_mean(a.command, commands);
    throw UsageError("unknown command '" + a.command + "'" + (dym.empty() ? "" : "; " + dym));
  } catch (const UsageError& e) {
    std::cerr << "error: " << e.what() << "\n"
              << kUsage << "(thermostamp --help: what each option does, and the exit statuses)\n";
    return 2;
  } catch (const ts::JobError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const ts::RunError& e) {
    std::cerr << "error: run failed: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 3;
  }
}
