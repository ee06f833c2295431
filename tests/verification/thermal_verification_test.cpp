// Verification of the thermal strategies against analytic solutions and an
// independent fine 1D reference. Each tolerance is stated with its reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <sstream>
#include <array>
#include <fstream>
#include <vector>

#include "io/logging.hpp"
#include "job/errors.hpp"
#include "plugins/registry.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

constexpr double kRhoC = 1294.0 * 1775.0;
constexpr double kH = 0.0005;

// Max error of a profile against the eigen-series (Robin on top, bottom adiabatic).
double series_error(const ProbeSample& s, double t, double hconv) {
  const double alpha = 0.31 / kRhoC;
  const double Bi = hconv * kH / 0.31;
  double e = 0;
  for (std::size_t k = 0; k < s.values.size(); ++k) {
    const double x = s.z[k] + 0.5 * kH;  // from the adiabatic face
    e = std::max(e, std::abs(s.values[k] - slab_robin_series(x, t, kH, alpha, Bi, 300.0, 260.0)));
  }
  return e;
}

json robin_job(const std::string& splitter, const std::string& scheme, int layers, double dt = 0) {
  json j = ply_job(splitter, layers, 2.0, 0.1);
  j["solvers"]["thermal"]["through_thickness"] = scheme;
  if (dt > 0) j["solvers"]["thermal"]["dt"] = dt;
  j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 260.0}}};
  return j;
}

// Tolerance: 1 % of the 40 K drop, as required; with 16 layers the spatial
// error of linear elements is ~ (e/h)^2/12 of the drop, well below that.
TEST(EigenSeries, ProfileWithin1PercentOfDrop) {
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    const JobRun r = run_json(robin_job(splitter, scheme, 16));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_EQ(r.result.limited_node_steps, 0);
    for (double t : {0.2, 0.5, 1.0, 2.0}) {
      const ProbeSample* s = r.sample(0, "temperature_profile", t);
      ASSERT_NE(s, nullptr);
      ASSERT_NEAR(s->time, t, 1e-9);
      const double err = series_error(*s, t, 1000.0);
      EXPECT_LT(err, 0.01 * 40.0) << splitter << " " << scheme << " at t = " << t;
      RecordProperty(splitter + "_" + scheme + "_t" + std::to_string(t), std::to_string(err));
    }
  }
}

// Convergence with the number of layers (explicit path with a step
// proportional to e^2, so that the time error follows the space error):
// linear elements give second order; the observed order must be >= 1.8.
TEST(EigenSeries, SecondOrderInLayers) {
  std::vector<double> errs;
  for (int layers : {4, 8, 16}) {
    const double e = kH / layers;
    const JobRun r = run_json(robin_job("adi", "explicit", layers, 0.25 * kRhoC * e * e / (2 * 0.31)));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    errs.push_back(series_error(*r.sample(0, "temperature_profile", 0.5), 0.5, 1000.0));
  }
  const double order1 = std::log2(errs[0] / errs[1]), order2 = std::log2(errs[1] / errs[2]);
  std::printf("layers 4/8/16: error %.4g %.4g %.4g K, order %.2f %.2f\n", errs[0], errs[1], errs[2], order1, order2);
  EXPECT_GT(order1, 1.8);
  EXPECT_GT(order2, 1.8);
}

// Convergence with the step (implicit = backward Euler, first order): fine
// layers so that the time error dominates; observed order at least 0.9.
TEST(EigenSeries, FirstOrderInTime) {
  std::vector<double> errs;
  for (double dt : {0.1, 0.05, 0.025}) {
    const JobRun r = run_json(robin_job("adi", "implicit", 64, dt));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    errs.push_back(series_error(*r.sample(0, "temperature_profile", 0.5), 0.5, 1000.0));
  }
  const double order1 = std::log2(errs[0] / errs[1]), order2 = std::log2(errs[1] / errs[2]);
  std::printf("dt 0.1/0.05/0.025: error %.4g %.4g %.4g K, order %.2f %.2f\n", errs[0], errs[1], errs[2], order1,
              order2);
  EXPECT_GT(order1, 0.9);
  EXPECT_GT(order2, 0.9);
}

