// What a run writes: the frames of results.h5, the probe samples, the time
// series (energy.csv, tools.csv, plies.csv and their tables in results.h5),
// summary.json and the log's first and last lines (docs/user-guide.md, "The
// output folder").
#include <sys/resource.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <utility>

#include <nlohmann/json.hpp>

#include "io/checkpoint.hpp"
#include "io/files.hpp"
#include "io/logging.hpp"
#include "solve/interrupt.hpp"
#include "solve/rigid_body.hpp"
#include "solve/simulation_internal.hpp"
#include "solve/stability.hpp"
#include "solve/tools.hpp"
#include "version.hpp"

namespace ts {

using detail::Clock;
using detail::fmt_g;
using detail::seconds_since;
using detail::thickness_mean;
using json = nlohmann::json;

namespace {

// The smallest and largest E11 (the strain along the initial fibre
// direction) of a part's elements, from their strains [E11, E22, E12].
std::pair<double, double> fibre_strain_range(const std::vector<double>& strain) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < strain.size(); i += 3) {
    lo = std::min(lo, strain[i]);
    hi = std::max(hi, strain[i]);
  }
  return {lo, hi};
}

// A ply's smallest, mean (by mass) and largest relative crystallinity (NaN
// for a ply whose material has no crystallisation kinetics).
std::array<double, 3> ply_crystallinity(const PartState& st) {
  if (st.X.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  double lo = 1, hi = 0, sum = 0, cap = 0;
  for (std::size_t k = 0; k < st.X.size(); ++k) {
    lo = std::min(lo, st.X[k]);
    hi = std::max(hi, st.X[k]);
    sum += st.cap[k] * st.X[k];
    cap += st.cap[k];
  }
  return {lo, cap > 0 ? sum / cap : st.X[0], hi};
}

// A ply's coldest, mean (weighted by heat capacity) and hottest value
// (degC), and the share of its heat capacity below the threshold (0
// without one): by node, the part of the thickness below it with the
// temperature linear between the values (a single value: all or nothing).
std::array<double, 4> ply_temperature(const PartState& st, const std::optional<double>& threshold) {
  const int nz = st.nz;
  const std::size_t nn = static_cast<std::size_t>(st.mesh.num_nodes());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, heat = 0, cap = 0, below = 0;
  for (std::size_t i = 0; i < nn; ++i) {
    const double* T = &st.T[i * nz];
    const double* c = &st.cap[i * nz];
    double column = 0, frac = 0;
    for (int k = 0; k < nz; ++k) {
      lo = std::min(lo, T[k]);
      hi = std::max(hi, T[k]);
      heat += c[k] * T[k];
      column += c[k];
    }
    if (threshold) {
      const double th = *threshold;
      if (nz == 1) {
        frac = T[0] < th ? 1.0 : 0.0;
      } else {
        for (int k = 0; k + 1 < nz; ++k) {
          const double a = std::min(T[k], T[k + 1]), b = std::max(T[k], T[k + 1]);
          frac += a >= th ? 0.0 : b <= th ? 1.0 : (th - a) / (b - a);
        }
        frac /= nz - 1;
      }
    }
    cap += column;
    below += column * frac;
  }
  return {lo, heat / cap, hi, below / cap};
}

// The peak resident memory of the process so far (MB), 0 where the system
// does not say (Linux reports ru_maxrss in KiB).
double peak_resident_mb() {
#if defined(__linux__)
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) == 0) return static_cast<double>(u.ru_maxrss) * 1024.0 / 1e6;
#endif
  return 0.0;
}

std::string csv_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

// A number of bytes as kB, MB, GB or TB (10^3, 10^6, 10^9, 10^12), 3 digits.
std::string bytes_text(double b) {
  if (b >= 1e12) return fmt_g(b / 1e12, 3) + " TB";
  if (b >= 1e9) return fmt_g(b / 1e9, 3) + " GB";
  if (b >= 1e6) return fmt_g(b / 1e6, 3) + " MB";
  return fmt_g(b / 1e3, 3) + " kB";
}

}  // namespace

void detail::Progress::update(double t, long long steps, bool force) {
  const auto now = Clock::now();
  const double el = std::chrono::duration<double>(now - start).count();
  const double frac = std::min(1.0, t / t_end);
  const double eta = frac > 0 ? el * (1 - frac) / frac : 0;
  const double rate = el > 0 ? steps / el : 0;
  if (tty && !quiet) {
    if (!force && std::chrono::duration<double>(now - last).count() < 0.2) return;
    last = now;
    std::fprintf(stderr, "\r  t = %.4g / %.4g s  %5.1f %%  %.0f steps/s  ETA %.0f s   ", t, t_end, 100 * frac, rate,
                 eta);
    if (force) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  } else {
    const int decile = static_cast<int>(10 * frac);
    if (decile == last_decile && !force) return;
    last_decile = decile;
    if (frac < 0.01 && !force)  // the first steps (setup, caches) say nothing of the rate yet
      logger("solve")->info("t = {:.4g} / {:.4g} s ({:.0f} %)", t, t_end, 100 * frac);
    else
      logger("solve")->info("t = {:.4g} / {:.4g} s ({:.0f} %), {:.0f} steps/s, ETA {:.0f} s", t, t_end, 100 * frac,
                            rate, eta);
  }
}

// A time series file: new with its header, or on a restart the run's file
// cut back to its length at the checkpoint and continued.
void Simulation::Run::open_series(std::ofstream& out, const char* name, int k, const std::string& header) {
  const auto path = opt.out_dir / name;
  if (opt.restart) {  // checked by read_checkpoint()
    std::filesystem::resize_file(path, csv_size[k]);
    out.open(path, std::ios::app);
  } else {
    out.open(path);
    out << header;
  }
}

void Simulation::Run::open_output() {
  if (opt.write_files) {
    std::filesystem::create_directories(opt.out_dir);
    // A new run replaces the folder's results: a checkpoint of an earlier
    // run there no longer fits them.
    if (!opt.restart) {
      std::filesystem::remove(opt.out_dir / kCheckpointFile);
      std::filesystem::remove_all(opt.out_dir / kKeptCheckpointFolder);
    }
    // The job as run (after --set, file paths absolute): `thermostamp run
    // DIR/job_as_run.json` runs it again, from anywhere.
    if (std::ofstream jf(opt.out_dir / "job_as_run.json"); !(jf << job.document_as_run.dump(2) << '\n'))
      throw RunError("cannot write " + (opt.out_dir / "job_as_run.json").string());
    std::vector<WriterPart> wparts = sim.writer_parts();
    try {
      const int level = job.output.compression;
      // The frames kept have the fields of the run that wrote them.
      writer = opt.restart ? std::make_unique<ResultsWriter>(opt.out_dir, std::move(wparts), frame_times,
                                                             sim.frame_fields(checkpoint_fields(*opt.restart)), level)
                           : std::make_unique<ResultsWriter>(opt.out_dir, std::move(wparts), level);
    } catch (const std::runtime_error& e) {
      if (opt.restart) throw JobError("", std::string("--restart: ") + e.what());
      throw;
    }
    // A kept checkpoint continued (--restart-at) is the folder's checkpoint
    // from now on; those after it continued the frames and rows just
    // removed, and go.
    if (!opt.restart_kept.empty()) {
      const auto kept = kept_checkpoints(opt.out_dir);
      const auto it = std::find_if(kept.begin(), kept.end(), [&](const KeptCheckpoint& k) {
        return k.file.filename() == opt.restart_kept.filename();
      });
      std::error_code ec;
      if (it != kept.end())
        for (auto k = std::next(it); k != kept.end(); ++k) std::filesystem::remove(k->file, ec);
      try {
        link_or_copy(opt.restart_kept, opt.out_dir / kCheckpointFile);
      } catch (const std::runtime_error& e) {
        throw RunError(e.what());
      }
    }
    const std::vector<WriterTool> tools =
        job.output.tool_surfaces && !sim.tools_.empty() ? sim.writer_tools() : std::vector<WriterTool>{};
    if (!tools.empty()) writer->set_tools(tools);
    frame_bytes = results_bytes(sim.writer_parts(), sim.frame_fields(), tools).per_frame;
    open_series(probes_csv, "probes.csv", 0, "probe,quantity,time,z,value\n");
  }

  energy_cols = {"time", "kinetic", "internal", "external_work", "damping", "contact", "contact_stored", "balance_error"};
  for (std::size_t c = 0; c < job.constraints.size(); ++c)
    for (const char* d : {"x", "y", "z"}) energy_cols.push_back("reaction" + std::to_string(c) + "_" + d);
  // 1/2 m v^2 at the half step just computed: never negative (the
  // "kinetic" column is the product form of the balance, which turns
  // negative when nodes vibrate near the step's frequency limit).
  energy_cols.push_back("kinetic_half_step");
  tool_cols = {"time"};
  for (const auto& td : job.tools)
    for (const char* q : {"_ux", "_uy", "_uz", "_fx", "_fy", "_fz", "_heat_J", "_temperature"})
      tool_cols.push_back(td.name + q);
  // plies.csv: each ply's temperatures (with thermal) and its shear angles
  // and fibre strains (with mechanics), a row per ply.
  if (job.thermal) {
    ply_fields = {"temperature_min", "temperature_mean", "temperature_max"};
    if (threshold) ply_fields.push_back("fraction_below");
    if (crystallising)
      for (const char* q : {"crystallinity_min", "crystallinity_mean", "crystallinity_max"}) ply_fields.push_back(q);
  }
  if (job.mechanics) {
    for (const char* q : {"shear_angle_min", "shear_angle_max", "fibre_strain_min", "fibre_strain_max"})
      ply_fields.push_back(q);
    if (shear_limit) ply_fields.push_back("fraction_over_shear_limit");
    for (const char* q : {"fraction_unstable", "stability_min", "thickness_min", "thickness_max"})
      ply_fields.push_back(q);
  }
  if (job.thermal)  // the heat the ply has received so far, by source (J)
    for (const char* q : {"heat_from_tools", "heat_from_exchanges", "heat_from_plies"}) ply_fields.push_back(q);
  ply_per = ply_fields.size();
  ply_cols = {"time"};
  for (const auto& st : sim.parts_)
    for (const auto& q : ply_fields) ply_cols.push_back(st->def->name + "_" + q);

  if (opt.write_files && job.mechanics) {
    std::string header;
    for (std::size_t c = 0; c < energy_cols.size(); ++c) header += (c ? "," : "") + energy_cols[c];
    open_series(energy_csv, "energy.csv", 1, header + "\n");
  }
  if (opt.write_files && !job.tools.empty())
    open_series(tools_csv, "tools.csv", 2, "time,tool,ux,uy,uz,fx,fy,fz,heat_J,temperature\n");
  if (opt.write_files && ply_series) {
    std::string header = "time,ply";
    for (const auto& q : ply_fields) header += "," + q;
    open_series(plies_csv, "plies.csv", 3, header + "\n");
  }
}

