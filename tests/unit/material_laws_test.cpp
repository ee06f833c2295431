// Material law plugins, loaded through the registry as a job would load
// them: stresses against finite-difference derivatives of the energy,
// rigid rotations, the transverse invariant under shear, the Prony-series
// relaxation against closed forms, and bad parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <span>
#include <vector>

#include <thermostamp/sdk/fd_check.hpp>
#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/prony.hpp>

#include "plugins/registry.hpp"

namespace ts {
namespace {

struct Law {
  PluginRegistry registry;
  std::unique_ptr<sdk::MaterialLaw> law;
  sdk::Status status;
  Law(const std::string& name, const json& params) {
    const auto& rec = registry.require(sdk::PluginKind::Material, name, "/materials/m/membrane/law");
    const sdk::Params p = validate_params(params, "/materials/m/membrane", rec.descriptor, {"law"});
    law.reset(reinterpret_cast<sdk::MaterialLaw* (*)()>(rec.create)());
    status = law->configure(p);
  }
};

// Card values (share/materials): N/mm converted to N/m.
const json kWoven = {{"k_warp", 1.0e5}, {"k_weft", 1.0e5}, {"k_sh", {18.5, 46.4, -21.3}}};
const json kUd = {{"k_fibre", 5.0e6}, {"p_ct", 50.0}, {"k_sh", {18.5, 46.4, -21.3}}};
const json kVisco = {{"k_sh", {18.5, 46.4, -21.3}}, {"omega_slope_below", -0.02}, {"omega_slope_above", -0.01},
                     {"g", {0.5, 0.3}}, {"tau", {0.2, 2.0}}};
const json kBending = {{"beta1_T", -2.0e-5}, {"beta1_B", 6.4e-3}, {"beta2_T", -2.0e-6}, {"beta2_B", 6.4e-4},
                       {"twist_ratio", 0.1}};

sdk::Sym2 cauchy_green(double f00, double f01, double f10, double f11) {
  return {f00 * f00 + f10 * f10, f01 * f01 + f11 * f11, f00 * f01 + f10 * f11};
}

// A block of T.size() points: strains C (also given as the previous
// strains), temperatures T, step dt, state, and the outputs S and W (W may
// be empty).
sdk::MaterialBlock block_of(std::span<const double> C, std::span<const double> T, std::span<double> S,
                            std::span<double> W = {}, std::span<double> state = {}, double dt = 0.0) {
  sdk::MaterialBlock b;
  b.n = T.size();
  b.strain = C;
  b.strain_old = C;
  b.temperature = T;
  b.dt = dt;
  b.state = state;
  b.stress = S;
  b.energy = W;
  return b;
}

// S = 2 dw/dC to 1e-6 relative at random deformations (central differences
// with step 1e-6 have a truncation error ~1e-12 and a round-off ~1e-10
// relative here, so 1e-6 leaves room only for a wrong derivative).
TEST(MaterialLaws, StressIsTheDerivativeOfTheEnergy) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3), temp(240.0, 330.0);
  for (const auto& [name, params] : std::vector<std::pair<std::string, json>>{
           {"woven_hyperelastic", kWoven}, {"ud_hyperelastic", kUd}, {"viscoelastic_shear", kVisco},
           {"thermo_linear_bending", kBending}}) {
    Law l(name, params);
    ASSERT_TRUE(l.status.ok) << l.status.message;
    for (int trial = 0; trial < 50; ++trial) {
      sdk::Sym2 e = name == "thermo_linear_bending" ? sdk::Sym2{u(rng) * 50, u(rng) * 50, u(rng) * 50}
                                                     : cauchy_green(1 + u(rng), u(rng), u(rng), 1 + u(rng));
      sdk::Sym2 dir2 = {0.0, 1.0, 0.0};
      if (name == "woven_hyperelastic") {  // a sheared initial weft direction too
        const double a = 1.3 + 0.3 * u(rng);
        dir2 = {std::cos(a), std::sin(a), 0.0};
      }
      const auto r = sdk::fd_check(*l.law, e, temp(rng), 1e-6, dir2);
      EXPECT_LT(r.max_relative_error, 1e-6) << name << " trial " << trial;
    }
  }
}

