// The time loop of a run (explicit mechanics with the thermal splitter
// every few steps, or the thermal steps alone), its checkpoints and
// restarts (docs/user-guide.md, "Checkpoints and restarts").
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <type_traits>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <nlohmann/json.hpp>

#include "io/checkpoint.hpp"
#include "io/fnv1a.hpp"
#include "io/logging.hpp"
#include "solve/interrupt.hpp"
#include "solve/simulation_internal.hpp"
#include "solve/subnormals.hpp"
#include "solve/tools.hpp"

namespace ts {

using detail::Clock;
using detail::fmt_g;
using detail::seconds_since;
using json = nlohmann::json;

namespace {

// The kinetic energy may not exceed this multiple of the energy supplied.
constexpr double kKineticGrowthLimit = 10.0;

// Moves a sampling time `next` past `limit` by whole intervals iv: one
// addition at a time where a few suffice (the times the schedule has always
// had), in one jump where many intervals fit in a step, and never stuck
// where iv is below the round-off of `next`.
void advance_past(double& next, double iv, double limit) {
  if (limit - next > 16 * iv) next += std::floor((limit - next) / iv) * iv;
  while (next <= limit) {
    const double n = next + iv;
    next = n > next ? n : std::nextafter(limit, std::numeric_limits<double>::infinity());
  }
}

// The job document a checkpoint stores: the run's, without the checkpoint
// settings and the compression of results.h5 (which a restart may change).
json restart_document(const json& doc) {
  json d = doc;
  if (d.contains("output") && d["output"].is_object()) {
    d["output"].erase("checkpoint_interval");
    d["output"].erase("checkpoint_at_end");
    d["output"].erase("keep_checkpoints");
    d["output"].erase("compression");
  }
  return d;
}

// Each part's mesh as the run numbers it (FNV-1a of its counts, triangles
// and node tags): a checkpoint holds them, so that a restart refuses a mesh
// file that changed, or that another version numbered otherwise.
std::vector<unsigned char> mesh_prints(const std::vector<std::unique_ptr<PartState>>& parts) {
  sdk::StateWriter w;
  for (const auto& st : parts) {
    std::uint64_t h = kFnv1aOffset;
    auto mix = [&](long long v) { fnv1a_mix(h, static_cast<std::uint64_t>(v)); };
    mix(st->mesh.num_nodes());
    mix(st->mesh.num_elements());
    for (const int t : st->mesh.triangles) mix(t);
    for (int i = 0; i < st->mesh.num_nodes(); ++i) mix(node_tag(st->mesh, i));
    w.put(h);
  }
  return std::move(w.bytes());
}

// What a restart compares: the stored document without time.end (a restart
// may move the end, to extend a finished run), output.interval and
// output.series_interval (a restart may write its frames and rows closer
// or further apart) and output.fields (the frames after the checkpoint may
// show other fields).
json restart_match(json d) {
  if (d.contains("time") && d["time"].is_object()) d["time"].erase("end");
  if (d.contains("output") && d["output"].is_object()) {
    d["output"].erase("interval");
    d["output"].erase("series_interval");
    d["output"].erase("fields");
  }
  return d;
}

// The time.end, frame interval (its output.interval, by default its
// time.end) and row interval (output.series_interval, by default time.end
// / 500) of the run that wrote a checkpoint, s; NaN where absent.
struct CheckpointTimes {
  double t_end, interval, series;
};
CheckpointTimes checkpoint_times(const Checkpoint& c) {
  const auto& bytes = c.section("job");
  const json d = json::parse(bytes.begin(), bytes.end());
  auto number = [&](const char* section, const char* key) {
    if (d.contains(section) && d[section].is_object() && d[section].contains(key) && d[section][key].is_number())
      return d[section][key].get<double>();
    return std::numeric_limits<double>::quiet_NaN();
  };
  const double t_end = number("time", "end"), interval = number("output", "interval");
  const double series = number("output", "series_interval");
  return {t_end, std::isnan(interval) ? t_end : interval, std::isnan(series) || series <= 0 ? t_end / 500 : series};
}

}  // namespace

// The output.fields of the run that wrote a checkpoint (the job's default
// where it gives none).
std::vector<std::string> checkpoint_fields(const Checkpoint& c) {
  const auto& bytes = c.section("job");
  const json d = json::parse(bytes.begin(), bytes.end());
  std::vector<std::string> fields;
  if (d.contains("output") && d["output"].is_object() && d["output"].contains("fields") &&
      d["output"]["fields"].is_array()) {
    for (const auto& f : d["output"]["fields"])
      if (f.is_string()) fields.push_back(f.get<std::string>());
    return fields;
  }
  return OutputDef::default_fields();
}

RunResult Simulation::run(const RunOptions& opt) {
  const auto wall0 = Clock::now();
#ifdef _OPENMP
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  omp_set_max_active_levels(1);  // loops inside a task run on its thread
  const int threads = omp_get_max_threads();
#else
  const int threads = 1;
#endif
  const SubnormalsFlushed flushed(opt.flush_subnormals);  // on every thread of the run, until it returns
  Run r(*this, opt, wall0, threads, flushed.mode());
  if (opt.restart) {  // everything read and checked before any file is touched
    r.read_checkpoint();
    r.restore();
  }
  r.open_output();
  r.log_start();
  try {
    if (r.resume)
      r.log_restore();
    else
      r.start();
    if (job_.mechanics)
      r.mechanics_loop();
    else
      r.thermal_loop();
    r.finish_interrupted();
  } catch (const RunError& e) {
    r.failure = e.what();
  } catch (const std::exception& e) {
    r.failure = std::string("unexpected error: ") + e.what();
  }
  r.finish();
  return std::move(r.result);
}

Simulation::Run::Run(Simulation& s, const RunOptions& o, Clock::time_point w0, int n_threads, const char* mode)
    : sim(s),
      job(s.job_),
      opt(o),
      wall0(w0),
      threads(n_threads),
      subnormals(mode),
      t_end(s.job_.t_end),
      interval(s.job_.output.interval),
      eps_t(1e-9 * (s.job_.thermal ? s.thermal_dt_ : s.job_.output.interval)),
      series_iv(s.job_.output.series_interval > 0 ? s.job_.output.series_interval : s.job_.t_end / 500),
      checkpoint_iv(s.job_.output.checkpoint_interval),
      last_checkpoint_wall(Clock::now()) {
  const auto& parts = sim.parts_;
  stored0 = sim.stored_heat();
  for (std::size_t p = 0; p < parts.size(); ++p) stored0_part.push_back(sim.stored_heat(static_cast<int>(p)));
  sim.link_heat_.assign(parts.size(), 0.0);
  sim.part_exchange_heat_.assign(parts.size(), 0.0);
  sim.part_tool_heat_.assign(parts.size(), 0.0);
  next_probe.assign(job.output.probes.size(), 0.0);
  for (std::size_t q = 0; q < next_probe.size(); ++q) next_probe[q] = job.output.probes[q].interval;
  progress.tty = isatty(STDERR_FILENO) && !opt.quiet;
  progress.quiet = opt.quiet;
  progress.t_end = t_end;
  for (auto& st : parts) Tspans.emplace_back(st->T);
  in.faces = sim.faces_;
  in.conductivity = sim.conductivity_;
  in.links = sim.contact_map_.links;
  in.links_changed = true;

  threshold = !job.output.temperature_threshold.empty();
  shear_limit = !job.output.shear_angle_limit.empty();
  ply_series = job.thermal || job.mechanics;
  crystallising = job.thermal && std::any_of(parts.begin(), parts.end(), [](const auto& st) { return !st->kin.empty(); });
  const std::size_t n_mech = sim.mech_.size();
  row_shear.resize(n_mech);
  row_strain.resize(n_mech);
  row_thickness.resize(n_mech);
  row_q.resize(n_mech);
  row_tol.resize(n_mech);
  row_theta.resize(n_mech);
  elem_area.resize(n_mech);
  for (std::size_t p = 0; p < n_mech; ++p) {
    const std::size_t ne = static_cast<std::size_t>(parts[p]->mesh.num_elements());
    row_shear[p].assign(ne, 0.0);
    row_strain[p].assign(3 * ne, 0.0);
    elem_area[p] = element_areas(parts[p]->mesh);
  }

  sim.seen_min_ = std::numeric_limits<double>::infinity();
  sim.seen_max_ = -sim.seen_min_;
  sim.below_from_.assign(parts.size(), -1.0);
  sim.all_below_from_.assign(parts.size(), -1.0);
  sim.over_from_.assign(parts.size(), -1.0);
  sim.unstable_from_.assign(parts.size(), -1.0);
  if (sim.want_below_from_)
    for (auto& st : parts) {
      st->below_from.assign(st->mesh.num_nodes(), std::numeric_limits<double>::quiet_NaN());
      st->all_below_from.assign(st->mesh.num_nodes(), std::numeric_limits<double>::quiet_NaN());
    }
  subcycle = job.thermal ? job.thermal->subcycle : 0;
  if (checkpoint_iv > 0) next_checkpoint = checkpoint_iv;
}

void Simulation::Run::read_checkpoint() {
  resume.emplace(opt.restart->section("run"));
  resume->get(resume_t);
  resume->get_vector(frame_times);
  for (auto& n : csv_size) resume->get(n);
  resume->get(wall_before);
  const char* names[4] = {"probes.csv", "energy.csv", "tools.csv", "plies.csv"};
  const bool used[4] = {true, job.mechanics, !job.tools.empty(), job.thermal.has_value()};
  for (int k = 0; k < 4; ++k) {
    const auto path = opt.out_dir / names[k];
    if (opt.write_files && used[k] &&
        (!std::filesystem::exists(path) || std::filesystem::file_size(path) < csv_size[k]))
      throw JobError("", "--restart: " + path.string() + " is missing or shorter than at the checkpoint");
  }
  if (opt.write_files && !std::filesystem::exists(opt.out_dir / "results.h5"))
    throw JobError("", "--restart: no " + (opt.out_dir / "results.h5").string() + " of the run to continue");
}

// The probe samples so far (RunResult::probes), as flat arrays (a reader
// checks each array's length against what is left of the checkpoint).
template <class A>
bool Simulation::Run::probes_io(A& a) {
  constexpr bool reading = std::is_same_v<A, sdk::StateReader>;
  const auto& known = known_probe_quantities();
  std::vector<int> id, quantity;
  std::vector<double> time, z, values;
  std::vector<std::uint64_t> nz, nv;
  for (const ProbeSample& ps : result.probes) {  // none when reading
    id.push_back(ps.probe);
    quantity.push_back(static_cast<int>(std::find(known.begin(), known.end(), ps.quantity) - known.begin()));
    time.push_back(ps.time);
    nz.push_back(ps.z.size());
    nv.push_back(ps.values.size());
    z.insert(z.end(), ps.z.begin(), ps.z.end());
    values.insert(values.end(), ps.values.begin(), ps.values.end());
  }
  if (!(a.io_vector(id) && a.io_vector(quantity) && a.io_vector(time) && a.io_vector(nz) && a.io_vector(nv) &&
        a.io_vector(z) && a.io_vector(values)))
    return false;
  if constexpr (reading) {
    const std::size_t n = id.size();
    if (quantity.size() != n || time.size() != n || nz.size() != n || nv.size() != n) return false;
    std::vector<ProbeSample> read(n);
    std::size_t iz = 0, iv = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (quantity[k] < 0 || static_cast<std::size_t>(quantity[k]) >= known.size() || nz[k] > z.size() - iz ||
          nv[k] > values.size() - iv)
        return false;
      read[k].probe = id[k];
      read[k].quantity = known[quantity[k]];
      read[k].time = time[k];
      read[k].z.assign(z.begin() + iz, z.begin() + iz + nz[k]);
      read[k].values.assign(values.begin() + iv, values.begin() + iv + nv[k]);
      iz += nz[k];
      iv += nv[k];
    }
    if (iz != z.size() || iv != values.size()) return false;
    result.probes = std::move(read);
  }
  return true;
}

