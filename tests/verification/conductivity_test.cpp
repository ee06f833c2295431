// Verification of the temperature-dependent conductivity
// (materials.*.conductivity as rows [T, k11, k22, k33]): a steady slab
// against its closed form (Kirchhoff transform), a cooled slab against an
// independent fine reference, and in-plane diffusion against the exact
// decay of a mode. Each tolerance is stated with its reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "io/logging.hpp"
#include "job/job.hpp"
#include "plugins/registry.hpp"
#include "solve/simulation.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

constexpr double kRho = 1294.0, kC = 1775.0, kH = 0.0005;

// k33 linear between two rows, held beyond them; its integral
// K(T) = int_{t0}^{T} k33 (the Kirchhoff transform) and the inverse.
struct LinearK {
  double t0, k0, t1, k1;
  double slope() const { return (k1 - k0) / (t1 - t0); }
  double k(double T) const { return T <= t0 ? k0 : T >= t1 ? k1 : k0 + slope() * (T - t0); }
  double K(double T) const {
    if (T <= t0) return k0 * (T - t0);
    const double s = std::min(T, t1) - t0;
    return k0 * s + 0.5 * slope() * s * s + (T > t1 ? k1 * (T - t1) : 0.0);
  }
  double inverse(double Kv) const {
    if (Kv <= 0) return t0 + Kv / k0;
    const double top = K(t1);
    if (Kv >= top) return t1 + (Kv - top) / k1;
    const double a = 0.5 * slope();  // a s^2 + k0 s = Kv
    return t0 + 2.0 * Kv / (k0 + std::sqrt(k0 * k0 + 4.0 * a * Kv));
  }
  json rows(double k11 = 3.89, double k22 = 0.31) const { return {{t0, k11, k22, k0}, {t1, k11, k22, k1}}; }
};

// A steady slab between two Robin faces, k33 linear in T: the flux q is the
// same through every layer, (K(T_j) - K(T_j+1)) / e. The splitters take
// k33 at the mean of a layer's two values, (k(T_j) + k(T_j+1)) / 2, which
// for a linear k times (T_j - T_j+1) / e is exactly that flux: the discrete
// steady state is exact at the nodes, and so are the face values. Closed
// form: q = h_b (T_b - T_amb,b) = h_t (T_amb,t - T_t) = (K(T_t) - K(T_b)) / h,
// solved for T_b by bisection; T(z) = K^-1(K(T_b) + q (z + h/2)).
// The run starts at 300 degC and lasts 30 s, some 30 of the slab's time
// constants (about 1 s): the transient is below 1e-10 K. Tolerance 1e-8 K
// (the conjugate gradients of layered3d stop at 1e-13 of the residual).
TEST(ConductivityTable, SteadySlabExactAtTheNodes) {
  const LinearK k{200.0, 0.2, 320.0, 0.5};
  const double hb = 1000.0, Tb_amb = 200.0, ht = 2000.0, Tt_amb = 320.0;
  auto top_of = [&](double Tb) {
    const double q = hb * (Tb - Tb_amb);
    return std::make_pair(q, k.inverse(k.K(Tb) + q * kH));
  };
  double lo = Tb_amb, hi = Tt_amb;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    const auto [q, Tt] = top_of(mid);
    (ht * (Tt_amb - Tt) - q > 0 ? lo : hi) = mid;
  }
  const double Tb = 0.5 * (lo + hi);
  const double q = top_of(Tb).first;
  auto exact = [&](double z) { return k.inverse(k.K(Tb) + q * (z + 0.5 * kH)); };
  std::printf("closed form: faces %.6f / %.6f degC, flux %.2f W/m^2\n", Tb, exact(0.5 * kH), q);
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    json j = ply_job(splitter, 16, 30.0, 10.0);
    j["materials"]["ply"]["conductivity"] = k.rows();
    j["solvers"]["thermal"]["through_thickness"] = scheme;
    j["interactions"] = {
        {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "bottom"}, {"h", hb}, {"ambient", Tb_amb}},
        {{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", ht}, {"ambient", Tt_amb}}};
    const JobRun r = run_json(j);
    ASSERT_TRUE(r.result.ok) << r.result.error;
    const ProbeSample* s = r.sample(0, "temperature_profile", 30.0);
    ASSERT_NE(s, nullptr);
    double err = 0;
    for (std::size_t m = 0; m < s->z.size(); ++m) err = std::max(err, std::abs(s->values[m] - exact(s->z[m])));
    std::printf("%s %s: largest error at the nodes %.3g K\n", splitter.c_str(), scheme.c_str(), err);
    EXPECT_LT(err, 1e-8) << splitter << " " << scheme;
    // With k33 constant at the table's mean the profile is a straight line:
    // the table's curvature is what the test sees (several kelvin here).
    const double mid = s->values[s->values.size() / 2];
    EXPECT_GT(std::abs(mid - 0.5 * (s->values.front() + s->values.back())), 1.0);
  }
}