// The ply history (plies.csv) of the Robin slab against the eigen-series:
// the coldest value is the cooled face's, the hottest the adiabatic face's,
// the mean the series' mean over the thickness; the share below 290 degC is
// the depth (L - x*) / L of the point x* where the series crosses it; the
// first time below it, where the cooled face crosses it. 32 layers,
// backward Euler at 0.5 ms, rows every 20 ms to 2 s. Tolerances: the
// face values carry the error of the profile, largest in the first
// milliseconds, when the cooled layer is a few elements deep (0.047 K;
// 0.2 K with 16 layers and 2 ms): 0.1 K. The mean follows the heat through
// the face, which the scheme conserves (0.001 K): 0.005 K. The share below
// is the crossing's depth, off by the profile's error over its gradient
// (6e-4 of the thickness): 2e-3. The first time below is the end of the
// step in which the face's value crossed: within two steps after the
// series' time, never before it.
TEST(PlyHistory, SlabAgainstEigenSeries) {
  const double dt = 0.0005, threshold = 290.0, alpha = 0.31 / kRhoC, Bi = 1000.0 * kH / 0.31;
  json j = robin_job("adi", "implicit", 32, dt);
  j["output"]["temperature_threshold"] = threshold;
  j["output"]["series_interval"] = 0.02;
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  auto T = [&](double x, double t) { return slab_robin_series(x, t, kH, alpha, Bi, 300.0, 260.0); };
  // Where a decreasing function of s in [lo, hi] crosses the threshold, by bisection.
  auto crossing = [&](double lo, double hi, auto f) {
    for (int it = 0; it < 100; ++it) (f(0.5 * (lo + hi)) > threshold ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  };
  double e_min = 0, e_mean = 0, e_max = 0, e_frac = 0, frac_end = 0;
  int rows = 0, partial = 0;
  for (const auto& s : r.result.ply_history) {
    ASSERT_EQ(s.part, 0);
    ++rows;
    if (s.time == 0) {
      EXPECT_EQ(s.min, 300.0);
      EXPECT_NEAR(s.mean, 300.0, 1e-12);
      EXPECT_EQ(s.fraction_below, 0.0);
      continue;
    }
    e_min = std::max(e_min, std::abs(s.min - T(kH, s.time)));
    e_max = std::max(e_max, std::abs(s.max - T(0, s.time)));
    e_mean = std::max(e_mean, std::abs(s.mean - slab_robin_mean(s.time, kH, alpha, Bi, 300.0, 260.0)));
    double frac = 0;
    if (T(0, s.time) <= threshold) frac = 1;
    else if (T(kH, s.time) < threshold) frac = 1 - crossing(0, kH, [&](double x) { return T(x, s.time); }) / kH;
    partial += frac > 0.05 && frac < 0.95;
    e_frac = std::max(e_frac, std::abs(s.fraction_below - frac));
    frac_end = frac;
  }
  const double first = crossing(0, 2, [&](double t) { return T(kH, std::max(t, 1e-9)); });
  const double all = crossing(0, 2, [&](double t) { return T(0, std::max(t, 1e-9)); });
  ASSERT_EQ(r.result.part_below_threshold_from_s.size(), 1u);
  ASSERT_EQ(r.result.part_all_below_threshold_from_s.size(), 1u);
  const double from = r.result.part_below_threshold_from_s[0], all_from = r.result.part_all_below_threshold_from_s[0];
  std::printf("rows %d (%d with a front inside the ply): errors min %.3g K, mean %.3g K, max %.3g K, share below "
              "%.3g; first below %.6g s (series %.6g s), all below %.6g s (series %.6g s)\n",
              rows, partial, e_min, e_mean, e_max, e_frac, from, first, all_from, all);
  EXPECT_EQ(rows, 101);  // t = 0 and every 20 ms
  EXPECT_GT(partial, 20) << "the front crosses the ply over many rows";
  EXPECT_GT(frac_end, 0.5);
  EXPECT_LT(e_min, 0.1);
  EXPECT_LT(e_max, 0.1);
  EXPECT_LT(e_mean, 0.005);
  EXPECT_LT(e_frac, 2e-3);
  EXPECT_GE(from, first);
  EXPECT_LE(from, first + 2 * dt);
  // Every value below: the adiabatic face's crossing, likewise.
  EXPECT_LT(all, 2.0);
  EXPECT_GE(all_from, all);
  EXPECT_LE(all_from, all + 2 * dt);
  // The last row's mean is the heat audit's: (mean - T0) times the ply's
  // heat capacity is the stored heat's change.
  const auto& last = r.result.ply_history.back();
  EXPECT_NEAR(last.time, 2.0, 1e-12);
  const double capacity = kRhoC * 0.01 * 0.01 * kH;
  EXPECT_NEAR((last.mean - 300.0) * capacity, r.result.part_heat_change[0], 1e-9 * std::abs(r.result.part_heat_change[0]));
}

// Independent reference for a stack of plies: lumped linear elements, 400
// per ply, backward Euler with dt = 1e-4 s, interface conductance between
// the facing end nodes of neighbouring plies. Bottom face Robin (h, 260),
// top face adiabatic.
struct TwoPlyReference {
  int n = 400;
  int plies = 2;
  std::vector<double> T;  // plies (n+1) values, from the lowest ply up
  void run(double t_end, double h, double hc) {
    const int m = n + 1;
    T.assign(plies * m, 300.0);
    const double e = kH / n, dt = 1e-4, g = 0.31 / e;
    const int N = plies * m;
    std::vector<double> a(N), b(N), c(N), d(N), cp(N);
    for (int step = 0; step < static_cast<int>(std::round(t_end / dt)); ++step) {
      for (int i = 0; i < N; ++i) {
        const int k = i % m;
        const double w = (k == 0 || k == n) ? 0.5 * e : e;
        const double cap = kRhoC * w / dt;
        a[i] = b[i] = c[i] = 0;
        b[i] = cap;
        d[i] = cap * T[i];
        if (k > 0) {
          a[i] = -g;
          b[i] += g;
        }
        if (k < n) {
          c[i] = -g;
          b[i] += g;
        }
      }
      b[0] += h;
      d[0] += h * 260.0;
      // interface links: top of ply q (index q m + n) and bottom of ply q+1 ((q+1) m)
      for (int q = 0; q + 1 < plies; ++q) {
        const int lo = q * m + n, up = (q + 1) * m;
        b[lo] += hc;
        c[lo] = -hc;
        b[up] += hc;
        a[up] = -hc;
      }
      // Thomas
      cp[0] = c[0] / b[0];
      d[0] /= b[0];
      for (int i = 1; i < N; ++i) {
        const double den = b[i] - a[i] * cp[i - 1];
        cp[i] = c[i] / den;
        d[i] = (d[i] - a[i] * d[i - 1]) / den;
      }
      for (int i = N - 2; i >= 0; --i) d[i] -= cp[i] * d[i + 1];
      T = d;
    }
  }
  double at(int ply, double z) const {  // z from -h/2 to h/2 in that ply
    const double s = (z / kH + 0.5) * n;
    const int k = std::min(n - 1, static_cast<int>(s));
    const double f = s - k;
    const int o = ply * (n + 1);
    return (1 - f) * T[o + k] + f * T[o + k + 1];
  }
};


// Tolerances: profile within 1 % of the 40 K drop (16 layers, as above);
// the interface jump T_upper,bottom - T_lower,top within 2 % of the
// reference jump plus 0.02 K (the jump is h_c times the interface flux; its
// error is the flux error of 16 layers).
TEST(TwoPlies, InterfaceJumpAgainstFine1D) {
  for (double hc : {1000.0, 300.0}) {
    for (const std::string splitter : {"adi", "layered3d"}) {
      const JobRun r = run_json(two_ply_job(splitter, 16, hc));
      ASSERT_TRUE(r.result.ok) << r.result.error;
      EXPECT_LT(r.result.heat_balance_error, 1e-9);
      for (double t : {0.5, 1.0, 2.0}) {
        TwoPlyReference ref;
        ref.run(t, 1000.0, hc);
        const ProbeSample* lo = r.sample(0, "temperature_profile", t);
        const ProbeSample* up = r.sample(1, "temperature_profile", t);
        double err = 0;
        for (std::size_t k = 0; k < lo->z.size(); ++k) {
          err = std::max(err, std::abs(lo->values[k] - ref.at(0, lo->z[k])));
          err = std::max(err, std::abs(up->values[k] - ref.at(1, up->z[k])));
        }
        EXPECT_LT(err, 0.4) << splitter << " hc " << hc << " t " << t;
        const double jump = up->values.front() - lo->values.back();
        const double ref_jump = ref.at(1, -0.5 * kH) - ref.at(0, 0.5 * kH);
        EXPECT_GT(ref_jump, 0.1);  // the case must have a visible jump
        EXPECT_NEAR(jump, ref_jump, 0.02 * std::abs(ref_jump) + 0.02) << splitter << " hc " << hc << " t " << t;
        std::printf("%s hc=%g t=%g: max error %.4f K, jump %.4f K (reference %.4f K)\n", splitter.c_str(), hc, t, err,
                    jump, ref_jump);
      }
    }
  }
}

// Three plies: the middle one is linked on both faces (its rods couple two
// interface unknowns each). Same reference and tolerances as above.
TEST(ThreePlies, MiddlePlyLinkedOnBothFaces) {
  const double hc = 1000.0;
  for (const std::string splitter : {"adi", "layered3d"}) {
    json j = two_ply_job(splitter, 16, hc);
    json top = j["parts"][1];
    top["name"] = "top";
    top["mesh"]["origin"] = {0, 0, 0.00125};
    j["parts"].push_back(top);
    j["interactions"].push_back(
        {{"type", "contact"}, {"handler", "penalty_node_surface"}, {"between", {"top", "upper"}}, {"conductance", hc}});
    j["output"]["probes"].push_back({{"name", "top"},
                                     {"part", "top"},
                                     {"at", {0.005, 0.005, 0.00125}},
                                     {"quantities", {"temperature_profile"}},
                                     {"interval", 0.5}});
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-9);
    for (double t : {1.0, 2.0}) {
      TwoPlyReference ref;
      ref.plies = 3;
      ref.run(t, 1000.0, hc);
      double err = 0;
      std::vector<const ProbeSample*> s;
      for (int q = 0; q < 3; ++q) {
        s.push_back(r.sample(q, "temperature_profile", t));
        ASSERT_NE(s.back(), nullptr);
        for (std::size_t k = 0; k < s[q]->z.size(); ++k)
          err = std::max(err, std::abs(s[q]->values[k] - ref.at(q, s[q]->z[k])));
      }
      EXPECT_LT(err, 0.4) << splitter << " t " << t;
      for (int q = 0; q < 2; ++q) {
        const double jump = s[q + 1]->values.front() - s[q]->values.back();
        const double ref_jump = ref.at(q + 1, -0.5 * kH) - ref.at(q, 0.5 * kH);
        EXPECT_GT(ref_jump, 0.1);  // the case must have a visible jump
        EXPECT_NEAR(jump, ref_jump, 0.02 * std::abs(ref_jump) + 0.02) << splitter << " interface " << q << " t " << t;
        std::printf("%s three plies t=%g interface %d: jump %.4f K (reference %.4f K)\n", splitter.c_str(), t, q, jump,
                    ref_jump);
      }
      std::printf("%s three plies t=%g: max error %.4f K\n", splitter.c_str(), t, err);
    }
  }
}

