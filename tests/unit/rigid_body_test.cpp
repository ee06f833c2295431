// The small algebra of swivelling jaws: the constrained rigid-body velocity
// (rigid_body.hpp) and the best-fit rotation of the summary.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "solve/rigid_body.hpp"

namespace ts::test {
namespace {

struct Body {
  std::vector<std::array<double, 3>> y;
  std::vector<double> m;
};

// M = sum m a a^T over every dof, p = sum a m v for the velocities v_j.
void sums(const Body& b, double L, const std::vector<std::array<double, 3>>& v, double* M, double* p) {
  for (int r = 0; r < 36; ++r) M[r] = 0;
  for (int r = 0; r < 6; ++r) p[r] = 0;
  for (std::size_t j = 0; j < b.y.size(); ++j)
    for (int d = 0; d < 3; ++d) {
      double a[6];
      rigid_row(b.y[j].data(), d, 1.0 / L, a);
      for (int r = 0; r < 6; ++r) {
        p[r] += a[r] * b.m[j] * v[j][d];
        for (int c = 0; c < 6; ++c) M[6 * r + c] += b.m[j] * a[r] * a[c];
      }
    }
}

std::array<double, 6> apply(const double* G, const double* p) {
  std::array<double, 6> q{};
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) q[r] += G[6 * r + c] * p[c];
  return q;
}

}  // namespace

// The momentum of a rigid velocity field gives it back, exactly to
// round-off (1e-12), for four nodes in space.
TEST(RigidBody, MomentumOfARigidMotionGivesItBack) {
  const Body b{{{0.01, 0.0, 0.0}, {0.0, 0.02, 0.0}, {-0.01, -0.005, 0.003}, {0.004, 0.0, -0.01}},
               {1.0, 2.0, 0.5, 1.5}};
  const double L = 0.02, V[3] = {0.3, -0.2, 0.1}, w[3] = {2.0, -1.0, 3.0};
  std::vector<std::array<double, 3>> v;
  for (const auto& y : b.y)
    v.push_back({V[0] + w[1] * y[2] - w[2] * y[1], V[1] + w[2] * y[0] - w[0] * y[2],
                 V[2] + w[0] * y[1] - w[1] * y[0]});
  double M[36], p[6], C[36] = {}, G[36];
  sums(b, L, v, M, p);
  constrained_rigid_inverse(M, C, G);
  const auto q = apply(G, p);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(q[d], V[d], 1e-12);
    EXPECT_NEAR(q[3 + d] / L, w[d], 1e-12 * 3.0);
  }
}

// Collinear nodes (along x): the turn about their line moves none of them
// and takes no velocity; the rest comes back. A held row (node 0 in y)
// removes the motion it forbids: node 0's y velocity is then zero.
TEST(RigidBody, CollinearNodesAndAHeldRow) {
  const Body b{{{-0.01, 0, 0}, {0.0, 0, 0}, {0.02, 0, 0}}, {1.0, 1.0, 1.0}};
  const double L = 0.02;
  std::vector<std::array<double, 3>> v;
  for (const auto& y : b.y) v.push_back({0.1, 0.5 + 4.0 * y[0], -2.0 * y[0]});  // w = (0, 2, 4)
  double M[36], p[6], C[36] = {}, G[36];
  sums(b, L, v, M, p);
  constrained_rigid_inverse(M, C, G);
  auto q = apply(G, p);
  EXPECT_NEAR(q[0], 0.1, 1e-12);
  EXPECT_NEAR(q[1], 0.5, 1e-12);
  EXPECT_NEAR(q[3], 0.0, 1e-12);  // about x: no velocity
  EXPECT_NEAR(q[4] / L, 2.0, 1e-10);
  EXPECT_NEAR(q[5] / L, 4.0, 1e-10);
  double a[6];
  rigid_row(b.y[0].data(), 1, 1.0 / L, a);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) C[6 * r + c] = a[r] * a[c];
  constrained_rigid_inverse(M, C, G);
  q = apply(G, p);
  double vy0 = 0;
  for (int r = 0; r < 6; ++r) vy0 += a[r] * q[r];
  EXPECT_NEAR(vy0, 0.0, 1e-12);
}

// The rotation increment is Rodrigues' formula: a quarter turn about z
// carries x onto y; the points keep their distance from the axis.
TEST(RigidBody, RotationIncrementIsExactForAnyAngle) {
  const double phi[3] = {0, 0, M_PI / 2}, y[3] = {1.0, 0.0, 0.5};
  double d[3];
  Rotation(phi).increment(y, d);
  EXPECT_NEAR(y[0] + d[0], 0.0, 1e-15);
  EXPECT_NEAR(y[1] + d[1], 1.0, 1e-15);
  EXPECT_NEAR(y[2] + d[2], 0.5, 1e-15);
  const double none[3] = {0, 0, 0};
  Rotation(none).increment(y, d);
  EXPECT_EQ(d[0], 0.0);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_EQ(d[2], 0.0);
}

// Kabsch: points turned by 40 degrees about (1, 2, 2) / 3 give that
// rotation back (1e-12); a plane of points gives a proper rotation, not a
// reflection.
TEST(RigidBody, BestFitRotationGivesTheTurnBack) {
  const double k[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, th = 40 * M_PI / 180;
  const double c = std::cos(th), s = std::sin(th);
  double R[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double kx = (i == j ? 0.0 : ((i + 1) % 3 == j ? -k[3 - i - j] : k[3 - i - j]));
      R[3 * i + j] = (i == j ? c : 0.0) + s * kx + (1 - c) * k[i] * k[j];
    }
  const std::vector<std::array<double, 3>> a = {{1, 0, 0}, {0, 1, 0}, {-1, -1, 0}, {0.2, 0.3, 0}};
  double H[9] = {};
  for (const auto& p : a) {
    double b[3];
    for (int i = 0; i < 3; ++i) b[i] = R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) H[3 * i + j] += p[i] * b[j];
  }
  double F[9];
  best_fit_rotation(H, F);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(F[i], R[i], 1e-12) << i;
}

}  // namespace ts::test