// Any rigid rotation leaves C = I: no stress, no energy.
TEST(MaterialLaws, RigidRotationsAreStressFree) {
  for (const auto& [name, params] : std::vector<std::pair<std::string, json>>{
           {"woven_hyperelastic", kWoven}, {"ud_hyperelastic", kUd}, {"viscoelastic_shear", kVisco}}) {
    Law l(name, params);
    for (double th = 0; th < 6.3; th += 0.7) {
      const double c = std::cos(th), s = std::sin(th);
      const auto r = sdk::fd_check(*l.law, cauchy_green(c, -s, s, c), 280.0);
      for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(r.stress[k]), 1e-9) << name << " theta " << th;
    }
  }
}

// Shear at constant area with inextensible fibres: I_lt = 0 exactly, while
// I_sh = sin(gamma) grows; the UD transverse term stores nothing.
TEST(MaterialLaws, TransverseInvariantIgnoresShear) {
  Law l("ud_hyperelastic", {{"k_fibre", 5.0e6}, {"p_ct", 50.0}});
  for (double g : {0.1, 0.5, 1.0, 2.0}) {
    const sdk::Sym2 C = cauchy_green(1.0, g, 0.0, 1.0);  // F = [[1, g], [0, 1]], det F = 1
    const auto v = sdk::invariants(C);
    EXPECT_NEAR(v.lt, 0.0, 1e-15);
    EXPECT_NEAR(v.sh, g / std::sqrt(1 + g * g), 1e-15);
    const auto r = sdk::fd_check(*l.law, C, 280.0);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.stress[k], 0.0, 1e-9);
  }
}

// ud_hyperelastic evaluates a block in one vector pass, by series for the
// logarithms near 1, and again point by point (library logarithms) where an
// elongation is beyond the series' range. A block mixing both, against the
// SDK's invariants point by point: the two differ only in the order of a
// few operations (2e-15, ten roundings, leaves room for that, not for a
// wrong term).
TEST(MaterialLaws, UdBlockMatchesPointwiseInvariants) {
  const double kf = 5.0e6, pct = 50.0, ksh[3] = {18.5, 46.4, -21.3};
  Law l("ud_hyperelastic", {{"k_fibre", kf}, {"p_ct", pct}, {"k_sh", {ksh[0], ksh[1], ksh[2]}}});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 203;
  std::vector<double> C(3 * n), S(3 * n), W(n), T(n, 280.0);
  for (int q = 0; q < n; ++q) {
    const double s = q % 3 == 0 ? 0.2 : 0.002;  // two in three within the series' range
    const sdk::Sym2 c = cauchy_green(1 + s * u(rng), s * u(rng), s * u(rng), 1 + s * u(rng));
    for (int k = 0; k < 3; ++k) C[3 * q + k] = c[k];
  }
  ASSERT_TRUE(l.law->evaluate(block_of(C, T, S, W)).ok);
  double worst = 0;
  for (int q = 0; q < n; ++q) {
    const auto v = sdk::invariants({C[3 * q], C[3 * q + 1], C[3 * q + 2]}, {}, sdk::kE1 | sdk::kLt | sdk::kSh);
    double wsh, dwsh;
    sdk::even_polynomial(ksh, 3, v.sh, &wsh, &dwsh);
    sdk::Sym2 ref{0, 0, 0};
    sdk::add_stress(ref, 2 * kf * v.e1, v.de1);
    sdk::add_stress(ref, 2 * pct * v.lt, v.dlt);
    sdk::add_stress(ref, dwsh, v.dsh);
    const double scale = std::max({std::abs(ref[0]), std::abs(ref[1]), std::abs(ref[2])});
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(S[3 * q + k] - ref[k]) / scale);
    const double w = kf * v.e1 * v.e1 + pct * v.lt * v.lt + wsh;
    worst = std::max(worst, std::abs(W[q] - w) / std::abs(w));
  }
  EXPECT_LT(worst, 2e-15);
  std::printf("ud_hyperelastic block against pointwise invariants: largest relative difference %.3g\n", worst);
}