void Simulation::Run::log_start() const {
  auto log = logger("solve");
  const auto& parts = sim.parts_;
  const auto& mech = sim.mech_;
  if (job.thermal)
    log->info("job '{}': {} part(s), {} tool(s), splitter '{}', thermal step {:.4g} s (stable {:.4g} s, "
              "accurate {:.4g} s), {} thread(s), subnormals {}",
              job.name, parts.size(), sim.tools_.size(), job.thermal->splitter, sim.thermal_dt_,
              sim.thermal_stable_dt_, sim.thermal_accurate_dt_, threads, subnormals);
  else
    log->info("job '{}': {} part(s), {} tool(s), isothermal, {} thread(s), subnormals {}", job.name, parts.size(),
              sim.tools_.size(), threads, subnormals);
  for (const std::string& line : sim.mesh_file_lines()) log->info("{}", line);
  for (const std::string& line : sim.tool_motion_lines()) log->info("{}", line);
  for (const auto& m : job.materials)
    if (const auto card = material_card_file(job, m); !card.empty())
      log->info("material '{}': from the material card {}", m.name, card.string());
  for (const auto& m : job.materials)
    if (const auto mix = describe_mixture(m); !mix.empty()) log->info("material '{}': {}", m.name, mix);
  if (job.thermal)
    for (const auto& st : parts)
      if (!st->cp.empty()) {
        const MaterialDef& m = job.materials[st->def->material];
        const auto& rows = m.specific_heat_table;
        log->info("part '{}': specific heat from {} rows between {:g} and {:g} degC, {:g} to {:g} J/(kg K) (the "
                  "thermal steps are taken with the smallest, the heat stored follows the rows)",
                  st->def->name, rows.size(), rows.front()[0], rows.back()[0], m.specific_heat, m.specific_heat_max);
      }
  if (job.thermal)
    for (const auto& st : parts)
      if (!st->kt.empty()) {
        const MaterialDef& m = job.materials[st->def->material];
        const auto& rows = m.conductivity_table;
        log->info("part '{}': conductivity from {} rows between {:g} and {:g} degC, k33 {:g} to {:g} W/(m K) (each "
                  "thermal step takes the values at its start; the step is chosen with the largest)",
                  st->def->name, rows.size(), rows.front()[0], rows.back()[0], m.k33_range()[0], m.k33_range()[1]);
      }
  if (job.thermal)
    for (const auto& st : parts)
      if (!st->kin.empty())
        log->info("part '{}': {}", st->def->name, describe_crystallisation(job.materials[st->def->material]));
  for (std::size_t p = 0; p < mech.size(); ++p)
    log->info("part '{}': mass {:.6g} kg, added by mass scaling {:.6g} kg ({:.3g} %)", parts[p]->def->name,
              mech[p]->mass_physical, mech[p]->mass_added, 100 * mech[p]->mass_added / mech[p]->mass_physical);
  for (const std::string& line : sim.gripper_lines()) log->info("{}", line);
  // More than a thousand times the ply's own mass: the inertia, not the
  // material, then decides how the ply deforms.
  for (std::size_t p = 0; p < mech.size(); ++p)
    if (const MechPart& m = *mech[p]; m.mass_added > 1e3 * m.mass_physical)
      log->warn("mass scaling multiplies the mass of part '{}' by {:.3g}{}: its inertia will dominate the "
                "response; lower solvers.mechanics.mass_scaling{}",
                parts[p]->def->name, (m.mass_physical + m.mass_added) / m.mass_physical,
                m.mass_added_contact > 0.5 * m.mass_added ? " (most of it for the contact springs)" : "",
                m.mass_added_contact > 0.5 * m.mass_added ? " or the contacts' penalty" : "");
  log->info("thermal contact: {} tool face node(s), {} ply/ply link(s)", sim.contact_map_.tool_contacts.size(),
            sim.contact_map_.links.size());
  // A probe without an interval records every thermal step: say so where
  // that is many samples (a short thermal step over a long stroke).
  if (job.thermal && sim.thermal_dt_ > 0)
    for (std::size_t q = 0; q < job.output.probes.size(); ++q)
      if (const double n = job.t_end / sim.thermal_dt_; job.output.probes[q].interval <= 0 && n > 1e5)
        log->warn("probe '{}' has no interval: it records at every thermal step, up to {:.3g} samples; set "
                  "{}/interval for fewer",
                  job.output.probes[q].name, n, job.output.probes[q].pointer);
  // (With the mechanics, once the step at the start is known.)
  if (!job.mechanics) announce_output(0.0);
}

void Simulation::Run::announce_output(double mech_step) const {
  if (opt.restart) return;
  auto log = logger("solve");
  for (const std::string& line : sim.output_lines(mech_step)) log->info("{}", line);
  if (!writer) return;
  std::error_code ec;
  const auto space = std::filesystem::space(opt.out_dir, ec);
  if (const double need = sim.results_estimate(mech_step), free = static_cast<double>(space.available);
      !ec && space.capacity > 0 && need > free)
    log->warn("the frames will take about {} of results.h5 and the device of {} has {} free: the run will stop "
              "before the first frame that does not fit (fewer frames or fields, or output.compression, take less)",
              bytes_text(need), opt.out_dir.string(), bytes_text(free));
}

// The per-node values derived from the temperatures (and crystallinities):
// the mean through the thickness, the bottom and top values.
void Simulation::Run::update_derived() {
  for (auto& st : sim.parts_) {
    const int nz = st->nz;
    const double h = st->def->thickness;
    for (int i = 0; i < st->mesh.num_nodes(); ++i) {
      const double* T = &st->T[static_cast<std::size_t>(nz) * i];
      st->mean[i] = thickness_mean(T, nz, h);
      st->bottom[i] = T[0];
      st->top[i] = T[nz - 1];
      if (!st->X.empty()) st->X_mean[i] = thickness_mean(&st->X[static_cast<std::size_t>(nz) * i], nz, h);
    }
  }
}

void Simulation::Run::write_frame(double time) {
  for (auto& st : sim.parts_)
    for (std::size_t k = 0; k < st->x.size(); ++k) st->displacement[k] = st->x[k] - st->x0[k];
  if (!writer) return;
  update_derived();
  if (sim.want_conductance_) sim.update_face_conductance();
  if (sim.want_tool_gap_) sim.update_tool_gap();
  std::vector<const double*> xs, ns;
  for (auto& st : sim.parts_) {
    xs.push_back(st->x.data());
    ns.push_back(st->normals.data());
  }
  std::vector<std::array<double, 3>> tool_u;
  for (const auto& tool : sim.tools_) tool_u.push_back(tool->displacement());
  check_space(time);
  try {
    writer->write_frame(time, xs, ns, sim.frame_fields(), tool_u);
  } catch (const std::runtime_error& e) {  // a full disk: the frames so far stay
    throw RunError(e.what());
  }
  frame_times.push_back(time);
  check_series_files();
}

void Simulation::Run::check_space(double time) const {
  std::error_code ec;
  const auto space = std::filesystem::space(opt.out_dir, ec);
  if (ec || space.capacity == 0) return;  // (a file system that tells nothing of its space)
  // The frame, the time series so far (into results.h5 at the end), HDF5's
  // structures and summary.json: a tenth and a megabyte more.
  const double series = 8.0 * static_cast<double>(energy_rows.size() + tool_rows.size() + ply_rows.size());
  const double need = 1.1 * (frame_bytes + series) + 1e6, free = static_cast<double>(space.available);
  if (free >= need) return;
  throw RunError("the device of " + opt.out_dir.string() + " has " + fmt_g(free / 1e6, 3) +
                 " MB free, too little for the frame at t = " + fmt_g(time) + " s and what follows it (about " +
                 fmt_g(need / 1e6, 3) + " MB): the run stops before writing it; results.h5 holds the " +
                 std::to_string(frame_times.size()) + " frame(s) before it");
}