// The loop's state, written or read back by the same list.
template <class A>
bool Simulation::Run::run_io(A& a) {
  return a.io(steps) && a.io(mech_steps) && a.io(mech_dt) && a.io(frame_index) && a.io(frame_t) &&
         a.io_array(next_probe) && a.io(heat_in) && a.io(substeps_max) && a.io(limited_total) && a.io(stored0) &&
         a.io_array(stored0_part) && a.io_vector(energy_rows) && a.io_vector(tool_rows) && a.io_vector(ply_rows) &&
         a.io(audit.kinetic) && a.io(audit.internal) && a.io(audit.external) && a.io(audit.damping) &&
         a.io(audit.balance_error) && a.io(audit.contact) && a.io(audit.contact_stored) && a.io(audit.kinetic_half) &&
         a.io_vector(audit.reactions) && a.io(t_thermal) && a.io(t_sampled) && a.io(since_thermal) && a.io(subcycle) &&
         a.io(stable) && a.io(next_sample) && a.io(audit_scale) && a.io(supplied_max) && a.io(next_checkpoint) &&
         a.io_vector(unstable) && probes_io(a);
}

// A checkpoint after this step: the end checkpoint, asked for by a stop,
// or due by simulated or wall time. None after the end checkpoint, which
// stays the last (a run stopped in its last steps continues from it).
bool Simulation::Run::checkpoint_due(int stop_seen) const {
  const bool at_end = job.output.checkpoint_at_end;
  if (at_end && landing_saved) return false;
  if (t >= t_end - eps_t) return at_end;
  if (stop_seen != 0) return true;
  return t >= next_checkpoint - eps_t ||
         (opt.checkpoint_wall_s > 0 && seconds_since(last_checkpoint_wall) >= opt.checkpoint_wall_s);
}

