// Grippers: a spring from an anchor to the centre of the gripped nodes,
// whose force they share by their mass. A plate gripped whole is a mass on
// a spring (its period and, with a spring that only pulls, its coasting
// speed); a UD strip between a held end and a gripper settles where the
// spring's force equals the strip's homogeneous solution. Rigid jaws move
// the bias-extension specimen as its clamp does, and a jaw held at one
// node is held whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <utility>
#include <vector>

#include "job/errors.hpp"
#include "job/job.hpp"
#include "mesh/shell_mesh.hpp"
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

// Swivelling jaws. A UD plate of a x b at the origin (crossed cells of
// 5 mm), every node gripped by swivelling jaws whose own spring is idle
// (1e-9 N/m), and turned by a second, flexible gripper at one node: a
// constant pull P from an anchor 100 m away. The reference is the rigid
// body of the mesh's lumped masses (a third of each triangle's area at
// each corner), integrated by RK4.
struct SwivelPlate {
  double a, b;
  json job;
  std::vector<double> mass;  // kg per node
  std::vector<double> x0;    // m, 3 per node
};

SwivelPlate swivel_plate(double a, double b, const std::array<double, 3>& corner, const std::array<double, 3>& pull,
                         double P, double t_end) {
  const std::array<int, 2> div{static_cast<int>(std::lround(a / 0.005)), static_cast<int>(std::lround(b / 0.005))};
  SwivelPlate s{a, b, {}, {}, {}};
  const ShellMesh mesh = rectangle_mesh({0, 0, 0}, {a, b}, div, true);
  s.x0 = mesh.x;
  s.mass.assign(mesh.num_nodes(), 0.0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int* n = &mesh.triangles[3 * e];
    const double ux = mesh.x[3 * n[1]] - mesh.x[3 * n[0]], uy = mesh.x[3 * n[1] + 1] - mesh.x[3 * n[0] + 1];
    const double vx = mesh.x[3 * n[2]] - mesh.x[3 * n[0]], vy = mesh.x[3 * n[2] + 1] - mesh.x[3 * n[0] + 1];
    for (int k = 0; k < 3; ++k) s.mass[n[k]] += kRhoH * 0.5 * std::abs(ux * vy - uy * vx) / 3;
  }
  const double D = 100.0;
  s.job = {{"format", "thermostamp-job/1"},
           {"name", "swivelling_plate"},
           {"time", {{"end", t_end}}},
           {"materials", {{"ud", ud_material()}}},
           {"parts",
            {{{"name", "plate"},
              {"mesh", {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {a, b}}, {"divisions", div},
                        {"pattern", "crossed"}}},
              {"thickness", 0.0005},
              {"material", "ud"},
              {"initial_temperature", 280.0}}}},
           {"constraints",
            {{{"type", "gripper"},
              {"name", "jaws"},
              {"part", "plate"},
              {"box", {{-1, -1, -1}, {1, 1, 1}}},
              {"anchor", {a / 2, b / 2 + 1.0, 0.0}},
              {"stiffness", 1e-9},
              {"jaws", "swivelling"}},
             {{"type", "gripper"},
              {"name", "pull"},
              {"part", "plate"},
              {"box", {{corner[0] - 1e-6, corner[1] - 1e-6, -1}, {corner[0] + 1e-6, corner[1] + 1e-6, 1}}},
              {"anchor", {corner[0] + D * pull[0], corner[1] + D * pull[1], corner[2] + D * pull[2]}},
              {"stiffness", 1e-9},
              {"preload", P}}}},
           {"solvers", {{"mechanics", {{"dt_safety", 0.8}}}, {"thermal", nullptr}}},
           {"output", {{"interval", t_end}, {"fields", {"displacement"}}, {"probes", json::array()}}}};
  const double at[4][2] = {{0, 0}, {a, 0}, {a, b}, {0, b}};
  for (int c = 0; c < 4; ++c)
    s.job["output"]["probes"].push_back({{"name", "corner" + std::to_string(c)},
                                         {"part", "plate"},
                                         {"at", {at[c][0], at[c][1], 0.0}},
                                         {"quantities", {"displacement_x", "displacement_y", "displacement_z"}},
                                         {"interval", t_end / 50}});
  return s;
}