void Simulation::Run::check_series_files() {
  const char* names[4] = {"probes.csv", "energy.csv", "tools.csv", "plies.csv"};
  std::ofstream* files[4] = {&probes_csv, &energy_csv, &tools_csv, &plies_csv};
  for (int k = 0; k < 4; ++k) {
    if (!files[k]->is_open()) continue;
    errno = 0;
    if (files[k]->flush(); !*files[k]) {
      const int err = errno;
      files[k]->close();  // nothing more into it
      throw RunError("cannot write " + (opt.out_dir / names[k]).string() + ": " +
                     write_failure_reason(opt.out_dir, err, "the stream failed"));
    }
  }
}

// The probes' samples at `time` (of probe `only`, or of every probe).
void Simulation::Run::sample_probes(double time, std::size_t only) {
  const auto& mech = sim.mech_;
  for (std::size_t q = 0; q < job.output.probes.size(); ++q) {
    if (only != static_cast<std::size_t>(-1) && q != only) continue;
    const ProbeDef& pr = job.output.probes[q];
    const PartState& st = *sim.parts_[pr.part];
    const int i = sim.probe_node_[q];
    const std::vector<int>& around = sim.probe_elements_[q];
    const int nz = st.nz;
    const double* T = &st.T[static_cast<std::size_t>(nz) * i];
    for (const auto& quantity : pr.quantities) {
      ProbeSample s;
      s.probe = static_cast<int>(q);
      s.time = time;
      s.quantity = quantity;
      if (quantity == "temperature_profile" || quantity == "crystallinity_profile") {
        const double* v = quantity == "temperature_profile" ? T : &st.X[static_cast<std::size_t>(nz) * i];
        for (int k = 0; k < nz; ++k) {
          s.z.push_back(nz > 1 ? -0.5 * st.def->thickness + st.def->thickness * k / (nz - 1) : 0.0);
          s.values.push_back(v[k]);
        }
      } else if (quantity == "temperature_mean") {
        double m = T[0];
        if (nz > 1) {
          m = 0;
          for (int k = 0; k < nz; ++k) m += (k == 0 || k == nz - 1 ? 0.5 : 1.0) * T[k];
          m /= (nz - 1);
        }
        s.values.push_back(m);
      } else if (quantity == "contact_pressure") {
        s.values.push_back(st.contact_pressure[i]);
      } else if (quantity == "tool_gap") {
        double gap = 0;
        sim.tool_gaps(pr.part, 1, &st.x[3 * static_cast<std::size_t>(i)], &gap);
        s.values.push_back(gap);
      } else if (quantity == "conductance") {  // bottom and top face, at z = -h/2 and +h/2
        sim.update_face_conductance();
        s.z = {-0.5 * st.def->thickness, 0.5 * st.def->thickness};
        s.values = {st.conductance_bottom[i], st.conductance_top[i]};
      } else if (quantity.rfind("displacement_", 0) == 0) {
        const int d = quantity.back() - 'x';
        s.values.push_back(st.x[3 * i + d] - st.x0[3 * i + d]);
      } else if (quantity == "fibre_strain") {  // E11: mean of the elements around the node (0 without mechanics)
        double a = 0;
        if (static_cast<std::size_t>(pr.part) < mech.size())
          for (int e : around) a += mech[pr.part]->strain[3 * static_cast<std::size_t>(e)];
        s.values.push_back(around.empty() ? 0.0 : a / around.size());
      } else if (quantity == "thickness") {  // mean of the elements around the node
        double a = 0;
        for (int e : around) a += st.thickness[e];
        s.values.push_back(around.empty() ? st.def->thickness : a / around.size());
      } else {  // shear_angle: mean of the elements around the node (0 without mechanics)
        double a = 0;
        for (int e : around) a += st.shear_angle[e];
        s.values.push_back(around.empty() ? 0.0 : a / around.size());
      }
      if (probes_csv.is_open()) {
        for (std::size_t k = 0; k < s.values.size(); ++k)
          probes_csv << pr.name << ',' << quantity << ',' << csv_number(time) << ','
                     << (s.z.empty() ? "" : csv_number(s.z[k])) << ',' << csv_number(s.values[k]) << '\n';
      }
      result.probes.push_back(std::move(s));
    }
  }
  if (probes_csv.is_open()) probes_csv.flush();
}

// A row of tools.csv: each tool's displacement, force, heat and temperature.
void Simulation::Run::sample_tools(double time) {
  tool_rows.push_back(time);
  for (std::size_t q = 0; q < sim.tools_.size(); ++q) {
    const auto& u = sim.tools_[q]->displacement();
    const double* f = &sim.tool_force_[3 * q];
    const double row[8] = {u[0], u[1], u[2], f[0], f[1], f[2], sim.tool_heat_[q], job.tools[q].temperature_over(time, time)};
    tool_rows.insert(tool_rows.end(), row, row + 8);
    if (tools_csv.is_open()) {
      tools_csv << csv_number(time) << ',' << job.tools[q].name;
      for (double v : row) tools_csv << ',' << csv_number(v);
      tools_csv << '\n';
    }
  }
  if (tools_csv.is_open()) tools_csv.flush();
}

std::optional<double> Simulation::Run::threshold_of(std::size_t p) const {
  return threshold ? std::optional<double>(job.output.temperature_threshold[p]) : std::nullopt;
}

// Part p's shear angle range, fibre strain range, share of its area
// beyond the shear limit at the current positions (ElementKernel::fields,
// as the frames show them), share of its area whose long-term response is
// unstable, the smallest long-term stiffness q (stability.hpp) and its
// thinnest and thickest element at constant volume; the first row beyond
// the limit and the first with an unstable element are noted at time, the
// latter with a warning.
std::array<double, 9> Simulation::Run::ply_mechanics(std::size_t p, double time) {
  sdk::ElementFields f;
  f.shear_angle = row_shear[p];
  f.strain = row_strain[p];
  if (auto s = sim.mech_[p]->element->fields(f); !s)
    throw RunError("element plugin of part '" + sim.parts_[p]->def->name + "' failed at t = " + fmt_g(time) +
                   " s: " + s.message);
  const auto [smn, smx] = std::minmax_element(row_shear[p].begin(), row_shear[p].end());
  const auto [fmn, fmx] = fibre_strain_range(row_strain[p]);
  double over = 0, total = 0;
  for (std::size_t e = 0; e < row_shear[p].size(); ++e) {
    total += elem_area[p][e];
    if (shear_limit && std::abs(row_shear[p][e]) > job.output.shear_angle_limit[p]) over += elem_area[p][e];
  }
  if (shear_limit && over > 0 && sim.over_from_[p] < 0) sim.over_from_[p] = time;
  const MechPart& m = *sim.mech_[p];
  const PartState& st = *sim.parts_[p];
  if (const std::string e = ply_stability(m.membrane, st.mesh.triangles, m.node_temperature, row_strain[p], row_q[p],
                                          row_tol[p], &row_theta[p]);
      !e.empty())
    throw RunError("material law of part '" + st.def->name + "' failed in the stability check at t = " +
                   fmt_g(time) + " s: " + e);
  double unstable = 0, q_min = std::numeric_limits<double>::infinity();
  int worst = -1;
  for (std::size_t e = 0; e < row_q[p].size(); ++e) {
    const double q = row_q[p][e];
    if (!(q < -row_tol[p][e])) continue;
    unstable += elem_area[p][e];
    if (q < q_min) {
      q_min = q;
      worst = static_cast<int>(e);
    }
  }
  if (worst < 0)
    for (double q : row_q[p])
      if (q < q_min) q_min = q;
  // No element with a value (every one collapsed): none, rather than infinity.
  if (!std::isfinite(q_min)) q_min = std::numeric_limits<double>::quiet_NaN();
  if (worst >= 0 && sim.unstable_from_[p] < 0) {
    sim.unstable_from_[p] = time;
    // The worst element: where it is, and the direction of the pattern
    // that lowers its energy most (n, from its initial fibre direction).
    const int* tri = &st.mesh.triangles[3 * static_cast<std::size_t>(worst)];
    double c[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a)
      for (int d = 0; d < 3; ++d) c[d] += st.x[3 * tri[a] + d] / 3.0;
    const double T = m.node_temperature[tri[0]] / 3.0 + m.node_temperature[tri[1]] / 3.0 +
                     m.node_temperature[tri[2]] / 3.0;
    const double deg = row_theta[p][worst] * 180.0 / 3.14159265358979323846;
    // With the fibres' in-plane bending (rigidity R at the element's
    // temperature), a pattern of wavelength l along n costs q k^2 + R
    // cos^4(theta) k^4 per amplitude squared (k = 2 pi / l): those shorter
    // than 2 pi cos^2(theta) sqrt(R / |q|) are held.
    std::string who = "the mesh, the step and the contact do";
    if (m.in_plane_bending) {
      double chi[3] = {1.0, 0.0, 0.0}, moment[3] = {0, 0, 0}, w = 0;
      sdk::MaterialBlock blk;
      blk.n = 1;
      blk.strain = chi;
      blk.temperature = std::span<const double>(&T, 1);
      blk.stress = moment;
      blk.energy = std::span<double>(&w, 1);
      const double cth = std::cos(row_theta[p][worst]);
      const double length = m.in_plane_bending->evaluate(blk) && moment[0] > 0
                                ? 2 * 3.14159265358979323846 * cth * cth * std::sqrt(moment[0] / -q_min)
                                : 0.0;
      who = length > 0 ? fmt::format("its in-plane fibre bending (in_plane_bending) holds such patterns shorter than "
                                     "{} mm there, the longer ones are the ply's own",
                                     fmt_g(1e3 * length, 3))
                       : "its in-plane fibre bending (in_plane_bending) does not hold this pattern; the mesh, the "
                         "step and the contact do";
    }
    logger("solve")->warn(
        "t = {} s: part '{}': the long-term (relaxed) response of its membrane law is unstable in {} % of its area "
        "(down to {} N/m at element {}, {} m, {:.4g} degC, for a pattern varying at {:.0f} deg from the initial "
        "fibre direction): there the law alone does not set the ply's in-plane shape (fibre waviness, shear); {} "
        "(user guide, \"Material stability\")",
        fmt_g(time, 4), st.def->name, fmt_g(100 * unstable / total, 3), fmt_g(q_min, 3), element_tag(st.mesh, worst),
        detail::fmt_vec3(c[0], c[1], c[2]), T, deg > 90 ? 180 - deg : deg, who);
  }
  // The thickness at constant volume (a collapsed element, NaN, left out).
  std::vector<double>& h = row_thickness[p];
  h.resize(elem_area[p].size());
  constant_volume_thickness(st.mesh, elem_area[p], st.x.data(), st.def->thickness, h.data());
  double hmn = std::numeric_limits<double>::quiet_NaN(), hmx = hmn;  // NaN where every element has collapsed
  for (const double v : h) {
    hmn = std::fmin(hmn, v);
    hmx = std::fmax(hmx, v);
  }
  return {*smn, *smx, fmn, fmx, over / total, unstable / total, q_min, hmn, hmx};
}

