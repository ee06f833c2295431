// Random polygons moved by a margin (scripts/fuzz_blank.py): star
// polygons of 3 to 60 vertices (half of them on a 6.25 mm grid, a third
// with fillets of 1-degree sides), a square hole in some, a second star
// beside in some; margins from 1e-7 to 0.1 of their size, out and in, and
// in a quarter of the grid cases whole and half grid spacings, where moved
// sides coincide, touch or pass through vertices. Each moved outline
// (ts::polygon_margin_rings) must agree with the distance to the polygon
// at every point of a 65 x 65 grid over it (points within the tangents'
// offset beyond the margin, or 1e-9 of the size, left out); where it
// cannot be found it must say why (counted: the cut then takes the
// polygon by its distance).
// Usage: blank_margin CASES SEED [CASE]   (CASE: only that one, with its rings and wrong points)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "io/blank.hpp"
using namespace ts;
using P2 = std::array<double, 2>;
using Ring = std::vector<P2>;

static bool inside(const std::vector<Ring>& rings, double x, double y) {
  bool in = false;
  for (const Ring& p : rings)
    for (size_t k = 0, j = p.size() - 1; k < p.size(); j = k++)
      if ((p[j][1] > y) != (p[k][1] > y) && x < p[j][0] + (y - p[j][1]) * (p[k][0] - p[j][0]) / (p[k][1] - p[j][1]))
        in = !in;
  return in;
}
static double distance(const std::vector<Ring>& rings, double x, double y) {
  double d = 1e300;
  for (const Ring& p : rings)
    for (size_t k = 0, j = p.size() - 1; k < p.size(); j = k++) {
      const double ex = p[k][0] - p[j][0], ey = p[k][1] - p[j][1];
      const double t = std::clamp(((x - p[j][0]) * ex + (y - p[j][1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
      d = std::min(d, std::hypot(x - p[j][0] - t * ex, y - p[j][1] - t * ey));
    }
  return d;
}
static double area(const Ring& q) {
  double a = 0;
  for (size_t k = 0; k < q.size(); ++k) {
    const P2& w = q[(k + 1) % q.size()];
    a += 0.5 * (q[k][0] * w[1] - w[0] * q[k][1]);
  }
  return a;
}
static int orient(const P2& o, const P2& a, const P2& b) {
  const double c = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  return (c > 0) - (c < 0);
}
// A star polygon about (cx, cy): n vertices at radii within [0.3 R, R], on
// a grid of g where g > 0, some replaced by a fillet (21 sides of 1
// degree on a small circle) where fillets is set.
static Ring star(std::mt19937& rng, double cx, double cy, double R, int n, double g, bool fillets) {
  std::uniform_real_distribution<double> u(0, 1);
  Ring p;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * (k + 0.8 * u(rng)) / n, r = R * (0.3 + 0.7 * u(rng));
    double x = cx + r * std::cos(a), y = cy + r * std::sin(a);
    if (g > 0) {
      x = std::round(x / g) * g;
      y = std::round(y / g) * g;
    }
    if (fillets && u(rng) < 0.3) {
      const double rr = 0.05 * R * u(rng) + 1e-4 * R;
      for (int j = -10; j <= 10; ++j) {
        const double b = a + M_PI * j / 180;
        p.push_back({x + rr * std::cos(b), y + rr * std::sin(b)});
      }
      continue;
    }
    if (!p.empty() && p.back()[0] == x && p.back()[1] == y) continue;
    p.push_back({x, y});
  }
  return p;
}

int main(int argc, char** argv) {
  const int N = argc > 1 ? std::atoi(argv[1]) : 1000;
  const unsigned seed0 = argc > 2 ? std::atoi(argv[2]) : 1;
  const int only = argc > 3 ? std::atoi(argv[3]) : -1;
  const std::string file = "/tmp/thermostamp_fuzz_margin_" + std::to_string(seed0) + ".csv";
  int bad = 0, refused = 0, moved = 0, cannot = 0, cannot_random = 0, on_grid = 0;
  long long points = 0;
  for (int it = 0; it < N; ++it) {
    if (only >= 0 && it != only) continue;
    std::mt19937 rng(seed0 * 100000 + it);
    std::uniform_real_distribution<double> u(0, 1);
    const double g = rng() % 2 ? 0.00625 : 0;
    std::vector<Ring> rings{star(rng, 0, 0, 0.02 + 0.05 * u(rng), 3 + rng() % 58, g, rng() % 3 == 0)};
    if (rng() % 4 == 0) {  // a hole
      const double h = 0.002 + 0.004 * u(rng);
      rings.push_back({{-h, -h}, {-h, h}, {h, h}, {h, -h}});
    }
    if (rng() % 4 == 0) rings.push_back(star(rng, 0.15, 0.02, 0.02 + 0.05 * u(rng), 3 + rng() % 20, g, false));
    // What the reader takes: each ring a polygon (read back as the reader
    // keeps it), the rings apart and the hole inside the star.
    bool ok = true;
    for (Ring& r : rings) {
      FILE* o = std::fopen(file.c_str(), "w");
      for (const auto& v : r) std::fprintf(o, "%.17g,%.17g\n", v[0], v[1]);
      std::fclose(o);
      try {
        r = parse_trim("polygon:" + file).rings[0];
      } catch (const std::exception&) {
        ok = false;
      }
    }
    for (size_t r = 0; r < rings.size() && ok; ++r)
      for (size_t q = r + 1; q < rings.size() && ok; ++q)
        for (size_t i = 0; i < rings[r].size() && ok; ++i)
          for (size_t j = 0; j < rings[q].size() && ok; ++j) {
            const P2 &a = rings[r][i], &b = rings[r][(i + 1) % rings[r].size()];
            const P2 &c = rings[q][j], &d = rings[q][(j + 1) % rings[q].size()];
            ok = !(orient(a, b, c) * orient(a, b, d) <= 0 && orient(c, d, a) * orient(c, d, b) <= 0);
          }
    if (ok && rings.size() > 1 && rings[1].size() == 4 && !inside({rings[0]}, rings[1][0][0], rings[1][0][1]))
      ok = false;
    if (!ok) {
      ++refused;
      continue;
    }
    TrimSurface t;
    t.kind = TrimSurface::Kind::Polygon;
    t.rings = rings;
    t.text = "fuzz";
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const Ring& r : rings)
      for (const auto& v : r)
        for (int d = 0; d < 2; ++d) {
          lo[d] = std::min(lo[d], v[d]);
          hi[d] = std::max(hi[d], v[d]);
        }
    const double size = std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
    const bool aligned = rng() % 4 == 0 && g > 0;
    double m = aligned ? (rng() % 2 ? 1.0 : 0.5) * g * (1 + rng() % 3) : size * std::pow(10.0, -7 + 6 * u(rng));
    if (rng() % 2) m = -m;
    on_grid += aligned;
    std::vector<Ring> out;
    try {
      out = polygon_margin_rings(t, m);
      ++moved;
    } catch (const std::runtime_error& e) {
      ++cannot;
      cannot_random += !aligned;
      if (only >= 0 || (!aligned && cannot_random <= 5) || cannot <= 3)
        std::printf("CANNOT it %d margin %g size %g: %s\n", it, m, size, e.what());
      continue;
    }
    if (only >= 0) {
      for (const Ring& q : rings) std::printf("ring of %zu vertices, area %.17g\n", q.size(), area(q));
      for (const Ring& q : out) std::printf("moved ring of %zu vertices, area %.17g\n", q.size(), area(q));
    }
    const double band = std::abs(m) * (1 / std::cos(M_PI / 180) - 1) + 1e-9 * (size + 2 * std::abs(m));
    int wrong = 0;
    const int n = 64;
    const double pad = std::max(m, 0.0) + 0.01 * size;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double x = lo[0] - pad + (hi[0] - lo[0] + 2 * pad) * i / n;
        const double y = lo[1] - pad + (hi[1] - lo[1] + 2 * pad) * j / n;
        const bool in = inside(rings, x, y);
        const double d = in ? -distance(rings, x, y) : distance(rings, x, y);
        if (std::abs(d - m) <= band) continue;
        ++points;
        if (inside(out, x, y) != (d < m)) {
          ++wrong;
          if (only >= 0) std::printf("wrong at (%.17g, %.17g): distance %.17g, margin %.17g\n", x, y, d, m);
        }
      }
    if (wrong) {
      ++bad;
      if (only >= 0 || bad <= 10)
        std::printf("BAD it %d margin %g size %g: %d grid points on the wrong side\n", it, m, size, wrong);
    }
  }
  std::printf("%d cases (%d polygons the reader refuses left out, %d with margins of whole or half grid spacings): "
              "%d moved, %d bad, %d cannot be moved (by the distance; %d of them with a margin not of whole or half "
              "grid spacings), %lld grid points checked\n",
              N, refused, on_grid, moved, bad, cannot, cannot_random, points);
  return bad > 0 ? 1 : 0;
}