// Points whose strains are beyond the first vector pass's series (C11 - 1
// or det C / C11 - 1 beyond 1e-2, common across the fibres in forming) are
// evaluated again in a second vector pass, with ln(1 + x) within 0.25 by
// log1p_wide, and beyond that with the library's logarithm. The energies
// of points on both sides of 0.25 against long-double logarithms of the
// same arguments: within 6 units in the last place (w = k_f I_e1^2 +
// p_ct I_lt^2, each logarithm within a unit, then squares, products and a
// sum; the library's logarithm everywhere gives 5.3e-16 here, log1p_wide
// 4.1e-16, a wrong coefficient of its series 5e-14).
TEST(MaterialLaws, UdWideStrainsMatchLongDoubleLogarithms) {
  const double kf = 5.0e6, pct = 50.0;
  Law l("ud_hyperelastic", {{"k_fibre", kf}, {"p_ct", pct}});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  const int n = 400;
  std::vector<double> C(3 * n), S(3 * n), W(n), T(n, 280.0);
  for (int q = 0; q < n; ++q) {
    // C11 = 1 + xa, det C / C11 = 1 + xt, C12 small: one of xa, xt at
    // most 1e-2 in every fourth point
    const double xa = q % 4 == 0 ? 0.005 * u(rng) : u(rng), xt = u(rng), c = 0.01 * u(rng);
    const double a = 1 + xa, b = (1 + xt) + c * c / a;
    C[3 * q] = a, C[3 * q + 1] = b, C[3 * q + 2] = c;
  }
  ASSERT_TRUE(l.law->evaluate(block_of(C, T, S, W)).ok);
  double worst = 0;
  int wide = 0;
  for (int q = 0; q < n; ++q) {
    const double a = C[3 * q], b = C[3 * q + 1], c = C[3 * q + 2];
    const double i3 = a * b - c * c, y = i3 / a;  // the arguments as the law forms them
    const long double e1 = 0.5L * logl(a), lt = 0.5L * logl(y);
    const long double w = kf * e1 * e1 + pct * lt * lt;
    worst = std::max(worst, static_cast<double>(fabsl(W[q] - w) / w));
    wide += std::abs(a - 1) < 0.25 && std::abs(a - 1) >= 1e-2;
  }
  EXPECT_GT(wide, n / 2);
  EXPECT_LT(worst, 6 * 1.1102230246251565e-16);
  std::printf("ud_hyperelastic beyond 1e-2: largest relative difference of w from long-double logarithms %.3g "
              "(%d points)\n", worst, n);
}

// Without shear coefficients (all +0, the UD card's case: viscoelastic_shear
// carries the shear) ud_hyperelastic leaves the shear terms out. Each of
// them is a signed zero there, so the stresses and energies must be the
// same bits, signs of zeros included, as with the terms: k_sh = (0, 0, -0)
// keeps them (a -0 coefficient) and gives the same values. Points in and
// beyond the series' range, at rest, and with C12 = +0 or -0 under
// transverse strain (where a left-out term would change the sign of a zero).
TEST(MaterialLaws, UdWithoutShearGivesTheSameBits) {
  Law without("ud_hyperelastic", {{"k_fibre", 5.0e6}, {"p_ct", 50.0}, {"k_sh", {0.0, 0.0, 0.0}}});
  Law with("ud_hyperelastic", {{"k_fibre", 5.0e6}, {"p_ct", 50.0}, {"k_sh", {0.0, 0.0, -0.0}}});
  ASSERT_TRUE(without.status.ok);
  ASSERT_TRUE(with.status.ok);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 211;
  std::vector<double> C(3 * n), T(n, 280.0);
  for (int q = 0; q < n; ++q) {
    sdk::Sym2 c;
    if (q % 7 == 0) {
      c = {1.0, 1.0, 0.0};  // at rest
    } else if (q % 7 == 1) {
      c = {1.0 + 0.001 * u(rng), 1.0 + 0.004 * std::abs(u(rng)) + 1e-4, q % 2 ? 0.0 : -0.0};  // C12 = +-0
    } else {
      const double s = q % 3 == 0 ? 0.2 : 0.002;  // in and beyond the series' range
      c = cauchy_green(1 + s * u(rng), s * u(rng), s * u(rng), 1 + s * u(rng));
    }
    for (int k = 0; k < 3; ++k) C[3 * q + k] = c[k];
  }
  std::vector<double> Sa(3 * n), Wa(n), Sb(3 * n), Wb(n);
  ASSERT_TRUE(without.law->evaluate(block_of(C, T, Sa, Wa)).ok);
  ASSERT_TRUE(with.law->evaluate(block_of(C, T, Sb, Wb)).ok);
  int differ = 0, zeros = 0;
  for (int i = 0; i < 3 * n; ++i) differ += std::memcmp(&Sa[i], &Sb[i], sizeof(double)) != 0;
  for (int q = 0; q < n; ++q) differ += std::memcmp(&Wa[q], &Wb[q], sizeof(double)) != 0;
  EXPECT_EQ(differ, 0);
  // With C12 = +0 under transverse strain, S12's own term is -0 and the
  // shear term +0: their sum is +0.
  for (int q = 1; q < n; q += 7)
    if (!std::signbit(C[3 * q + 2])) {
      EXPECT_EQ(Sa[3 * q + 2], 0.0);
      EXPECT_FALSE(std::signbit(Sa[3 * q + 2])) << "point " << q;
      ++zeros;
    }
  EXPECT_GT(zeros, 10);
}

