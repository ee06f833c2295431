// The specific heat table c(T) and its enthalpy H(T) = int_0^T c, against
// closed-form integrals of the piecewise linear c; the conductivity table.
#include <gtest/gtest.h>

#include <random>

#include "job/job.hpp"
#include "solve/conductivity.hpp"
#include "solve/heat_capacity.hpp"
#include "test_support.hpp"

namespace ts {
namespace {

// A latent heat peak of 30 kJ/kg between 220 and 240 degC on 1775 J/(kg K).
const std::vector<std::array<double, 2>> kRows = {{220.0, 1775.0}, {230.0, 4775.0}, {240.0, 1775.0}};

TEST(HeatCapacity, ValueAndEnthalpyAgainstTheClosedForm) {
  const HeatCapacityTable cp(kRows);
  EXPECT_EQ(cp.c_min(), 1775.0);
  EXPECT_EQ(cp.value(100.0), 1775.0);  // held below the first row
  EXPECT_EQ(cp.value(400.0), 1775.0);  // and above the last
  EXPECT_DOUBLE_EQ(cp.value(225.0), 3275.0);
  EXPECT_DOUBLE_EQ(cp.value(236.0), 1775.0 + 3000.0 * 0.4);
  // H = 1775 T plus the part of the peak's triangle below T.
  auto closed = [](double T) {
    double peak = 0;
    if (T > 220 && T <= 230) peak = 0.5 * (T - 220) * 300.0 * (T - 220);
    if (T > 230 && T <= 240) peak = 15000.0 + 15000.0 - 0.5 * (240 - T) * 300.0 * (240 - T);
    if (T > 240) peak = 30000.0;
    return 1775.0 * T + peak;
  };
  for (double T : {-20.0, 0.0, 100.0, 220.0, 223.0, 230.0, 237.5, 240.0, 300.0})
    EXPECT_NEAR(cp.enthalpy(T), closed(T), 1e-9 * 1775.0 * 300.0) << T;
  EXPECT_EQ(cp.enthalpy(0.0), 0.0);
}

// advance(T0, e) inverts the enthalpy: H(advance(T0, e)) - H(T0) = e, across
// any number of rows either way, and returns T0 itself for e = 0.
TEST(HeatCapacity, AdvanceInvertsTheEnthalpy) {
  const HeatCapacityTable cp({{200.0, 1500.0}, {220.0, 1775.0}, {230.0, 4775.0}, {240.0, 1775.0}, {300.0, 2000.0}});
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> T(150.0, 350.0), E(-2.0e5, 2.0e5);
  for (int i = 0; i < 2000; ++i) {
    const double T0 = T(gen), e = E(gen);
    const double T1 = cp.advance(T0, e);
    EXPECT_NEAR(cp.enthalpy(T1) - cp.enthalpy(T0), e, 1e-9 * 6e5) << T0 << " " << e;
    EXPECT_EQ(e > 0, T1 > T0);
  }
  for (double T0 : {150.0, 220.0, 225.0, 300.0}) EXPECT_EQ(cp.advance(T0, 0.0), T0);
  // Starting on a row and beyond the ends.
  EXPECT_NEAR(cp.advance(230.0, -15000.0 - 1775.0 * 10.0), 220.0, 1e-9);
  EXPECT_NEAR(cp.advance(400.0, -2000.0 * 50.0), 350.0, 1e-9);
  EXPECT_NEAR(cp.advance(100.0, 1500.0 * 50.0), 150.0, 1e-9);
}

// The conductivity table k(T): linear between rows, held beyond them, each
// column on its own; and the job reader's forms (a table of equal rows is
// a constant; a table's largest values are what the step limits take).
TEST(ConductivityTable, InterpolatesEachColumnAndHoldsBeyondTheRows) {
  const ConductivityTable kt({{200.0, 3.0, 0.2, 0.1}, {250.0, 4.0, 0.3, 0.5}, {300.0, 4.0, 0.5, 0.3}});
  double k[3];
  kt.value(100.0, k);
  EXPECT_EQ(k[0], 3.0);
  EXPECT_EQ(k[2], 0.1);
  kt.value(225.0, k);
  EXPECT_NEAR(k[0], 3.5, 1e-15);
  EXPECT_NEAR(k[1], 0.25, 1e-15);
  EXPECT_NEAR(k[2], 0.3, 1e-15);
  kt.value(250.0, k);
  EXPECT_NEAR(k[2], 0.5, 1e-15);
  kt.value(290.0, k);
  EXPECT_NEAR(k[1], 0.46, 1e-15);
  EXPECT_NEAR(k[2], 0.34, 1e-15);
  kt.value(1000.0, k);
  EXPECT_EQ(k[1], 0.5);
  EXPECT_EQ(k[2], 0.3);
}

TEST(ConductivityTable, JobFormsAndLargestValues) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  d["materials"]["ply"]["conductivity"] = {{200.0, 3.0, 0.2, 0.1}, {250.0, 4.0, 0.3, 0.5}, {300.0, 4.0, 0.5, 0.3}};
  Job j = parse_job(d, "job.json");
  EXPECT_EQ(j.materials[0].conductivity_table.size(), 3u);
  EXPECT_EQ(j.materials[0].conductivity, (std::array<double, 3>{4.0, 0.5, 0.5}));
  EXPECT_EQ(j.materials[0].k33_range(), (std::array<double, 2>{0.1, 0.5}));
  d["materials"]["ply"]["conductivity"] = {{200.0, 3.0, 0.2, 0.1}, {300.0, 3.0, 0.2, 0.1}};
  j = parse_job(d, "job.json");
  EXPECT_TRUE(j.materials[0].conductivity_table.empty());
  EXPECT_EQ(j.materials[0].conductivity, (std::array<double, 3>{3.0, 0.2, 0.1}));
  d["materials"]["ply"]["conductivity"] = {3.89, 0.31, 0.31};
  j = parse_job(d, "job.json");
  EXPECT_TRUE(j.materials[0].conductivity_table.empty());
  EXPECT_EQ(j.materials[0].conductivity[0], 3.89);
}

}  // namespace
}  // namespace ts