// In-plane anisotropic diffusion, fibres at 30 degrees: on the parallelogram
// whose slant is s = k_xy / k_yy, cos(pi (x - s y) / L) is an exact mode that
// decays at k_eff pi^2 / (rho c L^2) with k_eff = 1 / (K^-1)_xx. Tolerance
// 1 %: the discrete rate of 40 linear elements per half wave is within
// (pi/40)^2/12 = 0.05 % of it, and the time error is smaller still.
TEST(InPlane, AnisotropicCosineDecayRate) {
  const double k11 = 3.89, k22 = 0.31, th = 30.0 * M_PI / 180.0;
  const double c = std::cos(th), s = std::sin(th);
  const double kxx = k11 * c * c + k22 * s * s, kyy = k11 * s * s + k22 * c * c, kxy = (k11 - k22) * s * c;
  const double slant = kxy / kyy, keff = kxx - kxy * kxy / kyy;
  const double L = 0.02, W = 0.01;
  const auto dir = temp_dir("inplane");
  write_parallelogram(dir / "para.msh", L, W, slant, 40, 20);
  for (const std::string splitter : {"adi", "layered3d", "shell2d"}) {
    json j = ply_job(splitter, 4, 20.0, 5.0);
    j["parts"][0]["mesh"] = {{"file", (dir / "para.msh").string()}};
    j["parts"][0]["fibre_direction"] = {c, s, 0.0};
    j["output"]["probes"] = json::array();
    RunResult r;
    const double rate = mode_decay_rate(
        j, dir, L, slant, 10.0, [](double u) { return 300.0 + u; }, [](double T) { return T - 300.0; }, &r);
    ASSERT_TRUE(r.ok) << r.error;
    const double exact = keff * M_PI * M_PI / (kRhoC * L * L);
    std::printf("%s: decay rate %.6g 1/s, exact %.6g 1/s, error %.3f %%\n", splitter.c_str(), rate, exact,
                100 * (rate / exact - 1));
    EXPECT_NEAR(rate / exact, 1.0, 0.01) << splitter;
  }
}

}  // namespace
}  // namespace ts::test

namespace ts::test {
namespace {

// shell2d is a lumped body per node: with Robin on both faces and no
// in-plane gradient, backward Euler gives T_n = T_inf + (T0 - T_inf) /
// (1 + (h_b + h_t) dt / (rho c h))^n exactly (round-off tolerance), and
// forward Euler (1 - (h_b + h_t) dt / (rho c h))^n.
TEST(Shell2d, LumpedCoolingMatchesClosedForm) {
  for (const std::string scheme : {"implicit", "explicit"}) {
    json j = ply_job("shell2d", 4, 2.0, 0.1);
    j["solvers"]["thermal"]["through_thickness"] = scheme;
    j["solvers"]["thermal"]["dt"] = 0.05;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 260.0}},
                         {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 500.0}, {"ambient", 260.0}}};
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    const double a = 1500.0 * 0.05 / (kRhoC * kH);
    for (double t : {0.5, 1.0, 2.0}) {
      const int n = static_cast<int>(std::round(t / 0.05));
      const double factor = scheme == "implicit" ? std::pow(1 + a, -n) : std::pow(1 - a, n);
      EXPECT_NEAR(r.sample(0, "temperature_profile", t)->values[0], 260.0 + 40.0 * factor, 1e-9) << scheme << " " << t;
    }
  }
}

// The ply history of the lumped body: one value per node, so the coldest,
// mean and hottest values are T_n, and the share below 280 degC jumps from
// 0 to 1 at the first step n with T_n below it, (1 + a)^-n < 1/2 with
// backward Euler: n = 11 (t = 0.55 s) here. Round-off tolerances.
TEST(PlyHistory, LumpedPlyCrossesAtTheClosedFormStep) {
  json j = ply_job("shell2d", 4, 2.0, 0.1);
  j["solvers"]["thermal"]["dt"] = 0.05;
  j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 260.0}},
                       {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 500.0}, {"ambient", 260.0}}};
  j["output"]["temperature_threshold"] = 280.0;
  const JobRun r = run_json(j);
  ASSERT_TRUE(r.result.ok) << r.result.error;
  const double a = 1500.0 * 0.05 / (kRhoC * kH);
  const int n_cross = static_cast<int>(std::floor(std::log(2.0) / std::log(1 + a))) + 1;
  ASSERT_EQ(n_cross, 11);
  // The default spacing (time.end / 500 = 4 ms) is below the step: a row per step.
  ASSERT_EQ(r.result.ply_history.size(), 41u);
  for (const auto& s : r.result.ply_history) {
    const int n = static_cast<int>(std::round(s.time / 0.05));
    const double Tn = 260.0 + 40.0 * std::pow(1 + a, -n);
    EXPECT_NEAR(s.min, Tn, 1e-9) << s.time;
    EXPECT_NEAR(s.mean, Tn, 1e-9) << s.time;
    EXPECT_NEAR(s.max, Tn, 1e-9) << s.time;
    EXPECT_EQ(s.fraction_below, n >= n_cross ? 1.0 : 0.0) << s.time;
  }
  ASSERT_EQ(r.result.part_below_threshold_from_s.size(), 1u);
  EXPECT_NEAR(r.result.part_below_threshold_from_s[0], n_cross * 0.05, 1e-12);
  ASSERT_EQ(r.result.part_all_below_threshold_from_s.size(), 1u);  // one value per node: the same step
  EXPECT_NEAR(r.result.part_all_below_threshold_from_s[0], n_cross * 0.05, 1e-12);
}

