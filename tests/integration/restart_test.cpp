// Checkpoints and `thermostamp run --restart`: a run continued from a
// checkpoint gives, bit for bit, the output of the run that was never
// stopped (every time series, every frame, the summary's audits), on any
// thread count; a checkpoint that cannot continue the job is refused
// before anything is touched.
#include <gtest/gtest.h>

#include <cstring>

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "plugins/registry.hpp"
#include "solve/interrupt.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

std::string file_text(const std::filesystem::path& p) {
  std::stringstream s;
  s << std::ifstream(p, std::ios::binary).rdbuf();
  return s.str();
}

// Every dataset of a results file (path -> values as doubles) and every
// frame's time.
std::map<std::string, std::vector<double>> results_contents(const std::filesystem::path& file) {
  std::map<std::string, std::vector<double>> out;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return out;
  struct Ctx {
    hid_t file;
    std::map<std::string, std::vector<double>>* out;
  } ctx{f, &out};
  H5Ovisit(
      f, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        auto& c = *static_cast<Ctx*>(data);
        if (info->type == H5O_TYPE_DATASET) {
          const hid_t set = H5Dopen2(c.file, name, H5P_DEFAULT);
          const hid_t type = H5Dget_type(set);
          const bool ints = H5Tget_class(type) == H5T_INTEGER;
          H5Tclose(type);
          H5Dclose(set);
          if (ints) {
            const auto v = read_dataset<int>(c.file, name);
            (*c.out)[name].assign(v.begin(), v.end());
          } else {
            (*c.out)[name] = read_dataset<double>(c.file, name);
          }
        } else if (info->type == H5O_TYPE_GROUP && H5Aexists_by_name(c.file, name, "time", H5P_DEFAULT) > 0) {
          double t = 0;
          const hid_t at = H5Aopen_by_name(c.file, name, "time", H5P_DEFAULT, H5P_DEFAULT);
          H5Aread(at, H5T_NATIVE_DOUBLE, &t);
          H5Aclose(at);
          (*c.out)[std::string(name) + "@time"] = {t};
        }
        return 0;
      },
      &ctx);
  H5Fclose(f);
  return out;
}

// The same datasets with the same bits (a NaN, a time a node has not
// reached, equals itself).
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof a[0]) == 0);
}
bool same_bits(const std::map<std::string, std::vector<double>>& a,
               const std::map<std::string, std::vector<double>>& b) {
  if (a.size() != b.size()) return false;
  for (const auto& [name, v] : a) {
    const auto it = b.find(name);
    if (it == b.end() || !same_bits(v, it->second)) return false;
  }
  return true;
}

// The summary without what depends on the machine and the thread count.
json comparable_summary(const std::filesystem::path& dir) {
  json s = json::parse(std::ifstream(dir / "summary.json"));
  for (const char* k : {"wall_time_s", "wall_time_total_s", "peak_memory_MB", "timing_s", "threads",
                        "contact_beside_elements", "contact_schedule_share", "restarted_from_s", "checkpoint_s"})
    s.erase(k);
  return s;
}

// `b` holds what `a` holds, bit for bit.
void expect_same_output(const std::filesystem::path& a, const std::filesystem::path& b, const std::string& label) {
  for (const char* f : {"probes.csv", "energy.csv", "tools.csv", "plies.csv", "results.xdmf"}) {
    ASSERT_EQ(std::filesystem::exists(a / f), std::filesystem::exists(b / f)) << label << ": " << f;
    if (std::filesystem::exists(a / f)) {
      EXPECT_TRUE(file_text(a / f) == file_text(b / f)) << label << ": " << f;
    }
  }
  const auto ra = results_contents(a / "results.h5"), rb = results_contents(b / "results.h5");
  ASSERT_GT(ra.size(), 3u) << label;
  ASSERT_EQ(ra.size(), rb.size()) << label;
  int differing = 0;
  for (const auto& [name, v] : ra) {
    const auto it = rb.find(name);
    ASSERT_NE(it, rb.end()) << label << ": " << name;
    if (!same_bits(v, it->second)) {
      ++differing;
      ADD_FAILURE() << label << ": " << name << " differs";
    }
    if (differing > 5) break;
  }
  EXPECT_EQ(comparable_summary(a), comparable_summary(b)) << label;
}

std::filesystem::path write_job(const std::filesystem::path& dir, const json& j) {
  std::ofstream(dir / "job.json") << j.dump(2);
  return dir / "job.json";
}

CommandResult run_cli(const std::filesystem::path& job, const std::filesystem::path& out, int threads,
                      const std::string& extra = "") {
  return thermostamp("run " + q(job) + " --out " + q(out) + " --quiet --threads " + std::to_string(threads) + " " +
                     extra);
}

// The coarse hemisphere (10 x 10 cells per ply, mass scaling to 1e-4 s),
// 1 s of stroke, frames every 0.25 s with every mechanical field.
json coarse_hemisphere(const std::string& file) {
  json j = read_job_document(source_dir() / "share" / "jobs" / file);
  j["time"]["end"] = 1.0;
  j["output"]["interval"] = 0.25;
  for (auto& p : j["parts"]) p["mesh"]["divisions"] = {10, 10};
  j["solvers"]["mechanics"]["mass_scaling"]["target_dt"] = 1e-4;
  for (const char* f : {"velocity", "membrane_stress", "curvature", "contact_pressure"}) j["output"]["fields"].push_back(f);
  return j;
}

// Runs `j` without stop on 2 threads, and again with a checkpoint every
// `interval` s (and none at the end); continues a copy of the second from
// its last checkpoint on one thread, and expects the first's output. `how`:
// the options that ask for checkpoints, by default every `interval` s of
// simulated time. `where`, if given, receives the folder of the runs.
void check_restart(const std::string& label, json j, double interval, std::string how = "",
                   std::filesystem::path* where = nullptr) {
  if (how.empty()) how = "--set output.checkpoint_interval=" + std::to_string(interval);
  how += " --set output.checkpoint_at_end=false";
  const auto dir = temp_dir("restart_" + label);
  if (where) *where = dir;
  const auto job = write_job(dir, j);
  ASSERT_EQ(run_cli(job, dir / "full", 2).exit_code, 0) << label;
  EXPECT_TRUE(std::filesystem::exists(dir / "full" / "checkpoint.bin")) << label << ": the end checkpoint";
  const auto with = dir / "with";
  const auto r = run_cli(job, with, 2, how);
  ASSERT_EQ(r.exit_code, 0) << label << ": " << r.err;
  ASSERT_TRUE(std::filesystem::exists(with / "checkpoint.bin")) << label;
  // Writing checkpoints changes nothing.
  expect_same_output(dir / "full", with, label + " with checkpoints");
  const auto cont = dir / "continued";
  std::filesystem::copy(with, cont, std::filesystem::copy_options::recursive);
  const auto c = run_cli(job, cont, 1, "--restart");
  ASSERT_EQ(c.exit_code, 0) << label << ": " << c.err;
  const json s = json::parse(std::ifstream(cont / "summary.json"));
  ASSERT_TRUE(s["restarted_from_s"].is_number()) << label;
  EXPECT_GE(s["restarted_from_s"].get<double>(), interval) << label;
  EXPECT_LT(s["restarted_from_s"].get<double>(), j["time"]["end"].get<double>()) << label;
  expect_same_output(dir / "full", cont, label + " continued");
}

}  // namespace

// The hemisphere scene (UD laws with viscoelastic history, bending every
// few steps, tools under force and motion control, four contact pairs with
// rate friction and a ply/ply search every 64th step, adi), from a
// checkpoint at 0.6 s; with a shear angle limit that elements pass before
// the checkpoint (the first row beyond it comes from the checkpoint), a die
// whose temperature follows rows, a conductance that follows the contact
// pressure on the ply/ply pair, a friction coefficient that follows
// the temperature on the ply/ply pair and the die, a conductivity that
// follows the temperature, and a specific heat that
// follows the temperature (a peak inside the plies' range; heat balance of
// the continued run under 1e-9), crystallisation kinetics with a rate in
// the plies' range (the field crystallinity, every value's integral carried
// by the checkpoint), the field below_threshold_from (each node's
// times, some from before the checkpoint), and convection and radiation
// on every face of the plies, which the tools and the other ply cover
// for part of some thermal steps (the checkpoint carries each contact's
// and link's time in contact over the step under way).
TEST(Restart, HemisphereContinuesBitForBit) {
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["interactions"].push_back({{"type", "heat_exchange"}, {"part", "*"}, {"face", "both"}, {"h", 10.0},
                               {"ambient", 20.0}, {"emissivity", 0.9}});
  j["materials"]["pa66_cf_ud"]["specific_heat"] = {{260.0, 1775.0}, {280.0, 2775.0}, {300.0, 1775.0}};
  j["materials"]["pa66_cf_ud"]["conductivity"] = {{260.0, 3.5, 0.25, 0.25}, {300.0, 3.89, 0.31, 0.35}};
  j["materials"]["pa66_cf_ud"]["crystallisation"] = {
      {"latent_heat", 20000.0}, {"avrami_exponent", 3.0}, {"rate", {{270.0, 2.0}, {300.0, 0.0}}}};
  j["output"]["fields"].push_back("below_threshold_from");
  j["output"]["fields"].push_back("crystallinity");
  j["output"]["shear_angle_limit"] = 0.3;
  for (auto& t : j["tools"])
    if (t["name"] == "die") t["temperature"] = {{0.0, 260.0}, {0.5, 250.0}, {1.0, 265.0}};
  for (auto& c : j["interactions"])
    if (c.value("type", "") == "contact" && c["between"][0] == "ply_top" && c["between"][1] == "ply_bottom") {
      c.erase("conductance");
      c["conductance_pressures"] = {0.0, 1e3, 1e5};
      c["conductance_values"] = {300.0, 800.0, 2000.0};
    }
  for (auto& c : j["interactions"])
    if (c.value("type", "") == "contact" && (c["between"][0] == "ply_top" || c["between"][0] == "die")) {
      c["friction_temperatures"] = {260.0, 280.0, 300.0};
      c["friction_values"] = {0.4, 0.3, 0.2};
    }
  std::filesystem::path dir;
  check_restart("hemisphere", j, 0.6, "", &dir);
  const json s = json::parse(std::ifstream(dir / "continued" / "summary.json"));
  EXPECT_LT(s["heat"]["balance_error"].get<double>(), 1e-9);
  EXPECT_LT(s["heat"]["faces_in_J"].get<double>(), -1.0);
  for (const auto& p : s["parts"]) {
    ASSERT_TRUE(p["over_shear_limit_from_s"].is_number()) << p.dump();
    EXPECT_LT(p["over_shear_limit_from_s"].get<double>(), 0.6);
    EXPECT_GT(p["crystallinity_max"].get<double>(), 1e-3) << p.dump();  // the kinetics are at work
  }
}