// A slab cooled through its top (h = 1000 W/(m^2 K), 200 degC) from 300
// degC, insulated below, k33 from 0.2 W/(m K) at 200 degC to 0.5 at 300.
// The reference is written here independently: n cells of the thickness,
// explicit, the flux between two nodes (K(T_i) - K(T_i+1)) / e (exact for
// any k(T) between them), at 0.4 of the explicit limit with the largest k;
// 25 and 50 cells agree within 0.02 K (checked here). Tolerance: 1 % of
// the 100 K drop at every sample, as for the constant properties
// (EigenSeries.ProfileWithin1PercentOfDrop). The runs with k33 constant at
// either end of the table are off by more than 5 K: the test sees the
// table.
struct VaryingKSlabReference {
  int n = 50;
  LinearK k{200.0, 0.2, 300.0, 0.5};
  std::vector<std::vector<double>> profiles;  // at t = 1, 2, ... s
  void run(int seconds) {
    const double e = kH / n, h = 1000.0, Ta = 200.0;
    const double dt_limit = kRho * kC * 0.5 * e / (2 * k.k1 / e + h);
    const int per_second = static_cast<int>(std::ceil(1.0 / (0.4 * dt_limit)));
    const double dt = 1.0 / per_second;
    std::vector<double> T(n + 1, 300.0), q(n + 1);
    for (int s = 1; s <= seconds * per_second; ++s) {
      std::fill(q.begin(), q.end(), 0.0);
      for (int i = 0; i < n; ++i) {
        const double f = (k.K(T[i + 1]) - k.K(T[i])) / e;  // W/m^2 from i + 1 into i
        q[i] += f;
        q[i + 1] -= f;
      }
      q[n] += h * (Ta - T[n]);
      for (int i = 0; i <= n; ++i) T[i] += dt * q[i] / (kRho * kC * ((i == 0 || i == n) ? 0.5 * e : e));
      if (s % per_second == 0) profiles.push_back(T);
    }
  }
  double at(int second, double z) const { return profile_at(profiles.at(second - 1), kH, z); }  // z from -h/2 to h/2
};

TEST(ConductivityTable, CooledSlabAgainstAFineReference) {
  VaryingKSlabReference ref;
  ref.run(6);
  VaryingKSlabReference coarse;
  coarse.n = 25;
  coarse.run(6);
  const double ref_change = largest_difference(ref.profiles, coarse.profiles, kH);
  std::printf("reference: 25 against 50 cells, largest difference %.4f K\n", ref_change);
  EXPECT_LT(ref_change, 0.02);
  auto job = [&](const std::string& splitter, const std::string& scheme, const json& conductivity) {
    json j = ply_job(splitter, 16, 6.0, 1.0);
    j["materials"]["ply"]["conductivity"] = conductivity;
    j["solvers"]["thermal"]["through_thickness"] = scheme;
    j["interactions"] = {{{"type", "heat_exchange"}, {"part", "ply"}, {"face", "top"}, {"h", 1000.0}, {"ambient", 200.0}}};
    return j;
  };
  auto worst = [&](const JobRun& r) {
    double err = 0;
    for (int t = 1; t <= 6; ++t) {
      const ProbeSample* s = r.sample(0, "temperature_profile", t);
      for (std::size_t m = 0; m < s->z.size(); ++m) err = std::max(err, std::abs(s->values[m] - ref.at(t, s->z[m])));
    }
    return err;
  };
  for (const auto& [splitter, scheme] : std::vector<std::pair<std::string, std::string>>{
           {"adi", "implicit"}, {"adi", "explicit"}, {"layered3d", "implicit"}, {"layered3d", "explicit"}}) {
    const JobRun r = run_json(job(splitter, scheme, ref.k.rows()));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    EXPECT_LT(r.result.heat_balance_error, 1e-10) << splitter << " " << scheme;
    const double err = worst(r);
    EXPECT_LT(err, 1.0) << splitter << " " << scheme;
    std::printf("%s %s: largest error %.4f K; top face at 3 s %.3f degC (reference %.3f)\n", splitter.c_str(),
                scheme.c_str(), err, r.sample(0, "temperature_profile", 3.0)->values.back(), ref.at(3, 0.5 * kH));
  }
  for (double k33 : {0.2, 0.5}) {
    const JobRun r = run_json(job("adi", "implicit", {3.89, 0.31, k33}));
    ASSERT_TRUE(r.result.ok) << r.result.error;
    std::printf("k33 constant at %.1f W/(m K): largest difference %.3f K\n", k33, worst(r));
    EXPECT_GT(worst(r), 5.0);
  }
}