// A tool whose temperature follows a table (heated, held, cooled: a
// variotherm cycle), with kinks inside thermal steps. shell2d is a lumped
// body per node, here on the tool (contact conductance h_c, thermal-only,
// touching) with an adiabatic top: C dT/dt = h_c (T_tool(t) - T), C = rho c h.
// Backward Euler with the tool at its mean over each step gives
// T_{n+1} = (T_n + a m_n) / (1 + a), a = h_c dt / C, m_n the mean of the
// table over [t_n, t_n+1] (here by a fine trapezoid sum, independent of the
// kernel's exact integral): required to round-off (1e-9 K). The ODE's own
// solution (exponentials on each linear piece) is approached at first
// order: at dt = 0.05 s (a = 0.044) within 1 % of the tool's 60 K swing,
// and the error halves with the step (ratio 1.8-2.2). tools.csv gives the
// table's value at each row. The same rows as a heat exchange's ambient
// (h = h_c) give the same temperatures to the bit.
TEST(ToolTemperature, LumpedPlyFollowsAVariothermCycle) {
  const std::vector<std::array<double, 2>> table = {{0.0, 260.0}, {0.33, 290.0}, {1.07, 290.0}, {1.83, 230.0}};
  const double h_c = 1000.0, C = kRhoC * kH, tau = C / h_c, t_end = 2.5;
  auto tool_at = [&](double t) {
    if (t <= table.front()[0]) return table.front()[1];
    if (t >= table.back()[0]) return table.back()[1];
    std::size_t k = 1;
    while (table[k][0] < t) ++k;
    return table[k - 1][1] + (t - table[k - 1][0]) / (table[k][0] - table[k - 1][0]) * (table[k][1] - table[k - 1][1]);
  };
  // The ODE's solution: on each linear piece T_tool = b + r (t - t0),
  // T = T_tool - r tau + (T(t0) - b + r tau) exp(-(t - t0) / tau).
  auto exact = [&](double t) {
    double T = 300.0, t0 = 0.0;
    std::vector<double> breaks = {0.0};
    for (const auto& row : table)
      if (row[0] > 0) breaks.push_back(row[0]);
    breaks.push_back(1e9);
    for (std::size_t k = 0; k + 1 < breaks.size() && t0 < t; ++k) {
      const double t1 = std::min(t, breaks[k + 1]);
      const double b = tool_at(t0), r = (tool_at(std::min(breaks[k + 1], 1e3)) - b) / (std::min(breaks[k + 1], 1e3) - t0);
      T = tool_at(t1) - r * tau + (T - b + r * tau) * std::exp(-(t1 - t0) / tau);
      t0 = t1;
    }
    return T;
  };
  auto job = [&](double dt, const std::filesystem::path& out) {
    json j = ply_job("shell2d", 4, t_end, 0.25);
    j["solvers"]["thermal"]["dt"] = dt;
    json rows = json::array();
    for (const auto& row : table) rows.push_back({row[0], row[1]});
    j["tools"] = {{{"name", "die"},
                   {"surface", {{"type", "plane"}, {"point", {0, 0, -0.5 * kH}}, {"normal", {0, 0, 1}}}},
                   {"temperature", rows}}};
    j["interactions"] = {{{"type", "contact"}, {"between", {"die", "ply"}}, {"conductance", h_c}}};
    j["output"]["series_interval"] = 0.25;
    return run_json(j, 1, out);
  };
  double err[2] = {0, 0};
  for (int level = 0; level < 2; ++level) {
    const double dt = 0.05 / (1 << level);
    const auto dir = temp_dir("tool_temperature_" + std::to_string(level));
    const JobRun r = job(dt, dir);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    const double a = h_c * dt / C;
    double T = 300.0;
    const int steps = static_cast<int>(std::round(t_end / dt));
    for (int n = 0; n < steps; ++n) {
      const double t0 = n * dt;
      double m = 0;
      const int sub = 20000;
      for (int q = 0; q < sub; ++q)
        m += 0.5 * (tool_at(t0 + q * dt / sub) + tool_at(t0 + (q + 1) * dt / sub)) / sub;
      T = (T + a * m) / (1 + a);
      const double t1 = (n + 1) * dt;
      if (std::abs(std::remainder(t1, 0.25)) < 1e-9) {
        const ProbeSample* s = r.sample(0, "temperature_profile", t1);
        ASSERT_NEAR(s->time, t1, 1e-9);
        EXPECT_NEAR(s->values[0], T, 1e-9) << "dt " << dt << ", t " << t1;
        err[level] = std::max(err[level], std::abs(s->values[0] - exact(t1)));
      }
    }
    // tools.csv: the table's value at every row.
    std::ifstream in(dir / "tools.csv");
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "time,tool,ux,uy,uz,fx,fy,fz,heat_J,temperature");
    int rows_read = 0;
    while (std::getline(in, line)) {
      std::vector<double> v;
      std::stringstream ss(line);
      for (std::string item; std::getline(ss, item, ',');) v.push_back(item == "die" ? 0.0 : std::stod(item));
      ASSERT_EQ(v.size(), 10u);
      EXPECT_NEAR(v[9], tool_at(v[0]), 1e-6) << v[0];  // the CSV's 10 significant digits
      ++rows_read;
    }
    EXPECT_EQ(rows_read, 11);
    // The same rows as the ambient of a heat exchange with h = h_c: the
    // same face conditions, so the same temperatures to the bit.
    json jx = ply_job("shell2d", 4, t_end, 0.25);
    jx["solvers"]["thermal"]["dt"] = dt;
    json rows = json::array();
    for (const auto& row : table) rows.push_back({row[0], row[1]});
    jx["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", h_c}, {"ambient", rows}}};
    const JobRun rx = run_json(jx);
    ASSERT_TRUE(rx.result.ok) << rx.result.error;
    for (int k = 1; k <= 10; ++k)
      EXPECT_EQ(rx.sample(0, "temperature_profile", 0.25 * k)->values[0], r.sample(0, "temperature_profile", 0.25 * k)->values[0])
          << "ambient rows, t " << 0.25 * k;
  }
  // With the mechanics on (the ply resting on the die, held in plane), the
  // thermal steps end on mechanical steps: the same ODE, the same tolerance.
  json j = ply_job("shell2d", 4, t_end, 0.25);
  {
    json rows = json::array();
    for (const auto& row : table) rows.push_back({row[0], row[1]});
    j["tools"] = {{{"name", "die"},
                   {"surface", {{"type", "plane"}, {"point", {0, 0, -0.5 * kH}}, {"normal", {0, 0, 1}}}},
                   {"temperature", rows}}};
  }
  j["materials"]["ply"]["membrane"] = {{"law", "ud_hyperelastic"}, {"k_fibre", 5.0e4}, {"p_ct", 5.0e3}};
  j["interactions"] = {{{"type", "contact"}, {"between", {"die", "ply"}}, {"conductance", h_c}}};
  j["constraints"] = {{{"type", "fix"}, {"part", "ply"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"x", "y", "z"}}}};
  j["solvers"]["mechanics"] = {{"dt_safety", 0.8}, {"mass_scaling", {{"target_dt", 1e-4}}}};
  j["solvers"]["thermal"]["dt"] = 0.05;
  const JobRun rm = run_json(j);
  ASSERT_TRUE(rm.result.ok) << rm.result.error;
  double err_mech = 0;
  for (int k = 1; k <= 10; ++k) {
    const ProbeSample* s = rm.sample(0, "temperature_profile", 0.25 * k);
    err_mech = std::max(err_mech, std::abs(s->values[0] - exact(s->time)));
  }
  std::printf("variotherm tool, lumped ply: largest error against the ODE %.4f K at dt 0.05 s, %.4f K at 0.025 s "
              "(ratio %.3f); with the mechanics, %.4f K at 0.05 s\n",
              err[0], err[1], err[0] / err[1], err_mech);
  EXPECT_LT(err_mech, 0.01 * 60.0);
  EXPECT_LT(err[0], 0.01 * 60.0);
  EXPECT_GT(err[0] / err[1], 1.8);
  EXPECT_LT(err[0] / err[1], 2.2);
}

