// The Nakamura kinetics' rate K(T), the crystallinity of the integral and
// its inverse, and the half-crystallisation temperature at a constant
// cooling rate, against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "solve/crystallisation.hpp"

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

}  // namespace
}  // namespace ts