// A cold plane that arrives on a ply's upper face inside a thermal step,
// where a heat exchange covers that face (adi, 8 contact samples per
// step): the checkpoint at 0.155 s falls between the arrival (0.153 s)
// and the end of the thermal step (0.16 s), so it carries contact samples
// with and without the plane, and the continued run must weigh the
// exchange over that step as the run without stop does. The same for a
// ply lifted off another.
TEST(Restart, ContactSharesOfAThermalStepContinueBitForBit) {
  const double h = 0.0005, v = 0.05, t_c = 0.153, tol = 0.01 * h, gap = v * t_c + tol, travel = gap + 5e-6;
  json j = ply_job("adi", 8, 0.25, 0.05);
  j["materials"]["ply"]["membrane"] = {{"law", "ud_hyperelastic"}, {"k_fibre", 5.0e4}, {"p_ct", 5.0e3},
                                       {"k_sh", {2.0e3, 0.0, 0.0}}};
  j["parts"][0]["fibre_direction"] = {1, 0, 0};
  j["solvers"]["mechanics"] = {{"dt_safety", 0.8}};
  j["solvers"]["thermal"]["dt"] = 0.02;
  auto plane = [](const std::string& name, double z, int up) {
    return json{{"name", name},
                {"surface", {{"type", "plane"}, {"point", {0, 0, z}}, {"normal", {0, 0, up}}}},
                {"temperature", 260.0}};
  };
  j["tools"] = {plane("die", -0.5 * h, 1), plane("punch", 0.5 * h + gap, -1)};
  j["tools"][1]["motion"] = {
      {"displacement", {{0.0, 0.0, 0.0, 0.0}, {travel / v, 0.0, 0.0, -travel}, {1.0, 0.0, 0.0, -travel}}}};
  j["interactions"] = {{{"type", "contact"}, {"between", {"die", "ply"}}, {"conductance", 0.0}},
                       {{"type", "contact"}, {"between", {"punch", "ply"}}, {"conductance", 1000.0}},
                       {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0},
                        {"ambient", 220.0}}};
  j["constraints"] = {{{"type", "fix"}, {"part", "ply"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"x", "y"}}}};
  check_restart("arriving_tool", j, 0.155);
  // A ply lifted off another at a constant speed, beyond the gap tolerance
  // at 0.153 s; an exchange on every face of both: the links between them
  // end inside a thermal step.
  json k = ply_job("adi", 8, 0.25, 0.05);
  k["materials"]["ply"]["membrane"] = j["materials"]["ply"]["membrane"];
  k["parts"][0]["fibre_direction"] = {1, 0, 0};
  k["parts"].push_back(k["parts"][0]);
  k["parts"][1]["name"] = "ply_top";
  k["parts"][1]["mesh"]["origin"] = {0, 0, h};
  k["solvers"]["mechanics"] = {{"dt_safety", 0.8}};
  k["solvers"]["thermal"]["dt"] = 0.02;
  k["interactions"] = {{{"type", "contact"}, {"between", {"ply_top", "ply"}}, {"conductance", 1000.0}},
                       {{"type", "heat_exchange"}, {"part", "*"}, {"face", "both"}, {"h", 10.0}, {"ambient", 20.0},
                        {"emissivity", 0.9}}};
  const json everywhere = {{-1, -1, -1}, {1, 1, 1}};
  k["constraints"] = {{{"type", "fix"}, {"part", "ply"}, {"box", everywhere}, {"dofs", {"x", "y", "z"}}},
                      {{"type", "velocity"}, {"part", "ply_top"}, {"box", everywhere}, {"velocity", {0, 0, tol / t_c}}}};
  check_restart("lifted_ply", k, 0.155);
}

// Isothermal, with elastic-slip friction (tangential springs that carry
// over from step to step) and the search every step; a gripper with rigid
// jaws at the corner of both plies whose anchor moves (its load's work is
// carried to the next step in the audit's pending sums; its jaws tie nodes
// of two parts, which two threads integrate), and one with swivelling jaws
// across the symmetry plane y = 0.
TEST(Restart, StickingFrictionContinuesBitForBit) {
  json j = coarse_hemisphere("hemisphere_ud_2ply_isothermal.json");
  for (auto& c : j["interactions"])
    if (c.value("type", "") == "contact") c["slip_velocity"] = 0.0;
  j["constraints"].push_back({{"type", "gripper"},
                              {"part", "*"},
                              {"box", {{0.13, 0.13, -1.0}, {1.0, 1.0, 1.0}}},
                              {"anchor", {0.2, 0.2, 0.0}},
                              {"stiffness", 2000.0},
                              {"preload", 5.0},
                              {"ramp", 0.1},
                              {"anchor_motion", {{"velocity", {0.0, 0.0, -0.005}}}},
                              {"jaws", "rigid"}});
  j["constraints"].push_back({{"type", "gripper"},
                              {"part", "*"},
                              {"box", {{0.13, -1.0, -1.0}, {1.0, 0.02, 1.0}}},
                              {"anchor", {0.2, 0.01, 0.0}},
                              {"stiffness", 2000.0},
                              {"preload", 5.0},
                              {"ramp", 0.1},
                              {"jaws", "swivelling"}});
  check_restart("sticking", j, 0.45);
}

// The tools as STL meshes (their revolved surfaces in steps of 3 degrees):
// the contact handler keeps, per node, the tool's list of triangles near it
// (ToolView::query_kept), not saved at the checkpoint but formed again.
TEST(Restart, MeshedToolsContinueBitForBit) {
  json j = coarse_hemisphere("hemisphere_ud_2ply_isothermal.json");
  const auto dir = temp_dir("meshed_tools_stl");
  for (auto& t : j["tools"]) {
    const auto file = dir / (t["name"].get<std::string>() + ".stl");
    write_revolved_stl(file, t["surface"], 3.0);
    t["surface"] = {{"type", "mesh"}, {"file", file.string()}};
  }
  check_restart("meshed_tools", j, 0.45);
}

// Checkpoints by wall time (--checkpoint-minutes; here every 30 ms, so
// that a run of about a second writes several): where they fall depends
// on the machine, what the continued run gives does not.
TEST(Restart, WallTimeCheckpointsContinueBitForBit) {
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["time"]["end"] = 2.0;
  std::filesystem::path dir;
  check_restart("wall", j, 0.0, "--checkpoint-minutes 0.0005", &dir);
  const std::string log = file_text(dir / "with" / "log.txt");
  int checkpoints = 0;
  for (std::size_t at = 0; (at = log.find("checkpoint at t = ", at)) != std::string::npos; ++at) ++checkpoints;
  EXPECT_GE(checkpoints, 2) << "several checkpoints over the run";
}

// Thermal only: two plies in contact, the 3D reference splitter and adi
// with in-plane conduction per layer, with constant conductivities and with
// rows; a ply on a tool whose temperature follows rows.
TEST(Restart, ThermalSplittersContinueBitForBit) {
  json j = read_job_document(source_dir() / "share" / "verification" / "patch_contact.json");
  j["solvers"]["thermal"]["splitter"] = "layered3d";
  check_restart("layered3d", j, 1.5);
  j["solvers"]["thermal"]["splitter"] = "adi";
  j["solvers"]["thermal"]["in_plane"] = "layers";
  check_restart("adi_layers", j, 1.5);
  // Both with a conductivity that follows the temperature (every step
  // assembles again what a restart assembles first).
  for (auto& [name, m] : j["materials"].items()) m["conductivity"] = {{260.0, 3.5, 0.25, 0.25}, {300.0, 3.89, 0.31, 0.35}};
  check_restart("adi_layers_k_rows", j, 1.5);
  j["solvers"]["thermal"]["splitter"] = "layered3d";
  j["solvers"]["thermal"].erase("in_plane");
  check_restart("layered3d_k_rows", j, 1.5);
  // A ply on a die whose temperature follows rows, a kink inside a step.
  json v = ply_job("adi", 8, 2.0, 0.1);
  v["tools"] = {{{"name", "die"},
                 {"surface", {{"type", "plane"}, {"point", {0, 0, -0.00025}}, {"normal", {0, 0, 1}}}},
                 {"temperature", {{0.0, 260.0}, {0.73, 290.0}, {1.41, 240.0}}}}};
  v["interactions"] = {{{"type", "contact"}, {"between", {"die", "ply"}}, {"conductance", 1000.0}}};
  check_restart("tool_rows", v, 1.0);
}

