// Cut patterns with an exact answer (scripts/fuzz_blank.py): a flat plate
// on a regular grid, moved rigidly in plan; trims through its nodes and
// along its lines (planes through a node along the grid's lines or
// diagonals, rectangles and triangles of nodes), given formed; the
// pattern's area against the plate clipped by the trims in the blank
// (1e-14 m^2).
// Usage: blank_aligned CASES SEED [CASE]
// Exact-answer fuzz: a flat plate on a regular grid, moved rigidly in plan;
// trims through its nodes and along its lines (planes with node points and
// grid directions, polygons with vertices at nodes); the pattern's area
// against the polygon clipping done here in the blank.
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include "io/blank.hpp"
#include "mesh/shell_mesh.hpp"
using namespace ts;
using P2 = std::array<double, 2>;
static std::vector<P2> clip(const std::vector<P2>& poly, double a, double b, double c) {
  std::vector<P2> out;
  for (size_t k = 0; k < poly.size(); ++k) {
    const P2& p = poly[k];
    const P2& q = poly[(k + 1) % poly.size()];
    double fp = a * p[0] + b * p[1] + c, fq = a * q[0] + b * q[1] + c;
    if (fp >= 0) out.push_back(p);
    if ((fp >= 0) != (fq >= 0)) {
      double t = fp / (fp - fq);
      out.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
    }
  }
  return out;
}
static double area(const std::vector<P2>& p) {
  double a = 0;
  for (size_t k = 0; k < p.size(); ++k) {
    auto& u = p[k];
    auto& v = p[(k + 1) % p.size()];
    a += 0.5 * (u[0] * v[1] - v[0] * u[1]);
  }
  return a;
}
static int fallbacks = 0;
int main(int argc, char** argv) {
  int N = atoi(argv[1]);
  unsigned seed0 = atoi(argv[2]);
  int bad = 0, thrown = 0, checked = 0;
  int only = argc > 3 ? atoi(argv[3]) : -1;
  for (int it = 0; it < N; ++it) {
    if (only >= 0 && it != only) continue;
    std::mt19937 rng(seed0 * 1000003u + it);
    std::uniform_real_distribution<double> u(0, 1);
    const int n = 2 + rng() % 12;
    const bool crossed = rng() % 2;
    const double L = 0.1, h = L / n;
    ShellMesh m = rectangle_mesh({0, 0, 0}, {L, L}, {n, n}, crossed);
    const double ang = (rng() % 4 == 0) ? 0.0 : u(rng) * 6.28, c = std::cos(ang), s = std::sin(ang), tx = 0.3 * u(rng),
                 ty = -0.2 * u(rng);
    std::vector<double> x = m.x;
    for (size_t i = 0; i < x.size(); i += 3) {
      x[i] = c * m.x[i] - s * m.x[i + 1] + tx;
      x[i + 1] = s * m.x[i] + c * m.x[i + 1] + ty;
      x[i + 2] = 0.02;
    }
    std::vector<TrimSurface> trims;
    std::vector<std::vector<P2>> polys;
    std::vector<std::array<double, 3>> lines;
    const int nt = 1 + rng() % 3;
    std::ostringstream desc;
    for (int t = 0; t < nt; ++t) {
      const auto node = [&]() {
        int half = crossed && rng() % 3 == 0;
        double i = rng() % (n + 1), j = rng() % (n + 1);
        if (half && i < n && j < n) {
          i += 0.5;
          j += 0.5;
        }
        return P2{i * h, j * h};
      };
      std::ostringstream text;
      text.precision(17);
      if (rng() % 2) {  // a plane through a node along a grid direction (or the diagonals)
        const P2 q = node();
        const int dk = rng() % 8;
        const double dirs[8][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
        double nx = dirs[dk][0], ny = dirs[dk][1];
        text << "plane:" << c * q[0] - s * q[1] + tx << "," << s * q[0] + c * q[1] + ty << ",0," << c * nx - s * ny
             << "," << s * nx + c * ny << ",0";
        lines.push_back({nx, ny, -(nx * q[0] + ny * q[1])});
      } else {  // a polygon: a random rectangle or triangle of nodes
        std::vector<P2> v;
        if (rng() % 2) {
          P2 a = node(), b = node();
          if (a[0] == b[0] || a[1] == b[1]) {
            --t;
            continue;
          }
          v = {{std::min(a[0], b[0]), std::min(a[1], b[1])},
               {std::max(a[0], b[0]), std::min(a[1], b[1])},
               {std::max(a[0], b[0]), std::max(a[1], b[1])},
               {std::min(a[0], b[0]), std::max(a[1], b[1])}};
        } else {
          v = {node(), node(), node()};
          if (std::abs(area(v)) < 1e-9) {
            --t;
            continue;
          }
          if (area(v) < 0) std::swap(v[1], v[2]);
        }
        std::string f = (std::filesystem::temp_directory_path() /
                         ("thermostamp_fuzz_e" + std::to_string(seed0) + "_" + std::to_string(t) + ".csv"))
                            .string();
        std::ofstream o(f);
        o.precision(17);
        for (auto& p : v) o << c * p[0] - s * p[1] + tx << "," << s * p[0] + c * p[1] + ty << "\n";
        o.close();
        text << "polygon:" << f;
        polys.push_back(v);
      }
      trims.push_back(parse_trim(text.str()));
      desc << text.str() << " ";
    }
    // the reference: convex pieces only (rectangles, triangles, half-planes): clip the plate by each
    std::vector<P2> region = {{0, 0}, {L, 0}, {L, L}, {0, L}};
    for (auto& ln : lines) region = clip(region, ln[0], ln[1], ln[2]);
    for (auto& v : polys)
      for (size_t k = 0; k < v.size(); ++k) {
        const P2& a = v[k];
        const P2& b = v[(k + 1) % v.size()];
        region = clip(region, -(b[1] - a[1]), b[0] - a[0], (b[1] - a[1]) * a[0] - (b[0] - a[0]) * a[1]);
      }
    const double expected = region.size() >= 3 ? area(region) : 0.0;
    try {
      CutPattern p = cut_pattern(m.x, x, m.triangles, trims);
      if (!p.fallback.empty()) ++fallbacks;
      ++checked;
      if (std::abs(p.kept_blank_area - expected) > 1e-14) {
        ++bad;
        if (bad < 12)
          std::printf("BAD it %d n %d crossed %d ang %g: %.17g vs %.17g | %s\n", it, n, crossed, ang, p.kept_blank_area,
                      expected, desc.str().c_str());
      }
    } catch (const std::exception& e) {
      ++thrown;
      if (thrown < 12)
        std::printf("THROW it %d n %d crossed %d: %s | %s\n", it, n, crossed, e.what(), desc.str().c_str());
    }
  }
  std::printf("%d cases (%d checked), %d bad, %d thrown, %d by the distance\n", N, checked, bad, thrown, fallbacks);
  return bad + thrown > 0 ? 1 : 0;
}