// A probe's position at a sample (its initial place plus its displacement).
std::array<double, 3> probe_position(const JobRun& r, int probe, const double* at, double t) {
  std::array<double, 3> x{at[0], at[1], 0.0};
  const char* q[3] = {"displacement_x", "displacement_y", "displacement_z"};
  for (int d = 0; d < 3; ++d) x[d] += r.sample(probe, q[d], t)->values[0];
  return x;
}

// RK4 of a rigid body turning about a fixed axis e (through the point c(t)
// that moves with acceleration f / M, or held at c0 when M is infinite),
// pulled at the point c + R(theta) r0 by P towards the anchor A. Returns
// theta and the moving point's displacement at each time of `times`.
struct AxisState {
  double theta, omega, u[3];
};
std::vector<AxisState> rigid_body_reference(const std::array<double, 3>& e, const std::array<double, 3>& c0,
                                            const std::array<double, 3>& r0, const std::array<double, 3>& A,
                                            double P, double M, double I, const std::vector<double>& times) {
  auto rotate = [&](double th) {  // R(th) r0 about e (Rodrigues)
    const double c = std::cos(th), s = std::sin(th), er = e[0] * r0[0] + e[1] * r0[1] + e[2] * r0[2];
    const double ex[3] = {e[1] * r0[2] - e[2] * r0[1], e[2] * r0[0] - e[0] * r0[2], e[0] * r0[1] - e[1] * r0[0]};
    std::array<double, 3> out;
    for (int d = 0; d < 3; ++d) out[d] = r0[d] * c + ex[d] * s + e[d] * er * (1 - c);
    return out;
  };
  // y = (theta, omega, u[3], v[3])
  auto rate = [&](const std::array<double, 8>& y) {
    const std::array<double, 3> r = rotate(y[0]);
    double f[3], n = 0;
    for (int d = 0; d < 3; ++d) {
      f[d] = A[d] - (c0[d] + y[2 + d] + r[d]);
      n += f[d] * f[d];
    }
    n = std::sqrt(n);
    for (double& v : f) v *= P / n;
    const double tau = e[0] * (r[1] * f[2] - r[2] * f[1]) + e[1] * (r[2] * f[0] - r[0] * f[2]) +
                       e[2] * (r[0] * f[1] - r[1] * f[0]);
    std::array<double, 8> dy{y[1], tau / I, y[5], y[6], y[7], 0, 0, 0};
    if (std::isfinite(M))
      for (int d = 0; d < 3; ++d) dy[5 + d] = f[d] / M;
    return dy;
  };
  std::vector<AxisState> out;
  std::array<double, 8> y{};
  double t = 0;
  const double h = 1e-7;
  for (const double T : times) {
    while (t < T - 1e-15) {
      const double dt = std::min(h, T - t);
      auto add = [&](const std::array<double, 8>& k, double f) {
        std::array<double, 8> z = y;
        for (int i = 0; i < 8; ++i) z[i] += f * k[i];
        return z;
      };
      const auto k1 = rate(y), k2 = rate(add(k1, dt / 2)), k3 = rate(add(k2, dt / 2)), k4 = rate(add(k3, dt));
      for (int i = 0; i < 8; ++i) y[i] += dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
      t += dt;
    }
    out.push_back({y[0], y[1], {y[2], y[3], y[4]}});
  }
  return out;
}