// Radiation: a heat exchange with an emissivity gives the face the
// conductance h + eps sigma (T^2 + Ta^2)(T + Ta) (kelvin) at its temperature
// of the step's start, the ambient as its far temperature. A shell2d ply
// (lumped) radiating from both faces to 20 degC, eps = 0.9, from 300 degC:
// - backward Euler with that lagged conductance gives
//   T_{n+1} = (T_n + a_n Ta) / (1 + a_n), a_n = 2 h_n dt / C: required to
//   round-off (1e-9 K), also with convection (h = 15) added and with the
//   mechanics on;
// - the ODE C dT/dt = -2 eps sigma (T^4 - Ta^4) has the closed form
//   t = (F(T0) - F(T)) C / (2 eps sigma), F(T) = (ln((T - Ta)/(T + Ta))
//   - 2 atan(T / Ta)) / (4 Ta^3): at dt 0.1 s (a_n <= 0.003) within 1e-4 of
//   the 110 K the ply cools over the run (backward Euler's error, about
//   dt/2 times the change of the cooling rate, is of that order), and at
//   first order (error ratio 1.8-2.2 as the step halves).
TEST(Radiation, LumpedPlyAgainstTheClosedForm) {
  const double sigma = 5.670374419e-8, eps = 0.9, Ta = 293.15, C = kRhoC * kH, t_end = 20.0;
  auto F = [&](double T) { return (std::log((T - Ta) / (T + Ta)) - 2 * std::atan(T / Ta)) / (4 * Ta * Ta * Ta); };
  auto exact = [&](double t) {  // bisection on t(T), kelvin
    double lo = Ta + 1e-6, hi = 573.15;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      ((F(573.15) - F(mid)) * C / (2 * eps * sigma) > t ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi) - 273.15;
  };
  auto job = [&](double dt, double h, bool mechanics) {
    json j = ply_job("shell2d", 4, t_end, 1.0);
    j["solvers"]["thermal"]["dt"] = dt;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "both"}, {"emissivity", eps}, {"ambient", 20.0}}};
    if (h > 0) j["interactions"][0]["h"] = h;
    if (mechanics) {
      j["materials"]["ply"]["membrane"] = {{"law", "ud_hyperelastic"}, {"k_fibre", 5.0e4}, {"p_ct", 5.0e3}};
      j["constraints"] = {{{"type", "fix"}, {"part", "ply"}, {"box", {{-1, -1, -1}, {1, 1, 1}}}, {"dofs", {"x", "y", "z"}}}};
      j["solvers"]["mechanics"] = {{"dt_safety", 0.8}, {"mass_scaling", {{"target_dt", 1e-3}}}};
    }
    const JobRun r = run_json(j);
    EXPECT_TRUE(r.result.ok) << r.result.error;
    return r;
  };
  // The recurrence, to round-off.
  for (const auto& [h, mechanics] : std::vector<std::pair<double, bool>>{{0.0, false}, {15.0, false}, {15.0, true}}) {
    const double dt = 0.1;
    const JobRun r = job(dt, h, mechanics);
    double T = 300.0;
    for (int n = 1; n <= static_cast<int>(std::round(t_end / dt)); ++n) {
      const double Tk = T + 273.15;
      const double a = 2 * (h + eps * sigma * (Tk * Tk + Ta * Ta) * (Tk + Ta)) * dt / C;
      T = (T + a * 20.0) / (1 + a);
      if (n % 10 == 0) {
        EXPECT_NEAR(r.sample(0, "temperature_profile", n * dt)->values[0], T, 1e-9) << h << " " << n * dt;
      }
    }
  }
  // The ODE, at first order.
  double err[2] = {0, 0};
  for (int level = 0; level < 2; ++level) {
    const JobRun r = job(0.1 / (1 << level), 0.0, false);
    for (int k = 1; k <= 20; ++k)
      err[level] = std::max(err[level], std::abs(r.sample(0, "temperature_profile", k * 1.0)->values[0] - exact(k * 1.0)));
  }
  const double drop = 300.0 - exact(t_end);
  std::printf("radiating lumped ply: %.2f degC after %.0f s (closed form); largest error %.4f K at dt 0.1 s, %.4f K at "
              "0.05 s (ratio %.3f)\n",
              300.0 - drop, t_end, err[0], err[1], err[0] / err[1]);
  EXPECT_LT(err[0], 1e-4 * drop);
  EXPECT_GT(err[0] / err[1], 1.8);
  EXPECT_LT(err[0] / err[1], 2.2);
}

