// Crystallisation kinetics of the matrix (Nakamura): a ply's relative
// crystallinity X = 1 - exp(-theta^n), theta = int K(T) dt, with the latent
// heat it releases, against closed forms and independent references.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "test_support.hpp"

namespace ts::test {
namespace {

constexpr double kH = 0.0005;  // ply thickness (m)
constexpr double kRho = 1294.0, kC = 1775.0;
constexpr double kLatent = 30000.0;  // J/kg

// Ziabicki's Gaussian of the illustrative PA66 rate: 50 1/s at 150 degC,
// half width 50 K (half crystallised at 232 degC when cooled at 10 K/min).
double gaussian_rate(double T) { return 50.0 * std::exp(-4.0 * std::log(2.0) * (T - 150.0) * (T - 150.0) / 2500.0); }
const json kGaussian = {{"k_max", 50.0}, {"t_max", 150.0}, {"half_width", 50.0}};

json kinetics(double n, const json& rate, double latent = kLatent) {
  return {{"latent_heat", latent}, {"avrami_exponent", n}, {"rate", rate}};
}

// Probes of the temperature and crystallinity profiles at interval `every`.
void probe_both(json& j, double every) {
  j["output"]["probes"][0]["quantities"] = {"temperature_profile", "crystallinity_profile"};
  j["output"]["probes"][0]["interval"] = every;
}

// An adiabatic lumped ply (shell2d, no exchange) at a constant rate K
// (one row, held at every temperature): theta = K t exactly, so X(t) =
// 1 - exp(-(K t)^n) (the Avrami law) and, the heat staying in the ply,
// T = T0 + L X / c. Both to round-off (1e-12 in X, 1e-9 K), for an integer
// and a fractional exponent; the stored heat (mass x (c T - L X)) does not
// change.
TEST(Crystallisation, AdiabaticPlyAgainstTheAvramiClosedForm) {
  for (double n : {3.0, 1.7}) {
    json j = ply_job("shell2d", 4, 3.0, 0.1);
    j["parts"][0]["initial_temperature"] = 220.0;
    j["materials"]["ply"]["crystallisation"] = kinetics(n, {{0.0, 0.5}});
    j["solvers"]["thermal"]["dt"] = 0.01;
    probe_both(j, 0.1);
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    double worst_x = 0, worst_t = 0;
    int samples = 0;
    for (int k = 0; k <= 30; ++k) {
      const double t = 0.1 * k;
      const double x = 1.0 - std::exp(-std::pow(0.5 * t, n));
      const ProbeSample* sx = r.sample(0, "crystallinity_profile", t);
      const ProbeSample* st = r.sample(0, "temperature_profile", t);
      ASSERT_TRUE(sx && st);
      ASSERT_NEAR(sx->time, t, 1e-9);
      worst_x = std::max(worst_x, std::abs(sx->values[0] - x));
      worst_t = std::max(worst_t, std::abs(st->values[0] - (220.0 + kLatent / kC * x)));
      ++samples;
    }
    EXPECT_EQ(samples, 31);
    EXPECT_LT(worst_x, 1e-12) << n;
    EXPECT_LT(worst_t, 1e-9) << n;
    EXPECT_GT(r.sample(0, "crystallinity_profile", 3.0)->values[0], 0.8);  // the case crystallises
    EXPECT_LT(std::abs(r.result.stored_change), 1e-9 * kRho * kC * kH * 1e-4 * 220.0);
    std::printf("n = %.1f: largest error in X %.2e, in T %.2e K; X(3 s) = %.6f\n", n, worst_x, worst_t,
                r.sample(0, "crystallinity_profile", 3.0)->values[0]);
  }
}

// A lumped ply (shell2d) cooled on both faces (h_b + h_t = H = 1500
// W/(m^2 K), to 150 degC) from 260 degC through its crystallisation
// (the Gaussian rate, n = 3, 30 kJ/kg):
//   rho c h dT/dt = -H (T - T_a) + rho h L dX/dt,  X = 1 - exp(-theta^3),  dtheta/dt = K(T).
// (a) The scheme, written out: backward Euler T* = (C T_n + H dt T_a) /
//     (C + H dt), theta += K((T_n + T*) / 2) dt, T_n+1 = T* + L dX / c;
//     the run follows it to round-off (1e-9 K, 1e-12 in X).
// (b) The ODE, integrated here by RK4 at 1e-5 s: the largest errors in T
//     and X over 4 s halve with the step (ratios 1.8-2.2 from 0.02 to 0.01
//     to 0.005 s: first order, as the scheme without kinetics).
// (c) The heat: the stored change (mass x (c T - L X)) equals the heat
//     through the faces (relative 1e-12), and the latent heat holds the ply
//     warmer than the same run without kinetics.
TEST(Crystallisation, LumpedPlyCooledThroughItsCrystallisation) {
  const double Ta = 150.0, H = 1500.0, C = kRho * kC * kH, n = 3.0;
  auto job = [&](double dt, bool crystallising) {
    json j = ply_job("shell2d", 4, 4.0, 0.1);
    j["parts"][0]["initial_temperature"] = 260.0;
    if (crystallising) j["materials"]["ply"]["crystallisation"] = kinetics(n, kGaussian);
    j["solvers"]["thermal"]["dt"] = dt;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", Ta}},
                         {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 500.0}, {"ambient", Ta}}};
    if (crystallising) probe_both(j, 0.1);
    return j;
  };
  // The ODE by RK4 (T, theta), sampled every 0.1 s.
  std::vector<std::array<double, 2>> ode;  // T, X at 0, 0.1, ... 4 s
  {
    auto f = [&](const std::array<double, 2>& y) -> std::array<double, 2> {
      const double K = gaussian_rate(y[0]), th = y[1];
      const double dX = th > 0 ? n * std::pow(th, n - 1) * K * std::exp(-std::pow(th, n)) : 0.0;
      return {(-H * (y[0] - Ta) + kRho * kH * kLatent * dX) / C, K};
    };
    std::array<double, 2> y = {260.0, 0.0};
    const double h = 1e-5;
    const int per = 10000;
    ode.push_back({y[0], 0.0});
    for (int s = 1; s <= 40 * per; ++s) {
      const auto k1 = f(y);
      const auto k2 = f({y[0] + 0.5 * h * k1[0], y[1] + 0.5 * h * k1[1]});
      const auto k3 = f({y[0] + 0.5 * h * k2[0], y[1] + 0.5 * h * k2[1]});
      const auto k4 = f({y[0] + h * k3[0], y[1] + h * k3[1]});
      for (int d = 0; d < 2; ++d) y[d] += h / 6 * (k1[d] + 2 * k2[d] + 2 * k3[d] + k4[d]);
      if (s % per == 0) ode.push_back({y[0], 1.0 - std::exp(-std::pow(y[1], n))});
    }
  }
  std::vector<double> err_t, err_x;
  for (double dt : {0.02, 0.01, 0.005}) {
    const JobRun r = run_json(job(dt, true));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-12) << dt;
    EXPECT_LT(r.result.heat_in, -1.0);
    double T = 260.0, theta = 0, X = 0, t = 0, scheme_t = 0, scheme_x = 0, ode_t = 0, ode_x = 0;
    for (int k = 0; k <= 40; ++k) {
      const double ts = 0.1 * k;
      while (t < ts - 1e-9) {
        const double Ts = (C * T + H * dt * Ta) / (C + H * dt);
        theta += gaussian_rate(0.5 * (T + Ts)) * dt;
        const double x = 1.0 - std::exp(-std::pow(theta, n));
        T = Ts + kLatent * (x - X) / kC;
        X = x;
        t += dt;
      }
      const ProbeSample* st = r.sample(0, "temperature_profile", ts);
      const ProbeSample* sx = r.sample(0, "crystallinity_profile", ts);
      ASSERT_TRUE(st && sx);
      ASSERT_NEAR(st->time, ts, 1e-9);
      scheme_t = std::max(scheme_t, std::abs(st->values[0] - T));
      scheme_x = std::max(scheme_x, std::abs(sx->values[0] - X));
      ode_t = std::max(ode_t, std::abs(st->values[0] - ode[k][0]));
      ode_x = std::max(ode_x, std::abs(sx->values[0] - ode[k][1]));
    }
    EXPECT_LT(scheme_t, 1e-9) << dt;
    EXPECT_LT(scheme_x, 1e-12) << dt;
    err_t.push_back(ode_t);
    err_x.push_back(ode_x);
    std::printf("dt %.3f s: against the recursion %.1e K, %.1e; against the ODE %.4f K, %.5f in X\n", dt, scheme_t,
                scheme_x, ode_t, ode_x);
  }
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(err_t[k] / err_t[k + 1], 2.0, 0.2) << k;
    EXPECT_NEAR(err_x[k] / err_x[k + 1], 2.0, 0.2) << k;
  }
  // The crystallisation runs from 0.5 to 1 s (X 0.001 to 0.999), and its heat
  // holds the ply near 198 degC meanwhile.
  EXPECT_GT(ode.back()[1], 0.99);
  EXPECT_LT(ode[5][1], 0.002);
  EXPECT_GT(ode[10][1], 0.998);
  const JobRun plain = run_json(job(0.005, false));
  ASSERT_TRUE(plain.result.ok) << plain.result.error;
  const JobRun with = run_json(job(0.005, true));
  EXPECT_GT(with.sample(0, "temperature_profile", 0.8)->values[0],
            plain.sample(0, "temperature_profile", 0.8)->values[0] + 5.0);
  std::printf("at 0.8 s: %.2f degC crystallising, %.2f degC without kinetics (ODE %.2f)\n",
              with.sample(0, "temperature_profile", 0.8)->values[0],
              plain.sample(0, "temperature_profile", 0.8)->values[0], ode[8][0]);
}