// A thermal step ends at the first mechanical step at or after each
// multiple of the thermal step: runs whose mechanical steps differ (another
// mass scaling, bending subcycles, another mesh) sample the temperatures in
// phase, and a step whose length drifts during the run (contact, mass
// scaling) leaves the thermal step as chosen. A thermal step may so be up to
// one mechanical step longer than the one aimed at; where that would pass
// the stable step of an explicit scheme, it ends a mechanical step earlier.
// A job that sets `subcycle` gets that many mechanical steps per thermal
// step.
bool Simulation::Run::thermal_due(double next_dt) const {
  if (subcycle > 0) return since_thermal >= subcycle;
  const double h = sim.thermal_dt_;
  // The multiple after the one nearest to the last thermal step (which may
  // have ended a mechanical step before its multiple).
  const double next = (std::floor(t_thermal / h + 0.5) + 1) * h;
  return t >= next - eps_t || t + next_dt - t_thermal > sim.thermal_stable_dt_;
}

void Simulation::Run::save_checkpoint(const char* what) {
  if (!writer) return;
  const auto tc = Clock::now();
  Checkpoint c;
  const std::string doc = restart_document(job.document_as_run).dump();
  c.add("job", std::vector<unsigned char>(doc.begin(), doc.end()));
  sdk::StateWriter w;
  w.put(t);
  w.put_vector(frame_times);
  for (std::ofstream* f : {&probes_csv, &energy_csv, &tools_csv, &plies_csv}) {
    f->flush();
    w.put(static_cast<std::uint64_t>(f->is_open() ? static_cast<std::uint64_t>(f->tellp()) : 0));
  }
  w.put(wall_before + seconds_since(wall0));
  run_io(w);
  c.add("run", std::move(w.bytes()));
  sim.save_state(c);
  try {
    write_checkpoint(opt.out_dir / kCheckpointFile, c);
    if (job.output.keep_checkpoints) keep_checkpoint(opt.out_dir / kCheckpointFile, opt.out_dir, t);
  } catch (const std::runtime_error& e) {  // a full disk: the checkpoint before it, if any, stays
    throw RunError(e.what());
  }
  sim.timing_[kTimeOutput] += seconds_since(tc);
  last_checkpoint_wall = Clock::now();
  checkpoint_at = t;
  if (checkpoint_iv > 0 && t >= next_checkpoint - eps_t) advance_past(next_checkpoint, checkpoint_iv, t + eps_t);
  logger("solve")->info("checkpoint at t = {:.6g} s (mechanical step {}, thermal step {}{}): {}", t, mech_steps, steps,
                        what, (opt.out_dir / kCheckpointFile).string());
}

