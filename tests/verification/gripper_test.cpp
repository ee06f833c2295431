// Grippers: a spring from an anchor to the centre of the gripped nodes,
// whose force they share by their mass. A plate gripped whole is a mass on
// a spring (its period and, with a spring that only pulls, its coasting
// speed); a UD strip between a held end and a gripper settles where the
// spring's force equals the strip's homogeneous solution. Rigid jaws move
// the bias-extension specimen as its clamp does, and a jaw held at one
// node is held whole.
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

// A UD strip (fibres along x, L x W = 100 x 20 mm, crossed mesh 20 x 4)
// held at x = 0 (x and z; y at the corner), flat, to 0.25 s with damping
// 200 /s, a probe at the middle of its far end; callers add the gripper.
json gripped_strip() {
  const double L = 0.1, W = 0.02;
  return {{"format", "thermostamp-job/1"},
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
            {{"type", "fix"}, {"part", "strip"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"z"}}}}},
          {"solvers", {{"mechanics", {{"dt_safety", 0.8}, {"damping", 200.0}}}, {"thermal", nullptr}}},
          {"output",
           {{"interval", 0.25},
            {"fields", {"displacement"}},
            {"probes",
             {{{"name", "end"}, {"part", "strip"}, {"at", {L, W / 2, 0}}, {"quantities", {"displacement_x"}}}}}}}};
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
    json j = gripped_strip();
    j["constraints"].push_back({{"type", "gripper"},
                                {"part", "strip"},
                                {"box", {{L - 1e-6, -1, -1}, {L + 1e-6, 1, 1}}},
                                {"anchor", {L + 0.05, W / 2, 0.0}},
                                {"stiffness", kg},
                                {"preload", c.preload},
                                {"ramp", 0.05}});
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