// A slab crystallising from its cooled face: insulated at the bottom, Robin
// (h = 1000 W/(m^2 K), 150 degC) on top, from 260 degC, Gaussian rate,
// n = 3, 30 kJ/kg. The reference is written here independently: n cells
// of the thickness, explicit (rho c w dT_i/dt = sum of the fluxes at the
// cell's faces, k33 between values, h at the top; then theta_i += K(T_i)
// dt, X_i = 1 - exp(-theta_i^3), T_i += L dX_i / c) at 0.4 of the explicit
// limit, with 100 cells; 50 cells differ from it by under 0.01 K and 0.005
// in X (checked here).
struct CrystallisingSlabReference {
  int n = 50;
  std::vector<std::vector<double>> T_at, X_at;  // at t = 1, 2, ... s
  void run(int seconds) {
    const double e = kH / n, k = 0.31, h = 1000.0, Ta = 150.0;
    const double dt_limit = kRho * kC * 0.5 * e / (2 * k / e + h);
    const int per_second = static_cast<int>(std::ceil(1.0 / (0.4 * dt_limit)));
    const double dt = 1.0 / per_second;
    std::vector<double> T(n + 1, 260.0), theta(n + 1, 0.0), X(n + 1, 0.0), q(n + 1);
    for (int s = 1; s <= seconds * per_second; ++s) {
      slab_heat_flows(T, k, e, h, Ta, q);
      for (int i = 0; i <= n; ++i) {
        const double w = (i == 0 || i == n) ? 0.5 * e : e;
        theta[i] += gaussian_rate(T[i]) * dt;
        const double x = 1.0 - std::exp(-std::pow(theta[i], 3.0));
        T[i] += dt * q[i] / (kRho * kC * w) + kLatent * (x - X[i]) / kC;
        X[i] = x;
      }
      if (s % per_second == 0) {
        T_at.push_back(T);
        X_at.push_back(X);
      }
    }
  }
  static double interpolate(const std::vector<double>& v, int n, double z) {
    const double s = (z / kH + 0.5) * n;
    const int i = std::min(n - 1, static_cast<int>(s));
    return (1 - (s - i)) * v[i] + (s - i) * v[i + 1];
  }
  double temperature(int second, double z) const { return interpolate(T_at.at(second - 1), n, z); }
  double crystallinity(int second, double z) const { return interpolate(X_at.at(second - 1), n, z); }
};

