// Grippers: a spring from an anchor to the centre of the gripped nodes,
// whose force they share by their mass. A plate gripped whole is a mass on
// a spring (its period and, with a spring that only pulls, its coasting
// speed); a UD strip between a held end and a gripper settles where the
// spring's force equals the strip's homogeneous solution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "job/errors.hpp"
#include "job/job.hpp"
#include "plugins/registry.hpp"
#include "solve/simulation.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

constexpr double kRhoH = 1294.0 * 0.0005;  // kg/m^2

json ud_material() {
  return {{"density", 1294.0},
          {"membrane", {{"law", "ud_hyperelastic"}, {"k_fibre", 5.0e4}, {"p_ct", 5.0e3}, {"k_sh", {2.0e3, 0.0, 0.0}}}}};
}

// A square plate of side a at the origin, every node gripped by one spring
// along x from (a/2 + d, a/2, 0).
json plate_on_a_spring(double a, double d, double k, double preload, bool tension_only, double t_end) {
  return {{"format", "thermostamp-job/1"},
          {"name", "gripped_plate"},
          {"time", {{"end", t_end}}},
          {"materials", {{"ud", ud_material()}}},
          {"parts",
           {{{"name", "plate"},
             {"mesh", {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {a, a}}, {"divisions", {4, 4}}}},
             {"thickness", 0.0005},
             {"material", "ud"},
             {"initial_temperature", 280.0}}}},
          {"constraints",
           {{{"type", "gripper"},
             {"name", "spring"},
             {"part", "plate"},
             {"box", {{-1, -1, -1}, {1, 1, 1}}},
             {"anchor", {a / 2 + d, a / 2, 0.0}},
             {"stiffness", k},
             {"preload", preload},
             {"tension_only", tension_only}}}},
          {"solvers", {{"mechanics", {{"dt_safety", 0.8}}}, {"thermal", nullptr}}},
          {"output",
           {{"interval", t_end},
            {"fields", {"displacement"}},
            {"probes",
             {{{"name", "centre"},
               {"part", "plate"},
               {"at", {a / 2, a / 2, 0}},
               {"quantities", {"displacement_x", "displacement_y"}},
               {"interval", t_end / 200}}}}}}};
}

}  // namespace

// The whole plate moves as one mass M on the spring: started at rest with
// the preload P, it oscillates about u = P / k as u(t) = (P / k)(1 - cos wt),
// w = sqrt(k / M). Central differences run slow by (w dt)^2 / 24 of the
// phase (here w dt = 4.5e-3: 8e-7 of the phase, under 2e-5 of the amplitude
// after three periods); 1e-4 of the amplitude is required. The plate stays
// stress free (it only translates) and the spring's work balances the
// kinetic energy.
TEST(Gripper, PlateOnASpringOscillatesAtItsFrequency) {
  const double a = 0.02, k = 100.0, P = 1.0, M = kRhoH * a * a, w = std::sqrt(k / M);
  const double period = 2 * M_PI / w, t_end = 3 * period;
  const JobRun r = run_json(plate_on_a_spring(a, 0.1, k, P, false, t_end));
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const double amplitude = P / k;
  double err = 0, uy = 0;
  int n = 0;
  for (const ProbeSample& s : r.result.probes) {
    if (s.quantity == "displacement_x") {
      err = std::max(err, std::abs(s.values[0] - amplitude * (1 - std::cos(w * s.time))));
      ++n;
    } else {
      uy = std::max(uy, std::abs(s.values[0]));
    }
  }
  EXPECT_GT(n, 150);
  EXPECT_LT(err, 1e-4 * amplitude);
  EXPECT_LT(uy, 1e-12);
  EXPECT_LT(std::abs(r.result.energy.internal), 1e-12 * r.result.energy.external);
  EXPECT_LT(r.result.energy.balance_error, 1e-4);
  // The spring's force at the end (the constraint's reaction) is its
  // tension P - k u along +x.
  ASSERT_EQ(r.result.energy.reactions.size(), 3u);
  const double u_end = amplitude * (1 - std::cos(w * r.result.simulated_time_s));
  EXPECT_NEAR(r.result.energy.reactions[0], P - k * u_end, 1e-4 * P);
  ASSERT_EQ(r.result.energy.gripper_force_max.size(), 1u);
  EXPECT_NEAR(r.result.energy.gripper_force_max[0], P, 1e-3 * P);  // at t = 0 and every period
  std::printf("period %.4g s, %lld steps: largest error %.3g m (%.2e of the amplitude), balance %.2e\n", period,
              r.result.mechanical_steps, err, err / amplitude, r.result.energy.balance_error);
}