// The state before the first step that depends on time.end: the end
// checkpoint where the job asks for one.
void Simulation::Run::end_checkpoint(const char* what) {
  landing_saved = true;
  if (job.output.checkpoint_at_end) save_checkpoint(what);
}

void Simulation::Run::restore() {
  sdk::StateReader& r = *resume;
  if (!run_io(r) || !r.done()) throw JobError("", "--restart: the checkpoint does not fit this job (run state)");
  t = resume_t;
  restarted_from = t;
  checkpoint_at = t;
  // Another time.end (a run extended, or ended earlier), frame interval
  // or row interval (set, or time.end's defaults): the frames and the rows
  // of the time series after the checkpoint are at this run's multiples
  // of its intervals.
  const CheckpointTimes was = checkpoint_times(*opt.restart);
  if (was.t_end != t_end)
    restore_log.push_back(fmt::format("time.end {:.6g} s instead of the checkpointed run's {:.6g} s", t_end, was.t_end));
  if (was.series != series_iv) {
    next_sample = 0;
    advance_past(next_sample, series_iv, t + eps_t);
    restore_log.push_back(fmt::format(
        "rows every {:.6g} s from the checkpoint on, instead of the checkpointed run's {:.6g} s", series_iv, was.series));
  }
  if (was.interval != interval) {
    frame_index = static_cast<long long>(std::floor((t + eps_t) / interval)) + 1;
    restore_log.push_back(fmt::format(
        "frames every {:.6g} s from the checkpoint on, instead of the checkpointed run's {:.6g} s", interval,
        was.interval));
  }
  if (const std::vector<std::string> fields = checkpoint_fields(*opt.restart); fields != job.output.fields) {
    auto list = [](const std::vector<std::string>& v) {
      std::string out;
      for (const auto& f : v) out += (out.empty() ? "" : ", ") + f;
      return out.empty() ? std::string("none") : out;
    };
    restore_log.push_back(fmt::format("frames from the checkpoint on with the fields {} (the frames kept: {})",
                                      list(job.output.fields), list(fields)));
  }
  if (checkpoint_iv > 0) {  // the interval of this run, from the checkpoint on
    next_checkpoint = 0;
    advance_past(next_checkpoint, checkpoint_iv, t + eps_t);
  } else {
    next_checkpoint = std::numeric_limits<double>::infinity();
  }
  sim.load_state(*opt.restart);
  // The temperatures the elements see, as at the checkpoint (formed
  // from the temperatures at the last thermal step, which are those of
  // the checkpoint).
  if (job.mechanics) sim.update_node_temperature();
  restore_log.push_back(
      fmt::format("restarted from the checkpoint at t = {:.6g} s (mechanical step {}, thermal step {}, {} frame(s) kept)",
                  t, mech_steps, steps, frame_times.size()));
}

void Simulation::Run::log_restore() const {
  for (const std::string& line : restore_log) logger("solve")->info("{}", line);
}

void Simulation::Run::start() {
  sim.check_field(0.0, 0);
  write_frame(0.0);
  if (!sim.tools_.empty()) sample_tools(0.0);
  sample_plies(0.0);
  if (!job.mechanics) next_sample = series_iv;  // thermal-only: the next row after the first step past it
  sample_probes(0.0);
}