// Each ply's row of plies.csv (ply_temperature, ply_crystallinity, ply_mechanics).
void Simulation::Run::sample_plies(double time) {
  ply_rows.push_back(time);
  for (std::size_t p = 0; p < sim.parts_.size(); ++p) {
    const std::size_t at = ply_rows.size();
    if (job.thermal) {
      const std::array<double, 4> row = ply_temperature(*sim.parts_[p], threshold_of(p));
      ply_rows.insert(ply_rows.end(), row.begin(), row.begin() + (threshold ? 4 : 3));
      if (crystallising) {
        const std::array<double, 3> x = ply_crystallinity(*sim.parts_[p]);
        ply_rows.insert(ply_rows.end(), x.begin(), x.end());
      }
    }
    if (job.mechanics) {
      const std::array<double, 9> row = ply_mechanics(p, time);
      ply_rows.insert(ply_rows.end(), row.begin(), row.begin() + (shear_limit ? 5 : 4));
      ply_rows.insert(ply_rows.end(), row.begin() + 5, row.end());
    }
    if (job.thermal) {
      auto at_p = [p](const std::vector<double>& v) { return p < v.size() ? v[p] : 0.0; };
      ply_rows.push_back(at_p(sim.part_tool_heat_));
      ply_rows.push_back(at_p(sim.part_exchange_heat_));
      ply_rows.push_back(at_p(sim.link_heat_));
    }
    if (plies_csv.is_open()) {
      plies_csv << csv_number(time) << ',' << sim.parts_[p]->def->name;
      for (std::size_t k = at; k < ply_rows.size(); ++k) plies_csv << ',' << csv_number(ply_rows[k]);
      plies_csv << '\n';
    }
  }
  if (plies_csv.is_open()) plies_csv.flush();
}

// A row of energy.csv: the audit at t.
void Simulation::Run::sample_energy() {
  const double row[8] = {t,           audit.kinetic, audit.internal,      audit.external,
                         audit.damping, audit.contact, audit.contact_stored, audit.balance_error};
  energy_rows.insert(energy_rows.end(), row, row + 8);
  energy_rows.insert(energy_rows.end(), audit.reactions.begin(), audit.reactions.end());
  energy_rows.push_back(audit.kinetic_half);
  if (energy_csv.is_open()) {
    for (int c = 0; c < 8; ++c) energy_csv << (c ? "," : "") << csv_number(row[c]);
    for (double r : audit.reactions) energy_csv << ',' << csv_number(r);
    energy_csv << ',' << csv_number(audit.kinetic_half) << '\n';
  }
}

// Quasi-static check over the sampled energy history: kinetic (half-step)
// / internal energy at the end, and the time from which it stays under
// 5 % (-1: not at the end).
std::pair<double, double> Simulation::Run::quasi_static() const {
  // ratio NaN: no internal energy was ever stored (the check does not
  // apply). Internal energy at the round-off of the run's energies (plies
  // held in their plane and only pressed: 1e-20 J beside contact springs
  // of 1e-4 J) counts as none.
  const std::size_t w = energy_cols.size();
  double scale = 0;  // the largest energy of the run
  for (std::size_t r = 0; r + w <= energy_rows.size(); r += w)
    for (std::size_t c = 1; c <= 6; ++c) scale = std::max(scale, std::abs(energy_rows[r + c]));
  double ratio = std::numeric_limits<double>::quiet_NaN(), below_from = -1;
  for (std::size_t r = 0; r + w <= energy_rows.size(); r += w) {
    const double t_r = energy_rows[r], ie = energy_rows[r + 2], ke = energy_rows[r + w - 1];
    if (!(ie > 1e-9 * scale)) continue;
    ratio = ke / ie;
    if (ratio >= 0.05)
      below_from = -1;
    else if (below_from < 0)
      below_from = t_r;
  }
  return {ratio, below_from};
}