// Initial temperatures from an earlier run: a ply cooled on its top face
// (Robin, the eigen-series case) to 2 s in one run (A), and to 1 s, then
// from A's frame at 1 s for another second (B), take the same steps from the
// same values: B's profile at 1 s equals A's at 2 s to 1e-9 K (the frame's
// doubles are stored exactly; only the step lengths next to the frames may
// differ in their last bits). Read into other layers: 16 layers take A's 8
// at every second level and linear between (exact, round-off); shell2d the
// mean through the thickness (A's field temperature_mean). Errors name the
// key: a time without a frame, a part the file lacks, another mesh, a file
// without temperatures, and no thermal solver.
TEST(InitialTemperature, FromAFrameOfAnEarlierRun) {
  auto job = [](double t_end) {
    json j = ply_job("adi", 8, t_end, 0.5);
    j["solvers"]["thermal"]["dt"] = 0.01;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 260.0}}};
    j["output"]["fields"] = {"temperature"};
    return j;
  };
  const auto dir = temp_dir("initial_from_run");
  const JobRun a = run_json(job(2.0), 1, dir / "a");
  ASSERT_TRUE(a.result.ok) << a.result.error;
  const std::string file = (dir / "a" / "results.h5").string();
  json jb = job(1.0);
  jb["parts"][0]["initial_temperature"] = {{"results", file}, {"time", 1.0}};
  const JobRun b = run_json(jb);
  ASSERT_TRUE(b.result.ok) << b.result.error;
  const auto& a1 = a.sample(0, "temperature_profile", 1.0)->values;
  const auto& a2 = a.sample(0, "temperature_profile", 2.0)->values;
  const auto& b0 = b.sample(0, "temperature_profile", 0.0)->values;
  const auto& b1 = b.sample(0, "temperature_profile", 1.0)->values;
  ASSERT_EQ(b0.size(), 9u);
  double start = 0, end = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    start = std::max(start, std::abs(b0[k] - a1[k]));
    end = std::max(end, std::abs(b1[k] - a2[k]));
  }
  EXPECT_EQ(start, 0.0);  // the same doubles
  EXPECT_LT(end, 1e-9);  // (0 here: the same steps)
  std::printf("from an earlier run's frame: start %.3g K, after 1 s %.3g K from the run that went on\n", start, end);
  // Other layers: 16 (linear between A's 9 levels) and shell2d (the mean).
  json jc = jb;
  jc["parts"][0]["thickness_layers"] = 16;
  const JobRun c = run_json(jc);
  ASSERT_TRUE(c.result.ok) << c.result.error;
  const auto& c0 = c.sample(0, "temperature_profile", 0.0)->values;
  ASSERT_EQ(c0.size(), 17u);
  for (std::size_t k = 0; k < 17; ++k) {
    const double want = k % 2 == 0 ? a1[k / 2] : 0.5 * (a1[k / 2] + a1[k / 2 + 1]);
    EXPECT_NEAR(c0[k], want, 1e-12) << k;
  }
  json jd = jb;
  jd["solvers"]["thermal"]["splitter"] = "shell2d";
  const JobRun d = run_json(jd);
  ASSERT_TRUE(d.result.ok) << d.result.error;
  double mean = 0;
  for (std::size_t k = 0; k < 9; ++k) mean += (k == 0 || k == 8 ? 0.5 : 1.0) * a1[k] / 8;
  EXPECT_NEAR(d.sample(0, "temperature_profile", 0.0)->values[0], mean, 1e-12);
  // What cannot be read is named at its key.
  auto refused = [&](json j, const std::string& pointer, const std::string& what) {
    try {
      run_json(j);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const JobError& e) {
      EXPECT_EQ(e.pointer(), pointer) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  json e = jb;
  e["parts"][0]["initial_temperature"]["time"] = 0.75;
  refused(e, "/parts/0/initial_temperature/time", "has no frame at t = 0.75 s; its 5 frames run from 0 to 2 s");
  e = jb;
  e["parts"][0]["initial_temperature"]["part"] = "upper";
  refused(e, "/parts/0/initial_temperature/part", "has no part 'upper'");
  e = jb;
  e["parts"][0]["mesh"]["divisions"] = {3, 3};
  refused(e, "/parts/0/initial_temperature", "part 'ply' has 9 nodes, this part 16 (the same mesh is needed)");
  e = jb;
  e["solvers"]["thermal"] = nullptr;  // the mechanics alone
  e["solvers"]["mechanics"] = json::object();
  e["materials"]["ply"]["membrane"] = {{"law", "ud_hyperelastic"}, {"k_fibre", 5.0e4}, {"p_ct", 5.0e3}};
  e["interactions"] = json::array();
  refused(e, "/parts/0/initial_temperature", "need the thermal solver");
  json g = job(1.0);
  g["output"]["fields"] = {"displacement"};
  ASSERT_TRUE(run_json(g, 1, dir / "g").result.ok);
  e = jb;
  e["parts"][0]["initial_temperature"] = {{"results", (dir / "g" / "results.h5").string()}};
  refused(e, "/parts/0/initial_temperature", "has no temperature of part 'ply'");
  e["parts"][0]["initial_temperature"] = {{"results", (dir / "nowhere.h5").string()}};
  refused(e, "/parts/0/initial_temperature/results", "cannot read the results file");
}

}  // namespace
}  // namespace ts::test

namespace ts::test {
namespace {

// A specific heat table with a latent heat peak: 30 kJ/kg of crystallisation
// between 220 and 240 degC (a triangle up to 4775 J/(kg K) at 230 degC) on
// the 1775 J/(kg K) of the ply, held beyond the rows.
const json kLatentRows = {{220.0, 1775.0}, {230.0, 4775.0}, {240.0, 1775.0}};

// The table's c(T) and H(T) = int_0^T c, written out here independently of
// the kernel's HeatCapacityTable.
double latent_c(double T) {
  if (T <= 220 || T >= 240) return 1775.0;
  return T <= 230 ? 1775.0 + 300.0 * (T - 220) : 1775.0 + 300.0 * (240 - T);
}
double latent_h(double T) {
  double peak = 0;
  if (T > 220 && T <= 230) peak = 150.0 * (T - 220) * (T - 220);
  if (T > 230 && T < 240) peak = 30000.0 - 150.0 * (240 - T) * (240 - T);
  if (T >= 240) peak = 30000.0;
  return 1775.0 * T + peak;
}
// The T with latent_h(T) = h, by bisection.
double latent_h_inverse(double h) {
  double lo = -100, hi = 1000;
  for (int i = 0; i < 200 && hi - lo > 1e-13; ++i) (latent_h(0.5 * (lo + hi)) < h ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

// A lumped ply (shell2d, no in-plane gradient) between two Robin faces,
// h_b + h_t = H, to T_a = 200 degC from 300 degC: rho h c(T) dT/dt = -H (T - T_a).
json lumped_latent_job(double dt) {
  json j = ply_job("shell2d", 4, 4.0, 0.1);
  j["materials"]["ply"]["specific_heat"] = kLatentRows;
  j["solvers"]["thermal"]["dt"] = dt;
  j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 200.0}},
                       {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 500.0}, {"ambient", 200.0}}};
  return j;
}