// A spring that only pulls lets go at its free length: the plate, pulled
// from rest by P, reaches u = P / k at a quarter period with the speed
// w P / k and coasts on at that speed.
TEST(Gripper, SpringThatOnlyPullsLetsGoAtItsFreeLength) {
  const double a = 0.02, k = 100.0, P = 1.0, M = kRhoH * a * a, w = std::sqrt(k / M);
  const double quarter = 0.5 * M_PI / w, t_end = 3 * quarter;
  const JobRun r = run_json(plate_on_a_spring(a, 0.1, k, P, true, t_end));
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const double amplitude = P / k, speed = w * amplitude;
  double err = 0;
  for (const ProbeSample& s : r.result.probes) {
    if (s.quantity != "displacement_x") continue;
    const double exact =
        s.time <= quarter ? amplitude * (1 - std::cos(w * s.time)) : amplitude + speed * (s.time - quarter);
    err = std::max(err, std::abs(s.values[0] - exact));
  }
  // Beyond the phase error above, the step in which the spring goes slack
  // pulls for part of it too long or too short: a speed error of at most
  // (w dt)^2 / 2 of w P / k, under 1e-5 of the amplitude per quarter period.
  EXPECT_LT(err, 1e-4 * amplitude);
  EXPECT_NEAR(r.result.energy.reactions[0], 0.0, 1e-15);  // slack at the end
  EXPECT_NEAR(r.result.energy.kinetic, 0.5 * M * speed * speed, 1e-3 * 0.5 * M * speed * speed);
  EXPECT_LT(r.result.energy.balance_error, 1e-4);
  std::printf("coasting at %.5g m/s (w P / k = %.5g m/s): largest error %.3g m (%.2e of P / k)\n",
              std::sqrt(2 * r.result.energy.kinetic / M), speed, err, err / amplitude);
}

// A clamp that opens (`release`) at an eighth of the period lets the plate
// coast at the speed it had: the last force acts at the step before the
// release, so the plate keeps the half-step velocity after it, w (P / k)
// sin(w t) at a time within a step of the release (steps of at most 1e-5 s
// here). After it the plate moves at one speed (its positions on a line to
// round-off) within the speeds a step before and after the release, and
// the gripper's force is zero.
TEST(Gripper, ReleasedClampLetsThePlateCoast) {
  const double a = 0.02, k = 100.0, P = 1.0, M = kRhoH * a * a, w = std::sqrt(k / M);
  const double release = 0.25 * M_PI / w, t_end = 4 * release;
  json j = plate_on_a_spring(a, 0.1, k, P, false, t_end);
  j["constraints"][0]["release"] = release;
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  std::vector<std::pair<double, double>> after;  // (t, u) once the plate coasts
  for (const ProbeSample& s : r.result.probes)
    if (s.quantity == "displacement_x" && s.time > release + 1e-5) after.emplace_back(s.time, s.values[0]);
  ASSERT_GT(after.size(), 100u);
  const double speed = (after.back().second - after.front().second) / (after.back().first - after.front().first);
  double off_line = 0;
  for (const auto& [t, u] : after)
    off_line = std::max(off_line, std::abs(u - after.front().second - speed * (t - after.front().first)));
  const double amplitude = P / k;
  EXPECT_LT(off_line, 1e-9 * amplitude);
  EXPECT_GE(speed, w * amplitude * std::sin(w * (release - 1e-5)));
  EXPECT_LE(speed, w * amplitude * std::sin(w * (release + 1e-5)));
  EXPECT_EQ(r.result.energy.reactions[0], 0.0);
  std::printf("coasting at %.6g m/s after the release (%.6g to %.6g m/s within a step of it), off a line by %.2g m\n",
              speed, w * amplitude * std::sin(w * (release - 1e-5)), w * amplitude * std::sin(w * (release + 1e-5)),
              off_line);
}