void Simulation::Run::mechanics_loop() {
  const MechanicsDef& md = job.mechanics_settings;
  auto& timing = sim.timing_;
  // Continued in the steps that land on time.end: the end checkpoint
  // is the one it continues from, or one written after it.
  if (resume) landing_saved = t_end - t < 100 * md.dt_safety * stable;
  if (!resume) {  // the forces and stable step at t = 0 (a restart has them from its checkpoint)
    sim.update_node_temperature();
    sim.check_law_ranges(0.0);
    stable = sim.mechanics_stable_dt();
    sim.compute_contact_forces(0.0, 0.0);
    sim.finish_contact_forces();
    // Overlaps below 1e-6 of a ply's thickness (round-off where a ply
    // starts exactly on a tool) are not worth a warning.
    double k_max = 0, h_min = std::numeric_limits<double>::infinity();
    for (std::size_t p = 0; p < sim.parts_.size(); ++p) {
      for (double k : sim.mech_[p]->k_contact) k_max = std::max(k_max, k);
      h_min = std::min(h_min, sim.parts_[p]->def->thickness);
    }
    if (sim.contact_energy_ > 0.5 * k_max * (1e-6 * h_min) * (1e-6 * h_min)) {
      unstable += ", or it started with " + fmt_g(sim.contact_energy_, 3) +
                  " J in the contact springs (a ply inside a tool or another ply at t = 0)";
      logger("solve")->warn(
          "contact springs hold {:.4g} J at t = 0 on {} node(s): a ply starts inside a tool or another ply "
          "(check the tools' positions and the side their profile faces)",
          sim.contact_energy_, sim.contact_active_);
    }
    if (!std::isfinite(stable)) throw RunError("no element has a stiffness: the mechanical step is undefined");
    announce_output(md.dt_safety * stable);
  }
  // The stresses and curvatures are asked of the elements only for the
  // frames that show them, and for the last frame of an interrupted run.
  const auto& out_fields = job.output.fields;
  const bool frames_need_fields =
      std::find(out_fields.begin(), out_fields.end(), "membrane_stress") != out_fields.end() ||
      std::find(out_fields.begin(), out_fields.end(), "curvature") != out_fields.end();
  while (t < t_end - eps_t) {
    const double next_frame = std::min(t_end, frame_index * interval);
    // Over its last 100 steps the run lands on t_end in equal steps (at
    // most 1 % shorter than the stable one), not with one step cut short:
    // a sudden change of step upsets the kinetic energy of the audit (the
    // product of the half-step velocities) by the change times the
    // damping and contact forces.
    double dt = md.dt_safety * stable;
    const double remaining = t_end - t;
    if (remaining < 100 * dt) {
      if (!landing_saved) end_checkpoint(", before the steps that land on time.end");
      dt = remaining / std::max(1.0, std::ceil(remaining / dt - 1e-9));
    }
    // The stable step, not the last steps cut to land on t_end (those may
    // be as short as the time left).
    if (md.dt_safety * stable < 1e-14) throw RunError("the mechanical step fell below 1e-14 s at t = " + fmt_g(t) + " s");
    auto tc = Clock::now();
    sim.mechanics_step(dt, t, mech_steps, audit);
    timing[kTimeIntegrate] += seconds_since(tc);
    ++mech_steps;
    t += dt;
    mech_dt = dt;
    // Forces and stable step at the new positions (also for the next
    // step). A stop request seen here ends the loop after this step.
    const int stop_seen = stop_requested();
    sim.fields_due_ = frames_need_fields && (t >= next_frame - eps_t || stop_seen != 0);
    if (sim.want_pressure_) {
      sim.pressure_due_ = t >= next_frame - eps_t || stop_seen != 0;
      for (std::size_t q = 0; q < next_probe.size(); ++q)
        sim.pressure_due_ =
            sim.pressure_due_ || (sim.probe_pressure_[q] && (t >= next_probe[q] - eps_t || next_probe[q] <= 0));
    }
    stable = sim.forces_and_stable_dt(t, dt);
    audit.contact_stored = sim.contact_energy_;
    bool thermal_stepped = false;  // a thermal step ended at t
    if (job.thermal) {
      ++since_thermal;
      const int samples = job.thermal->contact_samples;
      if (thermal_due(md.dt_safety * stable) || t >= t_end - eps_t) {
        tc = Clock::now();
        sim.update_element_fields();
        sim.assemble_faces(t, samples > 1 ? t - t_sampled : -1.0);
        t_sampled = t;
        sim.update_far_temperatures(t_thermal, t);
        in.dt = t - t_thermal;
        in.geometry_changed = true;
        in.links = sim.contact_map_.links;
        in.links_changed = true;
        sdk::ThermalStepReport rep = sim.thermal_report();
        sim.keep_step_temperatures();
        if (auto st = sim.splitter_->advance(in, Tspans, &rep); !st)
          throw RunError("thermal plugin '" + job.thermal->splitter + "' failed at t = " + fmt_g(t) + " s: " + st.message);
        heat_in += rep.heat_in;
        limited_total += rep.limited;
        sim.accumulate_face_heat(in.dt, rep);
        sim.finish_thermal_step(in.dt);
        timing[kTimeThermal] += seconds_since(tc);
        ++steps;
        t_thermal = t;
        since_thermal = 0;
        thermal_stepped = true;
        sim.check_field(t, steps);
        sim.update_node_temperature();
        sim.check_law_ranges(t);
      } else if (samples > 1) {
        // A contact sample at the first mechanical step at or after each
        // multiple of thermal step / samples (after the one nearest to the
        // last sample, as the thermal steps).
        const double hs = sim.thermal_dt_ / samples;
        if (t >= (std::floor(t_sampled / hs + 0.5) + 1) * hs - eps_t) {
          tc = Clock::now();
          sim.sample_contacts(t, t - t_sampled);
          t_sampled = t;
          timing[kTimeThermal] += seconds_since(tc);
        }
      }
    }
    // Where: the fastest node (the last step's speeds), for the messages below.
    auto fastest = [&] {
      const std::string f = sim.fastest_node();
      return f.empty() ? f : "; fastest: " + f;
    };
    // Energy audit: W_int + kinetic + damping = external work.
    // Relative to the largest energy seen so far (a vibrating body passes
    // through states where every energy is nearly zero).
    audit_scale = std::max({audit_scale, std::abs(audit.internal), audit.kinetic, std::abs(audit.external),
                            std::abs(audit.contact)});
    const double scale = std::max(audit_scale, 1e-30);
    audit.balance_error =
        std::abs(audit.internal + audit.kinetic + audit.damping + audit.contact - audit.external) / scale;
    if (audit.balance_error > md.energy_tolerance && scale > 1e-12 && mech_steps > 20)
      throw RunError("energy balance error " + fmt_g(audit.balance_error, 3) + " above energy_tolerance " +
                     fmt_g(md.energy_tolerance, 3) + " at t = " + fmt_g(t) + " s (mechanical step " +
                     std::to_string(mech_steps) + ", step " + fmt_g(dt, 3) + " s): " + unstable + fastest());
    // Kinetic energy growth: the plies start at rest and stress free, so
    // their kinetic energy cannot exceed what loads, driven dofs and tools
    // have supplied (external work, plus the tools' work: the contact
    // work on the plies and the energy held in the penalty springs). An
    // unstable step grows it exponentially even where the audit stays
    // balanced (for a linear system central differences conserve the
    // product form of the kinetic energy, which turns negative instead).
    supplied_max = std::max(supplied_max, audit.external - audit.contact + audit.contact_stored);
    if (mech_steps > 20 && audit.kinetic_half > kKineticGrowthLimit * supplied_max + 1e-15)
      throw RunError("kinetic energy " + fmt_g(audit.kinetic_half, 3) + " J grew above " +
                     fmt_g(kKineticGrowthLimit, 3) + " times the energy supplied by loads, driven dofs and tools (" +
                     fmt_g(supplied_max, 3) + " J) at t = " + fmt_g(t) + " s (mechanical step " +
                     std::to_string(mech_steps) + ", step " + fmt_g(dt, 3) + " s): " + unstable + fastest());
    if (t >= next_sample - eps_t) {
      sample_energy();
      if (!sim.tools_.empty()) sample_tools(t);
      tc = Clock::now();
      sample_plies(t);
      timing[kTimeOutput] += seconds_since(tc);
      next_sample += series_iv;
    }
    for (std::size_t q = 0; q < next_probe.size(); ++q) {
      // A probe without an interval samples at every thermal step, or
      // without the thermal solver at the frames' interval.
      const bool every_thermal = job.thermal && job.output.probes[q].interval <= 0;
      const double iv = job.output.probes[q].interval > 0 ? job.output.probes[q].interval : interval;
      if (every_thermal ? !thermal_stepped : !(t >= next_probe[q] - eps_t || next_probe[q] <= 0)) continue;
      tc = Clock::now();
      sim.update_element_fields();
      sample_probes(t, q);
      timing[kTimeOutput] += seconds_since(tc);
      if (!every_thermal) advance_past(next_probe[q], iv, t + eps_t);
    }
    if (t >= next_frame - eps_t) {
      tc = Clock::now();
      sim.update_element_fields();
      write_frame(t);
      timing[kTimeOutput] += seconds_since(tc);
      ++frame_index;
      frame_t = t;
    }
    if (checkpoint_due(stop_seen)) save_checkpoint();
    progress.update(t, mech_steps);
    if ((stop_signal = stop_seen) != 0) break;
  }
}

