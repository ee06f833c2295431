// Stiff and extreme cases, heat conservation, thread independence, and the
// splitting error of adi against the layered3d reference.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "io/logging.hpp"
#include "plugins/registry.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

// Two plies on a die, a regional chill on top: every kind of face condition.
json stack_job(const std::string& splitter, const std::string& scheme, int layers) {
  json j = ply_job(splitter, layers, 1.0, 0.25);
  j["solvers"]["thermal"]["through_thickness"] = scheme;
  json lower = j["parts"][0];
  lower["name"] = "lower";
  lower["mesh"] = {{"generator", "rectangle"}, {"origin", {0, 0, 0.00025}}, {"size", {0.02, 0.02}}, {"divisions", {10, 10}}};
  json upper = lower;
  upper["name"] = "upper";
  upper["mesh"]["origin"] = {0, 0, 0.00075};
  upper["fibre_direction"] = {0, 1, 0};
  // Offset mesh: links land inside the lower ply's triangles, not on nodes.
  upper["mesh"]["divisions"] = {7, 9};
  j["parts"] = {lower, upper};
  j["tools"] = {{{"name", "die"}, {"surface", {{"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 0, 1}}}},
                 {"temperature", 260.0}}};
  j["interactions"] = {
      {{"type", "contact"}, {"between", {"die", "lower"}}, {"conductance", 1000.0}},
      {{"type", "contact"}, {"between", {"upper", "lower"}}, {"conductance", 1000.0}},
      {{"type", "heat_exchange"}, {"part", "upper"}, {"face", "top"}, {"h", 500.0}, {"ambient", 250.0},
       {"region", {{"circle", {{"centre", {0, 0}}, {"radius", 0.008}}}}}}};
  j["output"]["probes"] = {{{"name", "up"}, {"part", "upper"}, {"at", {0.006, 0.004, 0.00075}},
                            {"quantities", {"temperature_profile"}}, {"interval", 0.25}}};
  return j;
}

// Stored heat change equals the heat through the faces: the exchange between
// plies cancels exactly, so only round-off remains (1e-9 relative); also
// with a specific heat table.
TEST(Conservation, StoredHeatEqualsFaceHeat) {
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"shell2d", "implicit"}, {"shell2d", "explicit"},
           {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    const JobRun r = run_json(stack_job(splitter, scheme, 6));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_in, -1.0) << "the case must exchange heat";
    EXPECT_LT(r.result.heat_balance_error, 1e-9) << splitter << " " << scheme;
    std::printf("%s %s: heat in %.6f J, stored change %.6f J, relative balance error %.2e\n", splitter.c_str(),
                scheme.c_str(), r.result.heat_in, r.result.stored_change, r.result.heat_balance_error);
    // With a specific heat that follows the temperature (a peak inside the
    // plies' range): the stored heat is the mass times int_0^T c.
    json jt = stack_job(splitter, scheme, 6);
    jt["materials"]["ply"]["specific_heat"] = {{250.0, 1775.0}, {275.0, 3775.0}, {300.0, 1775.0}};
    const JobRun rt = run_json(jt);
    ASSERT_TRUE(rt.result.ok) << rt.result.error;
    EXPECT_LT(rt.result.heat_balance_error, 1e-9) << splitter << " " << scheme << " with a table";
    // The peak's latent heat keeps the plies hotter.
    EXPECT_GT(rt.result.probes.back().values.front(), r.result.probes.back().values.front() + 0.5);
    // With crystallisation kinetics on top of the table (a rate high enough
    // in the plies' range to crystallise them within the second): the stored
    // heat also counts the latent heat the melt still holds.
    json jk = jt;
    jk["materials"]["ply"]["crystallisation"] = {
        {"latent_heat", 20000.0}, {"avrami_exponent", 2.0}, {"rate", {{270.0, 3.0}, {300.0, 0.0}}}};
    const JobRun rk = run_json(jk);
    ASSERT_TRUE(rk.result.ok) << rk.result.error;
    EXPECT_LT(rk.result.heat_balance_error, 1e-9) << splitter << " " << scheme << " with crystallisation";
    EXPECT_GT(rk.result.probes.back().values.front(), rt.result.probes.back().values.front() + 0.5);
    // With melting too: plies at 300 degC holding half their crystals melt
    // at the first step (every crystal has melted above 285 degC), and
    // crystallise again where they cool.
    json jm = jk;
    jm["materials"]["ply"]["crystallisation"]["initial"] = 0.5;
    jm["materials"]["ply"]["crystallisation"]["melting"] = {{265.0, 1.0}, {285.0, 0.0}};
    jm["output"]["probes"][0]["quantities"] = {"temperature_profile", "crystallinity_profile"};
    const JobRun rm = run_json(jm);
    ASSERT_TRUE(rm.result.ok) << rm.result.error;
    EXPECT_LT(rm.result.heat_balance_error, 1e-9) << splitter << " " << scheme << " with melting";
    EXPECT_EQ(rm.sample(0, "crystallinity_profile", 0.0)->values.front(), 0.5);
    EXPECT_LT(rm.sample(0, "crystallinity_profile", 0.25)->values.back(), 0.2);  // melted
    EXPECT_GT(rm.sample(0, "crystallinity_profile", 1.0)->values.back(), 0.0);   // crystallising again
    // With a conductivity that follows the temperature on top of it all
    // (k33 halved at 250 degC): the plies keep more of their heat.
    json jc = jm;
    jc["materials"]["ply"]["conductivity"] = {{250.0, 2.0, 0.16, 0.16}, {300.0, 3.89, 0.31, 0.31}};
    const JobRun rc = run_json(jc);
    ASSERT_TRUE(rc.result.ok) << rc.result.error;
    EXPECT_LT(rc.result.heat_balance_error, 1e-9) << splitter << " " << scheme << " with a conductivity table";
    EXPECT_LT(rc.result.heat_in, 0.0);
    EXPECT_GT(rc.result.heat_in, rm.result.heat_in);
    std::printf("  with a table: balance error %.2e; with crystallisation too: %.2e; with melting: %.2e; with a "
                "conductivity table: %.2e (heat in %.4f J against %.4f J)\n",
                rt.result.heat_balance_error, rk.result.heat_balance_error, rm.result.heat_balance_error,
                rc.result.heat_balance_error, rc.result.heat_in, rm.result.heat_in);
  }
}

// Same answer, bit for bit, with 1 and 2 threads.
TEST(Determinism, OneAndTwoThreadsIdentical) {
  for (const std::string splitter : {"adi", "shell2d", "layered3d"}) {
    for (bool table : {false, true}) {
      json j = stack_job(splitter, "implicit", 6);
      if (table) j["materials"]["ply"]["conductivity"] = {{250.0, 2.0, 0.16, 0.16}, {300.0, 3.89, 0.31, 0.31}};
      const JobRun a = run_json(j, 1);
      const JobRun b = run_json(j, 2);
      ASSERT_EQ(a.result.probes.size(), b.result.probes.size());
      for (std::size_t i = 0; i < a.result.probes.size(); ++i)
        for (std::size_t k = 0; k < a.result.probes[i].values.size(); ++k)
          ASSERT_EQ(a.result.probes[i].values[k], b.result.probes[i].values[k]) << splitter << " table " << table;
    }
  }
}

// The lower ply cools through the upper one, and the upper through the lower
// (heat crosses the ply/ply links in both directions).
TEST(Stack, UpperPlyCoolsThroughLowerPly) {
  json j = stack_job("adi", "implicit", 6);
  j["interactions"].erase(2);  // no chill on top: the upper ply touches nothing but the lower ply
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok);
  const ProbeSample* s = r.sample(0, "temperature_profile", 1.0);
  EXPECT_LT(s->values.back(), 299.5);              // cooled by the die through the lower ply
  EXPECT_LT(s->values.front(), s->values.back());  // colder on the face looking at the lower ply
  j["interactions"][1]["conductance"] = 0.0;       // without the ply/ply conductance it stays hot
  const JobRun iso = run_json(j);
  EXPECT_NEAR(iso.sample(0, "temperature_profile", 1.0)->values.back(), 300.0, 1e-9);  // round-off only
}