// Rigid jaws in place of the bias-extension test's clamp: the specimen's
// pulled end gripped with `"jaws": "rigid"` by a spring of 1 N/mm whose
// anchor moves at 0.1 m/s (the end is not held in y: the jaw stays on the
// axis by the specimen's symmetry). The jaw moves as one body (its nodes'
// displacements equal to 1e-12 m), and the specimen follows the
// pin-jointed net at the jaw's displacement u as under the clamp
// (Woven.BiasExtensionFollowsThePinJointedNet): the central shear angle
// within 1 degree of the net's at u up to 30 degrees, the spring's force
// within 5 % of the net's force at the measured shear angle.
TEST(Gripper, RigidJawsPullTheBiasSpecimenAsItsClampDoes) {
  const double H = 0.230, W = 0.115, D = H - W, k = 1000.0, speed = 0.1, t_end = 0.33;
  const int nx = 44, ny = 22;
  const double a = W / ny;
  const auto dir = temp_dir("gripper_bias");
  write_yarn_lattice_gmsh(dir / "bias.msh", W, nx, ny);
  json j = bias_job({{"file", (dir / "bias.msh").string()}}, speed, t_end);
  j["constraints"][1] = {{"type", "gripper"},
                         {"name", "jaw"},
                         {"part", "specimen"},
                         {"box", {{H - 1e-6, -1, -1}, {H + 1e-6, 1, 1}}},
                         {"anchor", {H + 0.05, W / 2, 0.0}},
                         {"stiffness", k},
                         {"jaws", "rigid"},
                         {"anchor_motion", {{"velocity", {speed, 0.0, 0.0}}}}};
  j["constraints"].erase(2);  // the end's y is free
  json probes = json::array();
  probes.push_back({{"name", "centre"}, {"part", "specimen"}, {"at", {H / 2, W / 2 - a, 0}},
                    {"quantities", {"shear_angle"}}, {"interval", t_end / 10}});
  for (const double y : {0.0, W / 2 - a, W})  // nodes of the gripped end
    probes.push_back({{"name", "jaw" + std::to_string(probes.size())}, {"part", "specimen"}, {"at", {H, y, 0}},
                      {"quantities", {"displacement_x", "displacement_y"}}, {"interval", t_end / 10}});
  j["output"] = {{"interval", t_end}, {"fields", {"displacement"}}, {"probes", probes}};
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const double* k_sh = kBiasKsh;
  auto w = [&](double g) {
    const double s = std::sin(g);
    return k_sh[0] * s * s + k_sh[1] * std::pow(s, 4) + k_sh[2] * std::pow(s, 6);
  };
  auto gamma = [&](double d) { return M_PI / 2 - 2 * std::acos((D + d) / (std::sqrt(2.0) * D)); };
  auto e_of_gamma = [&](double g) { return W * (H - 1.5 * W) * w(g) + W * W * w(g / 2); };
  double worst = 0, spread = 0, uy = 0, u_end = 0;
  for (int n = 1; n <= 10; ++n) {
    const double t = n * t_end / 10;
    const double u = r.sample(2, "displacement_x", t)->values[0];
    for (int p = 1; p <= 3; ++p) {
      spread = std::max(spread, std::abs(r.sample(p, "displacement_x", t)->values[0] - u));
      spread = std::max(spread, std::abs(r.sample(p, "displacement_y", t)->values[0] -
                                         r.sample(2, "displacement_y", t)->values[0]));
      uy = std::max(uy, std::abs(r.sample(p, "displacement_y", t)->values[0]));
    }
    const double g_fe = std::abs(r.sample(0, "shear_angle", t)->values[0]);
    worst = std::max(worst, std::abs(g_fe - gamma(u) * 180 / M_PI));
    u_end = u;
  }
  EXPECT_LT(spread, 1e-12);
  EXPECT_GT(gamma(u_end) * 180 / M_PI, 30.0);  // the jaw has gone far enough
  EXPECT_LT(worst, 1.0);
  const double g_fe = std::abs(r.sample(0, "shear_angle", t_end)->values[0]) * M_PI / 180;
  const double dgdd = (gamma(u_end + 1e-6) - gamma(u_end - 1e-6)) / 2e-6;
  const double F_net = (e_of_gamma(g_fe + 1e-7) - e_of_gamma(g_fe - 1e-7)) / 2e-7 * dgdd;
  const double F_fe = r.result.energy.reactions[3 * 1 + 0];
  EXPECT_NEAR(F_fe / F_net, 1.0, 0.05) << F_fe << " N vs " << F_net << " N";
  EXPECT_LT(r.result.energy.balance_error, 1e-3);
  std::printf("rigid jaw at u = %.2f mm: worst shear-angle error %.3f deg; spring force %.4g N, pin-jointed net %.4g "
              "N at the measured shear angle; jaw nodes apart by %.2g m, off the axis by %.2g m; balance %.2e\n",
              u_end * 1e3, worst, F_fe, F_net, spread, uy, r.result.energy.balance_error);
}