void Simulation::Run::thermal_loop() {
  while (t < t_end - eps_t) {
    const double grid_frame = frame_index * interval;
    double next_frame = std::min(t_end, grid_frame);
    double step = std::min(sim.thermal_dt_, next_frame - t);
    for (std::size_t q = 0; q < next_probe.size(); ++q)
      if (job.output.probes[q].interval > 0) step = std::min(step, next_probe[q] - t);
    if (step <= eps_t) step = std::min(sim.thermal_dt_, t_end - t);
    // The last step, where time.end is off the frame times: the end
    // checkpoint is the state before it.
    if (!landing_saved && t_end < grid_frame && t + step >= t_end - eps_t)
      end_checkpoint(", before the step that lands on time.end");
    in.dt = step;
    sim.update_far_temperatures(t, t + step);
    sdk::ThermalStepReport rep = sim.thermal_report();
    sim.keep_step_temperatures();
    if (auto s = sim.splitter_->advance(in, Tspans, &rep); !s)
      throw RunError("thermal plugin '" + job.thermal->splitter + "' failed at t = " + fmt_g(t) + " s: " + s.message);
    in.links_changed = false;
    sim.accumulate_face_heat(step, rep);
    sim.finish_thermal_step(step);
    ++steps;
    t += step;
    heat_in += rep.heat_in;
    substeps_max = std::max(substeps_max, rep.substeps);
    limited_total += rep.limited;
    sim.check_field(t, steps);
    if (std::abs(t - next_frame) <= eps_t) t = next_frame;
    if (t >= next_sample - eps_t) {
      sample_plies(t);
      if (!sim.tools_.empty()) sample_tools(t);
      advance_past(next_sample, series_iv, t + eps_t);
    }
    bool any_step_probe = false;
    for (std::size_t q = 0; q < next_probe.size(); ++q) {
      const double iv = job.output.probes[q].interval;
      if (iv <= 0) {
        any_step_probe = true;
      } else if (t >= next_probe[q] - eps_t) {
        sample_probes(t, q);
        advance_past(next_probe[q], iv, t + eps_t);
      }
    }
    if (any_step_probe)
      for (std::size_t q = 0; q < next_probe.size(); ++q)
        if (job.output.probes[q].interval <= 0) sample_probes(t, q);
    if (t >= next_frame - eps_t) {
      write_frame(t);
      ++frame_index;
      frame_t = t;
    }
    const int stop_seen = stop_requested();
    if (checkpoint_due(stop_seen)) save_checkpoint();
    progress.update(t, steps);
    if ((stop_signal = stop_seen) != 0) break;
  }
}

void Simulation::Run::finish_interrupted() {
  if (stop_signal != 0 && t > frame_t) {  // interrupted: the state reached, as a last frame
    const auto tc = Clock::now();
    if (job.mechanics) sim.update_element_fields();
    write_frame(t);
    // (unless the stop came right after a row: the last row's time is t)
    if (!sim.tools_.empty() && (tool_rows.empty() || tool_rows[tool_rows.size() - tool_cols.size()] < t))
      sample_tools(t);
    if (ply_rows.empty() || ply_rows[ply_rows.size() - ply_cols.size()] < t) sample_plies(t);
    for (std::size_t q = 0; q < next_probe.size(); ++q) {  // the probes not sampled at t yet
      const double pi = job.output.probes[q].interval;
      if (pi <= 0 && job.mechanics && job.thermal) {  // sampled at every thermal step
        if (t_thermal < t - eps_t) sample_probes(t, q);
        continue;
      }
      const double iv = pi > 0 ? pi : job.mechanics ? interval : 0.0;
      if (iv > 0 && next_probe[q] - iv < t - eps_t) sample_probes(t, q);
    }
    sim.timing_[kTimeOutput] += seconds_since(tc);
  }
  if (!progress.tty && stop_signal == 0) progress.last_decile = 10;  // the last line was printed at 100 %
  progress.update(t, job.mechanics ? mech_steps : steps, progress.tty || stop_signal != 0);
}