// RK4 of a free rigid body in space (Newton-Euler: c'' = f / M, L' = r x f,
// R' = [w] R, w = R I^-1 R^T L), pulled at c + R r0 by P towards A; I the
// inertia tensor about the centre at t = 0. Returns R at each time of
// `times` (row-major) and c.
struct BodyState {
  std::array<double, 9> R;
  std::array<double, 3> c;
};
std::vector<BodyState> free_body_reference(const std::array<double, 3>& c0, const std::array<double, 3>& r0,
                                           const std::array<double, 3>& A, double P, double M,
                                           const std::array<double, 9>& I, const std::vector<double>& times) {
  // The inverse of I (symmetric 3 x 3) by cofactors.
  std::array<double, 9> Ii;
  const double det = I[0] * (I[4] * I[8] - I[5] * I[7]) - I[1] * (I[3] * I[8] - I[5] * I[6]) +
                     I[2] * (I[3] * I[7] - I[4] * I[6]);
  Ii = {(I[4] * I[8] - I[5] * I[7]) / det, (I[2] * I[7] - I[1] * I[8]) / det, (I[1] * I[5] - I[2] * I[4]) / det,
        (I[5] * I[6] - I[3] * I[8]) / det, (I[0] * I[8] - I[2] * I[6]) / det, (I[2] * I[3] - I[0] * I[5]) / det,
        (I[3] * I[7] - I[4] * I[6]) / det, (I[1] * I[6] - I[0] * I[7]) / det, (I[0] * I[4] - I[1] * I[3]) / det};
  using S = std::array<double, 18>;  // c (3), v (3), R (9), L (3)
  auto rate = [&](const S& y) {
    S dy{};
    const double* R = &y[6];
    double r[3], f[3], n = 0;
    for (int i = 0; i < 3; ++i) r[i] = R[3 * i] * r0[0] + R[3 * i + 1] * r0[1] + R[3 * i + 2] * r0[2];
    for (int d = 0; d < 3; ++d) {
      f[d] = A[d] - (y[d] + r[d]);
      n += f[d] * f[d];
    }
    n = std::sqrt(n);
    for (double& v : f) v *= P / n;
    // w = R I^-1 R^T L
    double b[3], ib[3], w[3];
    for (int i = 0; i < 3; ++i) b[i] = R[i] * y[15] + R[3 + i] * y[16] + R[6 + i] * y[17];
    for (int i = 0; i < 3; ++i) ib[i] = Ii[3 * i] * b[0] + Ii[3 * i + 1] * b[1] + Ii[3 * i + 2] * b[2];
    for (int i = 0; i < 3; ++i) w[i] = R[3 * i] * ib[0] + R[3 * i + 1] * ib[1] + R[3 * i + 2] * ib[2];
    for (int d = 0; d < 3; ++d) {
      dy[d] = y[3 + d];
      dy[3 + d] = f[d] / M;
    }
    for (int j = 0; j < 3; ++j) {  // column j of R' = w x (column j of R)
      const double col[3] = {R[j], R[3 + j], R[6 + j]};
      dy[6 + j] = w[1] * col[2] - w[2] * col[1];
      dy[9 + j] = w[2] * col[0] - w[0] * col[2];
      dy[12 + j] = w[0] * col[1] - w[1] * col[0];
    }
    dy[15] = r[1] * f[2] - r[2] * f[1];
    dy[16] = r[2] * f[0] - r[0] * f[2];
    dy[17] = r[0] * f[1] - r[1] * f[0];
    return dy;
  };
  S y{};
  for (int d = 0; d < 3; ++d) y[d] = c0[d];
  y[6] = y[10] = y[14] = 1.0;
  std::vector<BodyState> out;
  double t = 0;
  for (const double T : times) {
    while (t < T - 1e-15) {
      const double h = std::min(1e-7, T - t);
      auto add = [&](const S& k, double f) {
        S z = y;
        for (int i = 0; i < 18; ++i) z[i] += f * k[i];
        return z;
      };
      const S k1 = rate(y), k2 = rate(add(k1, h / 2)), k3 = rate(add(k2, h / 2)), k4 = rate(add(k3, h));
      for (int i = 0; i < 18; ++i) y[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
      t += h;
    }
    BodyState b;
    for (int i = 0; i < 9; ++i) b.R[i] = y[6 + i];
    for (int d = 0; d < 3; ++d) b.c[d] = y[d];
    out.push_back(b);
  }
  return out;
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

namespace {
// Each sample time of a probe's quantity.
std::vector<double> sample_times(const JobRun& r) {
  std::vector<double> t;
  for (const ProbeSample& s : r.result.probes)
    if (s.probe == 0 && s.quantity == "displacement_x") t.push_back(s.time);
  return t;
}

// The angle from the plate's diagonal at t = 0 to the line of two of its
// corners at t, about e; and the largest change of the six distances
// between the four corners.
struct PlateTurn {
  double angle, stretch;
};
PlateTurn plate_turn(const JobRun& r, const SwivelPlate& s, const std::array<double, 3>& e, double t) {
  const double at[4][2] = {{0, 0}, {s.a, 0}, {s.a, s.b}, {0, s.b}};
  std::array<std::array<double, 3>, 4> x;
  for (int c = 0; c < 4; ++c) x[c] = probe_position(r, c, at[c], t);
  PlateTurn out{0, 0};
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const double d0 = std::hypot(at[j][0] - at[i][0], at[j][1] - at[i][1]);
      const double d = std::hypot(x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]);
      out.stretch = std::max(out.stretch, std::abs(d - d0));
    }
  // The turn of the edge from corner 0 to corner 1 (along x at t = 0), seen along e.
  const double u[3] = {x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]};
  const double w0[3] = {s.a, 0, 0};
  const double cr[3] = {w0[1] * u[2] - w0[2] * u[1], w0[2] * u[0] - w0[0] * u[2], w0[0] * u[1] - w0[1] * u[0]};
  out.angle = std::atan2(e[0] * cr[0] + e[1] * cr[1] + e[2] * cr[2], w0[0] * u[0] + w0[1] * u[1] + w0[2] * u[2]);
  return out;
}
}  // namespace