// Shear stress history of the viscoelastic law for F = [[1, gamma(t)], [0, 1]].
struct ShearHistory {
  const sdk::MaterialLaw& law;
  double T;
  std::vector<double> state;
  explicit ShearHistory(const sdk::MaterialLaw& l, double temperature)
      : law(l), T(temperature), state(l.state_size(), 0.0) {}
  double step(double gamma, double dt) {
    const sdk::Sym2 C = cauchy_green(1.0, gamma, 0.0, 1.0);
    double stress[3], t[1] = {T};
    law.evaluate(block_of(std::span<const double>(C.data(), 3), std::span<const double>(t, 1), std::span<double>(stress, 3),
                          {}, state, dt));
    return stress[2];
  }
};

// Closed form: S(t) = g_inf S0(t) + sum_i g_i int_0^t exp(-(t-s)/tau_i) dS0/ds ds,
// by midpoint quadrature on 20000 sub-intervals (S0 from the same law with
// no relaxation). Tolerance 0.5 % of the largest stress (required); the
// recursion is exact for S0 linear within a step, so its error is O(dt^2).
TEST(MaterialLaws, ViscoelasticShearAgainstPronyClosedForm) {
  Law elastic("viscoelastic_shear", {{"k_sh", {18.5, 46.4, -21.3}}, {"omega_slope_below", -0.02}, {"omega_slope_above", -0.01}});
  Law visco("viscoelastic_shear", kVisco);
  const double g[2] = {0.5, 0.3}, tau[2] = {0.2, 2.0};
  // gamma(t): relaxation after a ramp (0.4 s at 1.25 /s, then hold), and constant rate (0.5 /s).
  const std::vector<std::pair<std::string, std::function<double(double)>>> histories = {
      {"relaxation", [](double t) { return 1.25 * std::min(t, 0.4); }}, {"constant rate", [](double t) { return 0.5 * t; }}};
  for (double T : {260.0, 290.0}) {
    for (const auto& history : histories) {
      const std::string& hname = history.first;
      const std::function<double(double)>& gamma = history.second;
      const double t_end = 2.0;
      // Reference at the output times.
      auto s0 = [&](double t) {
        ShearHistory h(*elastic.law, T);
        return h.step(gamma(t), 0.0);
      };
      auto reference = [&](double t) {
        const int n = 20000;
        double conv[2] = {0, 0};
        double prev = s0(0.0);
        for (int k = 0; k < n; ++k) {
          const double a = t * k / n, b = t * (k + 1) / n, mid = 0.5 * (a + b);
          const double cur = s0(b);
          for (int i = 0; i < 2; ++i) conv[i] += std::exp(-(t - mid) / tau[i]) * (cur - prev);
          prev = cur;
        }
        return (1 - g[0] - g[1]) * s0(t) + g[0] * conv[0] + g[1] * conv[1];
      };
      std::vector<double> times = {0.2, 0.4, 0.6, 1.0, 2.0};
      std::vector<double> ref;
      double scale = 0;
      for (double t : times) {
        ref.push_back(reference(t));
        scale = std::max(scale, std::abs(ref.back()));
      }
      for (double dt : {0.002, 0.01, 0.05}) {
        ShearHistory h(*visco.law, T);
        h.step(gamma(0.0), 0.0);
        const int steps = static_cast<int>(std::round(t_end / dt));
        std::size_t next = 0;
        double worst = 0;
        for (int k = 1; k <= steps; ++k) {
          const double s = h.step(gamma(k * dt), dt);
          if (next < times.size() && std::abs(k * dt - times[next]) < 1e-9) {
            worst = std::max(worst, std::abs(s - ref[next]) / scale);
            ++next;
          }
        }
        EXPECT_EQ(next, times.size());
        EXPECT_LT(worst, 0.005) << hname << " T " << T << " dt " << dt;
        std::printf("%s, T = %g degC, dt = %g s: max error %.2e of the peak stress %.4g N/m\n", hname.c_str(), T, dt,
                    worst, scale);
      }
    }
  }
}