// adi and layered3d (16 layers, both schemes, the step they choose) against
// the reference: temperatures within 1 % of the 110 K drop at every sample
// (as the constant-property profiles against the eigen-series), and the
// crystallinity within 0.03 (3 % of its range, the same share; where X
// moves fastest it gains 0.1 in 0.1 s here, so the implicit scheme's
// longer step alone is worth a few hundredths); the heat balance to
// round-off.
TEST(Crystallisation, SlabCrystallisingAgainstAFineReference) {
  CrystallisingSlabReference ref;
  ref.n = 100;
  ref.run(6);
  CrystallisingSlabReference coarse;
  coarse.n = 50;
  coarse.run(6);
  double ref_t = 0, ref_x = 0;
  for (int k = 1; k <= 6; ++k)
    for (int m = 0; m <= 16; ++m) {
      const double z = (m / 16.0 - 0.5) * kH;
      ref_t = std::max(ref_t, std::abs(ref.temperature(k, z) - coarse.temperature(k, z)));
      ref_x = std::max(ref_x, std::abs(ref.crystallinity(k, z) - coarse.crystallinity(k, z)));
    }
  std::printf("reference: 50 against 100 cells, largest difference %.4f K, %.5f in X\n", ref_t, ref_x);
  EXPECT_LT(ref_t, 0.01);
  EXPECT_LT(ref_x, 0.005);
  // The case: the top crystallises first, the bottom later, all within 6 s.
  EXPECT_LT(ref.crystallinity(1, -0.5 * kH), 0.5);
  EXPECT_GT(ref.crystallinity(6, -0.5 * kH), 0.9);
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    json j = ply_job(splitter, 16, 6.0, 1.0);
    j["parts"][0]["initial_temperature"] = 260.0;
    j["materials"]["ply"]["crystallisation"] = kinetics(3.0, kGaussian);
    j["solvers"]["thermal"]["through_thickness"] = scheme;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 150.0}}};
    probe_both(j, 1.0);
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-10) << splitter << " " << scheme;
    double worst_t = 0, worst_x = 0;
    for (int k = 1; k <= 6; ++k) {
      const ProbeSample* st = r.sample(0, "temperature_profile", k);
      const ProbeSample* sx = r.sample(0, "crystallinity_profile", k);
      ASSERT_TRUE(st && sx);
      for (std::size_t m = 0; m < st->z.size(); ++m) {
        worst_t = std::max(worst_t, std::abs(st->values[m] - ref.temperature(k, st->z[m])));
        worst_x = std::max(worst_x, std::abs(sx->values[m] - ref.crystallinity(k, sx->z[m])));
      }
    }
    EXPECT_LT(worst_t, 1.1) << splitter << " " << scheme;
    EXPECT_LT(worst_x, 0.03) << splitter << " " << scheme;
    std::printf("%s %s: largest error %.4f K, %.5f in X; X at 2 s bottom/top %.4f/%.4f (reference %.4f/%.4f)\n",
                splitter.c_str(), scheme.c_str(), worst_t, worst_x,
                r.sample(0, "crystallinity_profile", 2.0)->values.front(),
                r.sample(0, "crystallinity_profile", 2.0)->values.back(), ref.crystallinity(2, -0.5 * kH),
                ref.crystallinity(2, 0.5 * kH));
  }
}