// The side searched does not matter: lower nodes against the upper ply's
// triangles give the same faces (upper bottom, lower top) and conserve heat.
TEST(Stack, EitherSearchDirectionFindsTheFacingFaces) {
  json j = stack_job("adi", "implicit", 6);
  j["interactions"].erase(2);
  std::swap(j["interactions"][1]["between"][0], j["interactions"][1]["between"][1]);
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const ProbeSample* s = r.sample(0, "temperature_profile", 1.0);
  EXPECT_LT(s->values.back(), 299.0);
  EXPECT_LT(s->values.front(), s->values.back());
  EXPECT_LT(r.result.heat_balance_error, 1e-9);
}

double max_diff(const JobRun& a, const JobRun& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.result.probes.size(); ++i)
    for (std::size_t k = 0; k < a.result.probes[i].values.size(); ++k)
      d = std::max(d, std::abs(a.result.probes[i].values[k] - b.result.probes[i].values[k]));
  return d;
}

// Runs a job in-process from an initial temperature T(x, y) (uniform
// through the thickness), without files; heat_change: relative change of
// the stored heat over the run, when given.
RunResult run_from_field(const json& j, const std::function<double(double, double)>& field,
                         double* heat_change = nullptr) {
  log_to_terminal(true);
  const Job job = parse_job(j, source_dir() / "tests" / "inline.json");
  PluginRegistry reg;
  Simulation sim(job, reg);
  const auto x0 = sim.initial_coordinates(0);
  std::vector<double> T0(x0.size() / 3);
  for (std::size_t i = 0; i < T0.size(); ++i) T0[i] = field(x0[3 * i], x0[3 * i + 1]);
  sim.set_initial_temperature(0, T0);
  const double heat0 = sim.stored_heat();
  RunOptions opt;
  opt.write_files = false;
  opt.quiet = true;
  RunResult r = sim.run(opt);
  if (heat_change) *heat_change = (sim.stored_heat() - heat0) / heat0;
  return r;
}