// viscoelastic_shear keeps each point's parameters for its last
// temperature in its state. A shear ramp with the temperature switching
// every 7 steps between 250, 260, 270 and 280 degC (omega, g_i and tau_i
// all temperature-dependent): the stresses must equal, bit for bit, those
// of the same history with the kept parameters discarded before every
// step; and they must differ from the history at a constant 250 degC.
TEST(MaterialLaws, ViscoelasticShearFollowsTemperatureChanges) {
  json params = kVisco;
  params["g_slope_below"] = {0.004, 0.002};
  params["tau_slope_below"] = {-0.004, -0.05};
  Law visco("viscoelastic_shear", params);
  ASSERT_TRUE(visco.status) << visco.status.message;
  const int kept = 3 + 3 * 2;  // S0 and two branches come first
  ShearHistory a(*visco.law, 250.0), b(*visco.law, 250.0), c(*visco.law, 250.0);
  const double dt = 0.01;
  double sa = 0, sc = 0;
  for (int k = 0; k <= 200; ++k) {
    const double T = 250.0 + 10.0 * ((k / 7) % 4), gamma = 0.5 * k * dt;
    a.T = T;
    b.T = T;
    std::fill(b.state.begin() + kept, b.state.end(), 0.0);
    sa = a.step(gamma, k ? dt : 0.0);
    const double sb = b.step(gamma, k ? dt : 0.0);
    sc = c.step(gamma, k ? dt : 0.0);
    ASSERT_EQ(sa, sb) << "step " << k << ", T " << T;
  }
  EXPECT_GT(std::abs(sa - sc), 0.01 * std::abs(sc)) << sa << " vs " << sc;
  std::printf("temperature changes: S12 %.6g N/m at the end (%.6g at a constant 250 degC)\n", sa, sc);
}