// A UD strip (fibres along x, L x W) held at x = 0 and gripped at x = L by
// a spring of stiffness k_g from an anchor on its axis. Pulled by the
// preload P, or by the anchor moved away by D with no preload, it settles
// where the spring's tension P + k_g (D - u) equals the strip's homogeneous
// force N(lambda) = 2 k W ln(lambda) / lambda, lambda = 1 + u / L. On the
// crossed mesh the gripped end column's nodes take the force as a uniform
// traction would (their masses go as their lengths of edge), so the strip
// is in the homogeneous state. The damping (200 /s, a decay time of 10 ms)
// leaves e^-20 (2e-9) of the transient after the load's ramp; 1e-6 is
// required of the tension, of the held end's reaction and of u (4e-12
// found).
TEST(Gripper, StripBetweenAHeldEndAndASpringSettlesAtTheHomogeneousSolution) {
  const double L = 0.1, W = 0.02, k = 5.0e4, kg = 1.0e4;
  struct Case {
    double preload, moved;
  };
  for (const Case& c : {Case{100.0, 0.0}, Case{0.0, 0.01}}) {
    json j = {{"format", "thermostamp-job/1"},
              {"name", "gripped_strip"},
              {"time", {{"end", 0.25}}},
              {"materials", {{"ud", ud_material()}}},
              {"parts",
               {{{"name", "strip"},
                 {"mesh", {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {L, W}}, {"divisions", {20, 4}},
                             {"pattern", "crossed"}}},
                 {"thickness", 0.0005},
                 {"material", "ud"},
                 {"fibre_direction", {1.0, 0.0, 0.0}},
                 {"initial_temperature", 280.0}}}},
              {"constraints",
               {{{"type", "fix"}, {"part", "strip"}, {"box", {{-1e-6, -1, -1}, {1e-6, 1, 1}}}, {"dofs", {"x", "z"}}},
                {{"type", "fix"}, {"part", "strip"}, {"box", {{-1e-6, -1e-6, -1}, {1e-6, 1e-6, 1}}}, {"dofs", {"y"}}},
                {{"type", "fix"}, {"part", "strip"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"z"}}},
                {{"type", "gripper"},
                 {"part", "strip"},
                 {"box", {{L - 1e-6, -1, -1}, {L + 1e-6, 1, 1}}},
                 {"anchor", {L + 0.05, W / 2, 0.0}},
                 {"stiffness", kg},
                 {"preload", c.preload},
                 {"ramp", 0.05}}}},
              {"solvers", {{"mechanics", {{"dt_safety", 0.8}, {"damping", 200.0}}}, {"thermal", nullptr}}},
              {"output",
               {{"interval", 0.25},
                {"fields", {"displacement"}},
                {"probes",
                 {{{"name", "end"}, {"part", "strip"}, {"at", {L, W / 2, 0}}, {"quantities", {"displacement_x"}}}}}}}};
    if (c.moved > 0)
      j["constraints"][3]["anchor_motion"] = {
          {"displacement", {{0.0, 0.0, 0.0, 0.0}, {0.05, c.moved, 0.0, 0.0}, {1.0, c.moved, 0.0, 0.0}}}};
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    // The equilibrium by bisection: the spring's tension falls and the
    // strip's force rises with u.
    auto strip_force = [&](double u) { return 2 * k * W * std::log(1 + u / L) / (1 + u / L); };
    auto spring = [&](double u) { return c.preload + kg * (c.moved - u); };
    double lo = 0, hi = 0.05;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (strip_force(mid) < spring(mid) ? lo : hi) = mid;
    }
    const double u = 0.5 * (lo + hi), F = strip_force(u);
    const ProbeSample* s = r.sample(0, "displacement_x", 0.25);
    ASSERT_NE(s, nullptr);
    ASSERT_EQ(r.result.energy.reactions.size(), 12u);
    const double tension = r.result.energy.reactions[9], held = -r.result.energy.reactions[0];
    EXPECT_NEAR(s->values[0] / u, 1.0, 1e-6);
    EXPECT_NEAR(tension / F, 1.0, 1e-6);
    EXPECT_NEAR(held / F, 1.0, 1e-6);
    EXPECT_NEAR(r.result.energy.reactions[10], 0.0, 1e-9 * F);  // the anchor on the strip's axis
    EXPECT_LT(r.result.energy.balance_error, 1e-6);
    std::printf("preload %g N, anchor moved %g m: u %.6g m (%.1e from exact), tension %.6g N (%.1e), held end "
                "%.6g N (%.1e), balance %.2e\n",
                c.preload, c.moved, s->values[0], s->values[0] / u - 1, tension, tension / F - 1, held, held / F - 1,
                r.result.energy.balance_error);
  }
}