// A process chain carries the crystallinity: a slab crystallising from its
// cooled face (adi, 8 layers, dt 0.01 s) to 2 s in one run (A), and from
// A's frame at 1 s for another second (B: initial_temperature from the
// results file, whose frames have the field crystallinity). B starts with
// A's crystallinity at 1 s (the same doubles) and ends within 1e-9 of A at
// 2 s in X and in T (theta is taken back from X, exact to round-off). A
// frame without the field starts from crystallisation.initial.
TEST(Crystallisation, CarriedFromAFrameOfAnEarlierRun) {
  auto job = [](double t_end) {
    json j = ply_job("adi", 8, t_end, 0.5);
    j["parts"][0]["initial_temperature"] = 260.0;
    j["materials"]["ply"]["crystallisation"] = kinetics(3.0, kGaussian);
    j["solvers"]["thermal"]["dt"] = 0.01;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 150.0}}};
    j["output"]["fields"] = {"temperature", "crystallinity"};
    probe_both(j, 0.5);
    return j;
  };
  const auto dir = temp_dir("crystallinity_from_run");
  const JobRun a = run_json(job(2.0), 1, dir / "a");
  ASSERT_TRUE(a.result.ok) << a.result.error;
  json jb = job(1.0);
  jb["parts"][0]["initial_temperature"] = {{"results", (dir / "a" / "results.h5").string()}, {"time", 1.0}};
  const JobRun b = run_json(jb);
  ASSERT_TRUE(b.result.ok) << b.result.error;
  const auto& a1 = a.sample(0, "crystallinity_profile", 1.0)->values;
  const auto& b0 = b.sample(0, "crystallinity_profile", 0.0)->values;
  const auto& a2 = a.sample(0, "crystallinity_profile", 2.0)->values;
  const auto& b1 = b.sample(0, "crystallinity_profile", 1.0)->values;
  const auto& ta2 = a.sample(0, "temperature_profile", 2.0)->values;
  const auto& tb1 = b.sample(0, "temperature_profile", 1.0)->values;
  ASSERT_EQ(b0.size(), 9u);
  double start = 0, end_x = 0, end_t = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    start = std::max(start, std::abs(b0[k] - a1[k]));
    end_x = std::max(end_x, std::abs(b1[k] - a2[k]));
    end_t = std::max(end_t, std::abs(tb1[k] - ta2[k]));
  }
  EXPECT_EQ(start, 0.0);
  EXPECT_LT(end_x, 1e-9);
  EXPECT_LT(end_t, 1e-9);
  EXPECT_GT(a1.back(), 0.5);  // the top has crystallised at 1 s, the bottom not yet
  EXPECT_LT(a1.front(), 0.5);
  EXPECT_GT(a2.front() - a1.front(), 0.1);  // and goes on after it
  std::printf("crystallinity from an earlier run's frame: start %.3g, after 1 s %.3g in X, %.3g K\n", start, end_x,
              end_t);
  // A frame without the field: crystallisation.initial.
  json jc = job(2.0);
  jc["output"]["fields"] = {"temperature"};
  ASSERT_TRUE(run_json(jc, 1, dir / "c").result.ok);
  json jd = jb;
  jd["parts"][0]["initial_temperature"]["results"] = (dir / "c" / "results.h5").string();
  jd["materials"]["ply"]["crystallisation"]["initial"] = 0.25;
  const JobRun d = run_json(jd);
  ASSERT_TRUE(d.result.ok) << d.result.error;
  for (double x : d.sample(0, "crystallinity_profile", 0.0)->values) EXPECT_EQ(x, 0.25);
}