void Simulation::Run::finish() {
  const auto& parts = sim.parts_;
  const auto& tools = sim.tools_;
  // The time series into results.h5 and their files flushed; where the disk
  // is full, the first file that could not be written is the failure (or
  // the failure that stopped the run stays the one reported).
  try {
    if (writer && job.mechanics && energy_rows.size() % energy_cols.size() == 0)
      writer->write_series("energy", energy_cols, energy_rows);
    if (writer && !tools.empty() && tool_rows.size() % tool_cols.size() == 0 && !tool_rows.empty())
      writer->write_series("tools", tool_cols, tool_rows);
    if (writer && ply_series && ply_rows.size() % ply_cols.size() == 0 && !ply_rows.empty())
      writer->write_series("plies", ply_cols, ply_rows);
    check_series_files();
  } catch (const std::runtime_error& e) {
    if (failure.empty()) failure = e.what();
  }
  const double stored_change = sim.stored_heat() - stored0;
  const double scale = std::max({std::abs(stored_change), std::abs(heat_in), 1e-300});
  if (failure.empty() && stop_signal != 0) {
    failure = std::string("interrupted by ") + signal_name(stop_signal) + " at t = " + fmt_g(t) + " s of " +
              fmt_g(t_end) + " s (" +
              (job.mechanics ? "mechanical step " + std::to_string(mech_steps)
                             : "thermal step " + std::to_string(steps)) +
              "); the output folder holds the frames up to that time";
    result.interrupted = stop_signal;
  }
  // Each ply's share beyond the shear limit at the end (where the run
  // stopped; a first time beyond it found here is the end's).
  // The same for the share whose long-term response is unstable.
  over_end.assign(parts.size(), 0.0);
  unstable_end.assign(parts.size(), 0.0);
  stability_min_end.assign(parts.size(), 0.0);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  thickness_end.assign(parts.size(), {kNaN, kNaN});  // none where the check below fails
  if (job.mechanics) try {
      for (std::size_t p = 0; p < sim.mech_.size(); ++p) {
        const std::array<double, 9> row = ply_mechanics(p, t);
        over_end[p] = row[4];
        unstable_end[p] = row[5];
        stability_min_end[p] = row[6];
        thickness_end[p] = {row[7], row[8]};
      }
    } catch (const RunError& e) {
      if (failure.empty()) failure = e.what();
    }
  result.ok = failure.empty();
  result.error = failure;
  result.wall_time_s = seconds_since(wall0);
  result.wall_time_before_s = wall_before;
  result.checkpoint_s = checkpoint_at;
  result.peak_memory_mb = peak_resident_mb();
  result.simulated_time_s = t;
  result.thermal_steps = steps;
  result.thermal_dt = sim.thermal_dt_;
  result.heat_in = heat_in;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    result.part_heat_change.push_back(sim.stored_heat(static_cast<int>(p)) - stored0_part[p]);
    result.part_link_heat.push_back(sim.link_heat_.size() > p ? sim.link_heat_[p] : 0.0);
    const double exchanges_p = sim.part_exchange_heat_.size() > p ? sim.part_exchange_heat_[p] : 0.0;
    const double tools_p = sim.part_tool_heat_.size() > p ? sim.part_tool_heat_[p] : 0.0;
    result.part_tool_heat.push_back(tools_p);
    result.part_exchange_heat.push_back(exchanges_p);
    // With mechanics, one range per part (every part has elements, so its
    // shear angles and strains are not empty).
    const auto& sa = parts[p]->shear_angle;
    if (job.mechanics) {
      const auto [smn, smx] = std::minmax_element(sa.begin(), sa.end());
      result.part_shear_min_deg.push_back(*smn);
      result.part_shear_max_deg.push_back(*smx);
      const auto [fmn, fmx] = fibre_strain_range(sim.mech_[p]->strain);
      result.part_fibre_strain_min.push_back(fmn);
      result.part_fibre_strain_max.push_back(fmx);
      result.part_thickness_min_m.push_back(thickness_end[p][0]);
      result.part_thickness_max_m.push_back(thickness_end[p][1]);
    }
  }
  result.stored_change = stored_change;
  result.heat_balance_error = std::abs(stored_change - heat_in) / scale;
  result.limited_node_steps = limited_total;
  result.mechanical_steps = mech_steps;
  result.bending_evaluations = sim.bending_evaluations_;
  result.bending_largest = sim.bending_largest_;
  result.mechanical_dt = mech_dt;
  result.energy = audit;
  for (std::size_t q = 0; q < tools.size(); ++q) {
    const auto& u = tools[q]->displacement();
    result.energy.tool_displacements.insert(result.energy.tool_displacements.end(), u.begin(), u.end());
    for (int d = 0; d < 3; ++d) result.energy.tool_forces.push_back(sim.tool_force_[3 * q + d]);
    result.energy.tool_heat.push_back(sim.tool_heat_[q]);
    result.heat_from_tools += sim.tool_heat_[q];
  }
  result.heat_sources_at_step_end = sim.face_values_missing_;
  result.heat_from_exchanges = 0;
  for (double q : sim.part_exchange_heat_) result.heat_from_exchanges += q;
  if (job.mechanics && !tools.empty()) {  // the press force: the largest over the rows
    const std::size_t nt = tools.size(), stride = 1 + 8 * nt;
    result.energy.tool_force_max.assign(nt, 0.0);
    result.energy.tool_force_max_at.assign(nt, 0.0);
    for (std::size_t r = 0; r + stride <= tool_rows.size(); r += stride)
      for (std::size_t q = 0; q < nt; ++q) {
        const double* f = &tool_rows[r + 1 + 8 * q + 3];
        const double m = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (m > result.energy.tool_force_max[q]) {
          result.energy.tool_force_max[q] = m;
          result.energy.tool_force_max_at[q] = tool_rows[r];
        }
      }
  }
  if (!sim.grippers_.empty()) {  // each gripper's largest force over the rows of energy.csv
    const std::size_t w = energy_cols.size();
    result.energy.gripper_force_max.assign(sim.grippers_.size(), 0.0);
    result.energy.gripper_force_max_at.assign(sim.grippers_.size(), 0.0);
    for (std::size_t r = 0; r + w <= energy_rows.size(); r += w)
      for (std::size_t g = 0; g < sim.grippers_.size(); ++g) {
        const double* f = &energy_rows[r + 8 + 3 * static_cast<std::size_t>(sim.grippers_[g].constraint)];
        const double m = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (m > result.energy.gripper_force_max[g]) {
          result.energy.gripper_force_max[g] = m;
          result.energy.gripper_force_max_at[g] = energy_rows[r];
        }
      }
  }
  for (const auto& m : sim.mech_) result.energy.added_mass_percent.push_back(100 * m->mass_added / m->mass_physical);
  result.temperature_min = sim.seen_min_;
  result.temperature_max = sim.seen_max_;
  // Each ply's temperatures at the end (the summary and the log's last lines).
  if (job.thermal)
    for (std::size_t p = 0; p < parts.size(); ++p) ply_end.push_back(ply_temperature(*parts[p], threshold_of(p)));
  const std::size_t w = ply_cols.size();
  for (std::size_t r = 0; r + w <= ply_rows.size(); r += w)
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const double* v = &ply_rows[r + 1 + ply_per * p];
      RunResult::PlySample s;
      s.part = static_cast<int>(p);
      s.time = ply_rows[r];
      if (job.thermal) {
        s.min = v[0];
        s.mean = v[1];
        s.max = v[2];
        s.fraction_below = threshold ? v[3] : 0.0;
        v += threshold ? 4 : 3;
        if (crystallising) {
          s.crystallinity_min = v[0];
          s.crystallinity_mean = v[1];
          s.crystallinity_max = v[2];
          v += 3;
        }
      }
      if (job.mechanics) {
        s.shear_min = v[0];
        s.shear_max = v[1];
        s.fibre_strain_min = v[2];
        s.fibre_strain_max = v[3];
        s.fraction_over_shear_limit = shear_limit ? v[4] : 0.0;
        v += shear_limit ? 5 : 4;
        s.fraction_unstable = v[0];
        s.stability_min = v[1];
        s.thickness_min = v[2];
        s.thickness_max = v[3];
        v += 4;
      }
      if (job.thermal) {
        s.heat_from_tools = v[0];
        s.heat_from_exchanges = v[1];
        s.heat_from_plies = v[2];
      }
      result.ply_history.push_back(s);
    }
  if (threshold) result.part_below_threshold_from_s = sim.below_from_;
  if (threshold) result.part_all_below_threshold_from_s = sim.all_below_from_;
  if (shear_limit) result.part_over_shear_limit_from_s = sim.over_from_;
  if (job.mechanics) result.part_unstable_from_s = sim.unstable_from_;

  if (opt.write_files) {
    update_derived();
    if (std::string why; !write_summary(why) && result.ok) {
      result.ok = false;
      result.error = failure = why;
    }
  }
  log_end();
}

namespace {
// What the run took of each material: the density and the thermal data (a
// number, or the rows [T (degC), ...] where they follow the temperature),
// as given or as formed from a mixture, whose fractions it adds.
json materials_summary(const Job& job) {
  json out = json::object();
  for (const auto& m : job.materials) {
    json e = json::object();
    if (m.density > 0) e["density_kg_m3"] = m.density;
    if (m.has_thermal) {
      if (m.specific_heat_table.empty()) {
        e["specific_heat_J_kg_K"] = m.specific_heat;
      } else {
        json rows = json::array();
        for (const auto& r : m.specific_heat_table) rows.push_back({r[0], r[1]});
        e["specific_heat_J_kg_K"] = rows;
      }
      if (m.conductivity_table.empty()) {
        e["conductivity_W_m_K"] = {m.conductivity[0], m.conductivity[1], m.conductivity[2]};
      } else {
        json rows = json::array();
        for (const auto& r : m.conductivity_table) rows.push_back({r[0], r[1], r[2], r[3]});
        e["conductivity_W_m_K"] = rows;
      }
    }
    if (m.mixture_fibre_fraction >= 0) {
      e["fibre_volume_fraction"] = m.mixture_fibre_fraction;
      e["matrix_mass_fraction"] = m.mixture_matrix_mass_fraction;
    }
    out[m.name] = e;
  }
  return out;
}
// A gripper's gripped region at the end: its centre at t = 0 and the
// centre's displacement; the rigid motion that best carries the nodes'
// initial places (about their centre) onto their places at the end, its
// angle (degrees), and the largest distance of a node from where that
// motion puts it (how far the region has deformed).
struct JawMotion {
  std::array<double, 3> c0{0, 0, 0}, cu{0, 0, 0};
  double rotation_deg = 0, distortion = 0;
};
template <class G, class Parts>
JawMotion jaw_motion(const G& gr, const Parts& parts) {
  JawMotion out;
  auto& c0 = out.c0;
  auto& cu = out.cu;
  for (std::size_t j = 0; j < gr.nodes.size(); ++j)
    for (int d = 0; d < 3; ++d) {
      const std::size_t k = 3 * static_cast<std::size_t>(gr.nodes[j].second) + d;
      c0[d] += gr.share[j] * parts[gr.nodes[j].first]->x0[k];
      cu[d] += gr.share[j] * (parts[gr.nodes[j].first]->x[k] - parts[gr.nodes[j].first]->x0[k]);
    }
  double H[9] = {}, R[9];
  for (std::size_t j = 0; j < gr.nodes.size(); ++j) {
    const auto [p, i] = gr.nodes[j];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        H[3 * r + c] += gr.share[j] * (parts[p]->x0[3 * i + r] - c0[r]) * (parts[p]->x[3 * i + c] - c0[c] - cu[c]);
  }
  best_fit_rotation(H, R);
  for (const auto& [p, i] : gr.nodes) {
    double s2 = 0;
    for (int d = 0; d < 3; ++d) {
      double placed = c0[d] + cu[d];
      for (int e = 0; e < 3; ++e) placed += R[3 * d + e] * (parts[p]->x0[3 * i + e] - c0[e]);
      const double err = parts[p]->x[3 * static_cast<std::size_t>(i) + d] - placed;
      s2 += err * err;
    }
    out.distortion = std::max(out.distortion, std::sqrt(s2));
  }
  // The angle from its sine (the skew part) and cosine (the trace).
  const double sine =
      0.5 * std::sqrt(std::pow(R[7] - R[5], 2) + std::pow(R[2] - R[6], 2) + std::pow(R[3] - R[1], 2));
  out.rotation_deg = std::atan2(sine, 0.5 * (R[0] + R[4] + R[8] - 1.0)) * 180.0 / M_PI;
  return out;
}
}  // namespace