// A run stopped by SIGTERM (here after its first step) leaves a checkpoint;
// the restart drops the frame the stop wrote and continues as if there had
// been no stop.
TEST(Restart, AfterAStopRequest) {
  const auto dir = temp_dir("restart_stop");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["time"]["end"] = 0.3;
  j["output"]["interval"] = 0.1;
  const auto job = write_job(dir, j);
  ASSERT_EQ(run_cli(job, dir / "full", 1).exit_code, 0);
  const auto out = dir / "stopped";
  request_stop(SIGTERM);
  const JobRun stopped = run_json(j, 2, out);
  clear_stop();
  ASSERT_EQ(stopped.result.interrupted, SIGTERM);
  const json s0 = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s0["status"], "interrupted");
  EXPECT_EQ(s0["frames"], 2) << "the initial frame and the one at the stop";
  ASSERT_TRUE(std::filesystem::exists(out / "checkpoint.bin"));
  const auto c = run_cli(job, out, 2, "--restart");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  expect_same_output(dir / "full", out, "after a stop");
  const json s = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["status"], "completed");
  EXPECT_EQ(s["frames"], 4);
  EXPECT_DOUBLE_EQ(s["restarted_from_s"].get<double>(), s0["simulated_time_s"].get<double>());
  // The summary's total wall time adds the part before the checkpoint.
  EXPECT_GT(s["wall_time_total_s"].get<double>(), s["wall_time_s"].get<double>());

  // In the process: the continued run's RunResult holds every probe sample,
  // those before its checkpoint too, as the run never stopped (bit for bit),
  // and the wall time before the checkpoint.
  const JobRun full = run_json(j, 1);
  const auto out2 = dir / "stopped2";
  request_stop(SIGTERM);
  ASSERT_EQ(run_json(j, 1, out2).result.interrupted, SIGTERM);
  clear_stop();
  const Checkpoint c2 = read_checkpoint(out2 / kCheckpointFile);
  const Job job2 = parse_job(j, source_dir() / "tests" / "inline.json");
  PluginRegistry registry;
  Simulation sim(job2, registry);
  sim.check_restart(c2);
  RunOptions opt;
  opt.threads = 2;
  opt.quiet = true;
  opt.out_dir = out2;
  opt.restart = &c2;
  const RunResult continued = sim.run(opt);
  ASSERT_TRUE(continued.ok) << continued.error;
  EXPECT_GT(continued.wall_time_before_s, 0.0);
  EXPECT_EQ(full.result.wall_time_before_s, 0.0);
  ASSERT_EQ(continued.probes.size(), full.result.probes.size());
  ASSERT_GT(full.result.probes.size(), 10u);
  for (std::size_t k = 0; k < full.result.probes.size(); ++k) {
    const ProbeSample &a = full.result.probes[k], &b = continued.probes[k];
    EXPECT_TRUE(a.probe == b.probe && a.time == b.time && a.quantity == b.quantity && a.z == b.z &&
                a.values == b.values)
        << "probe sample " << k << " (" << a.quantity << " at t = " << a.time << ")";
  }
}

// What cannot be continued is refused with one line and exit 2, and the
// output folder is left as it was.
TEST(Restart, RefusesWhatItCannotContinue) {
  const auto dir = temp_dir("restart_refused");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["time"]["end"] = 0.2;
  j["output"]["interval"] = 0.1;
  j["output"]["checkpoint_interval"] = 0.15;
  j["output"]["checkpoint_at_end"] = false;
  const auto job = write_job(dir, j);
  const auto out = dir / "out";
  ASSERT_EQ(run_cli(job, out, 2).exit_code, 0);
  const std::string probes = file_text(out / "probes.csv"), energy = file_text(out / "energy.csv");
  const auto h5 = std::filesystem::file_size(out / "results.h5");
  auto unchanged = [&](const std::string& label) {
    EXPECT_EQ(file_text(out / "probes.csv"), probes) << label;
    EXPECT_EQ(file_text(out / "energy.csv"), energy) << label;
    EXPECT_EQ(std::filesystem::file_size(out / "results.h5"), h5) << label;
  };
  auto refused = [&](const CommandResult& r, const std::string& words, const std::string& label) {
    EXPECT_EQ(r.exit_code, 2) << label;
    EXPECT_NE(r.err.find("--restart: "), std::string::npos) << label << ": " << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << label << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << label << ": one line: " << r.err;
    unchanged(label);
  };
  // Another job (another step).
  refused(run_cli(job, out, 1, "--restart --set solvers.mechanics.dt_safety=0.7"), "written by another job",
          "other job");
  // An end before the checkpoint.
  refused(run_cli(job, out, 1, "--restart --set time.end=0.12"), "not before time.end = 0.12 s", "earlier end");
  // No checkpoint in the folder.
  refused(run_cli(job, dir / "elsewhere", 1, "--restart"), "no checkpoint", "no checkpoint");
  // A damaged checkpoint.
  const std::string ck = file_text(out / "checkpoint.bin");
  std::ofstream(out / "checkpoint.bin", std::ios::binary) << ck.substr(0, ck.size() / 2);
  refused(run_cli(job, out, 1, "--restart"), "truncated", "truncated");
  std::ofstream(out / "checkpoint.bin", std::ios::binary) << "not a checkpoint";
  refused(run_cli(job, out, 1, "--restart"), "not a ThermoStamp checkpoint", "not a checkpoint");
  // A checkpoint whose state does not fit the job (here the kernel's
  // section cut short; so would a plugin whose state changed): refused
  // before the frames after it are removed from results.h5 (before
  // 0.30.0: exit status 3, "unexpected error", the frames gone).
  {
    std::ofstream(out / "checkpoint.bin", std::ios::binary) << ck;
    Checkpoint c = read_checkpoint(out / "checkpoint.bin");
    for (auto& [name, bytes] : c.sections)
      if (name == "kernel") bytes.resize(bytes.size() - 8);
    write_checkpoint(out / "checkpoint.bin", c);
    const auto frames = results_contents(out / "results.h5");
    refused(run_cli(job, out, 1, "--restart"), "the checkpoint does not fit this job (kernel state)", "kernel state");
    EXPECT_TRUE(same_bits(results_contents(out / "results.h5"), frames)) << "every frame kept";
  }
  // A time series shorter than at the checkpoint (another run's folder).
  std::ofstream(out / "checkpoint.bin", std::ios::binary) << ck;
  std::ofstream(out / "energy.csv") << "time\n";
  const auto r = run_cli(job, out, 1, "--restart");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("energy.csv is missing or shorter than at the checkpoint"), std::string::npos) << r.err;
  EXPECT_EQ(file_text(out / "probes.csv"), probes) << "nothing cut before the check";
  EXPECT_EQ(std::filesystem::file_size(out / "results.h5"), h5);
  // A results file with fewer frames than the checkpoint kept (another
  // run's): refused, the file left as it was.
  std::ofstream(out / "energy.csv", std::ios::binary) << energy;
  std::filesystem::copy_file(out / "results.h5", dir / "results.h5");
  {
    const hid_t f = H5Fopen((out / "results.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    H5Ldelete(f, "frames/000001", H5P_DEFAULT);
    H5Fclose(f);
  }
  const auto frames_before = results_contents(out / "results.h5");
  const auto fewer = run_cli(job, out, 1, "--restart");
  EXPECT_EQ(fewer.exit_code, 2);
  EXPECT_NE(fewer.err.find("not the results of the run that wrote it"), std::string::npos) << fewer.err;
  EXPECT_TRUE(same_bits(results_contents(out / "results.h5"), frames_before));
  std::filesystem::copy_file(dir / "results.h5", out / "results.h5", std::filesystem::copy_options::overwrite_existing);
  // A new run in the folder removes the checkpoint of the earlier one.
  std::ofstream(out / "checkpoint.bin", std::ios::binary) << ck;
  j["output"].erase("checkpoint_interval");
  ASSERT_EQ(run_cli(write_job(dir, j), out, 2).exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(out / "checkpoint.bin"));
  // So is the wall-time period.
  const auto minutes = run_cli(job, out, 1, "--checkpoint-minutes 0");
  EXPECT_EQ(minutes.exit_code, 2);
  EXPECT_NE(minutes.err.find("--checkpoint-minutes expects a positive number, found '0'"), std::string::npos)
      << minutes.err;
  // The checkpoint interval is checked like every other value.
  const auto bad = thermostamp("validate " + q(job) + " --set output.checkpoint_interval=-1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("/output/checkpoint_interval"), std::string::npos) << bad.err;
}

// Plies meshed in files in a shuffled order, taken in the order of
// `mesh.reorder`: the run continues bit for bit (the order is the same at
// every reading of the file). A file that changed since the checkpoint
// (here the same mesh written in another order, which the run numbers
// otherwise) is refused at the part's mesh, and so is a checkpoint without
// the meshes' prints (as ThermoStamp 0.23 and earlier wrote them, whose
// numbering of a mesh file was the file's order) where a part reads a file
// in the order of `reorder`.
TEST(Restart, MeshFilesContinueAndAnotherNumberingIsRefused) {
  const auto meshes = temp_dir("restart_mesh_files_meshes");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["time"]["end"] = 0.5;
  for (auto& p : j["parts"]) {
    const auto& m = p["mesh"];
    const ShellMesh rect = rectangle_mesh(m["origin"].get<std::array<double, 3>>(),
                                          m["size"].get<std::array<double, 2>>(),
                                          m["divisions"].get<std::array<int, 2>>(), m.value("pattern", "") == "crossed");
    const auto file = meshes / (p["name"].get<std::string>() + ".msh");
    write_shuffled_gmsh(file, rect, 5);
    p["mesh"] = {{"file", file.string()}};
  }
  std::filesystem::path dir;
  check_restart("mesh_files", j, 0.2, "", &dir);
  const auto out = dir / "with";
  const auto job = dir / "job.json";
  ASSERT_TRUE(std::filesystem::exists(job));
  // The lower ply's file in another order.
  {
    const json p = coarse_hemisphere("hemisphere_ud_2ply.json")["parts"][0]["mesh"];
    const ShellMesh rect = rectangle_mesh(p["origin"].get<std::array<double, 3>>(), p["size"].get<std::array<double, 2>>(),
                                          p["divisions"].get<std::array<int, 2>>(), p.value("pattern", "") == "crossed");
    std::filesystem::copy_file(meshes / "ply_bottom.msh", meshes / "kept.msh");
    write_shuffled_gmsh(meshes / "ply_bottom.msh", rect, 6);
  }
  const auto changed = run_cli(job, out, 1, "--restart");
  EXPECT_EQ(changed.exit_code, 2);
  EXPECT_NE(changed.err.find("error: /parts/0/mesh: --restart: the mesh of part 'ply_bottom' is not the one of the "
                             "checkpoint (did its file change?)"),
            std::string::npos)
      << changed.err;
  std::filesystem::copy_file(meshes / "kept.msh", meshes / "ply_bottom.msh",
                             std::filesystem::copy_options::overwrite_existing);
  // A checkpoint without prints.
  const Checkpoint c = read_checkpoint(out / "checkpoint.bin");
  Checkpoint old;
  for (const auto& [name, bytes] : c.sections)
    if (name != "meshes") old.add(name, bytes);
  ASSERT_EQ(old.sections.size() + 1, c.sections.size());
  write_checkpoint(out / "checkpoint.bin", old);
  const auto earlier = run_cli(job, out, 1, "--restart");
  EXPECT_EQ(earlier.exit_code, 2);
  EXPECT_NE(earlier.err.find("error: /parts/0/mesh/reorder: --restart: the checkpoint was written by ThermoStamp 0.23 "
                             "or earlier, which numbered the mesh file of part 'ply_bottom' otherwise; continue it "
                             "with that version"),
            std::string::npos)
      << earlier.err;
  // The prints back: it continues.
  write_checkpoint(out / "checkpoint.bin", c);
  EXPECT_EQ(run_cli(job, out, 1, "--restart").exit_code, 0);
}

// The lines of a CSV file (header aside) whose first column, the time, is
// above `after`.
std::vector<std::string> rows_after(const std::filesystem::path& csv, double after) {
  std::vector<std::string> rows;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line))
    if (std::stod(line.substr(0, line.find(','))) > after) rows.push_back(line);
  return rows;
}