// viscoelastic_shear evaluates a block in one vector pass (the parameters
// at each point's temperature), the points whose steps are beyond the
// Prony factors' series one by one. Over a history of random strains,
// temperatures that change for some points, and steps in both series forms
// of the factors and beyond them, a block must give the same bits as each
// point evaluated alone (the pointwise path), for UD (no weft direction)
// and woven (sheared weft), and for a block at one temperature (parameters
// shared along the block). Steps of 1e-4 and 1e-3 s take the vector pass;
// 2e-3 and 1e-2 s (dt / tau = 1e-2 and 5e-2) do not.
// The second parameter set has every parameter temperature-dependent, with
// the Maxwell weights summing above 1 below the break (rescaled), omega
// negative (held at 0) above 290 degC, and temperatures beyond the range
// (held at its ends).
TEST(MaterialLaws, ViscoelasticBlockMatchesPointwise) {
  const json kVisco2 = {{"k_sh", {18.5, 46.4, -21.3}},
                        {"omega_slope_below", -0.02},
                        {"omega_slope_above", -0.05},
                        {"g", {0.5, 0.3}},
                        {"tau", {0.2, 2.0}},
                        {"g_slope_below", {-0.01, -0.01}},
                        {"g_slope_above", {-0.002, 0.001}},
                        {"tau_slope_below", {0.002, 0.02}},
                        {"tau_slope_above", {-0.001, -0.01}}};
  for (const json& params : {kVisco, kVisco2}) {
    Law visco("viscoelastic_shear", params);
    ASSERT_TRUE(visco.status) << visco.status.message;
    const int n = 37, ns = visco.law->state_size();
    ASSERT_EQ(ns, 3 + 3 * 2);  // S0 and the two branches' H
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int nc = visco.law->cache_size();
    ASSERT_EQ(nc, 3 + 2 * 2);  // temperature, omega, g_inf, g_i, 1 / tau_i
    // cached: the block keeps its parameters in MaterialBlock::cache between
    // calls (evaluated again where the temperatures changed).
    for (const int variant : {0, 1, 2, 3, 4, 5, 6, 7}) {
      const bool woven = variant & 1, uniform = variant & 2, cached = variant & 4;  // uniform: one temperature
      std::vector<double> sa(n * ns, 0.0), sb(n * ns, 0.0), C(3 * n), T(n), S(3 * n), W(n), dir2(2 * n);
      std::vector<double> cache(n * nc, std::numeric_limits<double>::quiet_NaN());
      for (int q = 0; q < n; ++q) {
        const double a = 1.3 + 0.3 * u(rng);
        dir2[2 * q] = std::cos(a);
        dir2[2 * q + 1] = std::sin(a);
        T[q] = uniform ? 265.0 : q % 9 == 8 ? 360.0 : q % 9 == 7 ? 190.0 : 245.0 + 15.0 * (q % 4);
      }
      for (int k = 0; k < 60; ++k) {
        const double dt = k % 3 == 0 ? 1e-4 : k % 3 == 1 ? 1e-3 : (k % 20 == 2 ? 0.01 : 2e-3);
        for (int q = 0; q < n; ++q) {
          const sdk::Sym2 c = cauchy_green(1 + 0.05 * u(rng), 0.2 * u(rng), 0.2 * u(rng), 1 + 0.05 * u(rng));
          for (int j = 0; j < 3; ++j) C[3 * q + j] = c[j];
          if (k % 7 == 6 && (uniform || q % 3 == 0)) T[q] += 1.5;  // a thermal step (for some points)
        }
        sdk::MaterialBlock b = block_of(C, T, S, W, sa, dt);
        if (woven) b.dir2 = dir2;
        if (cached) b.cache = cache;
        ASSERT_TRUE(visco.law->evaluate(b).ok);
        if (cached && !uniform) {  // the cache holds the temperatures its parameters are for (its first row)
          for (int q = 0; q < n; ++q) ASSERT_EQ(cache[q], T[q]) << "step " << k << " point " << q;
        }
        for (int q = 0; q < n; ++q) {
          double s1[3], w1;
          sdk::MaterialBlock p = block_of(std::span<const double>(&C[3 * q], 3), std::span<const double>(&T[q], 1),
                                          std::span<double>(s1, 3), std::span<double>(&w1, 1),
                                          std::span<double>(&sb[ns * q], ns), dt);
          if (woven) p.dir2 = std::span<const double>(&dir2[2 * q], 2);
          ASSERT_TRUE(visco.law->evaluate(p).ok);
          for (int j = 0; j < 3; ++j)
            ASSERT_EQ(S[3 * q + j], s1[j]) << "step " << k << " point " << q << " variant " << variant;
          ASSERT_EQ(W[q], w1) << "step " << k << " point " << q;
          // The block lays its state out by rows (value j of point q at j n + q).
          for (int j = 0; j < ns; ++j) ASSERT_EQ(sa[j * n + q], sb[ns * q + j]) << "state " << j << " step " << k;
        }
      }
    }
  }
}

// The Prony step factors exp(-x) and (1 - exp(-x)) / x, x = dt / tau: the
// series used for small x must agree with the library functions to 2 units
// in the last place over the whole range of explicit steps (x from 1e-12 to
// 1, across the switch at 1e-2).
TEST(MaterialLaws, PronyFactorsAreExactToRounding) {
  double worst_decay = 0, worst_ramp = 0;
  for (double x = 1e-12; x < 1.0; x *= 1.003) {
    const double tau = 2.0;
    double decay, ramp;
    sdk::prony_factors(1, &tau, x * tau, &decay, &ramp);
    worst_decay = std::max(worst_decay, std::abs(decay - std::exp(-x)) / std::exp(-x));
    const double r = -std::expm1(-x) / x;
    worst_ramp = std::max(worst_ramp, std::abs(ramp - r) / r);
  }
  EXPECT_LT(worst_decay, 4.5e-16);
  EXPECT_LT(worst_ramp, 4.5e-16);
}

// The logarithm of the invariants near 1 (series of ln(1 + x) below
// |x| = 1e-2) against the library's log, x from 1e-14 to 0.5 on both sides
// of 1 across the switch: within 2 units in the last place of ln y (the
// library's own error included).
TEST(MaterialLaws, LogNearOneIsExactToRounding) {
  double worst = 0;
  for (double x = 1e-14; x < 0.5; x *= 1.001)
    for (const double y : {1.0 + x, 1.0 - x}) {
      const double ref = std::log(y);
      worst = std::max(worst, std::abs(sdk::log_near_one(y) - ref) / std::abs(ref));
    }
  EXPECT_LT(worst, 4.5e-16);
  EXPECT_EQ(sdk::log_near_one(1.0), 0.0);
  EXPECT_TRUE(std::isnan(sdk::log_near_one(std::nan(""))));
  std::printf("log_near_one: largest relative difference from std::log %.3g\n", worst);
}