bool Simulation::Run::write_summary(std::string& why) const {
  const auto& parts = sim.parts_;
  const auto& mech = sim.mech_;
  const auto& timing = sim.timing_;
  json summary;
  summary["job"] = job.name;
  summary["job_file"] = std::filesystem::absolute(job.file).lexically_normal().string();
  summary["status"] = result.ok ? "completed" : result.interrupted ? "interrupted" : "failed";
  summary["version"] = kVersion;
  summary["threads"] = threads;
  summary["subnormals"] = subnormals;
  summary["wall_time_s"] = result.wall_time_s;
  summary["wall_time_total_s"] = result.wall_time_before_s + result.wall_time_s;
  summary["peak_memory_MB"] = result.peak_memory_mb > 0 ? json(result.peak_memory_mb) : json(nullptr);
  summary["simulated_time_s"] = t;
  summary["restarted_from_s"] = restarted_from >= 0 ? json(restarted_from) : json(nullptr);
  summary["checkpoint_s"] = checkpoint_at >= 0 ? json(checkpoint_at) : json(nullptr);
  summary["steps"] = {{"mechanics", mech_steps}, {"thermal", steps}};
  summary["dt"] = {{"mechanics", job.mechanics ? json(mech_dt) : json(nullptr)},
                   {"thermal", job.thermal ? json(sim.thermal_dt_) : json(nullptr)}};
  if (job.thermal)
    summary["thermal"] = {
        {"splitter", job.thermal->splitter},
        {"stable_dt", std::isfinite(sim.thermal_stable_dt_) ? json(sim.thermal_stable_dt_) : json(nullptr)},
        {"accurate_dt", sim.thermal_accurate_dt_},
        {"inplane_substeps_max", substeps_max},
        {"limited_node_steps", limited_total}};
  summary["plugins_loaded"] = sim.registry_.loaded_names();
  summary["materials"] = materials_summary(job);
  if (job.mechanics)
    summary["timing_s"] = {{"elements_and_laws", timing[kTimeElements]},
                           {"contact", timing[kTimeContact]},
                           {"thermal", timing[kTimeThermal]},
                           {"time_integration_and_audit", timing[kTimeIntegrate]},
                           {"output", timing[kTimeOutput]}};
  if (job.mechanics) {  // share of the steps whose contact ran beside the element blocks (either way)
    const ForceSchedule& fs = sim.schedule_;
    const double calls = static_cast<double>(std::max(fs.calls, 1LL));
    summary["contact_beside_elements"] = static_cast<double>(fs.way_calls[kBeside] + fs.way_calls[kByPart]) / calls;
    summary["contact_schedule_share"] = {{"in_turn", static_cast<double>(fs.way_calls[kInTurn]) / calls},
                                         {"beside", static_cast<double>(fs.way_calls[kBeside]) / calls},
                                         {"by_part", static_cast<double>(fs.way_calls[kByPart]) / calls}};
  }
  if (job.mechanics && job.mechanics_settings.bending_subcycles > 1)
    summary["bending_subcycles"] = {{"at_most", job.mechanics_settings.bending_subcycles},
                                    {"evaluations", sim.bending_evaluations_},
                                    {"largest", sim.bending_largest_}};
  summary["energy"] = {{"kinetic", audit.kinetic}, {"internal", audit.internal}, {"external_work", audit.external},
                       {"contact", audit.contact}, {"contact_stored", audit.contact_stored},
                       {"damping", audit.damping}, {"balance_error", audit.balance_error},
                       {"kinetic_half_step", audit.kinetic_half}};
  if (job.mechanics && !energy_rows.empty()) {
    const auto [ratio, below_from] = quasi_static();
    summary["energy"]["kinetic_to_internal"] = {
        {"at_end", std::isnan(ratio) ? json(nullptr) : json(ratio)},
        {"under_5_percent_from_s", below_from >= 0 ? json(below_from) : json(nullptr)}};
  }
  json tools = json::array();
  for (std::size_t q = 0; q < sim.tools_.size(); ++q) {
    const auto& u = sim.tools_[q]->displacement();
    const double* f = &sim.tool_force_[3 * q];
    tools.push_back({{"name", job.tools[q].name},
                     {"displacement_m", {u[0], u[1], u[2]}},
                     {"force_N", {f[0], f[1], f[2]}},
                     {"heat_to_plies_J", sim.tool_heat_[q]}});
    if (q < result.energy.tool_force_max.size()) {
      tools.back()["force_max_N"] = result.energy.tool_force_max[q];
      tools.back()["force_max_at_s"] = result.energy.tool_force_max_at[q];
    }
  }
  summary["tools"] = tools;
  if (job.mechanics) {
    json reactions = json::array();
    for (std::size_t c = 0; c < job.constraints.size(); ++c)
      reactions.push_back({{"constraint", job.constraints[c].pointer},
                           {"force", {audit.reactions.size() > 3 * c ? audit.reactions[3 * c] : 0.0,
                                      audit.reactions.size() > 3 * c ? audit.reactions[3 * c + 1] : 0.0,
                                      audit.reactions.size() > 3 * c ? audit.reactions[3 * c + 2] : 0.0}}});
    summary["reactions_N"] = reactions;
    if (!sim.grippers_.empty()) {
      json grippers = json::array();
      for (std::size_t g = 0; g < sim.grippers_.size(); ++g) {
        const Gripper& gr = sim.grippers_[g];
        const ConstraintDef& c = job.constraints[gr.constraint];
        const JawMotion jm = jaw_motion(gr, parts);
        const std::array<double, 3>& c0 = jm.c0;
        grippers.push_back({{"name", c.name},
                            {"constraint", c.pointer},
                            {"jaws", c.swivelling ? "swivelling" : c.rigid ? "rigid" : "flexible"},
                            {"nodes", gr.nodes.size()},
                            {"mass_kg", gr.mass},
                            {"force_N", gr.force},
                            {"tension_N", gr.tension},
                            {"extension_m", gr.extension},
                            {"centre_displacement_m",
                             {gr.centre[0] - c0[0], gr.centre[1] - c0[1], gr.centre[2] - c0[2]}},
                            {"jaw_distortion_m", jm.distortion},
                            {"jaw_rotation_deg", jm.rotation_deg},
                            {"force_max_N", result.energy.gripper_force_max[g]},
                            {"force_max_at_s", result.energy.gripper_force_max_at[g]}});
      }
      summary["grippers"] = grippers;
    }
    json added = json::object();
    for (std::size_t p = 0; p < mech.size(); ++p)
      added[parts[p]->def->name] = 100 * mech[p]->mass_added / mech[p]->mass_physical;
    summary["mass_scaling_added_percent"] = added;
  }
  summary["heat"] = {{"stored_change_J", result.stored_change},
                     {"faces_in_J", heat_in},
                     {"from_tools_J", result.heat_from_tools},
                     {"from_exchanges_J", result.heat_from_exchanges},
                     {"by_source_at", result.heat_sources_at_step_end ? "end-of-step values" : "face values"},
                     {"balance_error", result.heat_balance_error}};
  const std::vector<double>& thresholds = job.output.temperature_threshold;
  const std::vector<double>& shear_limits = job.output.shear_angle_limit;
  json plies = json::array();
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const auto& st = parts[p];
    const auto [mn, mx] = std::minmax_element(st->T.begin(), st->T.end());
    plies.push_back({{"name", st->def->name},
                     {"nodes", st->mesh.num_nodes()},
                     {"elements", st->mesh.num_elements()},
                     {"values_per_node", st->nz},
                     {"temperature_min", *mn},
                     {"temperature_max", *mx}});
    json& ply = plies.back();
    if (job.thermal) {
      ply["temperature_mean"] = ply_end[p][1];
      // The ply's heat audit (J, received): stored change = tools + heat
      // exchanges + other plies.
      const double dq = result.part_heat_change[p], tq = result.part_tool_heat[p],
                   xq = result.part_exchange_heat[p], lq = result.part_link_heat[p];
      const double scale_p = std::max({std::abs(dq), std::abs(tq) + std::abs(xq) + std::abs(lq), 1e-300});
      ply["heat_J"] = {{"stored_change", dq},
                       {"from_tools", tq},
                       {"from_exchanges", xq},
                       {"from_plies", lq},
                       {"balance_error", std::abs(dq - (tq + xq + lq)) / scale_p}};
      if (threshold) ply["fraction_below_threshold"] = ply_end[p][3];
      if (!st->X.empty()) {
        const std::array<double, 3> x = ply_crystallinity(*st);
        ply["crystallinity_min"] = x[0];
        ply["crystallinity_mean"] = x[1];
        ply["crystallinity_max"] = x[2];
      }
    }
    if (threshold) {
      ply["temperature_threshold"] = thresholds[p];
      ply["below_threshold_from_s"] = sim.below_from_[p] >= 0 ? json(sim.below_from_[p]) : json(nullptr);
      ply["all_below_threshold_from_s"] = sim.all_below_from_[p] >= 0 ? json(sim.all_below_from_[p]) : json(nullptr);
    }
    if (job.mechanics) {
      ply["shear_angle_min_deg"] = result.part_shear_min_deg[p];
      ply["shear_angle_max_deg"] = result.part_shear_max_deg[p];
      ply["fibre_strain_min"] = result.part_fibre_strain_min[p];
      ply["fibre_strain_max"] = result.part_fibre_strain_max[p];
      ply["thickness_min_m"] = result.part_thickness_min_m[p];
      ply["thickness_max_m"] = result.part_thickness_max_m[p];
      ply["fraction_unstable"] = unstable_end[p];
      ply["stability_min_N_m"] = std::isfinite(stability_min_end[p]) ? json(stability_min_end[p]) : json(nullptr);
      ply["unstable_from_s"] = sim.unstable_from_[p] >= 0 ? json(sim.unstable_from_[p]) : json(nullptr);
    }
    if (shear_limit) {
      ply["shear_angle_limit"] = shear_limits[p];
      ply["fraction_over_shear_limit"] = over_end[p];
      ply["over_shear_limit_from_s"] = sim.over_from_[p] >= 0 ? json(sim.over_from_[p]) : json(nullptr);
    }
  }
  summary["parts"] = plies;
  summary["frames"] = writer ? writer->frames() : 0;
  summary["error"] = result.ok ? json(nullptr) : json(failure);
  errno = 0;
  std::ofstream out(opt.out_dir / "summary.json");
  if (out << summary.dump(2) << '\n' && out.flush()) return true;
  why = "cannot write " + (opt.out_dir / "summary.json").string() + ": " +
        write_failure_reason(opt.out_dir, errno, "the stream failed");
  return false;
}