// The ODE's solution in closed form: t(T) = (rho h / H) int_T^T0 c(s) / (s - T_a) ds,
// c linear on each piece between the rows: int c / (s - T_a) = c_a ln((s2 - T_a) / (s1 - T_a))
// + slope (s2 - s1), c_a the piece's line at T_a. T(t) by bisection on it.
double lumped_latent_time(double T) {
  const double Ta = 200.0, T0 = 300.0, scale = 1294.0 * kH / 1500.0;
  std::vector<double> pts = {T};
  for (double r : {220.0, 230.0, 240.0})
    if (r > T && r < T0) pts.push_back(r);
  pts.push_back(T0);
  double sum = 0;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const double s1 = pts[k], s2 = pts[k + 1];
    const double slope = (latent_c(s2) - latent_c(s1)) / (s2 - s1);
    const double ca = latent_c(s1) + slope * (Ta - s1);
    sum += ca * std::log((s2 - Ta) / (s1 - Ta)) + slope * (s2 - s1);
  }
  return scale * sum;
}
double lumped_latent_exact(double t) {
  double lo = 200.0 + 1e-9, hi = 300.0;  // t(T) decreases with T
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) (lumped_latent_time(0.5 * (lo + hi)) > t ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

// The lumped ply through a latent heat peak.
// (a) The scheme, written out: backward Euler with c_min gives
//     T* = (C T_n + H dt T_a) / (C + H dt), C = rho h c_min, then
//     H(T_n+1) = H(T_n) + c_min (T* - T_n); the run follows this recursion to
//     round-off (1e-9 K) at every sample.
// (b) The ODE: the error against its closed-form solution is that of the
//     first-order scheme, halving with the step (ratio 1.8-2.2 from 0.02 to
//     0.01 to 0.005 s), and at dt = 0.005 s (1/150 of rho c_min h / H) at most
//     1.6 times the error of the same run with a constant specific heat.
// (c) The heat: stored change (mass x H) equals the heat through the faces
//     (relative 1e-12).
TEST(SpecificHeatTable, LumpedPlyThroughALatentPeak) {
  const double Ta = 200.0, C = 1294.0 * 1775.0 * kH, H = 1500.0;
  std::vector<double> errors;
  for (double dt : {0.02, 0.01, 0.005}) {
    const JobRun r = run_json(lumped_latent_job(dt));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-12) << dt;
    EXPECT_LT(r.result.heat_in, -1.0);
    double T = 300.0, err_scheme = 0, err_ode = 0, t = 0;
    int samples = 0;
    for (const auto& s : r.result.probes) {
      if (s.quantity != "temperature_profile") continue;
      while (t < s.time - 1e-9) {
        const double Ts = (C * T + H * dt * Ta) / (C + H * dt);
        T = latent_h_inverse(latent_h(T) + 1775.0 * (Ts - T));
        t += dt;
      }
      err_scheme = std::max(err_scheme, std::abs(s.values[0] - T));
      err_ode = std::max(err_ode, std::abs(s.values[0] - lumped_latent_exact(s.time)));
      ++samples;
    }
    EXPECT_EQ(samples, 41);
    EXPECT_LT(err_scheme, 1e-9) << dt;
    errors.push_back(err_ode);
    std::printf("dt %.3f s: largest error against the recursion %.2e K, against the ODE %.4f K\n", dt, err_scheme,
                err_ode);
  }
  EXPECT_NEAR(errors[0] / errors[1], 2.0, 0.2);
  EXPECT_NEAR(errors[1] / errors[2], 2.0, 0.2);
  // The same scheme with the constant 1775 J/(kg K) against its exponential:
  // the table's error is at most 1.6 times that one (the heat flows of each
  // step are those of T*, which lags through the peak).
  json jc = lumped_latent_job(0.005);
  jc["materials"]["ply"]["specific_heat"] = 1775.0;
  const JobRun rc = run_json(jc);
  ASSERT_TRUE(rc.result.ok) << rc.result.error;
  double err_const = 0;
  for (const auto& s : rc.result.probes)
    if (s.quantity == "temperature_profile")
      err_const = std::max(err_const, std::abs(s.values[0] - (Ta + 100.0 * std::exp(-H * s.time / C))));
  std::printf("dt 0.005 s, constant specific heat: largest error against the ODE %.4f K\n", err_const);
  EXPECT_LT(errors[2], 1.6 * err_const);
  // The peak delays the cooling: 230 degC is reached later than with the
  // constant 1775 J/(kg K), by the closed form's extra time.
  EXPECT_GT(lumped_latent_time(230.0) - C / H * std::log(100.0 / 30.0), 0.1);
}


// A slab cooled through a latent peak: insulated at the bottom, Robin
// (h = 1000 W/(m^2 K), 200 degC) on top, from 300 degC, with kLatentRows.
// The reference is written here independently: 50 cells of the thickness,
// explicit in the enthalpy (rho w dH_i/dt = sum of the fluxes at the
// cell's faces, k33 between cell values, h at the top), T_i = H^-1(H_i) by
// bisection, at a step of 0.4 of the explicit limit; it is converged to
// well below the tolerance (25 cells give the same profiles within 0.05 K,
// checked here).
struct LatentSlabReference {
  int n = 50;
  std::vector<std::vector<double>> profiles;  // at t = 1, 2, ... s
  void run(int seconds) {
    const double e = kH / n, k = 0.31, rho = 1294.0, h = 1000.0, Ta = 200.0;
    const double dt_limit = rho * 1775.0 * 0.5 * e / (2 * k / e + h);
    const int per_second = static_cast<int>(std::ceil(1.0 / (0.4 * dt_limit)));
    const double dt = 1.0 / per_second;
    std::vector<double> T(n + 1, 300.0), H(n + 1, latent_h(300.0)), q(n + 1);
    for (int s = 1; s <= seconds * per_second; ++s) {
      slab_heat_flows(T, k, e, h, Ta, q);
      for (int i = 0; i <= n; ++i) {
        const double w = (i == 0 || i == n) ? 0.5 * e : e;
        H[i] += dt * q[i] / (rho * w);
        T[i] = latent_h_inverse(H[i]);
      }
      if (s % per_second == 0) profiles.push_back(T);
    }
  }
  double at(int second, double z) const { return profile_at(profiles.at(second - 1), kH, z); }  // z from -h/2 to h/2
};