double Simulation::check_restart(const Checkpoint& c) const {
  const std::string what = "--restart: ";
  try {
    // The job as run (file paths absolute; checkpoints of 0.16.0 hold the
    // document as given): the job file or the output folder's job_as_run.json.
    const auto& job = c.section("job");
    const json stored = restart_match(json::parse(job.begin(), job.end()));
    if (stored != restart_match(restart_document(job_.document_as_run)) &&
        stored != restart_match(restart_document(job_.document)))
      throw JobError("", what + "the checkpoint was written by another job (or with other --set values); a restart "
                                "needs the job of the run it continues (time.end, output.interval, "
                                "output.series_interval, output.fields, output.checkpoint_interval, "
                                "output.checkpoint_at_end, output.keep_checkpoints and output.compression may "
                                "differ)");
    // Other fields, but not a node's first times below the threshold where
    // the checkpointed run did not follow them.
    const std::vector<std::string> was = checkpoint_fields(c);
    const auto& fields = job_.output.fields;
    for (std::size_t i = 0; i < fields.size(); ++i)
      if (fields[i] == "below_threshold_from" && std::find(was.begin(), was.end(), fields[i]) == was.end())
        throw JobError(pointer_append("/output/fields", i),
                       what + "the run that wrote the checkpoint did not follow each node's first time below the "
                              "threshold ('below_threshold_from' was not among its fields), and the times before "
                              "the checkpoint are not in it: run the job from the start for this field");
    // The same meshes, numbered alike (checkpoints before 0.24.0 have no
    // prints: their meshes are those of the generators or of files in the
    // files' order).
    if (const auto* prints = c.find("meshes")) {
      sdk::StateReader m(*prints);
      const std::vector<unsigned char> ours = mesh_prints(parts_);
      sdk::StateReader o(ours);
      for (const auto& st : parts_) {
        std::uint64_t a = 0, b = 0;
        if (!m.get(a) || !o.get(b) || a != b)
          throw JobError(st->def->pointer + "/mesh", what + "the mesh of part '" + st->def->name +
                                                         "' is not the one of the checkpoint (did its file change?)");
      }
    } else {
      for (const auto& st : parts_)
        if (st->def->mesh.kind == MeshDef::Kind::File && st->def->mesh.reorder)
          throw JobError(st->def->pointer + "/mesh/reorder",
                         what + "the checkpoint was written by ThermoStamp 0.23 or earlier, which numbered the mesh "
                                "file of part '" + st->def->name + "' otherwise; continue it with that version");
    }
    sdk::StateReader r(c.section("run"));
    double t = 0;
    if (!r.get(t)) throw JobError("", what + "the checkpoint's run section is truncated");
    // The same margin as the run's end test (a billionth of a step or interval).
    if (t >= job_.t_end * (1 - 1e-12)) {
      const double was = checkpoint_times(c).t_end;
      throw JobError("/time/end", what + "the checkpoint is at t = " + fmt_g(t, 9) + " s" +
                                      (t >= was * (1 - 1e-12) ? ", the end of the run that wrote it" : "") +
                                      ", not before time.end = " + fmt_g(job_.t_end, 9) +
                                      " s; to extend the run, set a later time.end (--set time.end=...)");
    }
    return t;
  } catch (const JobError&) {
    throw;
  } catch (const std::exception& e) {
    throw JobError("", what + e.what());
  }
}

// The kernel's state between two steps, written (sdk::StateWriter) or read
// back (sdk::StateReader) by the same list; false where a read failed.
template <class A>
bool Simulation::state_io(A& a) {
  constexpr bool saving = std::is_same_v<A, sdk::StateWriter>;
  // An array whose length follows output.fields (a restart may ask for
  // other fields, check_restart() tells which): read back where this run
  // has it at the length it was saved, else left as this run made it.
  const auto io_field = [&](std::vector<double>& v) {
    if constexpr (saving) {
      return a.io_vector(v);
    } else {
      std::vector<double> read;
      if (!a.io_vector(read)) return false;
      if (read.size() == v.size()) {
        std::copy(read.begin(), read.end(), v.begin());
        return true;
      }
      return read.empty() || v.empty();
    }
  };
  bool ok = a.io(last_mech_dt_) && a.io(bending_weight_) && a.io(bending_left_) && a.io(bending_largest_) &&
            a.io(bending_evaluations_) && a.io(last_stable_) && a.io(seen_min_) && a.io(seen_max_) &&
            a.io_array(below_from_) && a.io_array(all_below_from_) && a.io_array(over_from_) && a.io_array(unstable_from_) &&
            a.io_array(tool_force_) && a.io_array(tool_heat_) && a.io_array(link_heat_) && a.io(contact_energy_) &&
            a.io(contact_active_) && a.io_vector(contact_sums_.map.tool_contacts) &&
            a.io_vector(contact_sums_.map.links) && a.io(contact_sums_.time) &&
            a.io_vector(contact_last_.tool_contacts) && a.io_vector(contact_last_.links);
  if constexpr (!saving) index_contact_sums();
  std::vector<char> warned;
  for (const auto& u : law_uses_) warned.push_back(u.warned ? 1 : 0);
  ok = ok && a.io_array(warned);
  for (std::size_t k = 0; k < warned.size(); ++k) law_uses_[k].warned = warned[k] != 0;
  for (auto& st : parts_)
    ok = ok && a.io_array(st->x) && a.io_array(st->T) && a.io_array(st->contact_status) &&
         io_field(st->contact_pressure) && a.io_array(st->shear_angle) && io_field(st->below_from) &&
         io_field(st->all_below_from) && a.io_array(st->theta) && a.io_array(st->X);
  for (auto& m : mech_)
    ok = ok && a.io_array(m->v) && a.io_array(m->f_int) && a.io_array(m->f_con) && a.io(m->pending_work) &&
         a.io_array(m->block_dt) && a.io_array(m->block_bdt) && a.io(m->bend_dt) && a.io_array(m->stress) &&
         a.io_array(m->curvature) && a.io_array(m->strain);
  for (ContactTask& task : contact_tasks_) {
    // A task's forces on the other part are in cross_out where it handed
    // them over (published); a continued run reads them from cross.
    ok = ok && a.io_array(saving && task.published ? task.cross_out : task.cross);
    if (!saving) task.published = false;
    ok = ok && a.io_array(task.cross_status) && a.io_array(task.tool_force) && io_field(task.own_pressure) &&
         io_field(task.cross_pressure) && a.io(task.energy) && a.io(task.active);
  }
  for (auto& tool : tools_) {
    std::array<double, 3> u = tool->displacement(), v = tool->velocity();
    ok = ok && a.io(u) && a.io(v);
    if (!saving) tool->set_motion_state(u, v);
  }
  return ok;
}