// Melting: rows [T, s] of the share of the crystals still solid (PA66-like,
// from a DSC heating endotherm), and a rate that is zero above 160 degC, so
// that only the melting acts where these plies are.
const json kMelting = {{245.0, 1.0}, {255.0, 0.8}, {262.0, 0.3}, {268.0, 0.0}};
const json kRateBelow160 = {{150.0, 1.0}, {160.0, 0.0}};
double solid_share(double T) {
  const double rows[4][2] = {{245.0, 1.0}, {255.0, 0.8}, {262.0, 0.3}, {268.0, 0.0}};
  if (T <= rows[0][0]) return 1.0;
  if (T >= rows[3][0]) return 0.0;
  int k = 1;
  while (rows[k][0] < T) ++k;
  return rows[k - 1][1] + (T - rows[k - 1][0]) / (rows[k][0] - rows[k - 1][0]) * (rows[k][1] - rows[k - 1][1]);
}

// An adiabatic lumped ply (shell2d, no exchange) holding more crystals than
// survive at its temperature melts at its first step, down to the share
// still solid at the temperature its heat of melting leaves it at:
// X = s(T), T = T0 - a (X0 - X), a = L / c. With s linear from 1 at 250
// degC to 0 at 270 degC: partly from 262 degC and X0 = 0.9 (T = (T0 - a X0
// + 13.5 a) / (1 + a / 20)), wholly from 300 degC and X0 = 0.5 or 1 (T = T0
// - a X0), to round-off (1e-9 K, 1e-12 in X), and the state stays so (the
// crystallinity to the bit, the temperature to the splitter's round-off); the stored
// heat (mass x (c T - L X)) does not change. With a specific heat table
// (no closed form): X = s(T) and the stored heat unchanged, to round-off.
TEST(Crystallisation, MeltingAdiabaticPlyAgainstTheClosedForm) {
  const double a = kLatent / kC;
  struct Case {
    double T0, X0, T, X;
  };
  const double Tp = (262.0 - a * 0.9 + 13.5 * a) / (1.0 + a / 20.0);
  const Case cases[] = {{262.0, 0.9, Tp, (270.0 - Tp) / 20.0},
                        {300.0, 0.5, 300.0 - 0.5 * a, 0.0},
                        {300.0, 1.0, 300.0 - a, 0.0}};  // a consolidated blank, as crystalline as it gets
  ASSERT_GT(cases[0].X, 0.1);  // partly melted, inside the range
  ASSERT_LT(cases[0].X, 0.9);
  ASSERT_GT(cases[1].T, 270.0);  // wholly melted
  for (const Case& c : cases)
    for (bool table : {false, true}) {
      json j = ply_job("shell2d", 4, 1.0, 0.1);
      j["parts"][0]["initial_temperature"] = c.T0;
      json kin = kinetics(3.0, kRateBelow160);
      kin["initial"] = c.X0;
      kin["melting"] = {{250.0, 1.0}, {270.0, 0.0}};
      j["materials"]["ply"]["crystallisation"] = kin;
      if (table) j["materials"]["ply"]["specific_heat"] = {{200.0, 1500.0}, {300.0, 2100.0}};
      j["solvers"]["thermal"]["dt"] = 0.01;
      probe_both(j, 0.1);
      const JobRun r = run_json(j);
      ASSERT_TRUE(r.result.ok) << r.result.error;
      const double T1 = r.sample(0, "temperature_profile", 0.1)->values[0];
      const double X1 = r.sample(0, "crystallinity_profile", 0.1)->values[0];
      EXPECT_NEAR(r.sample(0, "temperature_profile", 1.0)->values[0], T1, 1e-9);
      EXPECT_EQ(r.sample(0, "crystallinity_profile", 1.0)->values[0], X1);
      EXPECT_LT(std::abs(r.result.stored_change), 1e-12 * kRho * kC * kH * 1e-4 * c.T0) << table;
      const double s = T1 >= 270.0 ? 0.0 : T1 <= 250.0 ? 1.0 : (270.0 - T1) / 20.0;
      EXPECT_NEAR(X1, s, 1e-12) << c.T0 << " " << table;
      if (!table) {
        EXPECT_NEAR(T1, c.T, 1e-9) << c.T0;
        EXPECT_NEAR(X1, c.X, 1e-12) << c.T0;
      } else {
        EXPECT_LT(T1, c.T0 - 2.0);  // the melting took its heat
      }
      std::printf("from %.0f degC, X0 = %.1f%s: T %.9f degC (closed form with a constant c %.9f), X %.12f (%.12f)\n", c.T0, c.X0,
                  table ? ", specific heat table" : "", T1, c.T, X1, c.X);
    }
}