// adi and layered3d (16 layers, both schemes, the step they choose) against
// the reference: within 1 % of the 100 K drop at every sample, as the
// constant-property profiles against the eigen-series (EigenSeries above);
// the heat balance to round-off.
TEST(SpecificHeatTable, SlabThroughALatentPeakAgainstAFineReference) {
  LatentSlabReference ref;
  ref.run(6);
  LatentSlabReference coarse;  // the reference's own convergence
  coarse.n = 25;
  coarse.run(6);
  const double ref_change = largest_difference(ref.profiles, coarse.profiles, kH);
  std::printf("reference: 25 against 50 cells, largest difference %.4f K\n", ref_change);
  EXPECT_LT(ref_change, 0.05);
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    json j = ply_job(splitter, 16, 6.0, 1.0);
    j["materials"]["ply"]["specific_heat"] = kLatentRows;
    j["solvers"]["thermal"]["through_thickness"] = scheme;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 200.0}}};
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-10) << splitter << " " << scheme;
    double worst = 0;
    for (int k = 0; k < 6; ++k) {
      const ProbeSample* s = r.sample(0, "temperature_profile", k + 1.0);
      ASSERT_NE(s, nullptr);
      double err = 0;
      for (std::size_t m = 0; m < s->z.size(); ++m) err = std::max(err, std::abs(s->values[m] - ref.at(k + 1, s->z[m])));
      EXPECT_LT(err, 1.0) << splitter << " " << scheme << " at t = " << k + 1;
      worst = std::max(worst, err);
    }
    std::printf("%s %s: largest error %.4f K; top face at 3 s %.3f degC (reference %.3f)\n", splitter.c_str(),
                scheme.c_str(), worst, r.sample(0, "temperature_profile", 3.0)->values.back(), ref.at(3, 0.5 * kH));
  }
}

// The field below_threshold_from: per node, the first thermal step at
// whose end a value of the node's thickness (below_threshold_from) and
// every value (all_below_threshold_from) was below
// output.temperature_threshold. A ply chilled on a disc of its top face
// (adi, 8 layers, dt 0.01 s, threshold 280 degC): at five nodes, probes
// without an interval record every thermal step's profile, from which the
// test finds both times; the field at the last frame must give them
// exactly (the same steps), and NaN at a node that never went below (the
// far corner, 20 mm from the disc). The ply's first time in summary.json is
// the smallest over the nodes. With the chill on the whole face every node
// sets through, and every node's times are the ply's.
TEST(PlyHistory, NodeTimesBelowTheThresholdAgainstTheProbes) {
  const auto dir = temp_dir("node_threshold_times");
  const std::vector<std::array<double, 2>> at = {{0.0, 0.0}, {0.005, 0.0}, {0.0075, 0.0025}, {0.01, 0.0}, {0.02, 0.02}};
  for (const bool disc : {true, false}) {
    json j = ply_job("adi", 8, 2.0, 0.5);
    j["parts"][0]["mesh"] = {{"generator", "rectangle"}, {"origin", {0, 0, 0}}, {"size", {0.02, 0.02}}, {"divisions", {8, 8}}};
    j["solvers"]["thermal"]["dt"] = 0.01;
    json chill = {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 200.0}};
    if (disc) chill["region"] = {{"circle", {{"centre", {0, 0}}, {"radius", 0.008}}}};
    j["interactions"] = json::array({chill});
    j["output"]["temperature_threshold"] = 280.0;
    j["output"]["fields"] = {"temperature_mean", "below_threshold_from"};
    j["output"]["probes"] = json::array();
    for (std::size_t q = 0; q < at.size(); ++q)
      j["output"]["probes"].push_back({{"name", "p" + std::to_string(q)}, {"part", "ply"}, {"at", {at[q][0], at[q][1], 0.0}},
                                       {"quantities", {"temperature_profile"}}});
    const auto out = dir / (disc ? "disc" : "face");
    const JobRun r = run_json(j, 0, out);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    // A run compared with itself is identical, its NaN (never below) included.
    EXPECT_EQ(thermostamp("compare " + q(out) + " " + q(out)).exit_code, 0);
    const hid_t file = H5Fopen((out / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const std::vector<double> x = read_dataset<double>(file, "frames/000000/ply/nodes");
    char last[32];
    std::snprintf(last, sizeof last, "frames/%06d/ply/", frame_count(file) - 1);
    const std::vector<double> some = read_dataset<double>(file, std::string(last) + "below_threshold_from");
    const std::vector<double> every = read_dataset<double>(file, std::string(last) + "all_below_threshold_from");
    H5Fclose(file);
    ASSERT_EQ(some.size(), x.size() / 3);
    int never = 0;
    for (std::size_t q = 0; q < at.size(); ++q) {
      int node = -1;
      for (std::size_t i = 0; i < some.size(); ++i)
        if (std::abs(x[3 * i] - at[q][0]) < 1e-9 && std::abs(x[3 * i + 1] - at[q][1]) < 1e-9) node = static_cast<int>(i);
      ASSERT_GE(node, 0);
      double first = std::nan(""), all = std::nan("");
      int samples = 0;
      for (const auto& smp : r.result.probes) {
        if (smp.probe != static_cast<int>(q)) continue;
        ++samples;
        const double lo = *std::min_element(smp.values.begin(), smp.values.end());
        const double hi = *std::max_element(smp.values.begin(), smp.values.end());
        if (std::isnan(first) && lo < 280.0) first = smp.time;
        if (std::isnan(all) && hi < 280.0) all = smp.time;
      }
      EXPECT_EQ(samples, 201);  // t = 0 and every step
      if (std::isnan(first)) {
        EXPECT_TRUE(std::isnan(some[node])) << q << ": " << some[node];
        ++never;
      } else {
        EXPECT_EQ(some[node], first) << "probe " << q;
      }
      if (std::isnan(all)) {
        EXPECT_TRUE(std::isnan(every[node])) << q << ": " << every[node];
      } else {
        EXPECT_EQ(every[node], all) << "probe " << q;
      }
      std::printf("%s, probe %zu: below 280 degC from %.2f s, all of it from %.2f s\n", disc ? "disc" : "face", q,
                  some[node], every[node]);
    }
    double smallest = std::numeric_limits<double>::infinity();
    for (double v : some)
      if (!std::isnan(v)) smallest = std::min(smallest, v);
    ASSERT_EQ(r.result.part_below_threshold_from_s.size(), 1u);
    EXPECT_EQ(r.result.part_below_threshold_from_s[0], smallest);
    if (disc) {
      EXPECT_GE(never, 1);  // the far corner at least
    } else {
      EXPECT_EQ(never, 0);
      for (std::size_t i = 0; i < some.size(); ++i) {
        EXPECT_EQ(some[i], r.result.part_below_threshold_from_s[0]);
        EXPECT_EQ(every[i], r.result.part_all_below_threshold_from_s[0]);
      }
    }
  }
}
}  // namespace
}  // namespace ts::test