// adi against layered3d: an in-plane cosine of wavelength 2L cooled from the
// top. The split drops the in-plane conduction of the through-thickness
// deviation, an error of order (k11/k33)(pi h/L)^2 of the deviation: going
// from L to 2L must divide the error by about 4 (at least 3 is required,
// the time-splitting error also contributes). With in_plane = "layers"
// every layer value is conducted in-plane, the deviation included: only the
// time-splitting error is left, required under a quarter of the mean-only
// error at L = 10 mm.
double cosine_split_error(double L, const std::string& in_plane, long long* limited) {
  std::vector<JobRun> runs;
  for (const std::string splitter : {"adi", "layered3d"}) {
    json j = ply_job(splitter, 8, 1.0, 0.05);
    j["parts"][0]["mesh"] = {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {L, L / 8}}, {"divisions", {48, 6}}};
    j["solvers"]["thermal"]["dt"] = 0.005;
    if (splitter == "adi") j["solvers"]["thermal"]["in_plane"] = in_plane;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 260.0}}};
    j["output"]["probes"] = {{{"name", "edge"}, {"part", "ply"}, {"at", {0, 0, 0}}, {"quantities", {"temperature_profile"}}, {"interval", 0.05}}};
    JobRun r;
    r.result = run_from_field(j, [L](double x, double) { return 300.0 + 20.0 * std::cos(M_PI * x / L); });
    EXPECT_TRUE(r.result.ok) << r.result.error;
    *limited += r.result.limited_node_steps;
    runs.push_back(std::move(r));
  }
  return max_diff(runs[0], runs[1]);
}

TEST(Splitting, AdiErrorShrinksWithHOverLSquared) {
  long long limited = 0;
  const double e10 = cosine_split_error(0.01, "mean", &limited), e20 = cosine_split_error(0.02, "mean", &limited);
  EXPECT_EQ(limited, 0) << "the bound-preserving correction must not act on smooth profiles";
  std::printf("adi - layered3d: L = 10 mm: %.4g K, L = 20 mm: %.4g K, ratio %.2f\n", e10, e20, e10 / e20);
  EXPECT_GT(e10 / e20, 3.0);
  const double l10 = cosine_split_error(0.01, "layers", &limited);
  std::printf("adi (in_plane layers) - layered3d: L = 10 mm: %.4g K (mean only: %.4g K)\n", l10, e10);
  EXPECT_LT(l10, 0.25 * e10);
}