// A finished run extended to a later time.end (`--restart --set
// time.end=...`) continues from its end checkpoint, the state before the
// first step that depended on its time.end (the mechanical steps that land
// on it; a thermal step cut short by it), or its end state where none did.
// So it gives, bit for bit, the run to the later end: every frame, every
// probe sample, the summary's audits, and the energy and tool rows after the
// checkpoint (those before it keep the first run's spacing, time.end / 500).
TEST(Restart, ExtendsAFinishedRunAsARunToTheLaterEnd) {
  const auto dir = temp_dir("restart_extend");
  const auto job = write_job(dir, coarse_hemisphere("hemisphere_ud_2ply.json"));  // to 1 s
  ASSERT_EQ(run_cli(job, dir / "direct", 2).exit_code, 0);
  const auto out = dir / "extended";
  ASSERT_EQ(run_cli(job, out, 2, "--set time.end=0.5").exit_code, 0);
  const auto e = run_cli(job, out, 1, "--restart --set time.end=1");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const json s = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["status"], "completed");
  const double from = s["restarted_from_s"].get<double>();
  EXPECT_LT(from, 0.5) << "the state before the last 100 steps of the first run";
  EXPECT_GT(from, 0.4);
  // The first row with an unstable element comes from the rows before the
  // checkpoint, which keep the first run's spacing (see compare below).
  auto without_row_times = [](json j) {
    for (auto& p : j["parts"]) p.erase("unstable_from_s");
    return j;
  };
  EXPECT_EQ(without_row_times(comparable_summary(dir / "direct")), without_row_times(comparable_summary(out)));
  for (const char* f : {"probes.csv", "results.xdmf"})
    EXPECT_TRUE(file_text(dir / "direct" / f) == file_text(out / f)) << f;
  auto frames = [](const std::filesystem::path& d) {
    auto all = results_contents(d / "results.h5");
    std::erase_if(all, [](const auto& kv) { return kv.first.rfind("series", 0) == 0; });
    return all;
  };
  const auto fd = frames(dir / "direct");
  ASSERT_GT(fd.size(), 20u);
  EXPECT_TRUE(same_bits(fd, frames(out))) << "the frames of the run to 1 s";
  for (const char* f : {"energy.csv", "tools.csv", "plies.csv"}) {
    const auto rows = rows_after(dir / "direct" / f, from);
    EXPECT_GT(rows.size(), 200u) << f;
    EXPECT_EQ(rows_after(out / f, from), rows) << f;
  }
  // `compare`: the rows before the checkpoint are at other times; from the
  // checkpoint on, every value is equal.
  const std::string cmp = "compare " + q(dir / "direct") + " " + q(out);
  EXPECT_EQ(thermostamp(cmp).exit_code, 1);
  std::ostringstream at;
  at.precision(17);
  at << from;
  const auto later = thermostamp(cmp + " --from " + at.str());
  EXPECT_EQ(later.exit_code, 0) << later.out;
  EXPECT_NE(later.out.find("identical: every value compared is equal"), std::string::npos) << later.out;
  // A run stopped in its last steps (here one of about 45 steps, all of
  // them landing on its end) leaves the end checkpoint as it was, from which
  // a later end gives the run to that end too.
  json brief = coarse_hemisphere("hemisphere_ud_2ply.json");
  brief["time"]["end"] = 0.004;
  const auto stopped = dir / "stopped";
  request_stop(SIGTERM);
  const JobRun st = run_json(brief, 1, stopped);
  clear_stop();
  ASSERT_EQ(st.result.interrupted, SIGTERM);
  EXPECT_GT(st.result.simulated_time_s, 0.0);
  const auto sc = run_cli(job, stopped, 2, "--restart");
  ASSERT_EQ(sc.exit_code, 0) << sc.err;
  EXPECT_EQ(json::parse(std::ifstream(stopped / "summary.json"))["restarted_from_s"].get<double>(), 0.0);
  EXPECT_TRUE(file_text(dir / "direct" / "probes.csv") == file_text(stopped / "probes.csv"));
  EXPECT_TRUE(same_bits(fd, frames(stopped))) << "the frames of the run to 1 s";
  // The completed run continued to the same end runs its last steps again
  // and leaves the same files.
  const auto again = dir / "again";
  std::filesystem::copy(dir / "direct", again, std::filesystem::copy_options::recursive);
  const auto a = run_cli(job, again, 2, "--restart");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  expect_same_output(dir / "direct", again, "the same end");

  // With output.series_interval the rows' spacing does not depend on
  // time.end either: the extended run gives every file of the run to 1 s.
  json rows = coarse_hemisphere("hemisphere_ud_2ply.json");
  rows["output"]["series_interval"] = 0.002;
  rows["output"]["temperature_threshold"] = 290.0;
  rows["output"]["shear_angle_limit"] = 0.3;
  const auto rdir = temp_dir("restart_extend_rows");
  const auto rjob = write_job(rdir, rows);
  ASSERT_EQ(run_cli(rjob, rdir / "direct", 2).exit_code, 0);
  ASSERT_EQ(run_cli(rjob, rdir / "extended", 2, "--set time.end=0.5").exit_code, 0);
  const auto re = run_cli(rjob, rdir / "extended", 1, "--restart");
  ASSERT_EQ(re.exit_code, 0) << re.err;
  expect_same_output(rdir / "direct", rdir / "extended", "rows every 2 ms");
  // One row at t = 0 and one at the first step at or after each multiple.
  EXPECT_EQ(rows_after(rdir / "direct" / "energy.csv", -1).size(), 501u);
  const auto many = thermostamp("validate " + q(rjob) + " --set output.series_interval=1e-7");
  EXPECT_EQ(many.exit_code, 2);
  EXPECT_NE(many.err.find("error: /output/series_interval: an interval of 1e-07 s would write 1e+07 rows"),
            std::string::npos)
      << many.err;

  // Thermal only, frames every 1 s, probes every 0.1 s, ply rows every
  // 0.05 s, to 4 s.
  const auto tdir = temp_dir("restart_extend_thermal");
  json patch = read_job_document(source_dir() / "share" / "verification" / "patch_contact.json");
  patch["output"]["series_interval"] = 0.05;
  patch["output"]["temperature_threshold"] = 280.0;
  const auto tjob = write_job(tdir, patch);
  ASSERT_EQ(run_cli(tjob, tdir / "direct", 2).exit_code, 0);
  // time.end off the frame and probe times: the checkpoint before the last step.
  ASSERT_EQ(run_cli(tjob, tdir / "off", 2, "--set time.end=2.55").exit_code, 0);
  const auto off = run_cli(tjob, tdir / "off", 1, "--restart");
  ASSERT_EQ(off.exit_code, 0) << off.err;
  const json so = json::parse(std::ifstream(tdir / "off" / "summary.json"));
  EXPECT_LT(so["restarted_from_s"].get<double>(), 2.55);
  expect_same_output(tdir / "direct", tdir / "off", "thermal, extended from 2.55 s");
  // On a frame time: the end state; continued to the same end, refused.
  ASSERT_EQ(run_cli(tjob, tdir / "on", 2, "--set time.end=2").exit_code, 0);
  const std::string probes = file_text(tdir / "on" / "probes.csv");
  const auto same = run_cli(tjob, tdir / "on", 1, "--restart --set time.end=2");
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_NE(same.err.find("error: /time/end: --restart: the checkpoint is at t = 2 s, the end of the run that wrote "
                          "it, not before time.end = 2 s; to extend the run, set a later time.end"),
            std::string::npos)
      << same.err;
  EXPECT_EQ(std::count(same.err.begin(), same.err.end(), '\n'), 1) << same.err;
  EXPECT_EQ(file_text(tdir / "on" / "probes.csv"), probes) << "nothing touched";
  const auto on = run_cli(tjob, tdir / "on", 1, "--restart");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  const json sn = json::parse(std::ifstream(tdir / "on" / "summary.json"));
  EXPECT_EQ(sn["restarted_from_s"].get<double>(), 2.0);
  expect_same_output(tdir / "direct", tdir / "on", "thermal, extended from 2 s");
}