// Input that cannot make a gripper is refused before the run, naming the key.
TEST(Gripper, BadInputNamesTheKey) {
  auto error_of = [](const json& j) -> std::string {
    try {
      const Job job = parse_job(j, source_dir() / "tests" / "inline.json");
      PluginRegistry registry;
      Simulation sim(job, registry);
    } catch (const JobError& e) {
      return e.what();
    }
    return "";
  };
  const json good = plate_on_a_spring(0.02, 0.1, 100.0, 1.0, true, 0.01);
  EXPECT_EQ(error_of(good), "");
  json bad = good;
  bad["constraints"][0]["stiffness"] = 0.0;
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/stiffness: must be > 0", 0), 0u) << error_of(bad);
  bad = good;
  bad["constraints"][0]["preload"] = -1.0;
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/preload:", 0), 0u) << error_of(bad);
  bad = good;
  bad["constraints"][0].erase("anchor");
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/anchor:", 0), 0u) << error_of(bad);
  bad = good;
  bad["constraints"][0]["anchor"] = {0.01, 0.01, 0.0};  // the gripped nodes' centre
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/anchor: lies at the centre of the gripped nodes", 0), 0u)
      << error_of(bad);
  bad = good;
  bad["constraints"][0]["box"] = {{1, 1, 1}, {2, 2, 2}};
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/box: no node of the part(s) lies inside the box", 0), 0u)
      << error_of(bad);
  bad = good;
  bad["constraints"][0]["anchor_motion"] = {{"velocity", {0, 0, 1}}, {"displacement", {{0, 0, 0, 0}}}};
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/anchor_motion: give exactly one of", 0), 0u) << error_of(bad);
  bad = good;
  bad["constraints"][0]["anchor_motion"] = {{"displacement", {{0, 0, 0, 0}, {0, 1, 0, 0}}}};
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/anchor_motion/displacement/1: times must increase", 0), 0u)
      << error_of(bad);
  bad = good;
  bad["constraints"].push_back(good["constraints"][0]);
  EXPECT_EQ(error_of(bad).rfind("/constraints/1/name: a gripper named 'spring' is already defined at /constraints/0",
                                0),
            0u)
      << error_of(bad);
  bad = good;
  bad["constraints"][0]["release"] = 0.0;
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/release: must be > 0", 0), 0u) << error_of(bad);
  bad = good;
  bad["constraints"][0]["tension_only"] = "yes";
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/tension_only:", 0), 0u) << error_of(bad);
}

}  // namespace ts::test
