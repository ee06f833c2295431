#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mesh/shell_mesh.hpp"
#include "test_support.hpp"
#include "thermal_common.hpp"

namespace ts {
namespace {

TEST(Tridiagonal, MatchesDirectProduct) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  const int n = 9;
  std::vector<double> a(n), b(n), c(n), x(n), d(n), work(n);
  for (int i = 0; i < n; ++i) {
    a[i] = -u(rng);
    c[i] = -u(rng);
    b[i] = 3 + u(rng);
    x[i] = u(rng) * 100;
  }
  for (int i = 0; i < n; ++i) d[i] = b[i] * x[i] + (i > 0 ? a[i] * x[i - 1] : 0) + (i + 1 < n ? c[i] * x[i + 1] : 0);
  thermal::solve_tridiagonal(n, a.data(), b.data(), c.data(), d.data(), work.data());
  for (int i = 0; i < n; ++i) EXPECT_NEAR(d[i], x[i], 1e-12);
}

struct PlyFixture {
  ShellMesh mesh;
  std::vector<double> fibre;
  sdk::PartView view;
  thermal::PlyThermal ply;
  PlyFixture(double angle) {
    mesh = rectangle_mesh({0, 0, 0}, {0.01, 0.008}, {5, 4});
    fibre.clear();
    for (int e = 0; e < mesh.num_elements(); ++e) fibre.insert(fibre.end(), {std::cos(angle), std::sin(angle), 0.0});
    view = test::part_view(mesh);
    view.fibre = fibre;
    view.thickness_layers = 4;
    view.thermal = {1000, 1000, 5.0, 1.0, 1.0};
    thermal::setup_ply(ply, view, 5);
  }
};

// K applied to a linear field gives the flux balance: zero at interior nodes
// (no source), and the rows of K sum to zero (a constant field carries no flux).
TEST(InPlaneMatrix, ConstantAndLinearFields) {
  PlyFixture f(0.4);
  const auto& k = f.ply.k2d;
  for (int i = 0; i < k.n; ++i) {
    double row = 0, lin = 0;
    for (int p = k.row_start[i]; p < k.row_start[i + 1]; ++p) {
      row += k.val[p];
      lin += k.val[p] * (3 * f.mesh.x[3 * k.col[p]] - 2 * f.mesh.x[3 * k.col[p] + 1]);
    }
    EXPECT_NEAR(row, 0.0, 1e-12);
    const double x = f.mesh.x[3 * i], y = f.mesh.x[3 * i + 1];
    const bool interior = x > 1e-9 && x < 0.01 - 1e-9 && y > 1e-9 && y < 0.008 - 1e-9;
    if (interior) {
      EXPECT_NEAR(lin, 0.0, 1e-10);
    }
  }
}

// The energy of a linear field T = g.x equals A g.Ks g with Ks rotated by the
// fibre angle: k_pp = k11 cos^2 + k22 sin^2, etc. (physics.md section 3).
TEST(InPlaneMatrix, RotatedConductivity) {
  const double th = 0.4;
  PlyFixture f(th);
  const double g[2] = {3.0, -2.0};
  const double c = std::cos(th), s = std::sin(th);
  const double kxx = 5 * c * c + 1 * s * s, kyy = 5 * s * s + 1 * c * c, kxy = (5 - 1) * s * c;
  const double expected = 0.01 * 0.008 * (kxx * g[0] * g[0] + 2 * kxy * g[0] * g[1] + kyy * g[1] * g[1]);
  const auto& k = f.ply.k2d;
  double energy = 0;
  for (int i = 0; i < k.n; ++i) {
    const double ti = g[0] * f.mesh.x[3 * i] + g[1] * f.mesh.x[3 * i + 1];
    for (int p = k.row_start[i]; p < k.row_start[i + 1]; ++p)
      energy += ti * k.val[p] * (g[0] * f.mesh.x[3 * k.col[p]] + g[1] * f.mesh.x[3 * k.col[p] + 1]);
  }
  EXPECT_NEAR(energy / expected, 1.0, 1e-12);
}

TEST(Rods, LumpingWeightsSumToThickness) {
  PlyFixture f(0.0);
  double s = 0;
  for (double w : f.ply.w) s += w;
  EXPECT_NEAR(s, 0.0005, 1e-18);
  EXPECT_DOUBLE_EQ(f.ply.w.front(), 0.5 * f.ply.e);
}

}  // namespace
}  // namespace ts