// Swivelling jaws over a whole plate make it a rigid body: pulled at a
// corner, it translates and turns as the rigid body of its lumped masses
// does (RK4 of the three equations of planar rigid motion, 1e-7 s steps).
// Central differences follow that motion to O(dt^2): at steps of about
// 2e-6 s over a turn of 1.4 rad, a phase error of (w dt)^2 / 24 per unit
// angle is under 1e-9 rad; 1e-6 rad of turn and 1e-6 of the centre's path
// are required. The plate stays rigid to 1e-12 m (the tie moves the nodes
// by exact rotations) and stress free; the energy balances to 1e-6. With
// rigid jaws the plate does not turn at all (checked too).
TEST(Gripper, SwivellingJawsTurnAPlateAsTheRigidBodyOfItsMasses) {
  const double a = 0.02, P = 0.01, t_end = 0.025;
  const SwivelPlate s = swivel_plate(a, a, {a, 0, 0}, {1, 0, 0}, P, t_end);
  double M = 0, I = 0;
  for (std::size_t n = 0; n < s.mass.size(); ++n) {
    M += s.mass[n];
    I += s.mass[n] * (std::pow(s.x0[3 * n] - a / 2, 2) + std::pow(s.x0[3 * n + 1] - a / 2, 2));
  }
  const auto out = temp_dir("swivelling_plate");
  const JobRun r = run_json(s.job, 0, out);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const std::vector<double> times = sample_times(r);
  ASSERT_GE(times.size(), 50u);
  const std::vector<AxisState> ref = rigid_body_reference({0, 0, 1}, {a / 2, a / 2, 0}, {a / 2, -a / 2, 0},
                                                          {a + 100.0, 0, 0}, P, M, I, times);
  double turn_err = 0, path_err = 0, stretch = 0;
  const double at0[2] = {0, 0}, at2[2] = {a, a};
  for (std::size_t k = 0; k < times.size(); ++k) {
    const PlateTurn pt = plate_turn(r, s, {0, 0, 1}, times[k]);
    turn_err = std::max(turn_err, std::abs(pt.angle - ref[k].theta));
    stretch = std::max(stretch, pt.stretch);
    // The centre: the middle of the diagonal's corners.
    const auto x0 = probe_position(r, 0, at0, times[k]), x2 = probe_position(r, 2, at2, times[k]);
    for (int d = 0; d < 2; ++d)
      path_err = std::max(path_err, std::abs(0.5 * (x0[d] + x2[d]) - (d == 0 ? a / 2 : a / 2) - ref[k].u[d]));
  }
  const double path = std::hypot(ref.back().u[0], ref.back().u[1]);
  EXPECT_GT(ref.back().theta, 1.0);  // a large turn
  EXPECT_LT(turn_err, 1e-6);
  EXPECT_LT(path_err, 1e-6 * path);
  EXPECT_LT(stretch, 1e-12);
  EXPECT_LT(std::abs(r.result.energy.internal), 1e-9 * r.result.energy.external);
  EXPECT_LT(r.result.energy.balance_error, 1e-6);
  std::printf("swivelling plate: turned %.4f rad (reference %.4f), largest error %.2e rad; centre moved %.4g mm, "
              "off by %.2e of it; corners' distances changed by %.1e m; internal %.1e J of %.3g J of work, balance "
              "%.2e, %lld steps\n",
              plate_turn(r, s, {0, 0, 1}, times.back()).angle, ref.back().theta, turn_err, 1e3 * path,
              path_err / path, stretch, r.result.energy.internal, r.result.energy.external,
              r.result.energy.balance_error, r.result.mechanical_steps);
  // The summary's turn of the jaws (the best-fit rotation of the gripped
  // nodes) is the plate's, and they have not deformed.
  const json summary = json::parse(std::ifstream(out / "summary.json"));
  const json& jaw = summary["grippers"][0];
  EXPECT_EQ(jaw["jaws"], "swivelling");
  EXPECT_NEAR(jaw["jaw_rotation_deg"].get<double>(), plate_turn(r, s, {0, 0, 1}, times.back()).angle * 180 / M_PI,
              1e-9);
  EXPECT_LT(jaw["jaw_distortion_m"].get<double>(), 1e-12);
  // Rigid jaws hold the plate from turning.
  json rigid = s.job;
  rigid["constraints"][0]["jaws"] = "rigid";
  const JobRun rr = run_json(rigid);
  ASSERT_TRUE(rr.result.ok) << rr.result.error;
  EXPECT_LT(std::abs(plate_turn(rr, s, {0, 0, 1}, times.back()).angle), 1e-12);
}