// A rigid jaw with a node held in y (a `fix` at its corner) is held in y
// whole: the UD strip of the test above, gripped over its end column and
// pulled by a spring whose anchor lies off the axis (20 mm aside, 50 mm
// ahead), stays in its homogeneous state. Its end moves along x only, to
// where the spring's x component T (0.05 - u) / d equals the strip's
// force N(u), T = P + k_g (d - d0); the spring's y component goes into the
// corner's support (its reaction), and every force on the strip sums to
// zero. Required as in the test above: 1e-6 (damped transient); the jaw's
// nodes stay at y to 1e-12 m. With flexible jaws the end column would be
// pulled aside and the strip sheared.
TEST(Gripper, RigidJawHeldAtOneNodeIsHeldWhole) {
  const double L = 0.1, W = 0.02, k = 5.0e4, kg = 1.0e4, P = 100.0, ahead = 0.05, aside = 0.02;
  json j = gripped_strip();
  j["constraints"].push_back({{"type", "fix"},
                              {"part", "strip"},
                              {"box", {{L - 1e-6, -1e-6, -1}, {L + 1e-6, 1e-6, 1}}},
                              {"dofs", {"y"}}});
  j["constraints"].push_back({{"type", "gripper"},
                              {"part", "strip"},
                              {"box", {{L - 1e-6, -1, -1}, {L + 1e-6, 1, 1}}},
                              {"anchor", {L + ahead, W / 2 + aside, 0.0}},
                              {"stiffness", kg},
                              {"preload", P},
                              {"ramp", 0.05},
                              {"jaws", "rigid"}});
  j["output"]["probes"][0]["quantities"].push_back("displacement_y");
  j["output"]["probes"].push_back(
      {{"name", "edge"}, {"part", "strip"}, {"at", {L, W, 0}}, {"quantities", {"displacement_y"}}});
  j["output"]["probes"].push_back(
      {{"name", "middle"}, {"part", "strip"}, {"at", {L / 2, W, 0}}, {"quantities", {"displacement_y"}}});
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const double d0 = std::hypot(ahead, aside);
  auto strip_force = [&](double u) { return 2 * k * W * std::log(1 + u / L) / (1 + u / L); };
  auto tension = [&](double u) { return P + kg * (std::hypot(ahead - u, aside) - d0); };
  auto pull_x = [&](double u) { return tension(u) * (ahead - u) / std::hypot(ahead - u, aside); };
  double lo = 0, hi = 0.04;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (strip_force(mid) < pull_x(mid) ? lo : hi) = mid;
  }
  const double u = 0.5 * (lo + hi), N = strip_force(u), Fy = tension(u) * aside / std::hypot(ahead - u, aside);
  const auto& R = r.result.energy.reactions;
  ASSERT_EQ(R.size(), 15u);
  const double ux = r.sample(0, "displacement_x", 0.25)->values[0];
  double uy = 0;
  for (const ProbeSample& s : r.result.probes)
    if (s.quantity == "displacement_y") uy = std::max(uy, std::abs(s.values[0]));
  EXPECT_NEAR(ux / u, 1.0, 1e-6);
  EXPECT_LT(uy, 1e-12);
  EXPECT_NEAR(R[12] / N, 1.0, 1e-6);   // the spring's x force on the strip
  EXPECT_NEAR(R[13] / Fy, 1.0, 1e-6);  // and its y force
  EXPECT_NEAR(R[10] / -Fy, 1.0, 1e-6);  // the corner's support takes it
  double sum_x = 0, sum_y = 0;
  for (std::size_t c = 0; c < 5; ++c) {
    sum_x += R[3 * c];
    sum_y += R[3 * c + 1];
  }
  EXPECT_LT(std::abs(sum_x), 1e-6 * N);
  EXPECT_LT(std::abs(sum_y), 1e-6 * N);
  EXPECT_LT(r.result.energy.balance_error, 1e-6);
  std::printf("jaw held in y: u %.6g m (%.1e from exact), spring %.6g / %.6g N (x / y), corner %.6g N, off y by "
              "%.1g m, forces sum to %.1g / %.1g N, balance %.2e\n",
              ux, ux / u - 1, R[12], R[13], R[10], uy, sum_x, sum_y, r.result.energy.balance_error);
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
  bad = good;
  bad["constraints"][0]["jaws"] = "stiff";
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/jaws:", 0), 0u) << error_of(bad);
  // Rigid jaws: driven nodes, a node held by two.
  json rigid = good;
  rigid["constraints"][0]["jaws"] = "rigid";
  EXPECT_EQ(error_of(rigid), "");
  bad = rigid;
  bad["constraints"].push_back({{"type", "velocity"}, {"part", "plate"}, {"box", {{-1, -1, -1}, {1, 1e-6, 1}}},
                                {"velocity", {0.0, 0.1, 0.0}}, {"dofs", {"y"}}});
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/box: rigid jaws: the box holds node ", 0), 0u) << error_of(bad);
  EXPECT_NE(error_of(bad).find("which /constraints/1 drives"), std::string::npos) << error_of(bad);
  bad = rigid;
  bad["constraints"][0]["box"] = {{-1, -1, -1}, {0.011, 1, 1}};
  bad["constraints"].push_back(bad["constraints"][0]);
  bad["constraints"][1]["name"] = "other";
  bad["constraints"][1]["box"] = {{0.009, -1, -1}, {1, 1, 1}};
  EXPECT_EQ(error_of(bad).rfind("/constraints/1/box: rigid jaws: the box shares node ", 0), 0u) << error_of(bad);
  EXPECT_NE(error_of(bad).find("with gripper 'spring'"), std::string::npos) << error_of(bad);
  bad["constraints"][1]["jaws"] = "flexible";  // a flexible one may pull on a rigid jaw
  EXPECT_EQ(error_of(bad), "");
}

}  // namespace ts::test