// Each frame of a results file by its time: dataset name below the frame
// (e.g. "ply_top/nodes") -> values.
std::map<double, std::map<std::string, std::vector<double>>> frames_by_time(const std::filesystem::path& file) {
  const auto all = results_contents(file);
  std::map<std::string, double> time_of;  // "frames/000003" -> t
  for (const auto& [name, v] : all)
    if (name.ends_with("@time")) time_of[name.substr(0, name.size() - 5)] = v.at(0);
  std::map<double, std::map<std::string, std::vector<double>>> out;
  for (const auto& [name, v] : all) {
    const auto slash = name.find('/', std::string("frames/").size());
    if (name.rfind("frames/", 0) != 0 || slash == std::string::npos || name.ends_with("@time")) continue;
    out[time_of.at(name.substr(0, slash))][name.substr(slash + 1)] = v;
  }
  return out;
}

// With the mechanics the frames fall at mechanical steps and a thermal
// step is a number of mechanical steps, whatever the frames: the coarse
// hemisphere (adi, four contact pairs) with frames every 0.25 s and every
// 0.05 s gives the same frames where both write one (at the first step at
// or after each multiple of 0.25 s), and the same time series and summary.
// (Before 0.31.0 the thermal step was cut to a whole number per frame
// interval: 0.0114 s and 0.01 s here.)
TEST(Frames, AnotherIntervalChangesNoCoupledResult) {
  const auto dir = temp_dir("frames_interval");
  const auto job = write_job(dir, coarse_hemisphere("hemisphere_ud_2ply.json"));  // frames every 0.25 s, to 1 s
  ASSERT_EQ(run_cli(job, dir / "coarse", 2).exit_code, 0);
  const auto r = run_cli(job, dir / "close", 2, "--set output.interval=0.05");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto coarse = frames_by_time(dir / "coarse" / "results.h5"), close = frames_by_time(dir / "close" / "results.h5");
  ASSERT_EQ(coarse.size(), 5u);
  ASSERT_EQ(close.size(), 21u);
  for (const auto& [t, fields] : coarse) {
    ASSERT_TRUE(close.contains(t)) << "the frame at " << t << " s";
    EXPECT_TRUE(same_bits(fields, close.at(t))) << "the frame at " << t << " s";
  }
  for (const char* f : {"probes.csv", "energy.csv", "tools.csv", "plies.csv"})
    EXPECT_TRUE(file_text(dir / "coarse" / f) == file_text(dir / "close" / f)) << f;
  json a = comparable_summary(dir / "coarse"), b = comparable_summary(dir / "close");
  a.erase("frames");
  b.erase("frames");
  EXPECT_EQ(a, b);
}

// `--restart --set output.interval=...`: a run continued from a checkpoint
// with closer frames. With the mechanics the frames change no step: every
// frame of the run without the restart is there with the same bits, the
// new ones fall at the multiples of the new interval, and the time series
// and the summary's audits are those of the run without the restart. A
// failed run names its checkpoint, and the restart with closer frames
// fails again at the same step, with the frames before the failure. In a
// thermal-only run the steps land on the new frames: the frames before the
// checkpoint are kept, and the temperatures differ from the uninterrupted
// run's by no more than the finer step alone makes them differ.
TEST(Restart, CloserFramesFromACheckpoint) {
  const auto dir = temp_dir("restart_closer");
  const auto job = write_job(dir, coarse_hemisphere("hemisphere_ud_2ply.json"));  // frames every 0.25 s, to 1 s
  ASSERT_EQ(run_cli(job, dir / "direct", 2).exit_code, 0);
  const auto out = dir / "closer";
  const std::string ck = "--set output.checkpoint_interval=0.5 --set output.checkpoint_at_end=false";
  ASSERT_EQ(run_cli(job, out, 2, ck).exit_code, 0);
  const auto r = run_cli(job, out, 1, ck + " --restart --set output.interval=0.05");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(std::ifstream(out / "summary.json"));
  const double from = s["restarted_from_s"].get<double>();
  EXPECT_GE(from, 0.5);
  EXPECT_LT(from, 0.501);
  const auto direct = frames_by_time(dir / "direct" / "results.h5"), closer = frames_by_time(out / "results.h5");
  ASSERT_EQ(direct.size(), 5u);
  ASSERT_EQ(closer.size(), 3u + 10u) << "0, 0.25 and 0.5 s kept; 0.55 to 1 s every 0.05 s";
  for (const auto& [t, fields] : direct) {
    ASSERT_TRUE(closer.contains(t)) << "the frame at " << t << " s";
    EXPECT_TRUE(same_bits(fields, closer.at(t))) << "the frame at " << t << " s";
  }
  const double dt = s["dt"]["mechanics"].get<double>();
  int k = 11;  // the frames after the checkpoint: the first step at or after each multiple of 0.05 s
  for (auto it = closer.upper_bound(from); it != closer.end(); ++it, ++k) {
    EXPECT_GE(it->first, 0.05 * k - 1e-12) << k;
    EXPECT_LT(it->first, 0.05 * k + 1.01 * dt) << k;
  }
  EXPECT_EQ(k, 21);
  for (const char* f : {"probes.csv", "energy.csv", "tools.csv", "plies.csv"})
    EXPECT_TRUE(file_text(dir / "direct" / f) == file_text(out / f)) << f;
  json a = comparable_summary(dir / "direct"), b = comparable_summary(out);
  EXPECT_EQ(a["frames"], 5);
  EXPECT_EQ(b["frames"], 13);
  a.erase("frames");
  b.erase("frames");
  EXPECT_EQ(a, b) << "the thermal steps keep their clock";

  // A run that fails (here: a balance error above a tight energy_tolerance
  // at about 0.3 s) names its checkpoint; from it, with closer frames, it
  // fails at the same step and keeps the frames up to there.
  const std::string tight = "--set solvers.mechanics.energy_tolerance=1e-8 --set output.checkpoint_interval=0.1";
  const auto failing = dir / "failing";
  const auto f1 = run_cli(job, failing, 2, tight);
  ASSERT_EQ(f1.exit_code, 3) << f1.err;
  const json sf = json::parse(std::ifstream(failing / "summary.json"));
  ASSERT_TRUE(sf["checkpoint_s"].is_number()) << f1.err;
  const double at = sf["checkpoint_s"].get<double>(), failed_at = sf["simulated_time_s"].get<double>();
  EXPECT_GE(at, 0.1);
  EXPECT_LT(at, failed_at);
  std::ostringstream at_text;  // as the message gives it (6 digits)
  at_text << at;
  EXPECT_NE(f1.err.find("(its checkpoint at t = " + at_text.str() +
                        " s remains: the same command with --restart --set output.interval=... runs on from it with "
                        "closer frames)"),
            std::string::npos)
      << f1.err;
  // The failure's line (the first run's warnings before the checkpoint are
  // not given again).
  const auto first_line = [](const std::string& e) {
    const std::size_t at = e.find("[error]");
    return at == std::string::npos ? std::string() : e.substr(at, e.find('\n', at) - at);
  };
  const std::string energy_before = file_text(failing / "energy.csv");
  const auto f2 =
      run_cli(job, failing, 1, tight + " --restart --set output.interval=0.01 --set output.series_interval=1e-3");
  ASSERT_EQ(f2.exit_code, 3) << f2.err;
  EXPECT_EQ(first_line(f2.err), first_line(f1.err)) << "the same failure, at the same step";
  const auto kept = frames_by_time(failing / "results.h5");
  const auto after = std::count_if(kept.begin(), kept.end(), [&](const auto& kv) { return kv.first > at; });
  EXPECT_EQ(after, static_cast<long>(std::floor(failed_at / 0.01) - std::floor(at / 0.01)))
      << "a frame every 0.01 s from the checkpoint to the failure";
  // The energy rows: those of the first run up to the checkpoint (every
  // 2 ms, time.end / 500), then one at the first step at or after each
  // millisecond; the same values where both runs wrote a row.
  auto by_time = [](const std::string& text) {  // each row of a CSV text by its time
    std::map<double, std::string> rows;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) rows[std::stod(line.substr(0, line.find(',')))] = line;
    return rows;
  };
  const auto first_rows = by_time(energy_before), rows = by_time(file_text(failing / "energy.csv"));
  int fine_rows = 0, common = 0;
  double last = at;
  for (const auto& [t, row] : rows) {
    if (t > at + 1e-9) {  // (the checkpoint's own row, its time written to 10 digits, may read a little above it)
      ++fine_rows;
      EXPECT_LT(t - last, 1e-3 + 1.01 * sf["dt"]["mechanics"].get<double>()) << t;
      last = t;
    } else {
      EXPECT_TRUE(first_rows.contains(t)) << "the first run's row at " << t << " s kept";
    }
    if (const auto it = first_rows.find(t); it != first_rows.end()) {
      ++common;
      EXPECT_EQ(it->second, row) << t;
    }
  }
  // (a millisecond whose first step is the failing one has no row: that
  // step's state is not written)
  const double before_failure = failed_at - sf["dt"]["mechanics"].get<double>();
  EXPECT_EQ(fine_rows, static_cast<int>(std::floor(before_failure / 1e-3) - std::floor(at / 1e-3))) << "a row every ms";
  EXPECT_GT(common, 100);

  // Thermal only, a step of 0.01 s, frames every 1 s, to 4 s; continued from
  // 3 s with frames every 0.015 s (two steps of 0.0075 s each).
  json patch = read_job_document(source_dir() / "share" / "verification" / "patch_contact.json");
  patch["solvers"]["thermal"]["dt"] = 0.01;
  const auto tdir = temp_dir("restart_closer_thermal");
  const auto tjob = write_job(tdir, patch);
  ASSERT_EQ(run_cli(tjob, tdir / "direct", 2).exit_code, 0);
  ASSERT_EQ(run_cli(tjob, tdir / "fine", 2, "--set output.interval=0.015").exit_code, 0);
  const std::string tck = "--set output.checkpoint_interval=1.5 --set output.checkpoint_at_end=false";
  ASSERT_EQ(run_cli(tjob, tdir / "closer", 2, tck).exit_code, 0);
  const auto tr = run_cli(tjob, tdir / "closer", 1, tck + " --restart --set output.interval=0.015");
  ASSERT_EQ(tr.exit_code, 0) << tr.err;
  const json ts = json::parse(std::ifstream(tdir / "closer" / "summary.json"));
  EXPECT_EQ(ts["restarted_from_s"].get<double>(), 3.0);
  EXPECT_EQ(ts["dt"]["thermal"].get<double>(), 0.0075);
  EXPECT_LT(ts["heat"]["balance_error"].get<double>(), 1e-9);
  const auto td = frames_by_time(tdir / "direct" / "results.h5"), tf = frames_by_time(tdir / "fine" / "results.h5"),
             tc = frames_by_time(tdir / "closer" / "results.h5");
  ASSERT_EQ(tc.size(), 4u + 67u) << "0 to 3 s kept, then 3.015 to 4 s every 0.015 s and the end";
  for (const double t : {0.0, 1.0, 2.0, 3.0}) EXPECT_TRUE(same_bits(td.at(t), tc.at(t))) << t;
  int n = 0;
  for (auto it = tc.upper_bound(3.0); std::next(it) != tc.end(); ++it)
    EXPECT_NEAR(it->first, 0.015 * (201 + n++), 1e-12) << "steps land on the frames";
  // At 4 s: the restarted run against the one with 0.01 s throughout, and
  // the finer step alone (0.0075 s throughout) against the same.
  ASSERT_TRUE(tc.contains(4.0) && td.contains(4.0) && tf.contains(4.0));
  for (const char* ply : {"upper", "lower"}) {
    const std::string f = std::string(ply) + "/temperature";
    const auto &base = td.at(4.0).at(f), &cont = tc.at(4.0).at(f), &fine = tf.at(4.0).at(f);
    double restarted = 0, step = 0;
    for (std::size_t i = 0; i < base.size(); ++i) {
      restarted = std::max(restarted, std::abs(cont[i] - base[i]));
      step = std::max(step, std::abs(fine[i] - base[i]));
    }
    std::printf("%s at 4 s: restarted with 0.0075 s steps from 3 s %.3g K, 0.0075 s throughout %.3g K from the "
                "run with 0.01 s\n",
                ply, restarted, step);
    EXPECT_GT(restarted, 0.0) << ply << ": the steps after the checkpoint are other steps";
    EXPECT_LE(restarted, step) << ply;
  }
}