// Pulled out of its plane at a corner, the swivelling plate (30 x 20 mm, so
// that its two in-plane axes differ) tumbles: it turns about an axis that
// is no principal axis and changes with time. The reference is the free
// rigid body of its lumped masses (Newton-Euler, RK4 at 1e-7 s). Each
// corner's place is required within 1e-6 of its path (the central
// differences' O(dt^2) error; the turn is 2.4 rad).
TEST(Gripper, SwivellingJawsTumbleAsAFreeRigidBody) {
  const double a = 0.03, b = 0.02, P = 0.01, t_end = 0.02;
  const SwivelPlate s = swivel_plate(a, b, {a, 0, 0}, {0, 0, 1}, P, t_end);
  double M = 0;
  std::array<double, 9> I{};
  for (std::size_t n = 0; n < s.mass.size(); ++n) {
    M += s.mass[n];
    const double r[3] = {s.x0[3 * n] - a / 2, s.x0[3 * n + 1] - b / 2, 0.0};
    const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) I[3 * i + j] += s.mass[n] * ((i == j ? r2 : 0.0) - r[i] * r[j]);
  }
  const JobRun r = run_json(s.job);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const std::vector<double> times = sample_times(r);
  ASSERT_GE(times.size(), 50u);
  const std::vector<BodyState> ref =
      free_body_reference({a / 2, b / 2, 0}, {a / 2, -b / 2, 0}, {a, 0, 100.0}, P, M, I, times);
  const double at[4][2] = {{0, 0}, {a, 0}, {a, b}, {0, b}};
  double err = 0, path = 0, stretch = 0, turn = 0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const BodyState& B = ref[k];
    for (int c = 0; c < 4; ++c) {
      const auto x = probe_position(r, c, at[c], times[k]);
      const double r0[3] = {at[c][0] - a / 2, at[c][1] - b / 2, 0.0};
      double e2 = 0, u2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double xr = B.c[d] + B.R[3 * d] * r0[0] + B.R[3 * d + 1] * r0[1] + B.R[3 * d + 2] * r0[2];
        e2 += (x[d] - xr) * (x[d] - xr);
        const double x0 = d < 2 ? at[c][d] : 0.0;
        u2 += (xr - x0) * (xr - x0);
      }
      err = std::max(err, std::sqrt(e2));
      path = std::max(path, std::sqrt(u2));
    }
    stretch = std::max(stretch, plate_turn(r, s, {0, 0, 1}, times[k]).stretch);
    turn = std::acos(std::clamp(0.5 * (B.R[0] + B.R[4] + B.R[8] - 1), -1.0, 1.0));
  }
  EXPECT_GT(turn, 1.0);
  EXPECT_LT(err, 1e-6 * path);
  EXPECT_LT(stretch, 1e-12);
  EXPECT_LT(r.result.energy.balance_error, 1e-6);
  std::printf("tumbling plate: turned %.4f rad, corners %.4g mm from their places, off by %.2e of that; distances "
              "changed by %.1e m; balance %.2e, %lld steps\n",
              turn, 1e3 * path, err / path, stretch, r.result.energy.balance_error, r.result.mechanical_steps);
}