// In-plane conduction with k11/k22 = 100 and the fibres at 30 degrees to the
// mesh lines: the stiffness has positive off-diagonal terms (not an
// M-matrix), and a plain explicit update overshoots next to a hot spot. The
// limited fluxes must keep every value within the initial range (300 and
// 260 degC; round-off margin 1e-9 K) and conserve heat to 1e-9, for shell2d
// and for adi with both in-plane modes.
TEST(Stiff, AnisotropicInPlaneConductionStaysBounded) {
  for (const std::string mode : {"shell2d", "mean", "layers"}) {
    json j = ply_job(mode == "shell2d" ? "shell2d" : "adi", 4, 2.0, 0.5);
    j["materials"]["ply"]["conductivity"] = {31.0, 0.31, 0.31};
    j["parts"][0]["fibre_direction"] = {std::cos(M_PI / 6), std::sin(M_PI / 6), 0.0};
    j["parts"][0]["mesh"] = {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {0.02, 0.02}}, {"divisions", {20, 20}}};
    if (mode != "shell2d") j["solvers"]["thermal"]["in_plane"] = mode;
    j["solvers"]["thermal"]["dt"] = 0.01;
    double change = 0;
    const RunResult r = run_from_field(
        j, [](double x, double y) { return std::hypot(x - 0.01, y - 0.01) < 0.003 ? 300.0 : 260.0; }, &change);
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_LE(r.temperature_max, 300.0 + 1e-9) << mode;
    EXPECT_GE(r.temperature_min, 260.0 - 1e-9) << mode;
    EXPECT_LT(std::abs(change), 1e-9) << mode;
    std::printf("%s: T in [%.6f, %.6f] degC, heat change %.2e\n", mode.c_str(), r.temperature_min, r.temperature_max,
                change);
  }
}

// Stiff and extreme: conductance 1e6 W/m2/K, layers of 2 micrometres
// (250 per 0.5 mm ply), k11/k33 = 1000, a 1000 K jump. The implicit path
// must stay bounded by the initial and boundary temperatures (backward Euler
// on an M-matrix keeps a discrete maximum principle); round-off margin 1e-9 K.
json stiff_job(const std::string& splitter, const std::string& scheme) {
  json j = stack_job(splitter, scheme, 250);
  for (auto& p : j["parts"]) p["initial_temperature"] = 1300.0;
  j["materials"]["ply"]["conductivity"] = {310.0, 0.31, 0.31};
  j["tools"][0]["temperature"] = 300.0;
  j["interactions"][0]["conductance"] = 1.0e6;
  j["interactions"][1]["conductance"] = 1.0e6;
  j["interactions"][2]["h"] = 1.0e6;
  j["interactions"][2]["ambient"] = 300.0;
  j["time"]["end"] = 0.02;
  j["output"]["interval"] = 0.01;
  j["output"]["probes"][0]["interval"] = 0.01;
  return j;
}

TEST(Stiff, ImplicitStaysBounded) {
  for (const std::string splitter : {"adi", "shell2d", "layered3d"}) {
    json j = stiff_job(splitter, "implicit");
    j["solvers"]["thermal"]["dt"] = 1e-3;  // steps far above every explicit limit
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << splitter << ": " << r.result.error;
    EXPECT_GE(r.result.temperature_min, 300.0 - 1e-9) << splitter;
    EXPECT_LE(r.result.temperature_max, 1300.0 + 1e-9) << splitter;
    EXPECT_LT(r.result.heat_balance_error, 1e-9) << splitter;
    std::printf("%s implicit stiff: T in [%.6f, %.6f], balance %.1e\n", splitter.c_str(), r.result.temperature_min,
                r.result.temperature_max, r.result.heat_balance_error);
  }
}

// The explicit path picks a step under its stability bound and stays bounded
// (forward Euler at dt <= C/K_ii is monotone) ...
TEST(Stiff, ExplicitRespectsItsStableStep) {
  json j = stiff_job("adi", "explicit");
  j["time"]["end"] = 0.002;
  j["output"]["interval"] = 0.001;
  j["output"]["probes"][0]["interval"] = 0.001;
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  EXPECT_GE(r.result.temperature_min, 300.0 - 1e-9);
  EXPECT_LE(r.result.temperature_max, 1300.0 + 1e-9);
  EXPECT_LT(r.result.thermal_dt, 1e-5);
}

// ... and refuses a step above it with a clear message naming the JSON path.
TEST(Stiff, ExplicitRefusesTooLargeStep) {
  json j = stiff_job("adi", "explicit");
  j["solvers"]["thermal"]["dt"] = 1e-3;
  try {
    run_json(j);
    FAIL() << "an explicit step above the stable step was accepted";
  } catch (const JobError& e) {
    EXPECT_EQ(e.pointer(), "/solvers/thermal/dt");
    EXPECT_NE(std::string(e.what()).find("exceeds the stable step"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ts::test