void Simulation::Run::log_end() const {
  auto log = logger("solve");
  const auto& parts = sim.parts_;
  const std::vector<double>& thresholds = job.output.temperature_threshold;
  const std::vector<double>& shear_limits = job.output.shear_angle_limit;
  if (limited_total > 0)
    log->info("the thermal splitter limited {} node-step(s) to keep temperatures inside their local range "
              "(steep through-thickness profiles next to strong in-plane conduction)",
              limited_total);
  if (result.ok && job.mechanics) {
    log->info("mechanics: {} steps (last {:.3g} s), energy balance error {:.2e}, kinetic {:.4g} J, internal {:.4g} J, "
              "contact {:.4g} J, damping {:.4g} J",
              mech_steps, mech_dt, audit.balance_error, audit.kinetic, audit.internal, audit.contact, audit.damping);
    if (!energy_rows.empty()) {
      const auto [ratio, below_from] = quasi_static();
      const std::string hint =
          ": the mass scaling makes part of the run dynamic; compare the results with a smaller "
          "solvers.mechanics.mass_scaling.target_dt";
      if (std::isnan(ratio))
        log->info("kinetic/internal energy: no internal energy was stored, the ratio does not apply");
      else if (below_from >= 0 && below_from <= 0.1 * t_end)
        log->info("kinetic/internal energy {:.2g} % at the end, under 5 % from t = {:.3g} s", 100 * ratio, below_from);
      else if (below_from >= 0)
        log->info("kinetic/internal energy {:.2g} % at the end, under 5 % only from t = {:.3g} s ({:.0f} % of the run){}",
                  100 * ratio, below_from, 100 * below_from / t_end, hint);
      else
        log->warn("kinetic/internal energy {:.2g} % at the end (above 5 %){}", 100 * ratio, hint);
    }
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const PartState& st = *parts[p];
      const auto [mn, mx] = std::minmax_element(st.T.begin(), st.T.end());
      std::string over;
      if (shear_limit && sim.over_from_[p] >= 0)
        over = fmt::format(", beyond {} deg from t = {} s, {:.1f} % of its area at the end", fmt_g(shear_limits[p]),
                           fmt_g(sim.over_from_[p], 4), 100 * over_end[p]);
      else if (shear_limit)
        over = fmt::format(", never beyond {} deg", fmt_g(shear_limits[p]));
      log->info("part '{}': temperature {:.2f} to {:.2f} degC, shear angle {:.2f} to {:.2f} deg{}, fibre strain {:.3g} "
                "to {:.3g}, thickness at constant volume {:.4g} to {:.4g} mm",
                st.def->name, *mn, *mx, result.part_shear_min_deg[p], result.part_shear_max_deg[p], over,
                result.part_fibre_strain_min[p], result.part_fibre_strain_max[p],
                1e3 * result.part_thickness_min_m[p], 1e3 * result.part_thickness_max_m[p]);
      if (sim.unstable_from_[p] >= 0)
        log->warn("part '{}': long-term membrane response unstable from t = {} s, in {} % of its area at the end "
                  "(down to {} N/m): the law alone does not set its in-plane shape there; {} (user guide, "
                  "\"Material stability\")",
                  st.def->name, fmt_g(sim.unstable_from_[p], 4), fmt_g(100 * unstable_end[p], 3),
                  fmt_g(stability_min_end[p], 3),
                  sim.mech_[p]->in_plane_bending
                      ? "its in-plane fibre bending gives fibre waviness a length there; compare with a finer mesh"
                      : "compare with a finer mesh");
    }
    for (std::size_t q = 0; q < result.energy.tool_force_max.size(); ++q)
      log->info("tool '{}': largest force {:.4g} N at t = {} s", job.tools[q].name, result.energy.tool_force_max[q],
                fmt_g(result.energy.tool_force_max_at[q], 4));
    for (std::size_t g = 0; g < result.energy.gripper_force_max.size(); ++g) {
      const Gripper& gr = sim.grippers_[g];
      const ConstraintDef& c = job.constraints[gr.constraint];
      std::string region;  // how the gripped region has turned (and deformed)
      if (c.swivelling || !c.rigid) {
        const JawMotion jm = jaw_motion(gr, parts);
        region = fmt::format("; the gripped region turned by {:.3g} deg", jm.rotation_deg);
        if (!c.rigid) region += fmt::format(" and deformed by {:.3g} mm beyond that", 1e3 * jm.distortion);
      }
      log->info("gripper '{}': largest force {:.4g} N at t = {} s; at the end {:.4g} N, its spring {} by {:.4g} mm{}",
                c.name, result.energy.gripper_force_max[g], fmt_g(result.energy.gripper_force_max_at[g], 4),
                gr.tension, gr.extension >= 0 ? "extended" : "shortened", 1e3 * std::abs(gr.extension), region);
    }
  }
  if (job.thermal) {
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const std::array<double, 4>& now = ply_end[p];
      std::ostringstream line;
      line << std::fixed << std::setprecision(2) << "part '" << parts[p]->def->name << "': ";
      if (!job.mechanics) line << "temperature " << now[0] << " to " << now[2] << " degC, ";
      line << "mean " << now[1] << " degC";
      if (threshold && sim.below_from_[p] >= 0)
        line << ", below " << fmt_g(thresholds[p]) << " degC from t = " << fmt_g(sim.below_from_[p], 4) << " s"
             << (sim.all_below_from_[p] >= 0 ? ", all of it from t = " + fmt_g(sim.all_below_from_[p], 4) + " s" : "")
             << ", " << std::setprecision(1) << 100 * now[3] << " % of it below at the end";
      else if (threshold)
        line << ", never below " << fmt_g(thresholds[p]) << " degC";
      if (!parts[p]->X.empty()) {
        const std::array<double, 3> x = ply_crystallinity(*parts[p]);
        line << std::setprecision(3) << ", relative crystallinity " << x[0] << " to " << x[2] << " (mean " << x[1]
             << ")";
      }
      // The heat the ply received, by the sources the job has.
      line << std::setprecision(2) << "; heat received " << result.part_heat_change[p] << " J";
      const char* sep = ": ";
      if (!job.tools.empty()) line << std::exchange(sep, ", ") << "tools " << result.part_tool_heat[p] << " J";
      if (!job.heat_exchanges.empty())
        line << std::exchange(sep, ", ") << "heat exchanges " << result.part_exchange_heat[p] << " J";
      if (parts.size() > 1) line << std::exchange(sep, ", ") << "other plies " << result.part_link_heat[p] << " J";
      log->info("{}", line.str());
    }
  }
  if (result.ok) {
    log->info("completed: {} thermal steps in {:.3g} s wall; heat into the plies {:.6g} J (tools {:.6g} J, heat "
              "exchanges {:.6g} J), stored change {:.6g} J (balance error {:.2e}); peak memory {:.0f} MB",
              steps, result.wall_time_s, heat_in, result.heat_from_tools, result.heat_from_exchanges,
              result.stored_change, result.heat_balance_error, result.peak_memory_mb);
  } else if (result.interrupted) {
    log->warn("{}", failure);
  } else {
    log->error("run failed: {}", failure);
  }
}

// The fields of a frame, per part (output.fields; each with its values;
// the same in every frame of a run, but for a restart with other fields).
std::vector<std::vector<FrameField>> Simulation::frame_fields() const { return frame_fields(job_.output.fields); }

