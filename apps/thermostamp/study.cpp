// `thermostamp study`: error against run time for several variants of a job.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <boost/dll/runtime_symbol_info.hpp>
#include <thermostamp/sdk/state.hpp>

#include "commands.hpp"
#include "io/checkpoint.hpp"
#include "io/compare.hpp"
#include "io/logging.hpp"
#include "job/job.hpp"
#include "plugins/registry.hpp"
#include "solve/interrupt.hpp"
#include "solve/simulation.hpp"

namespace ts::cli {

std::filesystem::path share_dir() {
  try {
    const std::filesystem::path exe = boost::dll::program_location().parent_path().string();
    const auto installed = exe / ".." / "share" / "thermostamp";
    if (std::filesystem::exists(installed / "scripts" / "report.py")) return std::filesystem::weakly_canonical(installed);
  } catch (...) {
  }
  return THERMOSTAMP_SOURCE_SHARE_DIR;
}

void make_output_folder(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw JobError("", "cannot create the output folder " + dir.string() + " (--out): " +
                           (ec ? ec.message() : std::string("a file of that name is there")));
}

int run_report(const std::filesystem::path& dir, const std::filesystem::path& against) {
  for (const auto& d : {dir, against}) {
    if (!d.empty() && !std::filesystem::is_directory(d)) {
      std::cerr << "error: '" << d.string() << "' is not a folder\n";
      return 2;
    }
  }
  const auto script = share_dir() / "scripts" / "report.py";
  const std::string python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::string cmd = python + " '" + script.string() + "' '" + dir.string() + "'";
  if (!against.empty()) cmd += " --against '" + against.string() + "'";
  const int rc = std::system(cmd.c_str());
  return rc == 0 ? 0 : 3;
}

namespace {

struct Variant {
  std::string label;
  json set;
};

// Reference profile interpolated at z (linear; constant for one value).
double interpolate(const ProbeSample& s, double z) {
  if (s.values.size() == 1) return s.values[0];
  if (z <= s.z.front()) return s.values.front();
  if (z >= s.z.back()) return s.values.back();
  const auto it = std::upper_bound(s.z.begin(), s.z.end(), z);
  const std::size_t k = static_cast<std::size_t>(it - s.z.begin());
  const double a = (z - s.z[k - 1]) / (s.z[k] - s.z[k - 1]);
  return (1 - a) * s.values[k - 1] + a * s.values[k];
}

// Plane wall insulated at the bottom face, Robin (h, T_inf) on the top
// face, uniform T0: the eigen-series with lambda tan lambda = Bi, at x from
// the insulated face, or (x < 0) its mean over the thickness.
double slab_robin(double x, double t, double L, double alpha, double Bi, double T0, double Tinf) {
  if (t <= 0) return T0;  // the truncated series is not the initial condition
  double theta = 0;
  for (int n = 0; n < 400; ++n) {
    double lo = n * M_PI + 1e-12, hi = n * M_PI + M_PI / 2 - 1e-12;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (mid * std::tan(mid) - Bi > 0 ? hi : lo) = mid;
    }
    const double l = 0.5 * (lo + hi);
    const double shape = x < 0 ? std::sin(l) / l : std::cos(l * x / L);
    theta += 4 * std::sin(l) / (2 * l + std::sin(2 * l)) * std::exp(-l * l * alpha * t / (L * L)) * shape;
  }
  return Tinf + (T0 - Tinf) * theta;
}

void check_slab_robin(const Job& j, const std::string& ptr) {
  const bool ok = j.parts.size() == 1 && j.contacts.empty() && j.heat_exchanges.size() == 1 &&
                  j.heat_exchanges[0].top && !j.heat_exchanges[0].bottom &&
                  j.heat_exchanges[0].region.kind == RegionDef::Kind::All;
  if (!ok)
    throw JobError(ptr, "the analytic reference 'slab_robin' needs one part, no contact and one heat_exchange on "
                        "its whole top face");
  if (!j.materials[j.parts[0].material].specific_heat_table.empty())
    throw JobError(ptr, "the analytic reference 'slab_robin' needs a constant specific_heat (the part's material "
                        "gives rows)");
}

// The slab of a job that check_slab_robin accepted, at x from its
// insulated face (x < 0: its mean) and time t.
double slab_robin_of(const Job& j, double x, double t) {
  const PartDef& p = j.parts[0];
  const MaterialDef& m = j.materials[p.material];
  const HeatExchangeDef& hx = j.heat_exchanges[0];
  const double L = p.thickness, alpha = m.conductivity[2] / (m.density * m.specific_heat);
  const double Bi = hx.h * L / m.conductivity[2];
  return slab_robin(x, t, L, alpha, Bi, p.initial_temperature, hx.ambient);
}

// The analytic profile at the sample's time, on the variant's own z points
// (or 17 points for a single-value variant).
ProbeSample slab_robin_sample(const Job& j, const ProbeSample& s) {
  const double L = j.parts[0].thickness;
  ProbeSample r = s;
  if (r.z.size() < 2) {
    r.z.clear();
    for (int k = 0; k <= 16; ++k) r.z.push_back(-0.5 * L + L * k / 16);
  }
  r.values.clear();
  for (double z : r.z) r.values.push_back(slab_robin_of(j, z + 0.5 * L, s.time));
  return r;
}

// What the study compares of a ply's rows: its mean temperature, its
// largest shear angle of either sign, and its mean crystallinity (NaN for
// a ply without crystallisation kinetics).
double ply_mean(const RunResult::PlySample& s) { return s.mean; }
double ply_shear(const RunResult::PlySample& s) { return std::max(std::abs(s.shear_min), std::abs(s.shear_max)); }
double ply_crystallinity(const RunResult::PlySample& s) { return s.crystallinity_mean; }
using PlyValue = double (*)(const RunResult::PlySample&);

// One ply's value by row (plies.csv), in time order.
struct PlySeries {
  std::vector<double> time, value;
};
PlySeries ply_series(const std::vector<RunResult::PlySample>& history, int part, PlyValue value) {
  PlySeries m;
  for (const auto& s : history)
    if (s.part == part) {
      m.time.push_back(s.time);
      m.value.push_back(value(s));
    }
  return m;
}
// The value at time t, linear between the rows; NaN outside them.
double value_at(const PlySeries& m, double t) {
  const auto it = std::lower_bound(m.time.begin(), m.time.end(), t);
  if (it == m.time.end()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t k = static_cast<std::size_t>(it - m.time.begin());
  if (m.time[k] == t) return m.value[k];
  if (k == 0) return std::numeric_limits<double>::quiet_NaN();
  const double a = (t - m.time[k - 1]) / (m.time[k] - m.time[k - 1]);
  return (1 - a) * m.value[k - 1] + a * m.value[k];
}

// What the forming comes to in a run: per ply its mean temperature at the
// end, with output.temperature_threshold the first time a value and every
// value were below it, with the mechanics its largest |shear angle| at the
// end, the share of its area whose long-term response is unstable at the
// end and, with output.shear_angle_limit, the share of its area beyond it;
// per tool the heat it gave to the plies, and with heat exchanges the heat
// they gave (exchanges_heat_J). Pairs [column, value or null], in
// column order.
json run_outcomes(const RunResult& r, const Job& job) {
  json o = json::array();
  auto when = [](const std::vector<double>& v, std::size_t p) {
    return p < v.size() && v[p] >= 0 ? json(v[p]) : json(nullptr);
  };
  const bool thermal = r.thermal_dt > 0, mechanics = r.mechanical_steps > 0;
  for (std::size_t p = 0; p < job.parts.size(); ++p) {
    const std::string& n = job.parts[p].name;
    const RunResult::PlySample* last = nullptr;
    for (const auto& s : r.ply_history)
      if (s.part == static_cast<int>(p)) last = &s;
    if (thermal) o.push_back({n + "_mean_end_degC", last ? json(last->mean) : json(nullptr)});
    if (thermal && job.materials[job.parts[p].material].crystallisation.present)
      o.push_back({n + "_crystallinity_mean_end", last ? json(last->crystallinity_mean) : json(nullptr)});
    if (thermal && !job.output.temperature_threshold.empty()) {
      o.push_back({n + "_below_from_s", when(r.part_below_threshold_from_s, p)});
      o.push_back({n + "_all_below_from_s", when(r.part_all_below_threshold_from_s, p)});
    }
    if (mechanics && p < r.part_shear_max_deg.size())
      o.push_back({n + "_shear_max_deg", std::max(std::abs(r.part_shear_min_deg[p]), std::abs(r.part_shear_max_deg[p]))});
    if (mechanics && p < r.part_shear_max_deg.size())
      o.push_back({n + "_unstable_end", last ? json(last->fraction_unstable) : json(nullptr)});
    if (mechanics && !job.output.shear_angle_limit.empty())
      o.push_back({n + "_over_shear_limit", last ? json(last->fraction_over_shear_limit) : json(nullptr)});
  }
  if (thermal)
    for (std::size_t t = 0; t < job.tools.size() && t < r.energy.tool_heat.size(); ++t)
      o.push_back({job.tools[t].name + "_heat_J", r.energy.tool_heat[t]});
  if (thermal && !job.heat_exchanges.empty()) o.push_back({"exchanges_heat_J", r.heat_from_exchanges});
  if (mechanics)
    for (std::size_t t = 0; t < job.tools.size() && t < r.energy.tool_force_max.size(); ++t)
      o.push_back({job.tools[t].name + "_force_max_N", r.energy.tool_force_max[t]});
  return o;
}

// The study's state file (in its output folder): what a study stopped
// before its end needs to go on with `--restart`.
constexpr const char* kStudyStateFile = "study_state.json";
constexpr const char* kStudyStateFormat = "thermostamp-study-state/1";

// What the study keeps of a run: its samples of the error's quantity
// (exact: JSON numbers round-trip), its wall time, thermal and mechanical
// steps, and its plies' rows (mean temperature, shear angle range).
json run_record(const RunResult& r, const std::string& quantity, int completed, const Job& job) {
  json samples = json::array(), plies = json::array();
  for (const auto& s : r.probes)
    if (s.quantity == quantity) samples.push_back({s.probe, s.time, s.z, s.values});
  for (const auto& s : r.ply_history)
    plies.push_back({s.part, s.time, s.mean, s.shear_min, s.shear_max,
                     std::isnan(s.crystallinity_mean) ? json(nullptr) : json(s.crystallinity_mean)});
  return {{"completed", completed},
          {"wall_time_s", r.wall_time_s},
          {"thermal_steps", r.thermal_steps},
          {"thermal_dt", r.thermal_dt},
          {"mechanical_steps", r.mechanical_steps},
          {"samples", samples},
          {"plies", plies},
          {"outcomes", run_outcomes(r, job)}};
}
RunResult from_record(const json& rec, const std::string& quantity) {
  RunResult r;
  r.wall_time_s = rec.at("wall_time_s").get<double>();
  r.thermal_steps = rec.at("thermal_steps").get<long long>();
  r.thermal_dt = rec.at("thermal_dt").get<double>();
  r.mechanical_steps = rec.value("mechanical_steps", 0LL);  // (a study state written before 0.16.3 has none)
  for (const auto& s : rec.at("samples")) {
    ProbeSample p;
    p.probe = s.at(0).get<int>();
    p.time = s.at(1).get<double>();
    p.quantity = quantity;
    p.z = s.at(2).get<std::vector<double>>();
    p.values = s.at(3).get<std::vector<double>>();
    r.probes.push_back(std::move(p));
  }
  if (const auto it = rec.find("plies"); it != rec.end())  // a study state written before 0.16.2 has none
    for (const auto& s : *it) {
      RunResult::PlySample p;
      p.part = s.at(0).get<int>();
      p.time = s.at(1).get<double>();
      p.mean = s.at(2).get<double>();
      p.crystallinity_mean = s.size() >= 6 && s.at(5).is_number() ? s.at(5).get<double>()
                                                                  : std::numeric_limits<double>::quiet_NaN();
      if (s.size() >= 5) {
        p.shear_min = s.at(3).get<double>();
        p.shear_max = s.at(4).get<double>();
      }
      r.ply_history.push_back(p);
    }
  return r;
}
// A variant's settings in a study document: its "set" ({} without one), or
// null where the document has no variant of that label.
json variant_set(const json& study_doc, const std::string& label) {
  const auto it = study_doc.find("variants");
  if (it == study_doc.end() || !it->is_array()) return nullptr;
  for (const auto& v : *it)
    if (v.is_object() && v.contains("label") && v["label"] == label) return v.contains("set") ? v["set"] : json::object();
  return nullptr;
}

// Written to a temporary name, then renamed: a study stopped while writing
// it keeps the state before.
void write_state(const std::filesystem::path& out, const json& state) {
  const auto path = out / kStudyStateFile, tmp = out / (std::string(kStudyStateFile) + ".tmp");
  {
    std::ofstream f(tmp);
    f << state.dump() << '\n';
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

int run_study(const std::filesystem::path& study_file, const std::filesystem::path& out_arg, int threads, bool quiet,
              bool flush_subnormals, bool restart, double checkpoint_wall_s) {
  install_stop_handlers();
  const json doc = read_job_document(study_file);
  ObjectReader top(doc, "");
  if (top.text("format") != "thermostamp-study/1")
    throw JobError("/format", "unsupported study format; this version reads 'thermostamp-study/1'");
  const std::filesystem::path base = study_file.has_parent_path() ? study_file.parent_path() : ".";
  const std::filesystem::path job_file = base / top.text("job");
  Variant reference{"reference", json::object()};
  std::string analytic;
  {
    ObjectReader r(top.raw("reference"), "/reference");
    if (r.has("analytic")) analytic = r.choice("analytic", {"slab_robin"});
    if (const json* s = r.optional_raw("set")) {
      if (!s->is_object()) throw JobError("/reference/set", "expected an object of path: value");
      reference.set = *s;
    }
    r.finish();
  }
  std::vector<Variant> variants;
  const json& vs = top.raw("variants");
  if (!vs.is_array() || vs.empty()) throw JobError("/variants", "expected a non-empty array");
  for (std::size_t i = 0; i < vs.size(); ++i) {
    ObjectReader r(vs[i], pointer_append("/variants", i));
    Variant v;
    v.label = r.text("label");
    if (v.label.empty() || v.label == "reference" || v.label.find_first_of("/,") != std::string::npos)
      throw JobError(r.at("label"), "a label must be non-empty, not 'reference', without '/' or ','");
    if (const json* s = r.optional_raw("set")) {
      if (!s->is_object()) throw JobError(r.at("set"), "expected an object of path: value");
      v.set = *s;
    } else {
      v.set = json::object();
    }
    r.finish();
    variants.push_back(v);
  }
  std::string quantity = "temperature_profile", norm = "max";
  if (const json* e = top.optional_raw("error")) {
    ObjectReader r(*e, "/error");
    quantity = r.choice("quantity", {"temperature_profile", "temperature_mean"}, std::string("temperature_profile"));
    norm = r.choice("norm", {"max", "rms"}, std::string("max"));
    r.finish();
  }
  // Each variant run this many times; the shortest wall time is reported
  // (the runs give identical results; a shared machine adds noise to times).
  const int repeat = static_cast<int>(top.integer("repeat", 1, 1, 100));
  top.declare("name");
  top.text("description", std::string());  // for the reader, as in a job
  top.finish();

  json base_doc;
  try {
    base_doc = read_job_document(job_file);
  } catch (const JobError& e) {  // the job file's own problem, named at the study's "job" key
    throw JobError("/job", e.what());
  }
  // Validate every variant before running anything.
  std::vector<Variant> all = {reference};
  all.insert(all.end(), variants.begin(), variants.end());
  std::vector<Job> jobs;
  for (std::size_t i = 0; i < all.size(); ++i) {
    json d = base_doc;
    const std::string ptr = i == 0 ? "/reference/set" : "/variants/" + std::to_string(i - 1) + "/set";
    for (auto it = all[i].set.begin(); it != all[i].set.end(); ++it) {
      try {
        apply_set_value(d, it.key(), it.value());
      } catch (const JobError& e) {
        throw JobError(pointer_append(ptr, it.key()), e.what());
      }
    }
    try {
      jobs.push_back(parse_job(d, job_file));
      // No end checkpoint unless the job asks for one: its write would count
      // in the wall times the study compares.
      if (!(d.contains("output") && d["output"].is_object() && d["output"].contains("checkpoint_at_end")))
        jobs.back().output.checkpoint_at_end = false;
    } catch (const JobError& e) {
      throw JobError("", "study " + ptr + " gives an invalid job: " + std::string(e.what()));
    }
  }
  const std::string study_name = doc.contains("name") && doc["name"].is_string() ? doc["name"].get<std::string>()
                                                                                  : study_file.stem().string();
  const std::filesystem::path out = out_arg.empty() ? std::filesystem::path("results") / study_name : out_arg;
  // The state of a study stopped before its end (or finished): a restart
  // goes on from it (the same job document, and the same study file but
  // for its variants, checked), a new study replaces it.
  json state = {{"format", kStudyStateFormat}, {"study", doc}, {"job", base_doc}, {"runs", json::object()}};
  std::set<std::string> changed;  // a restart: variants new or changed since the state was written
  if (restart) {
    const auto path = out / kStudyStateFile;
    if (!std::filesystem::exists(path))
      throw JobError("", "--restart: no study to continue in " + out.string() + " (no " + kStudyStateFile + ")");
    json saved;
    try {
      saved = json::parse(std::ifstream(path));
    } catch (const std::exception& e) {
      throw JobError("", "--restart: " + path.string() + " is not a study state: " + e.what());
    }
    if (!saved.is_object() || saved.value("format", "") != kStudyStateFormat || !saved.contains("runs") ||
        !saved["runs"].is_object())
      throw JobError("", "--restart: " + path.string() + " is not a study state of this version");
    // The same job and the same study but for its variants: the runs of
    // the variants it had with the same settings are kept; new variants and
    // those whose settings changed run from the start (a study extended by
    // a variant runs only that one).
    auto without_variants = [](json d) {
      if (d.is_object()) {
        d.erase("variants");
        d.erase("description");
      }
      return d;
    };
    if (saved["job"] != base_doc || !saved.contains("study") ||
        without_variants(saved["study"]) != without_variants(doc))
      throw JobError("", "--restart: the " + std::string(saved["job"] != base_doc ? "job" : "study file") +
                             " changed since " + path.string() +
                             " was written (a restart may add, remove or change variants, nothing else); run the "
                             "study anew (without --restart)");
    std::set<std::string> labels;
    for (const Variant& v : variants) {
      labels.insert(v.label);
      const json was = variant_set(saved["study"], v.label);
      if (was.is_null() || was != v.set) {
        changed.insert(v.label);
        if (!quiet)
          std::cerr << "study: variant '" << v.label << "' "
                    << (was.is_null() ? "is new" : "has other settings than when the study state was written")
                    << ": it runs from the start\n";
      }
    }
    for (auto it = saved["runs"].begin(); it != saved["runs"].end(); ++it) {
      if (it.key() == "reference" || (labels.count(it.key()) && !changed.count(it.key()))) {
        state["runs"][it.key()] = it.value();
      } else if (!labels.count(it.key()) && !quiet) {
        std::cerr << "study: variant '" << it.key() << "' is no longer in the study: left out of study.csv (its "
                  << "folder stays)\n";
      }
    }
  }
  make_output_folder(out);
  // From the start (a stop in the first run can continue too), and on a
  // restart with the study's variants as they are now.
  write_state(out, state);

  if (!analytic.empty())
    for (std::size_t i = 1; i < jobs.size(); ++i) check_slab_robin(jobs[i], "/variants/" + std::to_string(i - 1));
  PluginRegistry registry;
  std::vector<RunResult> results;
  std::vector<json> outcomes;  // per run: run_outcomes (a study state written before 0.17.0 has none)
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i == 0 && !analytic.empty()) {
      results.emplace_back();
      outcomes.emplace_back(json::array());
      continue;
    }
    const std::string& label = all[i].label;
    const int need = i == 0 ? 1 : repeat;  // the reference's runs are not timed against others
    const json* done = state["runs"].contains(label) ? &state["runs"][label] : nullptr;
    int completed = done ? done->at("completed").get<int>() : 0;
    if (completed >= need) {  // a restart: run to the end before
      if (!quiet) std::cerr << "study: " << label << " completed before the restart\n";
      results.push_back(from_record(*done, quantity));
      outcomes.push_back(done->value("outcomes", json::array()));
      continue;
    }
    RunOptions opt;
    opt.out_dir = out / label;
    opt.threads = threads;
    opt.quiet = true;
    opt.flush_subnormals = flush_subnormals;
    opt.checkpoint_wall_s = checkpoint_wall_s;
    std::filesystem::create_directories(opt.out_dir);
    // The status of a run that did not complete: 128 + the signal that
    // stopped it, or 3; the study state keeps the runs completed so far.
    auto stopped = [&](const RunResult& r) {
      if (r.interrupted) {
        std::cerr << "study variant '" << label << "' " << r.error << "\n";
        if (!quiet)
          std::cerr << "study: continue it with thermostamp study " << study_file.string() << " --out " << out.string()
                    << " --restart\n";
        return 128 + r.interrupted;
      }
      std::cerr << "error: run failed: study variant '" << label << "': " << r.error << "\n";
      return 3;
    };
    if (completed == 0) {
      // A restart continues the run from its checkpoint where it has one.
      std::optional<Checkpoint> checkpoint;
      // (Not that of a variant whose settings changed: it runs anew.)
      if (restart && !changed.count(label) && std::filesystem::exists(opt.out_dir / kCheckpointFile)) {
        try {
          checkpoint = read_checkpoint(opt.out_dir / kCheckpointFile);
          // One at the run's end (output.checkpoint_at_end): the run completed
          // but the study stopped before it recorded the run; it runs again.
          sdk::StateReader at(checkpoint->section("run"));
          if (double tc = 0; at.get(tc) && tc >= jobs[i].t_end * (1 - 1e-12)) checkpoint.reset();
        } catch (const std::exception& e) {
          throw JobError("", "--restart: study variant '" + label + "': " + e.what());
        }
      }
      log_hold();  // the set-up's lines go to the variant's log.txt too
      Simulation sim(jobs[i], registry);
      double from = 0;
      if (checkpoint) {
        from = sim.check_restart(*checkpoint);
        opt.restart = &*checkpoint;
      }
      log_to_file(opt.out_dir / "log.txt", checkpoint.has_value());
      if (!quiet) {
        if (checkpoint)
          std::cerr << "study: continuing " << label << " from its checkpoint at t = " << from << " s\n";
        else
          std::cerr << "study: running " << label << "\n";
      }
      RunResult r = sim.run(opt);
      log_close_file();
      opt.restart = nullptr;
      if (!r.ok) return stopped(r);
      // A continued run's time: both parts (each with its own set-up).
      r.wall_time_s += r.wall_time_before_s;
      state["runs"][label] = run_record(r, quantity, completed = 1, jobs[i]);
      write_state(out, state);
      outcomes.push_back(state["runs"][label]["outcomes"]);
      results.push_back(std::move(r));
    } else {  // a restart between the repeats
      results.push_back(from_record(*done, quantity));
      outcomes.push_back(done->value("outcomes", json::array()));
    }
    for (; completed < need; ++completed) {
      if (!quiet) std::cerr << "study: running " << label << " again (" << completed + 1 << " of " << need << ")\n";
      log_hold();
      Simulation again(jobs[i], registry);
      log_to_file(opt.out_dir / "log.txt");
      const RunResult r = again.run(opt);  // the same files again: output time counts alike
      log_close_file();
      if (!r.ok) return stopped(r);
      results.back().wall_time_s = std::min(results.back().wall_time_s, r.wall_time_s);
      state["runs"][label]["completed"] = completed + 1;
      state["runs"][label]["wall_time_s"] = results.back().wall_time_s;
      write_state(out, state);
    }
  }
  // Errors against the reference at its probe samples.
  long long ref_samples = 0;
  for (const auto& s : results[0].probes) ref_samples += s.quantity == quantity;
  const auto& probes = jobs[0].output.probes;
  std::ofstream csv(out / "study.csv");
  csv << "label,wall_time_s,error_K,norm,samples,thermal_steps,thermal_dt_s";
  for (const auto& p : probes) csv << ",error_" << p.name << "_K";
  const auto& plies = jobs[0].parts;
  for (const auto& p : plies) csv << ",error_" << p.name << "_mean_K";
  // With the mechanics in the reference run: each ply's largest shear angle.
  const bool shear = analytic.empty() && results[0].mechanical_steps > 0;
  if (shear)
    for (const auto& p : plies) csv << ",error_" << p.name << "_shear_deg";
  // With crystallisation kinetics in the reference run: each ply's mean
  // relative crystallinity.
  const bool crystallinity = analytic.empty() && std::any_of(results[0].ply_history.begin(),
                                                             results[0].ply_history.end(),
                                                             [](const auto& s) { return !std::isnan(s.crystallinity_mean); });
  if (crystallinity)
    for (const auto& p : plies) csv << ",error_" << p.name << "_crystallinity";
  // Then what each run's forming comes to (run_outcomes): every column any
  // run has, in the order of first appearance; an empty cell where a run
  // has none.
  std::vector<std::string> outcome_cols;
  for (const json& o : outcomes)
    for (const json& pair : o)
      if (std::find(outcome_cols.begin(), outcome_cols.end(), pair.at(0).get<std::string>()) == outcome_cols.end())
        outcome_cols.push_back(pair.at(0).get<std::string>());
  for (const auto& c : outcome_cols) csv << "," << c;
  csv << "\n";
  auto write_outcomes = [&](std::size_t i) {
    for (const auto& c : outcome_cols) {
      csv << ",";
      for (const json& pair : outcomes[i])
        if (pair.at(0).get<std::string>() == c && pair.at(1).is_number()) csv << pair.at(1).get<double>();
    }
  };
  csv << "reference," << results[0].wall_time_s << ",0," << norm << "," << ref_samples << ","
      << results[0].thermal_steps << "," << results[0].thermal_dt;
  for (std::size_t k = 0; k < probes.size() + plies.size() * (1 + shear + crystallinity); ++k) csv << ",0";
  write_outcomes(0);
  csv << "\n";
  // The error of a variant's value of ply p (the history of plies.csv: its
  // mean temperature, its largest shear angle, or its mean crystallinity)
  // in the study's norm, at the reference's rows (the variant linear
  // between its rows; rows where either has no value are left out) or, for the
  // mean against the analytic slab, at the variant's own rows; NaN where
  // there is none to compare (a job without the thermal solver, or without
  // the mechanics, other plies).
  auto ply_error = [&](std::size_t i, int p, PlyValue value) {
    double e_max = 0, e_sq = 0;
    long long n = 0;
    auto take = [&](double d) {
      e_max = std::max(e_max, d);
      e_sq += d * d;
      ++n;
    };
    const bool mean = value == ply_mean, thermal = mean || value == ply_crystallinity;
    auto has = [&](const RunResult& r) { return thermal ? r.thermal_dt > 0 : r.mechanical_steps > 0; };
    if (jobs[i].parts.size() != plies.size() || jobs[i].parts[p].name != plies[p].name || !has(results[i]) ||
        (analytic.empty() && !has(results[0])) || (!analytic.empty() && !mean))
      return std::numeric_limits<double>::quiet_NaN();
    const PlySeries variant = ply_series(results[i].ply_history, p, value);
    for (const auto& s : (analytic.empty() ? results[0] : results[i]).ply_history) {
      if (s.part != p) continue;
      if (!analytic.empty()) {
        take(std::abs(s.mean - slab_robin_of(jobs[i], -1, s.time)));
      } else if (const double v = value_at(variant, s.time); !std::isnan(v) && !std::isnan(value(s))) {
        take(std::abs(v - value(s)));
      }
    }
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    return norm == "max" ? e_max : std::sqrt(e_sq / n);
  };
  for (std::size_t i = 1; i < all.size(); ++i) {
    double err_max = 0, err_sq = 0;
    long long count = 0;
    double offset = 0;  // the largest time between the samples compared (s)
    std::vector<double> probe_max(probes.size(), 0.0), probe_sq(probes.size(), 0.0);
    std::vector<long long> probe_n(probes.size(), 0);
    // One value compared: the variant's v against w at probe `probe`.
    auto take = [&](int probe, double v, double w) {
      const double d = std::abs(v - w);
      err_max = std::max(err_max, d);
      err_sq += d * d;
      ++count;
      probe_max[probe] = std::max(probe_max[probe], d);
      probe_sq[probe] += d * d;
      ++probe_n[probe];
    };
    // A sample's value at the reference's through-thickness point k of r.
    auto at = [](const ProbeSample& s, const ProbeSample& r, std::size_t k) {
      return r.z.empty() ? s.values[0] : interpolate(s, r.z[k]);
    };
    if (!analytic.empty()) {  // each of the variant's samples against the series at its time
      for (const auto& s : results[i].probes) {
        if (s.quantity != quantity) continue;
        const ProbeSample r = slab_robin_sample(jobs[i], s);
        for (std::size_t k = 0; k < (r.z.empty() ? 1 : r.z.size()); ++k) take(s.probe, at(s, r, k), r.values[k]);
      }
    } else {
      // Each of the reference's samples against the variant's of the same
      // time (match_times: the nearest, within a quarter of the spacing;
      // with the mechanics the samples fall at the first step at or after
      // each multiple of the interval, and the two runs' steps differ).
      std::map<int, std::vector<const ProbeSample*>> ref_of, var_of;  // by probe, in time order
      for (const auto& s : results[0].probes)
        if (s.quantity == quantity) ref_of[s.probe].push_back(&s);
      for (const auto& s : results[i].probes)
        if (s.quantity == quantity) var_of[s.probe].push_back(&s);
      for (const auto& [probe, rs] : ref_of) {
        const auto& vs = var_of[probe];
        std::vector<double> tr, tv;
        for (const ProbeSample* s : rs) tr.push_back(s->time);
        for (const ProbeSample* s : vs) tv.push_back(s->time);
        const std::vector<int> m = match_times(tr, tv, offset);
        for (std::size_t j = 0; j < rs.size(); ++j) {
          if (m[j] < 0) continue;
          const ProbeSample &r = *rs[j], &s = *vs[m[j]];
          for (std::size_t k = 0; k < (r.z.empty() ? 1 : r.z.size()); ++k) take(probe, at(s, r, k), r.values[k]);
        }
      }
    }
    if (count == 0) {
      std::cerr << "error: study variant '" << all[i].label
                << "' has no probe sample at the reference's times; give the probes an \"interval\"\n";
      return 2;
    }
    const double err = norm == "max" ? err_max : std::sqrt(err_sq / count);
    csv << all[i].label << "," << results[i].wall_time_s << "," << err << "," << norm << "," << count << ","
        << results[i].thermal_steps << "," << results[i].thermal_dt;
    for (std::size_t k = 0; k < probes.size(); ++k)
      csv << "," << (norm == "max" ? probe_max[k] : (probe_n[k] ? std::sqrt(probe_sq[k] / probe_n[k]) : 0.0));
    for (const PlyValue value : {ply_mean, ply_shear, ply_crystallinity}) {
      if ((value == ply_shear && !shear) || (value == ply_crystallinity && !crystallinity)) continue;
      for (std::size_t p = 0; p < plies.size(); ++p) {
        const double e = ply_error(i, static_cast<int>(p), value);
        csv << ",";
        if (!std::isnan(e)) csv << e;  // an empty cell where there is nothing to compare
      }
    }
    write_outcomes(i);
    csv << "\n";
    if (!quiet) {
      std::cout << all[i].label << ": error " << err << " K (" << norm << "), wall " << results[i].wall_time_s
                << " s";
      if (offset > 0) std::cout << ", samples paired up to " << offset << " s apart";
      std::cout << "\n";
    }
  }
  csv.close();
  run_report(out);
  if (!quiet) std::cout << "study: " << (out / "study.csv").string() << "\n";
  return 0;
}

}  // namespace ts::cli
