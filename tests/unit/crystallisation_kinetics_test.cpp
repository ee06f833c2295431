// The Nakamura kinetics' rate K(T), the crystallinity of the integral and
// its inverse, the half-crystallisation temperature at a constant cooling
// rate, and the melting, against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "solve/crystallisation.hpp"
#include "solve/heat_capacity.hpp"

namespace ts {
namespace {

TEST(CrystallisationKinetics, RateFromRowsAndFromTheGaussian) {
  const CrystallisationKinetics rows(3e4, 3.0, {{150.0, 2.0}, {200.0, 1.0}, {250.0, 0.0}}, 0, 0, 0);
  EXPECT_FALSE(rows.empty());
  EXPECT_TRUE(CrystallisationKinetics().empty());
  EXPECT_EQ(rows.rate(100.0), 2.0);  // held below the first row
  EXPECT_EQ(rows.rate(300.0), 0.0);  // and above the last
  EXPECT_DOUBLE_EQ(rows.rate(175.0), 1.5);
  EXPECT_DOUBLE_EQ(rows.rate(240.0), 0.2);
  EXPECT_EQ(rows.upper_temperature(), 250.0);
  const CrystallisationKinetics g(3e4, 3.0, {}, 50.0, 150.0, 40.0);
  EXPECT_DOUBLE_EQ(g.rate(150.0), 50.0);
  EXPECT_NEAR(g.rate(170.0), 25.0, 1e-12);  // half the peak at half the width from it
  EXPECT_NEAR(g.rate(130.0), 25.0, 1e-12);
  EXPECT_NEAR(g.half_width(), 40.0, 1e-12);
  EXPECT_DOUBLE_EQ(g.upper_temperature(), 310.0);
  EXPECT_GT(g.rate(150.0 + 3.99 * 40.0), 0.0);  // zero beyond four half widths only
  EXPECT_EQ(g.rate(150.0 + 4.01 * 40.0), 0.0);
  EXPECT_EQ(g.rate(150.0 - 4.01 * 40.0), 0.0);
}

TEST(CrystallisationKinetics, CrystallinityAndItsIntegral) {
  for (double n : {1.0, 2.0, 2.5, 3.0, 4.0}) {
    const CrystallisationKinetics k(0, n, {{0.0, 1.0}}, 0, 0, 0);
    EXPECT_EQ(k.crystallinity(0.0), 0.0);
    EXPECT_EQ(k.integral(0.0), 0.0);
    // (up to theta^n = 5, X = 0.993: nearer 1, the inverse loses the digits
    // 1 - X has lost)
    for (double theta : {1e-3, 0.3, 1.0, 1.49}) {
      EXPECT_NEAR(k.crystallinity(theta), 1.0 - std::exp(-std::pow(theta, n)), 1e-15);
      EXPECT_NEAR(k.integral(k.crystallinity(theta)), theta, 1e-12 * std::max(1.0, theta));
    }
  }
}

// Cooling at beta from T0 at a constant K: theta = K (T0 - T) / beta, so X
// reaches x at T0 - beta (-ln(1 - x))^(1/n) / K (the sum's steps of 0.01 K
// are exact for a constant K).
TEST(CrystallisationKinetics, TemperatureAtAConstantCoolingRate) {
  const CrystallisationKinetics k(0, 3.0, {{0.0, 0.02}}, 0, 0, 0);
  const double beta = 10.0 / 60.0;
  for (double x : {0.1, 0.5, 0.9})
    EXPECT_NEAR(k.temperature_at(x, beta, 250.0), 250.0 - beta * std::cbrt(-std::log(1.0 - x)) / 0.02, 1e-9) << x;
  // A rate that vanishes below 240 degC: X never reaches 0.5 from 250 degC.
  const CrystallisationKinetics low(0, 3.0, {{240.0, 0.0}, {250.0, 1e-4}}, 0, 0, 0);
  EXPECT_TRUE(std::isinf(low.temperature_at(0.5, beta, 250.0)));
  // A Gaussian too wide to matter: the sum starts at 2000 degC (not at
  // four half widths above the peak), and ends.
  const CrystallisationKinetics wide(0, 3.0, {}, 0.02, 150.0, 1e30);
  EXPECT_NEAR(wide.temperature_at(0.5, beta, wide.upper_temperature()),
              2000.0 - beta * std::cbrt(std::log(2.0)) / 0.02, 1e-6);
}

// The share still solid: 1 below the first row, 0 above the last, linear
// between; the temperature at which a share is left; none without rows.
TEST(CrystallisationKinetics, SolidShareOfTheMeltingRows) {
  const CrystallisationKinetics k(3e4, 3.0, {{0.0, 1.0}}, 0, 0, 0, {{245.0, 1.0}, {255.0, 0.8}, {262.0, 0.3}, {268.0, 0.0}});
  EXPECT_TRUE(k.melts());
  EXPECT_EQ(k.melting_onset(), 245.0);
  EXPECT_EQ(k.melting_end(), 268.0);
  EXPECT_EQ(k.solid_share(20.0), 1.0);
  EXPECT_EQ(k.solid_share(245.0), 1.0);
  EXPECT_DOUBLE_EQ(k.solid_share(250.0), 0.9);
  EXPECT_DOUBLE_EQ(k.solid_share(258.5), 0.55);
  EXPECT_DOUBLE_EQ(k.solid_share(265.0), 0.15);
  EXPECT_EQ(k.solid_share(268.0), 0.0);
  EXPECT_EQ(k.solid_share(400.0), 0.0);
  EXPECT_DOUBLE_EQ(k.melting_temperature(0.5), 259.2);
  EXPECT_DOUBLE_EQ(k.melting_temperature(0.9), 250.0);
  EXPECT_DOUBLE_EQ(k.melting_temperature(0.15), 265.0);
  const CrystallisationKinetics none(3e4, 3.0, {{0.0, 1.0}}, 0, 0, 0);
  EXPECT_FALSE(none.melts());
  EXPECT_EQ(none.solid_share(1e6), 1.0);
  EXPECT_TRUE(std::isinf(none.melting_onset()));
}

// melt() with a constant specific heat c: T' = T - L (X - x) / c and x =
// s(T'), in closed form on the segment of s where the root lies (here s =
// 0.8 - (T - 255) / 14 between 255 and 262 degC); with a specific heat
// table, the heat balance of the root and x = s(T').
TEST(CrystallisationKinetics, MeltingAgainstItsClosedForm) {
  const double L = 3e4, c = 1775.0, a = L / c;
  const CrystallisationKinetics k(L, 3.0, {{0.0, 1.0}}, 0, 0, 0, {{245.0, 1.0}, {255.0, 0.8}, {262.0, 0.3}, {268.0, 0.0}});
  const double X = 0.9, T = 264.0;
  const auto [x, t] = k.melt(X, T, [&](double tt) { return c * tt; }, [&](double xm) { return T - a * (X - xm); });
  // T' = T - a X + a (0.8 + 255 / 14) - a T' / 14
  const double t_exact = (T - a * X + a * (0.8 + 255.0 / 14.0)) / (1.0 + a / 14.0);
  ASSERT_GT(t_exact, 255.0);
  ASSERT_LT(t_exact, 262.0);
  EXPECT_NEAR(t, t_exact, 1e-12);
  EXPECT_NEAR(x, 0.8 - (t_exact - 255.0) / 14.0, 1e-14);
  EXPECT_EQ(t, T - a * (X - x));  // the temperature is that of the crystals melted
  // With a specific heat table (H piecewise quadratic): the root of
  // H(T') - H(T) + L (X - s(T')) = 0, to round-off in the heat.
  const HeatCapacityTable cp({{200.0, 1500.0}, {258.0, 2600.0}, {300.0, 1900.0}});
  const auto [xt, tt] = k.melt(X, T, [&](double u) { return cp.enthalpy(u); },
                               [&](double xm) { return cp.advance(T, L * (xm - X)); });
  EXPECT_NEAR(cp.enthalpy(tt) - cp.enthalpy(T) + L * (X - xt), 0.0, 1e-9);  // J/kg, of about 1e4
  EXPECT_NEAR(xt, k.solid_share(tt), 1e-12);
  EXPECT_GT(xt, k.solid_share(T));
  EXPECT_LT(xt, X);
  // Without latent heat the value melts at its temperature.
  const CrystallisationKinetics cold(0.0, 3.0, {{0.0, 1.0}}, 0, 0, 0, {{250.0, 1.0}, {270.0, 0.0}});
  const auto [x0, t0] = cold.melt(0.9, 265.0, [&](double tt) { return c * tt; }, [](double) { return 265.0; });
  EXPECT_NEAR(x0, 0.25, 1e-15);
  EXPECT_EQ(t0, 265.0);
}

}  // namespace
}  // namespace ts