// `--restart --set output.fields=...`: the frames after the checkpoint show
// other fields. From two fields (no through-thickness mesh, no contact
// pressure, no stresses) to every field but one, and from every field to
// two: each frame holds the fields of the run that wrote it, with the bits
// of a run that had every field throughout; the index names what the file
// holds; the time series and the summary are those of that run (the
// fields change no step). A node's first times below the threshold, which
// the checkpointed run did not follow, are refused before anything is
// touched.
TEST(Restart, OtherFieldsFromACheckpoint) {
  const auto dir = temp_dir("restart_fields");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  for (auto& pr : j["output"]["probes"]) {  // the contact pressure only where the frames ask for it
    json kept = json::array();
    for (const auto& quantity : pr["quantities"])
      if (quantity != "contact_pressure") kept.push_back(quantity);
    pr["quantities"] = kept;
  }
  const json all = j["output"]["fields"];
  json most = json::array();
  for (const auto& f : all)
    if (f != "below_threshold_from") most.push_back(f);
  const json two = {"displacement", "shear_angle"};
  const auto job = write_job(dir, j);
  ASSERT_EQ(run_cli(job, dir / "direct", 2).exit_code, 0);
  const auto direct = frames_by_time(dir / "direct" / "results.h5");
  ASSERT_EQ(direct.size(), 5u);
  std::set<std::string> plies;
  for (const auto& p : j["parts"]) plies.insert(p["name"].get<std::string>());
  // The datasets of a frame with these fields: each ply's positions and
  // fields, and the moving tools' positions.
  auto datasets = [&](const std::map<std::string, std::vector<double>>& frame, const json& fields) {
    std::set<std::string> names = {"nodes"};
    for (const auto& f : fields) {
      const std::string s = f;
      if (s == "temperature") {
        names.insert({"temperature", "temperature_mean", "temperature_top", "temperature_bottom", "layer_nodes"});
      } else if (s == "conductance") {
        names.insert({"conductance_bottom", "conductance_top"});
      } else if (s == "below_threshold_from") {
        names.insert({"below_threshold_from", "all_below_threshold_from"});
      } else {
        names.insert(s);
      }
    }
    std::map<std::string, std::vector<double>> out;
    for (const auto& [name, v] : frame) {
      const auto slash = name.find('/');
      if (!plies.contains(name.substr(0, slash)) || names.contains(name.substr(slash + 1))) out[name] = v;
    }
    return out;
  };
  const std::string ck = "--set output.checkpoint_interval=0.5 --set output.checkpoint_at_end=false";
  auto fields_set = [](const json& f) { return " --set " + q("output.fields=" + f.dump()); };
  struct Case {
    std::string name;
    json before, after;
  };
  for (const Case& c : {Case{"more", two, most}, Case{"fewer", all, two}}) {
    const auto out = dir / c.name;
    ASSERT_EQ(run_cli(job, out, 2, ck + fields_set(c.before)).exit_code, 0) << c.name;
    if (c.name == "more") {
      // below_threshold_from needs each node's times since the start.
      const std::string h5 = file_text(out / "results.h5");
      const auto r = run_cli(job, out, 1, ck + fields_set(all) + " --restart");
      EXPECT_EQ(r.exit_code, 2);
      std::size_t at = 0;
      while (all[at] != "below_threshold_from") ++at;
      EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
                "error: /output/fields/" + std::to_string(at) +
                    ": --restart: the run that wrote the checkpoint did not follow each node's first time below the "
                    "threshold ('below_threshold_from' was not among its fields), and the times before the "
                    "checkpoint are not in it: run the job from the start for this field")
          << r.err;
      EXPECT_TRUE(file_text(out / "results.h5") == h5) << "results.h5 untouched";
    }
    const auto r = run_cli(job, out, 1, ck + fields_set(c.after) + " --restart");
    ASSERT_EQ(r.exit_code, 0) << c.name << ": " << r.err;
    const json s = json::parse(std::ifstream(out / "summary.json"));
    const double from = s["restarted_from_s"].get<double>();
    EXPECT_GE(from, 0.5) << c.name;
    EXPECT_LT(from, 0.501) << c.name;
    const auto frames = frames_by_time(out / "results.h5");
    ASSERT_EQ(frames.size(), direct.size()) << c.name;
    for (const auto& [t, frame] : direct) {
      ASSERT_TRUE(frames.contains(t)) << c.name << ": the frame at " << t << " s";
      const auto want = datasets(frame, t <= from ? c.before : c.after);
      std::string names;
      for (const auto& [name, v] : frames.at(t)) names += name + " ";
      EXPECT_EQ(frames.at(t).size(), want.size()) << c.name << " at " << t << " s: " << names;
      EXPECT_TRUE(same_bits(want, frames.at(t))) << c.name << ": the frame at " << t << " s";
    }
    EXPECT_EQ(xdmf_mismatch(out), "") << c.name;
    for (const char* f : {"probes.csv", "energy.csv", "tools.csv", "plies.csv"})
      EXPECT_TRUE(file_text(dir / "direct" / f) == file_text(out / f)) << c.name << ": " << f;
    EXPECT_EQ(comparable_summary(dir / "direct"), comparable_summary(out)) << c.name;
    std::stringstream log;
    log << std::ifstream(out / "log.txt").rdbuf();
    EXPECT_NE(log.str().find("frames from the checkpoint on with the fields " +
                             std::string(c.name == "more" ? "displacement, temperature" : "displacement, shear_angle (")),
              std::string::npos)
        << c.name;
  }
}