// A lumped ply (shell2d) heated on both faces (H = 300 W/(m^2 K) from 320
// degC) from 200 degC with 60 % of its crystals (the melting rows above,
// 30 kJ/kg from X = 0 to 1):
//   rho c h dT/dt = H (T_a - T) + rho h L dX/dt,  X = min(X0, s(T)).
// In the enthalpy form e = c T - L X, de/dt = H (T_a - T) / (rho h), with T
// the root of c T - L min(X0, s(T)) = e; integrated here by RK4 at 1e-4 s.
// The run's largest errors in T and X over 6 s halve with the step (ratios
// 1.8-2.2 from 0.02 to 0.01 to 0.005 s: first order, as without melting);
// the heat balance holds to round-off; the melting holds the ply cooler
// than the same ply without crystals while it melts, and leaves none.
TEST(Crystallisation, LumpedPlyHeatedThroughItsMelting) {
  const double Ta = 320.0, H = 300.0, rho_h = kRho * kH, X0 = 0.6;
  const int samples = 60;  // every 0.1 s to 6 s
  auto job = [&](double dt, double initial) {
    json j = ply_job("shell2d", 4, 0.1 * samples, 0.1);
    j["parts"][0]["initial_temperature"] = 200.0;
    json kin = kinetics(3.0, kRateBelow160);
    kin["initial"] = initial;
    kin["melting"] = kMelting;
    j["materials"]["ply"]["crystallisation"] = kin;
    j["solvers"]["thermal"]["dt"] = dt;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 200.0}, {"ambient", Ta}},
                         {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 100.0}, {"ambient", Ta}}};
    probe_both(j, 0.1);
    return j;
  };
  auto temperature_of = [&](double e) {  // c T - L min(X0, s(T)) = e, increasing in T
    double lo = 0.0, hi = 1000.0;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (kC * mid - kLatent * std::min(X0, solid_share(mid)) < e ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  std::vector<std::array<double, 2>> ode;  // T, X at 0, 0.1, ... 6 s
  {
    double e = kC * 200.0 - kLatent * X0;
    auto f = [&](double ee) { return H * (Ta - temperature_of(ee)) / rho_h; };
    const double h = 1e-4;
    const int per = 1000;
    ode.push_back({200.0, X0});
    for (int s = 1; s <= samples * per; ++s) {
      const double k1 = f(e), k2 = f(e + 0.5 * h * k1), k3 = f(e + 0.5 * h * k2), k4 = f(e + h * k3);
      e += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      if (s % per == 0) {
        const double T = temperature_of(e);
        ode.push_back({T, std::min(X0, solid_share(T))});
      }
    }
  }
  std::vector<double> err_t, err_x;
  for (double dt : {0.02, 0.01, 0.005}) {
    const JobRun r = run_json(job(dt, X0));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-12) << dt;
    EXPECT_GT(r.result.heat_in, 1.0);
    double ode_t = 0, ode_x = 0, last_x = X0;
    for (int k = 0; k <= samples; ++k) {
      const ProbeSample* st = r.sample(0, "temperature_profile", 0.1 * k);
      const ProbeSample* sx = r.sample(0, "crystallinity_profile", 0.1 * k);
      ASSERT_TRUE(st && sx);
      ode_t = std::max(ode_t, std::abs(st->values[0] - ode[k][0]));
      ode_x = std::max(ode_x, std::abs(sx->values[0] - ode[k][1]));
      EXPECT_LE(sx->values[0], last_x);  // heated, it only melts
      last_x = sx->values[0];
    }
    EXPECT_EQ(last_x, 0.0);
    err_t.push_back(ode_t);
    err_x.push_back(ode_x);
    std::printf("dt %.3f s: against the ODE %.4f K, %.5f in X\n", dt, ode_t, ode_x);
  }
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(err_t[k] / err_t[k + 1], 2.0, 0.2) << k;
    EXPECT_NEAR(err_x[k] / err_x[k + 1], 2.0, 0.2) << k;
  }
  // The case: the ply melts over more than a second (from 245 to 268 degC),
  // and the heat of melting holds it cooler than a ply without crystals
  // meanwhile.
  int first = -1, last = -1;
  for (int k = 0; k <= samples; ++k) {
    if (first < 0 && ode[k][1] < X0) first = k;
    if (last < 0 && ode[k][1] == 0.0) last = k;
  }
  EXPECT_GT(first, 2);
  EXPECT_GT(last, first + 10);
  const JobRun with = run_json(job(0.005, X0));
  const JobRun without = run_json(job(0.005, 0.0));
  ASSERT_TRUE(without.result.ok) << without.result.error;
  const int mid = (first + last) / 2;
  const double tm = 0.1 * mid;
  EXPECT_LT(with.sample(0, "temperature_profile", tm)->values[0],
            without.sample(0, "temperature_profile", tm)->values[0] - 3.0);
  std::printf("melting from %.1f to %.1f s; at %.2f s %.2f degC melting, %.2f degC without crystals (ODE %.2f)\n",
              0.1 * first, 0.1 * last, tm, with.sample(0, "temperature_profile", tm)->values[0],
              without.sample(0, "temperature_profile", tm)->values[0], ode[mid][0]);
}