// Two plies on a die (300 degC plies, 260 degC die, 1000 W/(m^2 K)), joined
// by a ply/ply conductance of 300 W/(m^2 K), uniform in plane: adi's rods
// joined by links (the interface system with every rod's own factors) and
// layered3d's one 3D system (conjugate gradients) discretise the same
// problem the same way through the thickness, and without in-plane
// gradients the split adds nothing: they must agree to the solvers'
// tolerance, 1e-8 K (5e-11 K here), while the table moves the
// profiles by more than 0.5 K from the constant k33 of its largest value.
TEST(ConductivityTable, LinkedPliesAdiAgainstLayered3d) {
  auto job = [](const std::string& splitter, bool table) {
    json j = two_ply_job(splitter, 12, 300.0);
    j["materials"]["ply"]["conductivity"] =
        table ? json{{260.0, 3.89, 0.31, 0.15}, {300.0, 3.89, 0.31, 0.45}} : json{3.89, 0.31, 0.45};
    j["solvers"]["thermal"]["dt"] = 0.01;
    return j;
  };
  const JobRun adi = run_json(job("adi", true)), l3d = run_json(job("layered3d", true)), flat = run_json(job("adi", false));
  for (const JobRun* r : {&adi, &l3d, &flat}) ASSERT_TRUE(r->result.ok) << r->result.error;
  double diff = 0, moved = 0;
  for (std::size_t s = 0; s < adi.result.probes.size(); ++s)
    for (std::size_t k = 0; k < adi.result.probes[s].values.size(); ++k) {
      diff = std::max(diff, std::abs(adi.result.probes[s].values[k] - l3d.result.probes[s].values[k]));
      moved = std::max(moved, std::abs(adi.result.probes[s].values[k] - flat.result.probes[s].values[k]));
    }
  std::printf("adi against layered3d: %.3g K; the table against k33 = 0.45: %.3f K\n", diff, moved);
  EXPECT_LT(diff, 1e-8);
  EXPECT_GT(moved, 0.5);
  EXPECT_LT(adi.result.heat_balance_error, 1e-10);
}

// In-plane: with c(T) and k(T) in proportion, c = c0 f(T), k = k0 f(T),
// the Kirchhoff variable u = int_T0^T f satisfies the linear diffusion
// equation with the diffusivity of (k0, c0): a cosine mode of u decays at
// k_eff pi^2 / (rho c0 L^2), exactly as the constant-property mode of
// InPlane.AnisotropicCosineDecayRate (fibres at 30 degrees on the
// parallelogram that follows its level lines). f = 1 + (T - 300) / 100,
// the mode's amplitude 10 K in u: k and c vary by -10 % to +10 % over the
// ply. Tolerance 1 %, as the constant-property test: the same mesh and
// steps; the coefficients lagged by one step and the element's mean of its
// nodes' k add errors of order dt and (element size)^2, well below it.
TEST(ConductivityTable, InPlaneModeWithProportionalTables) {
  const double k11 = 3.89, k22 = 0.31, th = 30.0 * M_PI / 180.0;
  const double c = std::cos(th), s = std::sin(th);
  const double kxx = k11 * c * c + k22 * s * s, kyy = k11 * s * s + k22 * c * c, kxy = (k11 - k22) * s * c;
  const double slant = kxy / kyy, keff = kxx - kxy * kxy / kyy;
  const double L = 0.02, W = 0.01, amp = 10.0;
  constexpr double beta = 0.01;
  auto f = [](double T) { return 1.0 + beta * (T - 300.0); };
  double (*U)(double) = [](double T) { return (T - 300.0) + 0.5 * beta * (T - 300.0) * (T - 300.0); };
  double (*U_inverse)(double) = [](double u) { return 300.0 + 2.0 * u / (1.0 + std::sqrt(1.0 + 2.0 * beta * u)); };
  const auto dir = temp_dir("inplane_k_table");
  write_parallelogram(dir / "para.msh", L, W, slant, 40, 20);
  for (const std::string name : {"adi", "adi_layers", "layered3d", "shell2d"}) {
    const std::string splitter = name == "adi_layers" ? "adi" : name;
    json j = ply_job(splitter, 4, 20.0, 5.0);
    j["parts"][0]["mesh"] = {{"file", (dir / "para.msh").string()}};
    j["parts"][0]["fibre_direction"] = {c, s, 0.0};
    j["output"]["probes"] = json::array();
    j["materials"]["ply"]["specific_heat"] = {{250.0, kC * f(250.0)}, {350.0, kC * f(350.0)}};
    j["materials"]["ply"]["conductivity"] = {{250.0, k11 * f(250.0), k22 * f(250.0), 0.31 * f(250.0)},
                                             {350.0, k11 * f(350.0), k22 * f(350.0), 0.31 * f(350.0)}};
    if (name == "adi_layers") j["solvers"]["thermal"]["in_plane"] = "layers";
    RunResult r;
    const double rate = mode_decay_rate(j, dir, L, slant, amp, U_inverse, U, &r);
    ASSERT_TRUE(r.ok) << r.error;
    const double exact = keff * M_PI * M_PI / (kRho * kC * L * L);
    std::printf("%s: decay rate of u %.6g 1/s, exact %.6g 1/s, error %.3f %%\n", name.c_str(), rate, exact,
                100 * (rate / exact - 1));
    EXPECT_NEAR(rate / exact, 1.0, 0.01) << name;
    // Insulated: the stored heat (some 70 J) stays to round-off.
    EXPECT_LT(std::abs(r.stored_change), 1e-9) << name;
  }
}

}  // namespace
}  // namespace ts::test