// Half the plate on a symmetry plane (y = 0, the model of a 20 x 20 mm plate
// by its half y >= 0), pulled out of its plane at the corner (a, b) and its
// mirror image: the whole turns about y only, through its centre, and
// moves in z (and x). A gripped node on the plane lets the jaw turn only
// about the plane's normal, which this requires: the half alone, free,
// would also roll about x. Reference: RK4 of the turn about the axis
// through the half's centre along y (the inertia of the half about it);
// required as for the plate in its plane.
TEST(Gripper, SwivellingJawsOnASymmetryPlaneTurnAboutItsNormal) {
  const double a = 0.02, b = 0.01, P = 0.01, t_end = 0.02;
  SwivelPlate s = swivel_plate(a, b, {a, b, 0}, {0, 0, 1}, P, t_end);
  s.job["constraints"].push_back({{"type", "symmetry"}, {"part", "plate"}, {"plane", "y"}});
  double M = 0, I = 0, cy = 0;
  for (std::size_t n = 0; n < s.mass.size(); ++n) {
    M += s.mass[n];
    cy += s.mass[n] * s.x0[3 * n + 1];
    I += s.mass[n] * std::pow(s.x0[3 * n] - a / 2, 2);
  }
  cy /= M;
  const JobRun r = run_json(s.job);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const std::vector<double> times = sample_times(r);
  ASSERT_GE(times.size(), 50u);
  const std::vector<AxisState> ref =
      rigid_body_reference({0, 1, 0}, {a / 2, cy, 0}, {a / 2, b - cy, 0}, {a, b, 100.0}, P, M, I, times);
  const double at0[2] = {0, 0}, at1[2] = {a, 0}, at2[2] = {a, b}, at3[2] = {0, b};
  double turn_err = 0, path_err = 0, roll = 0, off_plane = 0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const PlateTurn pt = plate_turn(r, s, {0, 1, 0}, times[k]);
    turn_err = std::max(turn_err, std::abs(pt.angle - ref[k].theta));
    const auto x0 = probe_position(r, 0, at0, times[k]), x1 = probe_position(r, 1, at1, times[k]);
    const auto x2 = probe_position(r, 2, at2, times[k]), x3 = probe_position(r, 3, at3, times[k]);
    // The centre line's middle (on the plane): (x0 + x1) / 2.
    for (int d : {0, 2})
      path_err = std::max(path_err, std::abs(0.5 * (x0[d] + x1[d]) - (d == 0 ? a / 2 : 0.0) - ref[k].u[d]));
    roll = std::max({roll, std::abs(x3[2] - x0[2]), std::abs(x2[2] - x1[2])});  // turning about x
    off_plane = std::max({off_plane, std::abs(x0[1]), std::abs(x1[1])});
  }
  const double path = std::hypot(ref.back().u[0], ref.back().u[2]);
  EXPECT_GT(std::abs(ref.back().theta), 1.0);
  EXPECT_LT(turn_err, 1e-6);
  EXPECT_LT(path_err, 1e-6 * path);
  EXPECT_LT(roll, 1e-12);
  EXPECT_EQ(off_plane, 0.0);
  EXPECT_LT(r.result.energy.balance_error, 1e-6);
  std::printf("half plate on y = 0: turned %.4f rad about y (reference %.4f), largest error %.2e rad; centre moved "
              "%.4g mm, off by %.2e of it; rolled by %.1e m; balance %.2e\n",
              plate_turn(r, s, {0, 1, 0}, times.back()).angle, ref.back().theta, turn_err, 1e3 * path,
              path_err / path, roll, r.result.energy.balance_error);
}