// Melted, a ply crystallises again from what is left: a lumped ply with
// the illustrative kinetics (Gaussian rate) and melting, 50 % crystalline
// at 200 degC, heated from 320 degC for 3 s (it first crystallises further
// on the way up, the rate being high near 200 degC, then melts entirely
// above 268 degC), then cooled to 150 degC for 5 s: it crystallises again
// as a melt would, as a ply that starts amorphous at the temperature it had
// at 3 s and is cooled the same way (within 1e-6 K and 1e-7 in X: the
// ambient's rows fall from 320 to 150 degC over 1 ns at 3 s, which puts
// the mean ambient of the step after it 8.5e-6 K above 150 degC, 1e-7 K on
// the ply). The heat balance holds to round-off throughout.
TEST(Crystallisation, MeltsAndCrystallisesAgainOnCooling) {
  auto job = [](double T0, double X0, const json& ambient, double t_end) {
    json j = ply_job("shell2d", 4, t_end, 0.1);
    j["parts"][0]["initial_temperature"] = T0;
    json kin = kinetics(3.0, kGaussian);
    kin["initial"] = X0;
    kin["melting"] = kMelting;
    j["materials"]["ply"]["crystallisation"] = kin;
    j["solvers"]["thermal"]["dt"] = 0.01;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", ambient}},
                         {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 500.0}, {"ambient", ambient}}};
    probe_both(j, 0.1);
    return j;
  };
  const JobRun r = run_json(job(200.0, 0.5, {{0.0, 320.0}, {3.0, 320.0}, {3.0 + 1e-9, 150.0}}, 8.0));
  ASSERT_TRUE(r.result.ok) << r.result.error;
  EXPECT_LT(r.result.heat_balance_error, 1e-12);
  double peak = 0;
  for (int k = 0; k <= 10; ++k) peak = std::max(peak, r.sample(0, "crystallinity_profile", 0.1 * k)->values[0]);
  EXPECT_GT(peak, 0.6);  // crystallised further on the way up
  const double T3 = r.sample(0, "temperature_profile", 3.0)->values[0];
  EXPECT_EQ(r.sample(0, "crystallinity_profile", 3.0)->values[0], 0.0);
  EXPECT_GT(T3, 300.0);
  const double X8 = r.sample(0, "crystallinity_profile", 8.0)->values[0];
  EXPECT_GT(X8, 0.99);
  // Against a melt at T3 cooled from 0 s for 5 s (the same steps: the ambient
  // rows of the first run are at 150 degC from 3 s on).
  const JobRun m = run_json(job(T3, 0.0, 150.0, 5.0));
  ASSERT_TRUE(m.result.ok) << m.result.error;
  double worst_x = 0, worst_t = 0;
  for (int k = 1; k <= 50; ++k) {
    worst_x = std::max(worst_x, std::abs(r.sample(0, "crystallinity_profile", 3.0 + 0.1 * k)->values[0] -
                                         m.sample(0, "crystallinity_profile", 0.1 * k)->values[0]));
    worst_t = std::max(worst_t, std::abs(r.sample(0, "temperature_profile", 3.0 + 0.1 * k)->values[0] -
                                         m.sample(0, "temperature_profile", 0.1 * k)->values[0]));
  }
  EXPECT_LT(worst_x, 1e-7);
  EXPECT_LT(worst_t, 1e-6);
  std::printf("largest X on the way up %.4f; at 3 s %.2f degC, X 0; at 8 s X %.6f; against a melt cooled from "
              "3 s: %.2e in X, %.2e K\n", peak, T3, X8, worst_x, worst_t);
}