std::vector<std::vector<FrameField>> Simulation::frame_fields(const std::vector<std::string>& names) const {
  const auto& mech = mech_;
  std::vector<std::vector<FrameField>> fields(parts_.size());
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    for (const auto& f : names) {
      if (f == "temperature") {
        fields[p].push_back({"temperature", st.T.data(), 1, false, true});
        fields[p].push_back({"temperature_mean", st.mean.data()});
        fields[p].push_back({"temperature_top", st.top.data()});
        fields[p].push_back({"temperature_bottom", st.bottom.data()});
      } else if (f == "temperature_mean") {
        fields[p].push_back({"temperature_mean", st.mean.data()});
      } else if (f == "temperature_top") {
        fields[p].push_back({"temperature_top", st.top.data()});
      } else if (f == "temperature_bottom") {
        fields[p].push_back({"temperature_bottom", st.bottom.data()});
      } else if (f == "displacement") {
        fields[p].push_back({"displacement", st.displacement.data(), 3});
      } else if (f == "velocity" && p < mech.size()) {
        // Half-step velocity v^{n-1/2} of the step that ended at the frame.
        fields[p].push_back({"velocity", mech[p]->v.data(), 3});
      } else if (f == "shear_angle") {
        fields[p].push_back({"shear_angle", st.shear_angle.data(), 1, true});
      } else if (f == "fibre_direction") {
        fields[p].push_back({"fibre_direction", st.fibre.data(), 3, true});
      } else if (f == "contact_status") {
        fields[p].push_back({"contact_status", st.contact_status.data()});
      } else if (f == "contact_pressure") {
        fields[p].push_back({"contact_pressure", st.contact_pressure.data()});
      } else if (f == "conductance") {
        fields[p].push_back({"conductance_bottom", st.conductance_bottom.data()});
        fields[p].push_back({"conductance_top", st.conductance_top.data()});
      } else if (f == "tool_gap") {
        fields[p].push_back({"tool_gap", st.tool_gap.data()});
      } else if (f == "thickness" && !st.thickness.empty()) {
        fields[p].push_back({"thickness", st.thickness.data(), 1, true});
      } else if (f == "crystallinity" && !st.X.empty()) {
        fields[p].push_back({"crystallinity", st.X.data(), 1, false, true});
        fields[p].push_back({"crystallinity_mean", st.X_mean.data()});
      } else if (f == "below_threshold_from") {
        fields[p].push_back({"below_threshold_from", st.below_from.data()});
        fields[p].push_back({"all_below_threshold_from", st.all_below_from.data()});
      } else if (f == "membrane_stability" && p < mech.size()) {
        // Sized at the first frame that shows it (update_element_fields).
        if (mech[p]->stability.empty())
          mech[p]->stability.assign(static_cast<std::size_t>(st.mesh.num_elements()),
                                    std::numeric_limits<double>::quiet_NaN());
        fields[p].push_back({f, mech[p]->stability.data(), 1, true});
      } else if ((f == "membrane_stress" || f == "curvature" || f == "membrane_strain") && p < mech.size()) {
        // Material-frame components [11, 22, 12] per element, as vectors.
        fields[p].push_back({f,
                             f == "membrane_stress" ? mech[p]->stress.data()
                             : f == "curvature"     ? mech[p]->curvature.data()
                                                    : mech[p]->strain.data(),
                             3, true});
      }
    }
    // No field twice (e.g. "temperature" and "temperature_mean").
    auto& v = fields[p];
    std::vector<FrameField> unique;
    for (const auto& ff : v)
      if (std::none_of(unique.begin(), unique.end(), [&](const FrameField& u) { return u.name == ff.name; }))
        unique.push_back(ff);
    v = std::move(unique);
  }
  return fields;
}

// results.h5's parts: each ply's mesh, thickness and through-thickness
// values, with the through-thickness mesh where the ply's frames show a
// field on it ("temperature", or "crystallinity" for a ply with kinetics).
std::vector<WriterPart> Simulation::writer_parts() const {
  std::vector<WriterPart> wparts;
  const std::vector<std::vector<FrameField>> fields = frame_fields();
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    const auto& st = parts_[p];
    const bool layers =
        std::any_of(fields[p].begin(), fields[p].end(), [](const FrameField& f) { return f.on_layers; });
    WriterPart& wp = wparts.emplace_back(WriterPart{st->def->name, st->mesh.num_nodes(), st->mesh.num_elements(),
                                                    &st->mesh.triangles, st->def->thickness, st->nz, layers, {}, {}});
    for (int i = 0; i < wp.num_nodes; ++i) wp.node_tags.push_back(node_tag(st->mesh, i));
    for (int e = 0; e < wp.num_elements; ++e) wp.element_tags.push_back(element_tag(st->mesh, e));
  }
  return wparts;
}

// The tools' surfaces as results.h5 shows them (output.tool_surfaces; none
// without): each tool's display mesh over the plies' initial box, cut at
// the symmetry planes of the plies.
std::vector<WriterTool> Simulation::writer_tools() const {
  if (!job_.output.tool_surfaces) return {};
  // A plane is drawn over the plies' initial box.
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::array<double, 3> lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  for (const auto& st : parts_)
    for (std::size_t i = 0; i < st->x0.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], st->x0[i]);
      hi[i % 3] = std::max(hi[i % 3], st->x0[i]);
    }
  // The symmetry planes that every ply has, with the side the plies
  // lie on: the tools are drawn on that side only, as the plies are.
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  std::vector<std::pair<int, double>> planes;  // axis, side
  for (int d = 0; d < 3 && !job_.output.tool_surfaces_whole; ++d) {
    bool every_ply = true;
    for (std::size_t p = 0; p < job_.parts.size(); ++p)
      every_ply = every_ply &&
                  std::any_of(job_.constraints.begin(), job_.constraints.end(), [&](const ConstraintDef& c) {
                    return c.type == ConstraintDef::Type::Symmetry && c.plane == d &&
                           std::find(c.parts.begin(), c.parts.end(), static_cast<int>(p)) != c.parts.end();
                  });
    if (!every_ply || job_.parts.empty() || hi[d] - lo[d] <= 1e-6 * size) continue;  // (plies in the plane)
    if (lo[d] >= -1e-6 * size)
      planes.emplace_back(d, 1.0);
    else if (hi[d] <= 1e-6 * size)
      planes.emplace_back(d, -1.0);
  }
  std::vector<WriterTool> wtools;
  for (std::size_t t = 0; t < tools_.size(); ++t) {
    WriterTool& wt = wtools.emplace_back();
    wt.name = job_.tools[t].name;
    wt.moves = job_.mechanics && job_.tools[t].motion.kind != MotionDef::Kind::Fixed;
    tools_[t]->display_mesh(lo, hi, wt.nodes, wt.triangles);
    std::vector<double> nodes = wt.nodes;
    std::vector<int> triangles = wt.triangles;
    for (const auto& [axis, sign] : planes) cut_display_mesh(nodes, triangles, axis, sign, 1e-9 * size);
    if (!triangles.empty()) {  // a tool wholly beyond the planes is drawn whole
      wt.nodes = std::move(nodes);
      wt.triangles = std::move(triangles);
    }
  }
  return wtools;
}

double Simulation::frame_count() const {
  return 1 + std::ceil(job_.t_end / job_.output.interval * (1 - 1e-9));
}

double Simulation::frames_expected(double mech_step) const {
  if (job_.mechanics && mech_step > 0 && job_.output.interval < mech_step)  // a frame after every step
    return 1 + std::ceil(job_.t_end / mech_step);
  return frame_count();
}

double Simulation::results_estimate(double mech_step) const {
  const ResultsBytes b = results_bytes(writer_parts(), frame_fields(), writer_tools());
  return b.once + frames_expected(mech_step) * b.per_frame;
}

std::vector<std::string> Simulation::output_lines(double mech_step) const {
  const ResultsBytes b = results_bytes(writer_parts(), frame_fields(), writer_tools());
  const double n = frames_expected(mech_step), iv = job_.output.interval;
  std::string count = fmt_g(n, 15), times;
  if (job_.mechanics && mech_step > 0 && iv < mech_step) {  // a frame after every step
    const double r = n >= 1000 ? std::pow(10.0, std::floor(std::log10(n)) - 2) : 1.0;  // three digits
    count = "about " + fmt_g(std::round(n / r) * r, 15);
    times = "at t = 0 and after every mechanical step (output.interval " + fmt_g(iv) + " s is below the step, " +
            fmt_g(mech_step, 4) + " s at the start)";
  } else if (n <= 2) {
    times = n == 1 ? "at t = 0" : "at t = 0 and " + fmt_g(job_.t_end) + " s";
  } else if (std::abs(iv * (n - 1) - job_.t_end) <= 1e-9 * job_.t_end) {
    times = "at t = 0 and every " + fmt_g(iv) + " s to " + fmt_g(job_.t_end) + " s";
  } else {
    times = "at t = 0, every " + fmt_g(iv) + " s and " + fmt_g(job_.t_end) + " s";
  }
  const int level = job_.output.compression;
  return {"frames: " + count + " " + times + ", " + bytes_text(b.per_frame) + " each: about " +
          bytes_text(b.once + n * b.per_frame) + " of results.h5" +
          (level > 0 ? " before compression (level " + std::to_string(level) + ")" : "")};
}

}  // namespace ts