// `output.keep_checkpoints` and `--restart-at T`: a run keeps each
// checkpoint it writes; a restart from the last kept one at or before T
// runs on from there (here with closer frames) and gives what a restart
// from that checkpoint gives. The kept checkpoints after it are replaced by
// those of the continued run, from which a later `--restart-at` gives the
// same output again. A time before every kept checkpoint, or a folder
// without any, is refused before anything is touched; a new run in the
// folder removes them.
TEST(Restart, FromAKeptCheckpoint) {
  const auto dir = temp_dir("restart_kept");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");  // frames every 0.25 s, to 1 s
  j["output"]["checkpoint_interval"] = 0.25;
  j["output"]["keep_checkpoints"] = true;
  const auto job = write_job(dir, j);
  ASSERT_EQ(run_cli(job, dir / "direct", 2).exit_code, 0);
  const auto direct = frames_by_time(dir / "direct" / "results.h5");
  const auto kept = kept_checkpoints(dir / "direct");
  ASSERT_EQ(kept.size(), 4u) << "0.25, 0.5 and 0.75 s, and the end checkpoint";
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(kept[k].t, 0.25 * (k + 1)) << k;
    EXPECT_LT(kept[k].t, 0.25 * (k + 1) + 1e-3) << k;
    EXPECT_EQ(kept[k].file.filename().string(), kept_checkpoint_name(kept[k].t));
  }
  EXPECT_LT(kept[3].t, 1.0);
  EXPECT_TRUE(file_text(kept[3].file) == file_text(dir / "direct" / "checkpoint.bin")) << "the latest";
  const std::string at_half = file_text(kept[1].file);

  // From the one at 0.5 s (asked for 0.5 s: it fell on the first step after
  // 0.5 s), with frames every 0.05 s and checkpoints every 0.3 s.
  const std::string closer_set = " --set output.interval=0.05 --set output.checkpoint_interval=0.3";
  const auto out = dir / "closer";
  std::filesystem::copy(dir / "direct", out, std::filesystem::copy_options::recursive);
  ASSERT_GT(kept[1].t, 0.5);
  const auto r = run_cli(job, out, 1, "--restart-at 0.5" + closer_set);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_NEAR(s["restarted_from_s"].get<double>(), kept[1].t, 1e-8) << "its name's 9 digits";
  const auto closer = frames_by_time(out / "results.h5");
  ASSERT_EQ(closer.size(), 3u + 10u) << "0, 0.25 and 0.5 s kept; 0.55 to 1 s every 0.05 s";
  for (const auto& [t, fields] : direct) {
    ASSERT_TRUE(closer.contains(t)) << "the frame at " << t << " s";
    EXPECT_TRUE(same_bits(fields, closer.at(t))) << "the frame at " << t << " s";
  }
  for (const char* f : {"probes.csv", "energy.csv", "tools.csv", "plies.csv"})
    EXPECT_TRUE(file_text(dir / "direct" / f) == file_text(out / f)) << f;
  // The same as a restart from that checkpoint as the folder's latest.
  const auto latest = dir / "latest";
  std::filesystem::copy(dir / "direct", latest, std::filesystem::copy_options::recursive);
  std::filesystem::remove_all(latest / "checkpoints");
  std::ofstream(latest / "checkpoint.bin", std::ios::binary) << at_half;
  ASSERT_EQ(run_cli(job, latest, 1, "--restart" + closer_set).exit_code, 0);
  EXPECT_TRUE(same_bits(results_contents(out / "results.h5"), results_contents(latest / "results.h5")));
  EXPECT_TRUE(file_text(out / "results.xdmf") == file_text(latest / "results.xdmf"));
  // The kept checkpoints: the two up to the one continued, unchanged, and
  // the continued run's at 0.6 and 0.9 s and its end; the first run's at
  // 0.75 s is gone.
  const auto now = kept_checkpoints(out);
  ASSERT_EQ(now.size(), 5u);
  EXPECT_TRUE(file_text(now[0].file) == file_text(kept[0].file));
  EXPECT_TRUE(file_text(now[1].file) == at_half);
  EXPECT_NEAR(now[2].t, 0.6, 1e-3);
  EXPECT_NEAR(now[3].t, 0.9, 1e-3);
  EXPECT_TRUE(file_text(now[4].file) == file_text(out / "checkpoint.bin"));
  // From the new one at 0.6 s: the same output again.
  const auto frames_before = results_contents(out / "results.h5");
  const std::string energy_before = file_text(out / "energy.csv");
  const auto again = run_cli(job, out, 2, "--restart-at 0.8" + closer_set);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NEAR(json::parse(std::ifstream(out / "summary.json"))["restarted_from_s"].get<double>(), now[2].t, 1e-8);
  EXPECT_TRUE(same_bits(results_contents(out / "results.h5"), frames_before));
  EXPECT_TRUE(file_text(out / "energy.csv") == energy_before);
  // A continued run that writes no checkpoint (to 0.55 s, none at its end)
  // leaves the one it continued as the folder's checkpoint: a plain
  // restart goes on from it to the first run's output.
  const auto shorter = dir / "shorter";
  std::filesystem::copy(dir / "direct", shorter, std::filesystem::copy_options::recursive);
  ASSERT_EQ(
      run_cli(job, shorter, 1, "--restart-at 0.6 --set time.end=0.55 --set output.checkpoint_at_end=false").exit_code,
      0);
  EXPECT_EQ(kept_checkpoints(shorter).size(), 2u);
  EXPECT_TRUE(file_text(shorter / "checkpoint.bin") == at_half);
  ASSERT_EQ(run_cli(job, shorter, 2, "--restart").exit_code, 0);
  expect_same_output(dir / "direct", shorter, "from the kept checkpoint, then the folder's");

  // Refused, the folder as it was: a time before every kept checkpoint, a
  // folder without kept checkpoints.
  const std::string before = file_text(out / "energy.csv");
  const auto early = run_cli(job, out, 1, "--restart-at 0.1");
  EXPECT_EQ(early.exit_code, 2);
  EXPECT_NE(early.err.find("error: --restart-at 0.1: no kept checkpoint at or before it in " +
                           (out / "checkpoints").string() + " (kept at t = "),
            std::string::npos)
      << early.err;
  std::filesystem::remove_all(latest / "checkpoints");  // those its restart kept
  const auto none = run_cli(job, latest, 1, "--restart-at 0.6");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("error: --restart-at 0.6: no kept checkpoints in " + (latest / "checkpoints").string() +
                          " (a run keeps every checkpoint it writes with output.keep_checkpoints: true)"),
            std::string::npos)
      << none.err;
  EXPECT_TRUE(file_text(out / "energy.csv") == before);
  EXPECT_EQ(kept_checkpoints(out).size(), 5u);
  const auto usage = run_cli(job, out, 1, "--restart-at soon");
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_NE(usage.err.find("--restart-at expects a time of at least 0, found 'soon'"), std::string::npos) << usage.err;
  // A new run in the folder removes them.
  ASSERT_EQ(run_cli(job, out, 2, "--set output.keep_checkpoints=false").exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(out / "checkpoints"));
}

