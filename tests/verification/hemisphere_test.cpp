// The hemispherical stamping of two UD plies (share/jobs/hemisphere_ud_2ply.json)
// on a coarse mesh (10 x 10 per quarter ply, 15 mm) with a larger mass-scaling
// step, end to end: what the results must show (physics.md section 5).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <vector>
#include <map>
#include <utility>

#include "test_support.hpp"

namespace ts::test {
namespace {

json coarse_scene(const std::string& job = "hemisphere_ud_2ply.json", double target_dt = 1e-4) {
  json j = read_job_document(source_dir() / "share" / "jobs" / job);
  for (auto& p : j["parts"]) p["mesh"]["divisions"] = {10, 10};
  j["solvers"]["mechanics"]["mass_scaling"]["target_dt"] = target_dt;
  j["output"]["probes"] = {
      {{"name", "pole_top"}, {"part", "ply_top"}, {"at", {0, 0, 0}}, {"quantities", {"temperature_profile"}}, {"interval", 1.0}},
      {{"name", "pole_bottom"}, {"part", "ply_bottom"}, {"at", {0, 0, 0}}, {"quantities", {"temperature_profile"}}, {"interval", 1.0}},
      {{"name", "ring_top"}, {"part", "ply_top"}, {"at", {0.12, 0.0, 0}}, {"quantities", {"temperature_profile"}}, {"interval", 1.0}},
      {{"name", "ring_bottom"}, {"part", "ply_bottom"}, {"at", {0.12, 0.0, 0}}, {"quantities", {"temperature_profile"}}, {"interval", 1.0}}};
  return j;
}

struct Faces {
  double bottom, mean, top;
};
Faces faces(const JobRun& r, int probe, double t) {
  const auto& v = r.sample(probe, "temperature_profile", t)->values;
  double m = 0;
  for (std::size_t k = 0; k < v.size(); ++k) m += (k == 0 || k + 1 == v.size() ? 0.5 : 1.0) * v[k];
  return {v.front(), m / (v.size() - 1), v.back()};
}

// How far two runs of the coarse scene are apart: the largest relative
// difference of the plies' shear extrema, and the largest difference of
// the through-thickness temperatures at the four probes, every second (K).
std::pair<double, double> apart(const JobRun& a, const JobRun& b,
                                const std::vector<double>& times = {1.0, 2.0, 3.0, 4.0, 5.0}) {
  double shear = 0, temp = 0;
  for (std::size_t p = 0; p < a.result.part_shear_max_deg.size(); ++p) {
    const double ma = a.result.part_shear_max_deg[p], mb = b.result.part_shear_max_deg[p];
    const double na = a.result.part_shear_min_deg[p], nb = b.result.part_shear_min_deg[p];
    shear = std::max({shear, std::abs(mb - ma) / std::abs(ma), std::abs(nb - na) / std::abs(na)});
  }
  for (int probe = 0; probe < 4; ++probe)
    for (double t : times) {
      const auto& va = a.sample(probe, "temperature_profile", t)->values;
      const auto& vb = b.sample(probe, "temperature_profile", t)->values;
      for (std::size_t k = 0; k < va.size(); ++k) temp = std::max(temp, std::abs(va[k] - vb[k]));
    }
  return {shear, temp};
}

}  // namespace

// Prints: the upper ply carries the punch (pole) and holder (ring, r = 120 mm)
// prints on its upper face; the lower ply carries the die print on its lower
// face under the ring; at the pole the lower ply, which never touches the
// punch (no contact pair between them), cools through the upper ply, its
// upper face more than its lower face. Required: each of these cooler than
// the opposite face by at least 1 K (the drops are 5-30 K), and the lower
// ply's pole below 295 degC at the end of the stroke. Energy balance error
// under 2 %, heat balance under 1e-9, the run completes (no inverted element).
// Contact pressure at the end of the stroke: over the flange (the nodes
// within 2 mm of the holder plane), the sum of pressure x node area of the
// upper ply must give the holder's force and that of the lower ply the
// die's, within 2 % (each node shows its more loaded face, the holder's or
// the die's there, against the interface's, and the die also pushes on the
// lower ply at its entry radius; measured 0.3 % and 0.04 % here, 0.26 %
// and 0.02 % on the default mesh).
TEST(Hemisphere, ThermalPrintsReachTheLowerPlyThroughTheUpperOne) {
  const auto out = temp_dir("hemisphere_prints");
  const JobRun r = run_json(coarse_scene(), 0, out);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  {
    const hid_t file = H5Fopen((out / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    char last[32];
    std::snprintf(last, sizeof last, "frames/%06d/", frame_count(file) - 1);
    double pressed[2];
    for (int q = 0; q < 2; ++q) {
      const std::string ply = q == 0 ? "ply_top" : "ply_bottom";
      ShellMesh initial;  // the node areas the contact divides by
      initial.triangles = read_dataset<int>(file, "parts/" + ply + "/triangles");
      initial.x = read_dataset<double>(file, "frames/000000/" + ply + "/nodes");
      const std::vector<double> area = node_areas(initial);
      const std::vector<double> x = read_dataset<double>(file, last + ply + "/nodes");
      const std::vector<double> p = read_dataset<double>(file, last + ply + "/contact_pressure");
      pressed[q] = 0;
      for (std::size_t i = 0; i < p.size(); ++i)
        if (x[3 * i + 2] > -0.002) pressed[q] += p[i] * area[i];
    }
    H5Fclose(file);
    const double holder = r.result.energy.tool_forces[3 * 2 + 2], die = -r.result.energy.tool_forces[3 * 1 + 2];
    EXPECT_NEAR(pressed[0] / holder, 1.0, 0.02);
    EXPECT_NEAR(pressed[1] / die, 1.0, 0.02);
    std::printf("flange: upper ply pressure x area %.2f N (holder %.2f N), lower ply %.2f N (die %.2f N)\n", pressed[0],
                holder, pressed[1], die);
  }
  const double t = 5.0;
  const Faces pt = faces(r, 0, t), pb = faces(r, 1, t), rt = faces(r, 2, t), rb = faces(r, 3, t);
  EXPECT_LT(pt.top, pt.bottom - 1.0);  // punch print on the upper ply
  EXPECT_LT(rt.top, rt.bottom - 1.0);  // holder print on the upper ply
  EXPECT_LT(rb.bottom, rb.top - 1.0);  // die print on the lower ply
  EXPECT_LT(pb.top, pb.bottom - 1.0);  // the punch reaches the lower ply from above
  EXPECT_LT(pb.mean, 295.0);
  EXPECT_LT(r.result.energy.balance_error, 0.02);
  EXPECT_LT(r.result.heat_balance_error, 1e-9);
  std::printf("pole: upper ply %.2f / %.2f, lower ply %.2f / %.2f degC (bottom / top faces); ring: upper %.2f / %.2f, "
              "lower %.2f / %.2f; energy balance %.2e, kinetic/internal at the end %.4f, %lld steps\n",
              pt.bottom, pt.top, pb.bottom, pb.top, rt.bottom, rt.top, rb.bottom, rb.top, r.result.energy.balance_error,
              r.result.energy.kinetic / r.result.energy.internal, r.result.mechanical_steps);
}

// Fibres perpendicular to the diagonal ([1,-1,0]) make the problem symmetric
// about the diagonal x = y, with the shear angle changing sign in the mirror;
// fibres along y do not. On the default mesh (mass scaling to 1e-4 s as in
// the other tests here): shear angles at node pairs mirrored
// about the diagonal (average of the elements around the node) and the
// extrema of each ply at the end of the stroke.
// Required for [1,-1,0]: + and - extrema within 5 % of each other (physics.md
// section 5), and s(p) + s(mirror p) within 5 % of the peak shear angle at
// every pair. Measured: 0.049 / 0.045 % (extrema) and 0.007 / 0.025 % (pairs).
// The check is kept tighter, at 0.5 %: on this scene the field is
// symmetric to round-off, and each defect that broke the symmetry so far
// (sticking friction, a snag on the holder rim, the friction vibration at
// the step's frequency limit) showed as 2-30 %. The default scene, with
// its smaller step and the job's ply/ply search every 64th step, takes a
// slightly asymmetric state instead (extrema 1.0 and 1.6 % apart), which
// fibres turned by 0.006 deg also give with the search every step: should
// this scene ever take it, the 5 % of physics.md is the bound, not 0.5 %.
// Fibres along y: extrema more than 30 % apart (measured 75 %).
TEST(Hemisphere, ShearSymmetricAboutTheDiagonalOnlyForDiagonalFibres) {
  // Nodes of the [1,-1,0] scene's mesh (10 mm cells: corners and centres).
  const std::vector<std::array<double, 2>> points = {{0.045, 0.015}, {0.06, 0.03},  {0.075, 0.015},
                                                     {0.09, 0.04},   {0.105, 0.035}, {0.03, 0.01}};
  for (const char* job : {"hemisphere_ud_2ply.json", "hemisphere_ud_2ply_fibres_y.json"}) {
    json j = coarse_scene(job);
    // Each job's own mesh (coarse_scene() sets a coarser one).
    const json own = read_job_document(source_dir() / "share" / "jobs" / job);
    for (std::size_t q = 0; q < 2; ++q) j["parts"][q]["mesh"]["divisions"] = own["parts"][q]["mesh"]["divisions"];
    j["output"]["probes"] = json::array();
    for (const char* ply : {"ply_bottom", "ply_top"})
      for (const auto& p : points)
        for (int m = 0; m < 2; ++m)
          j["output"]["probes"].push_back({{"name", std::string(ply) + std::to_string(j["output"]["probes"].size())},
                                           {"part", ply},
                                           {"at", {p[m], p[1 - m], 0.0}},
                                           {"quantities", {"shear_angle"}},
                                           {"interval", 5.0}});
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << job << ": " << r.result.error;
    ASSERT_EQ(r.result.part_shear_min_deg.size(), 2u);
    for (int ply = 0; ply < 2; ++ply) {
      const double mn = r.result.part_shear_min_deg[ply], mx = r.result.part_shear_max_deg[ply];
      const double peak = std::max(-mn, mx), spread = std::abs(mx + mn) / peak;
      double worst = 0;
      for (std::size_t q = 0; q < points.size(); ++q) {
        const int k = static_cast<int>(2 * (ply * points.size() + q));
        const double a = r.sample(k, "shear_angle", 5.0)->values[0], b = r.sample(k + 1, "shear_angle", 5.0)->values[0];
        worst = std::max(worst, std::abs(a + b) / peak);
      }
      std::printf("%s, ply %d: shear %.3f / %.3f deg (extrema %.3f %% apart), mirrored pairs within %.3f %% of the "
                  "peak\n",
                  job, ply, mn, mx, 100 * spread, 100 * worst);
      if (std::string(job) == "hemisphere_ud_2ply.json") {
        EXPECT_LT(spread, 0.005) << "ply " << ply;
        EXPECT_LT(worst, 0.005) << "ply " << ply;
      } else {
        EXPECT_GT(spread, 0.3) << "ply " << ply;
      }
    }
  }
}

// Same answer, bit for bit, with 1 and 2 threads over the first second of
// the stroke, and on 2 threads with every contact_schedule: the contact
// pairs on the first thread beside the element blocks, after them in their
// own loops, each ply with its own contact on its own thread (also on 3
// threads, one of them without a ply), and the trial of the three. The
// probes record the contact pressure too (summed from the tasks' arrays of
// each pair, which by_part runs on different threads).
TEST(Hemisphere, OneAndTwoThreadsIdentical) {
  json j = coarse_scene();
  j["time"]["end"] = 1.0;
  for (auto& p : j["output"]["probes"]) {
    p["interval"] = 0.1;
    p["quantities"].push_back("contact_pressure");
  }
  const JobRun a = run_json(j, 1);
  ASSERT_TRUE(a.result.ok) << a.result.error;
  ASSERT_GT(a.result.probes.size(), 80u);
  // The ring's probes are under the holder, pressed from the start (0.9 s:
  // a probe's sample between two frames, 0.75 and 1 s).
  ASSERT_GT(a.sample(2, "contact_pressure", 0.9)->values[0], 0.0);
  ASSERT_GT(a.sample(3, "contact_pressure", 0.9)->values[0], 0.0);
  const std::pair<const char*, int> cases[] = {{"beside", 2}, {"in_turn", 2}, {"by_part", 2}, {"by_part", 3}, {"auto", 2}};
  for (const auto& [way, threads] : cases) {
    j["solvers"]["mechanics"]["contact_schedule"] = way;
    const JobRun b = run_json(j, threads);
    const std::string what = std::string(way) + " on " + std::to_string(threads) + " threads";
    ASSERT_TRUE(b.result.ok) << b.result.error;
    ASSERT_EQ(a.result.probes.size(), b.result.probes.size()) << what;
    for (std::size_t i = 0; i < a.result.probes.size(); ++i)
      EXPECT_EQ(a.result.probes[i].values, b.result.probes[i].values) << what << ", sample " << i;
    EXPECT_EQ(a.result.energy.tool_forces, b.result.energy.tool_forces) << what;
    EXPECT_EQ(a.result.energy.internal, b.result.energy.internal) << what;
    EXPECT_EQ(a.result.mechanical_steps, b.result.mechanical_steps) << what;
  }
}

// The bending evaluated at most every 8th step (bending_subcycles; on this
// scene the bending's stable step allows all 8) against every step (8 is
// the jobs' own setting): the same forming within 2 % (shear extrema of
// both plies) and the same temperatures (through-thickness profiles at the
// four probes, every second), with the scene's energy balance under 2 %.
// The temperatures depend on the punch's first touch at the pole, which
// the contact samples (8 a thermal step) resolve: on this coarse mesh at
// its 1e-4 s step the pole's node bounces on the punch for some 0.04 s,
// in contact at some samples and not at others, and the bending's
// evaluations move those bounces by a few steps. One sample more in
// contact in the thermal step that ends at 0.082 s (the run with the
// held part of shell_rf_t3 0.10.0 against the one every step) is 0.6 K
// at the upper face then, 0.027 K at 1 s, 0.013 K at 2 s and 0.009 K at 5
// s. Required: within 0.05 K at 1 s (under two samples' worth) and 0.02 K
// from 2 s on. (With the contact map of each step's end only, before
// 0.32.0, the two runs saw that touch in adjacent thermal steps: 3.6 K
// apart at the upper face at 0.08 s, 0.12 K over the profile at 1 s; with
// the bending's forces as a bare impulse, before shell_rf_t3 0.10.0, the
// bounces fell at the same samples: 0.0001 K.)
TEST(Hemisphere, BendingSubcyclesKeepTheAnswer) {
  json j = coarse_scene();
  j["solvers"]["mechanics"]["bending_subcycles"] = 1;
  const JobRun a = run_json(j);
  j["solvers"]["mechanics"]["bending_subcycles"] = 8;
  const JobRun b = run_json(j);
  ASSERT_TRUE(a.result.ok) << a.result.error;
  ASSERT_TRUE(b.result.ok) << b.result.error;
  EXPECT_EQ(b.result.bending_largest, 8);
  EXPECT_LT(b.result.bending_evaluations, b.result.mechanical_steps / 7);
  const auto [shear, temp] = apart(a, b, {2.0, 3.0, 4.0, 5.0});
  const double first = apart(a, b, {1.0}).second;
  std::printf("bending every step / at most every 8th: %lld / %lld evaluations of %lld steps, shear extrema %.2e apart "
              "(relative), temperatures %.4f K apart at 1 s, %.4f K from 2 s on, energy balance %.2e / %.2e\n",
              a.result.mechanical_steps, b.result.bending_evaluations, b.result.mechanical_steps, shear, first, temp,
              a.result.energy.balance_error, b.result.energy.balance_error);
  EXPECT_LT(shear, 0.02);
  EXPECT_LT(first, 0.05);
  EXPECT_LT(temp, 0.02);
  EXPECT_LT(b.result.energy.balance_error, 0.02);
}

// The ply/ply search every k-th step (search_interval as the job sets it,
// 64; between searches each node keeps its triangle) against every step:
// the same forming within 1 % (shear extrema of both plies), 0.1 K
// (through-thickness temperatures at the four probes, every second) and
// 1e-5 m (the punch's travel is prescribed; the holder's, which follows
// the force balance, at the end), with the energy balance under 2 %. On
// this coarse scene a step is 7 times the default scene's, so the plies
// slide further between searches (up to 6.4 ms of stroke, 64 um at the
// punch's 10 mm/s, against 15 mm cells).
TEST(Hemisphere, PlyPlySearchIntervalKeepsTheAnswer) {
  json j = coarse_scene();
  json* plies = nullptr;
  for (auto& i : j["interactions"])
    if (i["between"][0] == "ply_top" && i["between"][1] == "ply_bottom") plies = &i;
  ASSERT_NE(plies, nullptr);
  const int k = plies->value("search_interval", 1);
  ASSERT_GT(k, 1) << "the job searches every step";
  const JobRun b = run_json(j);
  (*plies)["search_interval"] = 1;
  const JobRun a = run_json(j);
  ASSERT_TRUE(a.result.ok) << a.result.error;
  ASSERT_TRUE(b.result.ok) << b.result.error;
  const auto [shear, temp] = apart(a, b);
  double travel = 0;
  for (std::size_t k = 0; k < a.result.energy.tool_displacements.size(); ++k)
    travel = std::max(travel, std::abs(a.result.energy.tool_displacements[k] - b.result.energy.tool_displacements[k]));
  std::printf("ply/ply search every step / every %d: shear extrema %.2e apart (relative), temperatures %.4f K apart, "
              "tool travel %.2e m apart, energy balance %.2e / %.2e\n",
              k, shear, temp, travel, a.result.energy.balance_error, b.result.energy.balance_error);
  EXPECT_GT(shear + temp, 0.0);  // the option changed the run
  EXPECT_LT(shear, 0.01);
  EXPECT_LT(temp, 0.1);
  EXPECT_LT(travel, 1e-5);
  EXPECT_LT(b.result.energy.balance_error, 0.02);
}

// Two clocks: the thermal answer does not depend on the mass-scaling factor
// (required: temperatures within 0.5 K for mass factors 4x apart, i.e. target
// steps 2x apart).
TEST(Hemisphere, TemperaturesIndependentOfMassScaling) {
  const JobRun a = run_json(coarse_scene("hemisphere_ud_2ply.json", 1e-4));
  const JobRun b = run_json(coarse_scene("hemisphere_ud_2ply.json", 2e-4));
  ASSERT_TRUE(a.result.ok) << a.result.error;
  ASSERT_TRUE(b.result.ok) << b.result.error;
  double diff = 0;
  for (int probe = 0; probe < 4; ++probe)
    for (double t : {1.0, 2.0, 3.0, 4.0, 5.0}) {
      const auto& va = a.sample(probe, "temperature_profile", t)->values;
      const auto& vb = b.sample(probe, "temperature_profile", t)->values;
      double d = 0;
      for (std::size_t k = 0; k < va.size(); ++k) d = std::max(d, std::abs(va[k] - vb[k]));
      if (d > 0.5) std::printf("probe %d, t = %.1f s: %.3f K apart\n", probe, t, d);
      diff = std::max(diff, d);
    }
  EXPECT_LT(diff, 0.5);
  std::printf("mass scaling to 1e-4 s and 2e-4 s: %lld and %lld steps, largest temperature difference %.3f K\n",
              a.result.mechanical_steps, b.result.mechanical_steps, diff);
}

// Two clocks, in phase: a thermal step ends at the first mechanical step at
// or after each multiple of the thermal step, whatever the mechanical step
// (mass scaling to 1e-4 and 2e-4 s; a probe sampled at every thermal step
// gives the times), so the k-th step ends in [k h, k h + one mechanical
// step). (Counting mechanical steps per thermal step instead drifts: 134
// steps of 8.54e-5 s are 3.5e-5 s short of h, and the 3rd step would be off
// by more than a step.) With the explicit through-thickness scheme at its
// stable step (thermal dt set to it), no thermal step is longer than that,
// and the steps that end a mechanical step early to stay under it leave no
// short step behind them.
TEST(Hemisphere, ThermalStepsKeepTheirOwnClock) {
  auto every_thermal_step = [](json j) {
    j["time"]["end"] = 1.0;
    j["output"]["probes"] = {
        {{"name", "pole_top"}, {"part", "ply_top"}, {"at", {0, 0, 0}}, {"quantities", {"temperature_mean"}}}};
    return j;
  };
  auto times = [](const JobRun& r) {
    std::vector<double> t;
    for (const auto& s : r.result.probes) t.push_back(s.time);
    return t;
  };
  std::vector<std::size_t> counts;
  for (double target : {1e-4, 2e-4}) {
    const JobRun r = run_json(every_thermal_step(coarse_scene("hemisphere_ud_2ply.json", target)));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    const double h = r.result.thermal_dt;
    const std::vector<double> t = times(r);
    ASSERT_EQ(static_cast<long long>(t.size()), r.result.thermal_steps + 1) << "a sample at 0 and one per step";
    double late = 0;
    for (std::size_t k = 1; k < t.size() && k * h <= 1.0; ++k) {
      EXPECT_GE(t[k], k * h * (1 - 1e-9)) << "thermal step " << k << " at mass scaling to " << target << " s";
      EXPECT_LT(t[k], k * h + target) << "thermal step " << k << " at mass scaling to " << target << " s";
      late = std::max(late, t[k] - k * h);
    }
    std::printf("mass scaling to %g s: %lld thermal steps of %.6g s, each ended at most %.3g s after its multiple "
                "(mechanical step %.4g s)\n",
                target, r.result.thermal_steps, h, late, r.result.mechanical_dt);
    counts.push_back(t.size());
  }
  EXPECT_EQ(counts[0], counts[1]);

  json j = every_thermal_step(coarse_scene());
  j["solvers"]["thermal"]["through_thickness"] = "explicit";
  const auto dir = temp_dir("thermal_clock");
  ASSERT_TRUE(run_json(j, 0, dir).result.ok);
  const double stable = json::parse(std::ifstream(dir / "summary.json"))["thermal"]["stable_dt"].get<double>();
  j["solvers"]["thermal"]["dt"] = stable;
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const std::vector<double> t = times(r);
  double longest = 0;
  for (std::size_t k = 1; k < t.size(); ++k) longest = std::max(longest, t[k] - t[k - 1]);
  std::printf("explicit scheme at its stable step %.6g s: %lld thermal steps, the longest %.6g s\n", stable,
              r.result.thermal_steps, longest);
  EXPECT_LE(longest, stable * (1 + 1e-9));
  // and no short step after one ended early: one step per multiple, and the last at time.end
  EXPECT_LE(r.result.thermal_steps, static_cast<long long>(std::ceil(1.0 / stable)) + 1);
  EXPECT_GT(longest, stable - 2 * r.result.mechanical_dt);
}

// The paper's point: a plain thermal shell (one temperature through the
// thickness) misses the gradient in the lower ply under the punch. The ADI
// answer against shell2d and against the 3D reference (layered3d) at the
// lower ply's pole, end of stroke. Required: ADI within 1 K of layered3d
// (same mesh, same layers); shell2d has no through-thickness gradient.
TEST(Hemisphere, AdiAgainstShell2dAndLayered3d) {
  std::map<std::string, JobRun> runs;
  for (const char* s : {"adi", "shell2d", "layered3d"}) {
    json j = coarse_scene();
    j["solvers"]["thermal"] = {{"splitter", s}};
    if (std::string(s) == "adi") j["solvers"]["thermal"]["through_thickness"] = "implicit";
    runs[s] = run_json(j);
    ASSERT_TRUE(runs[s].result.ok) << s << ": " << runs[s].result.error;
  }
  const double t = 5.0;
  const Faces adi = faces(runs["adi"], 1, t), ref = faces(runs["layered3d"], 1, t);
  const auto& shell = runs["shell2d"].sample(1, "temperature_profile", t)->values;
  EXPECT_EQ(shell.size(), 1u);
  EXPECT_NEAR(adi.top, ref.top, 1.0);
  EXPECT_NEAR(adi.bottom, ref.bottom, 1.0);
  std::printf("lower ply at the pole, t = 5 s: adi %.3f / %.3f (mean %.3f), layered3d %.3f / %.3f (mean %.3f), "
              "shell2d %.3f degC (bottom / top faces)\n",
              adi.bottom, adi.top, adi.mean, ref.bottom, ref.top, ref.mean, shell[0]);
}

}  // namespace ts::test

namespace ts::test {

// The scene held by grippers instead of the holder ring
// (hemisphere_ud_2ply_grippers.json; mass scaling to 1e-4 s as in the other
// tests here): grippers placed symmetrically about the diagonal pull along
// the fibres ([1,-1,0]), so the shear field stays symmetric about it
// (extrema within 0.5 %, as for the holder's scene above) and the grippers
// mirrored in the diagonal pull alike (within 0.5 % of the preload). The
// blank draws in at the clamps, so each spring ends stretched, its tension
// above the preload.
TEST(Hemisphere, GrippersHoldTheStackSymmetricallyAboutTheDiagonal) {
  const std::string job = "hemisphere_ud_2ply_grippers.json";
  json j = coarse_scene(job);
  const json own = read_job_document(source_dir() / "share" / "jobs" / job);
  for (std::size_t q = 0; q < 2; ++q) j["parts"][q]["mesh"]["divisions"] = own["parts"][q]["mesh"]["divisions"];
  j["output"]["probes"] = json::array();
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  EXPECT_LT(r.result.energy.balance_error, 1e-4);
  for (int ply = 0; ply < 2; ++ply) {
    const double mn = r.result.part_shear_min_deg[ply], mx = r.result.part_shear_max_deg[ply];
    EXPECT_LT(std::abs(mx + mn) / std::max(-mn, mx), 0.005) << "ply " << ply;
    std::printf("ply %d: shear %.3f / %.3f deg\n", ply, mn, mx);
  }
  // Constraints 2-5: x_near, x_far, y_near, y_far; their reactions are
  // their forces on the plies.
  const auto& f = r.result.energy.reactions;
  ASSERT_EQ(f.size(), 18u);
  const double preload = own["constraints"][2]["preload"].get<double>();
  for (int g = 2; g < 4; ++g) {
    const double* a = &f[3 * g];
    const double* b = &f[3 * (g + 2)];  // its mirror image in the diagonal
    EXPECT_NEAR(a[0], b[1], 0.005 * preload) << "gripper " << g;
    EXPECT_NEAR(a[1], b[0], 0.005 * preload) << "gripper " << g;
    const double tension = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    EXPECT_GT(tension, preload) << "gripper " << g;
    std::printf("%s: %.4f N at the end (%.4f N mirrored)\n", own["constraints"][g]["name"].get<std::string>().c_str(),
                tension, std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]));
  }
}

}  // namespace ts::test
