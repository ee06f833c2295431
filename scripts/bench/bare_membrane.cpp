// The yardstick of the mechanics benchmark: a bare explicit membrane loop,
// what the least an explicit shell code does per element and cycle costs on
// the machine at the time of the measurement.
//
// The plate of scripts/bench/mechanics.py (n x n cells of 1 mm, two
// triangles each, 2 n^2 elements), one thread:
//   - constant-strain triangle, total Lagrangian: F = sum_a x_a (x) grad0 N_a
//     (3 x 2), C = F^T F, Green strain E = (C - I) / 2;
//   - St Venant-Kirchhoff membrane, S = lambda tr(E) I + 2 mu E (N/m);
//   - nodal forces f_a = -A0 F S grad0 N_a added into a per-node array;
//   - central differences with lumped mass, the edge x = 0 held and the
//     edge x = L pulled at 1 cm/s (the plate stays sound over any number
//     of steps).
// Flat arrays, no allocation in the loop, no bending, no history, no
// temperature, no energy audit. Built with -O3 -march=native by
// mechanics.py (the fastest plain build of this loop).
//
// Usage: bare_membrane N STEPS   prints one JSON object: elements, steps,
// seconds of the time loop, ns per element-cycle, and a checksum of the
// final positions (so that the loop cannot be optimised away).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: bare_membrane N STEPS\n");
    return 2;
  }
  const int n = std::atoi(argv[1]), steps = std::atoi(argv[2]);
  if (n < 1 || steps < 1) {
    std::fprintf(stderr, "bare_membrane: N and STEPS must be positive\n");
    return 2;
  }
  const double h = 1e-3, rho_a = 1294.0 * 5e-4;  // cell size (m), mass per area (kg/m2)
  const double k = 5.0e6, nu = 0.3;                // membrane stiffness E t (N/m), Poisson ratio
  const double lambda = k * nu / (1 - nu * nu), mu = k / (2 * (1 + nu));
  const int nn = (n + 1) * (n + 1), ne = 2 * n * n;
  std::vector<double> x(3 * static_cast<std::size_t>(nn)), v(x.size(), 0.0), f(x.size()), inv_m(nn, 0.0);
  std::vector<int> tri(3 * static_cast<std::size_t>(ne));
  std::vector<double> grad(6 * static_cast<std::size_t>(ne)), area(ne);
  std::vector<char> held(nn, 0);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int a = j * (n + 1) + i;
      x[3 * a] = i * h;
      x[3 * a + 1] = j * h;
      x[3 * a + 2] = 0;
      held[a] = i == 0 || i == n;
      if (i == n) v[3 * a] = 0.01;
    }
  int e = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      const int cells[2][3] = {{a, b, d}, {a, d, c}};
      for (const auto& t : cells) {
        const double x1 = x[3 * t[1]] - x[3 * t[0]], y1 = x[3 * t[1] + 1] - x[3 * t[0] + 1];
        const double x2 = x[3 * t[2]] - x[3 * t[0]], y2 = x[3 * t[2] + 1] - x[3 * t[0] + 1];
        const double det = x1 * y2 - x2 * y1;
        const double g1x = y2 / det, g1y = -x2 / det, g2x = -y1 / det, g2y = x1 / det;
        const double g[6] = {-g1x - g2x, -g1y - g2y, g1x, g1y, g2x, g2y};
        for (int q = 0; q < 3; ++q) tri[3 * e + q] = t[q];
        for (int q = 0; q < 6; ++q) grad[6 * e + q] = g[q];
        area[e] = 0.5 * det;
        for (int q = 0; q < 3; ++q) inv_m[t[q]] += rho_a * area[e] / 3;
        ++e;
      }
    }
  for (double& m : inv_m) m = 1.0 / m;
  const double dt = 0.5 * h / std::sqrt(k / rho_a);

  const auto t0 = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s) {
    std::fill(f.begin(), f.end(), 0.0);
    for (int q = 0; q < ne; ++q) {
      const int* t = &tri[3 * q];
      const double* g = &grad[6 * q];
      double F[3][2] = {};
      for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 3; ++d) {
          F[d][0] += x[3 * t[a] + d] * g[2 * a];
          F[d][1] += x[3 * t[a] + d] * g[2 * a + 1];
        }
      const double C11 = F[0][0] * F[0][0] + F[1][0] * F[1][0] + F[2][0] * F[2][0];
      const double C22 = F[0][1] * F[0][1] + F[1][1] * F[1][1] + F[2][1] * F[2][1];
      const double C12 = F[0][0] * F[0][1] + F[1][0] * F[1][1] + F[2][0] * F[2][1];
      const double E11 = 0.5 * (C11 - 1), E22 = 0.5 * (C22 - 1), E12 = 0.5 * C12;
      const double tr = lambda * (E11 + E22), A = area[q];
      const double S11 = A * (tr + 2 * mu * E11), S22 = A * (tr + 2 * mu * E22), S12 = A * 2 * mu * E12;
      for (int a = 0; a < 3; ++a) {
        const double c1 = S11 * g[2 * a] + S12 * g[2 * a + 1], c2 = S12 * g[2 * a] + S22 * g[2 * a + 1];
        for (int d = 0; d < 3; ++d) f[3 * t[a] + d] -= F[d][0] * c1 + F[d][1] * c2;
      }
    }
    for (int a = 0; a < nn; ++a) {
      const double w = held[a] ? 0.0 : dt * inv_m[a];
      for (int d = 0; d < 3; ++d) {
        v[3 * a + d] += w * f[3 * a + d];
        x[3 * a + d] += dt * v[3 * a + d];
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double checksum = 0;
  for (double c : x) checksum += c;
  std::printf("{\"elements\": %d, \"steps\": %d, \"seconds\": %.6f, \"ns_per_element_cycle\": %.3f, \"checksum\": %.12e}\n",
              ne, steps, seconds, seconds / (static_cast<double>(ne) * steps) * 1e9, checksum);
  return std::isfinite(checksum) ? 0 : 3;
}