void Simulation::save_state(Checkpoint& c) {
  sdk::StateWriter w;
  state_io(w);
  c.add("kernel", std::move(w.bytes()));
  {
    // The contact samples' time in contact, per tool contact and link
    // summed so far (a section of its own: checkpoints written before it
    // continue with every such contact counted over the whole step).
    sdk::StateWriter tw;
    tw.io_vector(contact_sums_.touched);
    tw.io_vector(contact_sums_.link_touched);
    c.add("kernel/contact_touch", std::move(tw.bytes()));
  }
  {
    // Each part's heat from the heat exchanges and from the tools.
    sdk::StateWriter hw;
    hw.io_vector(part_exchange_heat_);
    hw.io_vector(part_tool_heat_);
    c.add("kernel/heat_sources", std::move(hw.bytes()));
  }
  c.add("meshes", mesh_prints(parts_));
  auto plugin = [&](const std::string& name, auto&& save) {
    sdk::StateWriter pw;
    if (auto st = save(pw); !st) throw RunError("checkpoint of " + name + ": " + st.message);
    c.add(name, std::move(pw.bytes()));
  };
  for (std::size_t p = 0; p < mech_.size(); ++p)
    plugin("element/" + parts_[p]->def->name, [&](sdk::StateWriter& pw) { return mech_[p]->element->save_state(pw); });
  for (std::size_t k = 0; k < contacts_.size(); ++k)
    plugin("contact" + job_.contacts[k].pointer, [&](sdk::StateWriter& pw) { return contacts_[k]->save_state(pw); });
  if (splitter_) plugin("thermal", [&](sdk::StateWriter& pw) { return splitter_->save_state(pw); });
}

void Simulation::load_state(const Checkpoint& c) {
  auto fail = [](const std::string& what) {
    throw JobError("", "--restart: the checkpoint does not fit this job (" + what + ")");
  };
  sdk::StateReader r(c.section("kernel"));
  if (!state_io(r) || !r.done()) fail("kernel state");
  contact_sums_.touched.assign(contact_sums_.map.tool_contacts.size(), contact_sums_.time);
  contact_sums_.link_touched.assign(contact_sums_.map.links.size(), contact_sums_.time);
  if (const std::vector<unsigned char>* bytes = c.find("kernel/contact_touch")) {
    sdk::StateReader tr(*bytes);
    std::vector<double> touched, link_touched;
    if (!tr.io_vector(touched) || !tr.io_vector(link_touched) || !tr.done() ||
        touched.size() != contact_sums_.touched.size() || link_touched.size() != contact_sums_.link_touched.size())
      fail("kernel/contact_touch");
    contact_sums_.touched = std::move(touched);
    contact_sums_.link_touched = std::move(link_touched);
  }
  {
    const std::vector<unsigned char>* bytes = c.find("kernel/heat_sources");
    if (!bytes) fail("no section kernel/heat_sources");
    sdk::StateReader hr(*bytes);
    std::vector<double> exchanges, tools;
    if (!hr.io_vector(exchanges) || !hr.io_vector(tools) || !hr.done() || exchanges.size() != parts_.size() ||
        tools.size() != parts_.size())
      fail("kernel/heat_sources");
    part_exchange_heat_ = std::move(exchanges);
    part_tool_heat_ = std::move(tools);
  }
  auto plugin = [&](const std::string& name, auto&& load) {
    const std::vector<unsigned char>* bytes = c.find(name);
    if (!bytes) fail("no section " + name);
    sdk::StateReader pr(*bytes);
    if (auto st = load(pr); !st) fail(name + ": " + st.message);
    if (!pr.done()) fail(name);
  };
  for (std::size_t p = 0; p < mech_.size(); ++p)
    plugin("element/" + parts_[p]->def->name, [&](sdk::StateReader& pr) { return mech_[p]->element->load_state(pr); });
  for (std::size_t k = 0; k < contacts_.size(); ++k)
    plugin("contact" + job_.contacts[k].pointer, [&](sdk::StateReader& pr) { return contacts_[k]->load_state(pr); });
  if (splitter_) plugin("thermal", [&](sdk::StateReader& pr) { return splitter_->load_state(pr); });
}

}  // namespace ts