// Heated, melting by rows s(T) is the model of an apparent specific heat
// with the melting as its peak, c + L (-ds/dT). A lumped ply (shell2d),
// fully crystalline (initial 1), heated from 230 degC by H = 300 W/(m^2 K)
// from 320 degC: (a) c = 1775 J/(kg K) with a triangular peak of 30 kJ/kg
// between 250 and 270 degC (a specific heat table), (b) c = 1775 and
// melting rows of that peak's cumulative share, s(T) = 1 - int_250^T (c -
// 1775) / L, every 0.5 K. Both schemes come to H(T_new) = H(T_old) + c (T*
// - T_old) (T* the splitter's value), so they differ only by the rows'
// linear interpolation of the quadratic cumulative: at most L h^2 |s''| /
// (8 c) = 0.0053 K (h = 0.5 K, s'' = 0.01 /K^2). Every sample within 0.01 K.
TEST(Crystallisation, MeltingRowsAgainstTheEquivalentSpecificHeatPeak) {
  auto job = [](bool table) {
    json j = ply_job("shell2d", 4, 6.0, 0.1);
    j["parts"][0]["initial_temperature"] = 230.0;
    if (table) {
      j["materials"]["ply"]["specific_heat"] = {{250.0, 1775.0}, {260.0, 4775.0}, {270.0, 1775.0}};
    } else {
      json rows = json::array();
      for (int k = 0; k <= 40; ++k) {
        const double T = 250.0 + 0.5 * k, d = T - 250.0;
        // the peak's area from 250 degC to T (J/kg), 300 J/(kg K^2) up and down
        const double area = d <= 10.0 ? 150.0 * d * d : 15000.0 + 3000.0 * (d - 10.0) - 150.0 * (d - 10.0) * (d - 10.0);
        rows.push_back({T, k == 40 ? 0.0 : 1.0 - area / kLatent});
      }
      json kin = kinetics(3.0, kRateBelow160);
      kin["initial"] = 1.0;
      kin["melting"] = rows;
      j["materials"]["ply"]["crystallisation"] = kin;
    }
    j["solvers"]["thermal"]["dt"] = 0.01;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 200.0}, {"ambient", 320.0}},
                         {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", 100.0}, {"ambient", 320.0}}};
    return j;
  };
  const JobRun a = run_json(job(true)), b = run_json(job(false));
  ASSERT_TRUE(a.result.ok) << a.result.error;
  ASSERT_TRUE(b.result.ok) << b.result.error;
  double worst = 0;
  for (int k = 0; k <= 60; ++k)
    worst = std::max(worst, std::abs(a.sample(0, "temperature_profile", 0.1 * k)->values[0] -
                                     b.sample(0, "temperature_profile", 0.1 * k)->values[0]));
  EXPECT_LT(worst, 0.01);
  // The case crosses the peak: from below 250 to above 270 degC.
  EXPECT_GT(a.sample(0, "temperature_profile", 6.0)->values[0], 272.0);
  EXPECT_LT(b.result.heat_balance_error, 1e-12);
  std::printf("specific heat peak against melting rows: largest difference %.4f K; at 6 s %.4f degC\n", worst,
              a.sample(0, "temperature_profile", 6.0)->values[0]);
}

}  // namespace
}  // namespace ts::test