// A plate held at a corner node (a `fix` in x, y and z) turns about it as
// a rigid body on a pin: pulled along y at the far corner of its x edge,
// it turns about z by the moment about the pin over the inertia about the
// pin (RK4 reference). The pin's reaction is the force that keeps the
// centre on its circle, M a_c - F, required within 1e-4 of F.
TEST(Gripper, SwivellingJawsTurnAboutAHeldNode) {
  const double a = 0.02, P = 0.01, t_end = 0.03;
  SwivelPlate s = swivel_plate(a, a, {a, 0, 0}, {0, 1, 0}, P, t_end);
  s.job["constraints"].push_back(
      {{"type", "fix"}, {"part", "plate"}, {"box", {{-1e-6, -1e-6, -1}, {1e-6, 1e-6, 1}}}, {"dofs", {"x", "y", "z"}}});
  double M = 0, I = 0;
  for (std::size_t n = 0; n < s.mass.size(); ++n) {
    M += s.mass[n];
    I += s.mass[n] * (std::pow(s.x0[3 * n], 2) + std::pow(s.x0[3 * n + 1], 2));
  }
  const JobRun r = run_json(s.job);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const std::vector<double> times = sample_times(r);
  ASSERT_GE(times.size(), 50u);
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<AxisState> ref = rigid_body_reference({0, 0, 1}, {0, 0, 0}, {a, 0, 0}, {a, 100.0, 0}, P, inf, I,
                                                          times);
  double turn_err = 0, pin = 0;
  const double at0[2] = {0, 0};
  for (std::size_t k = 0; k < times.size(); ++k) {
    turn_err = std::max(turn_err, std::abs(plate_turn(r, s, {0, 0, 1}, times[k]).angle - ref[k].theta));
    const auto x0 = probe_position(r, 0, at0, times[k]);
    pin = std::max({pin, std::abs(x0[0]), std::abs(x0[1]), std::abs(x0[2])});
  }
  // The pin's reaction at the last step's start, t_end - dt (equal steps):
  // M a_c - F, a_c = alpha k x r_c - w^2 r_c.
  const AxisState e = rigid_body_reference({0, 0, 1}, {0, 0, 0}, {a, 0, 0}, {a, 100.0, 0}, P, inf, I,
                                           {t_end - t_end / static_cast<double>(r.result.mechanical_steps)})[0];
  const double th = e.theta, cth = std::cos(th), sth = std::sin(th);
  const double rc[2] = {a / 2 * cth - a / 2 * sth, a / 2 * sth + a / 2 * cth};  // centre, turned
  const double corner[2] = {a * cth, a * sth};
  double f[2] = {a - corner[0], 100.0 - corner[1]};
  const double fn = std::hypot(f[0], f[1]);
  f[0] *= P / fn;
  f[1] *= P / fn;
  const double alpha = (corner[0] * f[1] - corner[1] * f[0]) / I;
  const double ac[2] = {-alpha * rc[1] - e.omega * e.omega * rc[0], alpha * rc[0] - e.omega * e.omega * rc[1]};
  const auto& R = r.result.energy.reactions;
  ASSERT_EQ(R.size(), 9u);
  EXPECT_GT(ref.back().theta, 1.0);
  EXPECT_LT(turn_err, 1e-6);
  EXPECT_EQ(pin, 0.0);
  EXPECT_NEAR(R[6], M * ac[0] - f[0], 1e-4 * P);
  EXPECT_NEAR(R[7], M * ac[1] - f[1], 1e-4 * P);
  EXPECT_LT(r.result.energy.balance_error, 1e-6);
  std::printf("plate on a pin: turned %.4f rad (reference %.4f), largest error %.2e rad; pin's reaction %.6g / %.6g "
              "N, expected %.6g / %.6g N; balance %.2e\n",
              plate_turn(r, s, {0, 0, 1}, times.back()).angle, ref.back().theta, turn_err, R[6], R[7],
              M * ac[0] - f[0],
              M * ac[1] - f[1], r.result.energy.balance_error);
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
  // Swivelling jaws: the same two.
  bad["constraints"][0]["jaws"] = "swivelling";
  bad["constraints"][1]["jaws"] = "swivelling";
  EXPECT_EQ(error_of(bad).rfind("/constraints/1/box: swivelling jaws: the box shares node ", 0), 0u)
      << error_of(bad);
  bad["constraints"][1]["jaws"] = "rigid";
  EXPECT_EQ(error_of(bad).rfind("/constraints/1/box: rigid jaws: the box shares node ", 0), 0u) << error_of(bad);
  EXPECT_NE(error_of(bad).find("two rigid or swivelling jaws cannot hold one node"), std::string::npos);
  bad = rigid;
  bad["constraints"][0]["jaws"] = "swivelling";
  EXPECT_EQ(error_of(bad), "");
  bad["constraints"].push_back({{"type", "velocity"}, {"part", "plate"}, {"box", {{-1, -1, -1}, {1, 1e-6, 1}}},
                                {"velocity", {0.0, 0.1, 0.0}}, {"dofs", {"y"}}});
  EXPECT_EQ(error_of(bad).rfind("/constraints/0/box: swivelling jaws: the box holds node ", 0), 0u)
      << error_of(bad);
}

}  // namespace ts::test