TEST(MaterialLaws, BadParametersAreRefused) {
  EXPECT_THROW(Law("ud_hyperelastic", {{"k_fibre", -1.0}, {"p_ct", 50.0}}), JobError);
  Law sum("viscoelastic_shear", {{"k_sh", {1, 0, 0}}, {"g", {0.7, 0.5}}, {"tau", {0.2, 2.0}}});
  EXPECT_FALSE(sum.status.ok);
  EXPECT_NE(sum.status.message.find("sum to 1.2"), std::string::npos) << sum.status.message;
  Law zero("viscoelastic_shear", {{"k_sh", {1, 0, 0}}, {"g", {0.5}}, {"tau", {0.0}}});
  EXPECT_FALSE(zero.status.ok);
  EXPECT_NE(zero.status.message.find("tau[0] must be > 0"), std::string::npos) << zero.status.message;
  Law mismatch("viscoelastic_shear", {{"k_sh", {1, 0, 0}}, {"g", {0.5, 0.2}}, {"tau", {1.0}}});
  EXPECT_FALSE(mismatch.status.ok);
}

// Outside the data (200-350 degC) the parameters are clamped: omega >= 0,
// bending rigidities >= 0; the stress stays finite.
TEST(MaterialLaws, ExtremeTemperaturesAreClamped) {
  Law visco("viscoelastic_shear", kVisco);
  Law bend("thermo_linear_bending", kBending);
  for (double T : {200.0, 350.0, 400.0}) {
    EXPECT_GE(visco.law->max_stiffness(T), 0.0);
    EXPECT_GE(bend.law->max_stiffness(T), 0.0);
    const auto r = sdk::fd_check(*visco.law, cauchy_green(1.0, 0.3, 0.0, 1.0), T);
    for (double s : r.stress) EXPECT_TRUE(std::isfinite(s));
  }
  EXPECT_EQ(bend.law->max_stiffness(400.0), 0.0);  // R_1 = -2e-5 * 400 + 6.4e-3 < 0 -> 0
}

// The bending law over a block of points at different temperatures (some
// outside 200-350 degC, held at the bounds; R_1 = -2e-5 T + 6.4e-3 is
// negative above 320 degC, held at 0) against the closed form:
// M11 = R_1 chi11, M22 = R_2 chi22, M12 = R_12 chi12, R_12 = 0.1 (R_1 +
// R_2) / 2, w = (R_1 chi11^2 + R_2 chi22^2 + 2 R_12 chi12^2) / 2. The
// operations are those of the closed form, so the tolerance is a few ulps.
TEST(MaterialLaws, BendingMomentsAreTheClosedForm) {
  Law bend("thermo_linear_bending", kBending);
  ASSERT_TRUE(bend.status.ok) << bend.status.message;
  const std::vector<double> T = {150.0, 200.0, 260.0, 300.0, 330.0, 349.0, 400.0};
  const std::size_t n = T.size();
  std::vector<double> chi(3 * n), M(3 * n), W(n), state;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (double& c : chi) c = u(rng);
  for (int with_energy = 0; with_energy < 2; ++with_energy) {
    ASSERT_TRUE(bend.law->evaluate(block_of(chi, T, M, with_energy ? std::span<double>(W) : std::span<double>())).ok);
    for (std::size_t q = 0; q < n; ++q) {
      const double t = std::clamp(T[q], 200.0, 350.0);
      const double r1 = std::max(0.0, -2.0e-5 * t + 6.4e-3), r2 = std::max(0.0, -2.0e-6 * t + 6.4e-4);
      const double r12 = 0.1 * 0.5 * (r1 + r2);
      const double* c = &chi[3 * q];
      const double ref[3] = {r1 * c[0], r2 * c[1], r12 * c[2]};
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(M[3 * q + k], ref[k], 4e-16 * std::abs(ref[k]) + 1e-300) << q << " " << k;
      if (with_energy) {
        const double w = 0.5 * (r1 * c[0] * c[0] + r2 * c[1] * c[1] + 2 * r12 * c[2] * c[2]);
        EXPECT_NEAR(W[q], w, 4e-16 * w) << q;
      }
    }
    EXPECT_EQ(M[3 * 6], 0.0);  // 400 degC: held at 350, R_1 < 0 -> 0
  }
}

}  // namespace
}  // namespace ts