// `thermostamp study --restart`: a study stopped by SIGTERM in the middle of
// a variant's run goes on from where it stopped: the reference, completed
// before, is not run again, the stopped run continues from its checkpoint,
// and the table is the uninterrupted study's (but for the wall times). A
// second restart of the completed study runs nothing and gives the same
// table byte for byte; a folder without a study state, or a study changed
// since, is refused.
TEST(Restart, StudyContinuesWhereItStopped) {
  const auto dir = temp_dir("restart_study");
  json j = coarse_hemisphere("hemisphere_ud_2ply.json");
  j["time"]["end"] = 0.6;
  write_job(dir, j);
  json st = {{"format", "thermostamp-study/1"},
             {"job", "job.json"},
             {"reference", {{"set", json::object()}}},
             {"repeat", 2},
             {"variants",
              {{{"label", "shell2d"}, {"set", {{"solvers.thermal.splitter", "shell2d"}}}},
               {{"label", "adi-4"}, {"set", {{"parts.*.thickness_layers", 4}}}}}}};
  std::ofstream(dir / "study.json") << st.dump(2);
  const std::string study = "study " + q(dir / "study.json") + " --threads 2 --out ";
  ASSERT_EQ(thermostamp(study + q(dir / "full") + " --quiet").exit_code, 0);
  // The study in the background, stopped once the run in folder `run` has
  // begun; returns the study's exit status.
  auto stop_study_in = [&](const std::filesystem::path& out, const std::string& run) {
    const std::string script = "( " + (binary_dir() / "bin" / "thermostamp").string() + " " + study + q(out) +
                               " --quiet >/dev/null 2>&1 ) & pid=$!; for i in $(seq 1 6000); do [ -f " +
                               q(out / run / "probes.csv") + " ] && break; sleep 0.01; done; kill -TERM $pid; wait $pid";
    const int rc = std::system(("bash -c " + q(script)).c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  const auto out = dir / "stopped";
  ASSERT_EQ(stop_study_in(out, "shell2d"), 128 + SIGTERM);
  const json state = json::parse(std::ifstream(out / "study_state.json"));
  EXPECT_EQ(state["runs"]["reference"]["completed"], 1);
  EXPECT_FALSE(state["runs"].contains("shell2d"));
  ASSERT_TRUE(std::filesystem::exists(out / "shell2d" / "checkpoint.bin"));
  const auto c = thermostamp(study + q(out) + " --restart");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(c.err.find("study: running reference"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("study: reference completed before the restart"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("study: continuing shell2d from its checkpoint at t = "), std::string::npos) << c.err;
  auto table = [](const std::filesystem::path& csv, bool with_times) {
    std::vector<std::string> rows;
    std::ifstream in(csv);
    for (std::string line; std::getline(in, line);) {
      if (!with_times) {  // the second column, wall_time_s, left out
        const auto a = line.find(','), b = line.find(',', a + 1);
        line.erase(a, b - a);
      }
      rows.push_back(line);
    }
    return rows;
  };
  const auto full = table(dir / "full" / "study.csv", false);
  ASSERT_EQ(full.size(), 4u);
  // The error of each ply's mean temperature and of its largest shear angle
  // (of either sign): the largest difference, at the reference's rows,
  // between its value and the variant's, linear between the variant's rows
  // (the steps, and so the rows' times, follow the temperature-dependent
  // stiffness), to the table's 6 digits.
  auto cells = [](const std::string& line) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    return c;
  };
  const auto head = cells(table(dir / "full" / "study.csv", true)[0]);
  // ply -> (time, value) of plies.csv, the value the mean temperature or the largest |shear angle|
  auto values = [&](const std::filesystem::path& csv, bool shear) {
    std::map<std::string, std::vector<std::pair<double, double>>> m;
    const auto rows = table(csv, true);
    const auto names = cells(rows[0]);
    auto col = [&](const char* name) { return std::find(names.begin(), names.end(), name) - names.begin(); };
    const auto mean = col("temperature_mean"), lo = col("shear_angle_min"), hi = col("shear_angle_max");
    for (std::size_t r = 1; r < rows.size(); ++r) {
      const auto c = cells(rows[r]);
      m[c[1]].emplace_back(std::stod(c[0]), shear ? std::max(std::abs(std::stod(c[lo])), std::abs(std::stod(c[hi])))
                                                  : std::stod(c[mean]));
    }
    return m;
  };
  for (const bool shear : {false, true})
  for (const std::string label : {"shell2d", "adi-4"}) {
    auto ref = values(dir / "full" / "reference" / "plies.csv", shear);
    auto var = values(dir / "full" / label / "plies.csv", shear);
    std::vector<std::string> row;
    for (const auto& line : table(dir / "full" / "study.csv", true))
      if (line.rfind(label + ",", 0) == 0) row = cells(line);
    ASSERT_EQ(row.size(), head.size()) << label;
    for (const std::string ply : {"ply_top", "ply_bottom"}) {
      double largest = 0;
      const auto& v = var[ply];
      int compared = 0;
      for (const auto& [t, mean] : ref[ply]) {
        for (std::size_t k = 0; k < v.size(); ++k) {
          if (v[k].first < t) continue;
          if (v[k].first == t) {
            largest = std::max(largest, std::abs(v[k].second - mean));
          } else if (k > 0) {
            const double a = (t - v[k - 1].first) / (v[k].first - v[k - 1].first);
            largest = std::max(largest, std::abs((1 - a) * v[k - 1].second + a * v[k].second - mean));
          } else {
            break;
          }
          ++compared;
          break;
        }
      }
      EXPECT_GT(compared, 400) << label << " " << ply;
      const std::string name = "error_" + ply + (shear ? "_shear_deg" : "_mean_K");
      const auto col = std::find(head.begin(), head.end(), name) - head.begin();
      ASSERT_LT(static_cast<std::size_t>(col), head.size()) << name;
      EXPECT_GT(largest, 0.0) << label << " " << name;
      EXPECT_NEAR(std::stod(row[col]), largest, 1e-5 * largest) << label << " " << name;
      if (shear) std::printf("%s %s: %.6g deg\n", label.c_str(), name.c_str(), largest);
    }
  }
  // The probe errors: every sample of the reference (13 times x 4 probes,
  // 9 values through the thickness each) against the variant's sample of
  // the same multiple of the probe interval (the steps, and so the sample
  // times, differ by up to a step), the variant's profile linear between its
  // values at the reference's heights: recomputed from probes.csv for the
  // upper pole.
  auto profiles = [&](const std::filesystem::path& csv) {
    std::map<double, std::vector<std::pair<double, double>>> m;  // time -> (z, value)
    const auto rows = table(csv, true);
    for (std::size_t r = 1; r < rows.size(); ++r) {
      const auto c = cells(rows[r]);
      if (c[0] == "pole_top" && c[1] == "temperature_profile") m[std::stod(c[2])].emplace_back(std::stod(c[3]), std::stod(c[4]));
    }
    return m;
  };
  const auto ref_pole = profiles(dir / "full" / "reference" / "probes.csv");
  ASSERT_EQ(ref_pole.size(), 13u);
  for (const std::string label : {"shell2d", "adi-4"}) {
    const auto var_pole = profiles(dir / "full" / label / "probes.csv");
    std::vector<std::string> row;
    for (const auto& line : table(dir / "full" / "study.csv", true))
      if (line.rfind(label + ",", 0) == 0) row = cells(line);
    EXPECT_EQ(row[4], "468") << label << ": every value of the reference's samples compared";
    double largest = 0, offset = 0;
    for (const auto& [t, ref_values] : ref_pole) {
      auto near = var_pole.lower_bound(t);
      if (near == var_pole.end() || (near != var_pole.begin() && t - std::prev(near)->first < near->first - t))
        near = std::prev(near);
      offset = std::max(offset, std::abs(near->first - t));
      const auto& v = near->second;
      for (const auto& [z, value] : ref_values) {
        double at = v.front().second;
        if (z >= v.back().first) {
          at = v.back().second;
        } else if (z > v.front().first) {
          std::size_t k = 1;
          while (v[k].first < z) ++k;
          const double a = (z - v[k - 1].first) / (v[k].first - v[k - 1].first);
          at = (1 - a) * v[k - 1].second + a * v[k].second;
        }
        largest = std::max(largest, std::abs(at - value));
      }
    }
    EXPECT_LT(offset, 1e-3) << label;  // a step or so, against the 50 ms interval
    const auto col = std::find(head.begin(), head.end(), "error_pole_top_K") - head.begin();
    EXPECT_NEAR(std::stod(row[col]), largest, 1e-5 * largest) << label;
    std::printf("%s pole_top: %.6g K, samples up to %.3g s apart\n", label.c_str(), largest, offset);
  }
  EXPECT_EQ(table(out / "study.csv", false), full);
  EXPECT_TRUE(file_text(dir / "full" / "shell2d" / "probes.csv") == file_text(out / "shell2d" / "probes.csv"));
  // Stopped in its first run, the reference: it continues from its checkpoint.
  const auto first = dir / "stopped_first";
  ASSERT_EQ(stop_study_in(first, "reference"), 128 + SIGTERM);
  ASSERT_TRUE(std::filesystem::exists(first / "reference" / "checkpoint.bin"));
  const auto cf = thermostamp(study + q(first) + " --restart");
  ASSERT_EQ(cf.exit_code, 0) << cf.err;
  EXPECT_NE(cf.err.find("study: continuing reference from its checkpoint at t = "), std::string::npos) << cf.err;
  EXPECT_EQ(table(first / "study.csv", false), full);
  // Completed: a restart runs nothing and writes the same table.
  const auto before = table(out / "study.csv", true);
  const auto again = thermostamp(study + q(out) + " --restart");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.err.find("study: running"), std::string::npos) << again.err;
  EXPECT_EQ(table(out / "study.csv", true), before);
  // Refused: no state in the folder; a study changed since other than in
  // its variants (those, Restart.StudyTakesNewAndChangedVariants).
  const auto none = thermostamp(study + q(dir / "elsewhere") + " --restart");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("error: --restart: no study to continue in"), std::string::npos) << none.err;
  st["repeat"] = 3;
  std::ofstream(dir / "study.json") << st.dump(2);
  const auto changed = thermostamp(study + q(out) + " --restart");
  EXPECT_EQ(changed.exit_code, 2);
  EXPECT_NE(changed.err.find("error: --restart: the study file changed since"), std::string::npos) << changed.err;
  EXPECT_EQ(table(out / "study.csv", true), before);
}

// `thermostamp study --restart` after the study file's variants changed:
// the runs of the variants it kept with the same settings are not run
// again (their rows, wall time included, are those of the first study),
// new variants and those with other settings run, and those it dropped
// are left out of study.csv; the table is that of the new study run from
// the start, wall times aside. Another reference or job is refused.
TEST(Restart, StudyTakesNewAndChangedVariants) {
  const auto dir = temp_dir("restart_study_variants");
  json j = read_job_document(source_dir() / "share" / "jobs" / "two_ply_thermal_demo.json");
  j["time"]["end"] = 1.0;
  write_job(dir, j);
  auto variant = [](const std::string& label, int layers) {
    return json{{"label", label}, {"set", {{"parts.*.thickness_layers", layers}}}};
  };
  json first = {{"format", "thermostamp-study/1"},
                {"job", "job.json"},
                {"reference", {{"set", {{"parts.*.thickness_layers", 16}}}}},
                {"variants", {variant("adi-4", 4), variant("coarse", 2), variant("old", 6)}}};
  json second = first;
  second["variants"] = {variant("adi-4", 4), variant("coarse", 3), variant("adi-8", 8)};
  std::ofstream(dir / "first.json") << first.dump(2);
  std::ofstream(dir / "second.json") << second.dump(2);
  auto study = [&](const std::string& file, const std::filesystem::path& out, const std::string& extra = "") {
    return thermostamp("study " + q(dir / file) + " --threads 2 --out " + q(out) + " " + extra);
  };
  auto rows = [](const std::filesystem::path& csv, bool with_times) {
    std::map<std::string, std::string> by_label;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      if (!with_times) {  // the second column, wall_time_s, left out
        const auto a = line.find(','), b = line.find(',', a + 1);
        line.erase(a, b - a);
      }
      by_label[line.substr(0, line.find(','))] = line;
    }
    return by_label;
  };
  const auto out = dir / "study";
  ASSERT_EQ(study("first.json", out).exit_code, 0);
  const auto before = rows(out / "study.csv", true);
  ASSERT_EQ(before.size(), 4u);
  const auto r = study("second.json", out, "--restart");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* said :
       {"study: reference completed before the restart", "study: adi-4 completed before the restart",
        "study: variant 'coarse' has other settings than when the study state was written: it runs from the start",
        "study: variant 'adi-8' is new: it runs from the start", "study: running coarse", "study: running adi-8",
        "study: variant 'old' is no longer in the study: left out of study.csv (its folder stays)"})
    EXPECT_NE(r.err.find(said), std::string::npos) << said << "\n" << r.err;
  EXPECT_EQ(r.err.find("study: running adi-4"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("study: running reference"), std::string::npos) << r.err;
  const auto after = rows(out / "study.csv", true);
  ASSERT_EQ(after.size(), 4u);
  EXPECT_EQ(after.at("adi-4"), before.at("adi-4")) << "its run kept, wall time included";
  EXPECT_EQ(after.at("reference"), before.at("reference"));
  EXPECT_FALSE(after.contains("old"));
  EXPECT_TRUE(std::filesystem::exists(out / "old" / "summary.json"));
  // The table of the second study run from the start, wall times aside.
  ASSERT_EQ(study("second.json", dir / "fresh").exit_code, 0);
  EXPECT_EQ(rows(out / "study.csv", false), rows(dir / "fresh" / "study.csv", false));
  {
    std::ifstream a(out / "study.csv"), b(dir / "fresh" / "study.csv");
    std::string ha, hb;
    std::getline(a, ha);
    std::getline(b, hb);
    EXPECT_EQ(ha, hb) << "the same columns";
  }
  // Again with nothing changed: nothing runs, the same table.
  const auto again = study("second.json", out, "--restart");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.err.find("study: running"), std::string::npos) << again.err;
  EXPECT_EQ(rows(out / "study.csv", true), after);
  // Another reference, or another job: refused, the folder as it was.
  json other = second;
  other["reference"]["set"]["parts.*.thickness_layers"] = 12;
  std::ofstream(dir / "other.json") << other.dump(2);
  const auto ref = study("other.json", out, "--restart");
  EXPECT_EQ(ref.exit_code, 2);
  EXPECT_NE(ref.err.find("--restart: the study file changed since " + (out / "study_state.json").string() +
                         " was written (a restart may add, remove or change variants, nothing else)"),
            std::string::npos)
      << ref.err;
  j["time"]["end"] = 1.5;
  write_job(dir, j);
  const auto job = study("second.json", out, "--restart");
  EXPECT_EQ(job.exit_code, 2);
  EXPECT_NE(job.err.find("--restart: the job changed since"), std::string::npos) << job.err;
  EXPECT_EQ(rows(out / "study.csv", true), after);
}

}  // namespace ts::test
