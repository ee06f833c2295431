// Random cut patterns (scripts/fuzz_blank.py): meshes of a 100 mm plate
// (2 to 15 cells a side, crossed or not, nodes moved at random or not)
// formed flat and turned, into a step with a vertical wall, folded over
// itself in plan, into a dome, or stood up vertical; 1 to 3 trims (planes,
// cylinders, spheres, star polygons, half of them with vertices on a
// 6.25 mm grid), a margin in a third of the cases, a trim given twice in
// half of them. Every pattern must close, its outlines' area equal its
// area (1e-8 of the blank's: the points' joining), and a trim twice give
// the pattern once (1e-12 of the blank's area).
// Usage: blank_random CASES SEED [CASE]   (CASE: only that one, to look at it)
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/blank.hpp"
#include "io/export.hpp"
#include "mesh/shell_mesh.hpp"
using namespace ts;
static double sarea(const Outline& o) {
  double a = 0;
  for (size_t k = 0; k < o.points.size(); ++k) {
    auto& p = o.points[k].blank;
    auto& q = o.points[(k + 1) % o.points.size()].blank;
    a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
  }
  return a;
}
static int fallbacks = 0, joined = 0;
int main(int argc, char** argv) {
  int N = argc > 1 ? atoi(argv[1]) : 1000;
  unsigned seed0 = argc > 2 ? atoi(argv[2]) : 1;
  int bad = 0, thrown = 0;
  int only = argc > 3 ? atoi(argv[3]) : -1;
  for (int it = 0; it < N; ++it) {
    if (only >= 0 && it != only) continue;
    std::mt19937 rng(seed0 * 100000 + it);
    std::uniform_real_distribution<double> u(0, 1);
    int nx = 2 + rng() % 14, ny = 2 + rng() % 14;
    bool crossed = rng() % 2;
    ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {nx, ny}, crossed);
    double amp = (rng() % 2) ? 0.12 * 0.1 / std::max(nx, ny) : 0;
    for (size_t i = 0; i < m.x.size(); i += 3) {
      bool ex = m.x[i] < 1e-12 || m.x[i] > 0.1 - 1e-12, ey = m.x[i + 1] < 1e-12 || m.x[i + 1] > 0.1 - 1e-12;
      if (!ex) m.x[i] += amp * (2 * u(rng) - 1);
      if (!ey) m.x[i + 1] += amp * (2 * u(rng) - 1);
    }
    int kind = rng() % 5;
    std::vector<double> x = m.x;
    double ang = u(rng) * 6.28;
    for (size_t i = 0; i < x.size(); i += 3) {
      double X = m.x[i], Y = m.x[i + 1], px = X, py = Y, pz = 0;
      if (kind == 1) {  // vertical wall at node lines? use X thresholds
        if (X < 0.04) {
          px = X;
          pz = 0;
        } else if (X <= 0.06) {
          px = 0.04;
          pz = X - 0.04;
        } else {
          px = X - 0.02;
          pz = 0.02;
        }
      } else if (kind == 2) {  // fold back: overlapping plan
        px = std::abs(X - 0.05);
        pz = 0.01 * (X > 0.05);
      } else if (kind == 3) {  // smooth dome
        double r2 = (X - 0.05) * (X - 0.05) + (Y - 0.05) * (Y - 0.05);
        pz = 0.05 * std::exp(-r2 / 0.001);
        px = X * (1 + 0.1 * std::sin(30 * Y));
      } else if (kind == 4) {  // fully vertical plate
        px = 0.03;
        py = Y;
        pz = X;
      }
      double c = std::cos(ang), s = std::sin(ang);
      x[i] = c * px - s * py;
      x[i + 1] = s * px + c * py;
      x[i + 2] = pz;
    }
    std::vector<TrimSurface> trims;
    int nt = 1 + rng() % 3;
    std::ostringstream desc;
    for (int t = 0; t < nt; ++t) {
      int tk = rng() % 4;
      std::ostringstream text;
      text.precision(17);
      double cx = 0.1 * (u(rng) - 0.5) * 2, cy = 0.1 * (u(rng) - 0.5) * 2;
      if (tk == 0) {
        double a = u(rng) * 6.28, b = (u(rng) - 0.5);
        text << "plane:" << cx << "," << cy << "," << 0.01 * u(rng) << "," << std::cos(a) << "," << std::sin(a) << ","
             << b;
      } else if (tk == 1)
        text << "cylinder:" << cx << "," << cy << ",0,0,0,1," << 0.01 + 0.08 * u(rng);
      else if (tk == 2)
        text << "sphere:" << cx << "," << cy << ",0," << 0.01 + 0.08 * u(rng);
      else {
        std::string f = (std::filesystem::temp_directory_path() /
                         ("thermostamp_fuzz_p" + std::to_string(seed0) + "_" + std::to_string(t) + ".csv"))
                            .string();
        std::ofstream o(f);
        o.precision(17);
        int n = 3 + rng() % 12;
        double R = 0.01 + 0.06 * u(rng);
        bool grid = rng() % 2 == 0;
        for (int k = 0; k < n; ++k) {
          double a = 6.283185307179586 * (k + 0.8 * u(rng)) / n, r = R * (0.3 + 0.7 * u(rng));
          double vx = cx + r * std::cos(a), vy = cy + r * std::sin(a);
          if (grid) {
            vx = std::round(vx / 0.00625) * 0.00625;
            vy = std::round(vy / 0.00625) * 0.00625;
          }
          o << vx << "," << vy << "\n";
        }
        o.close();
        text << "polygon:" << f;
      }
      try {
        trims.push_back(parse_trim(text.str()));
        desc << text.str() << " ";
      } catch (const std::exception& e) {
      }
    }
    double margin = (rng() % 3 == 0) ? 0.005 * (u(rng) - 0.5) : 0;
    try {
      if (!trims.empty() && rng() % 2) {  // a trim twice: the same pattern
        std::vector<TrimSurface> twice = trims;
        twice.insert(twice.begin() + rng() % (twice.size() + 1), trims[rng() % trims.size()]);
        CutPattern a = cut_pattern(m.x, x, m.triangles, trims, margin);
        CutPattern b = cut_pattern(m.x, x, m.triangles, twice, margin);
        if (std::abs(a.kept_blank_area - b.kept_blank_area) > 1e-12 * a.blank_area ||
            a.outlines.size() != b.outlines.size()) {
          ++bad;
          if (bad < 15)
            std::printf("TWICE it %d kind %d: %.17g vs %.17g (%zu, %zu) %s\n", it, kind, a.kept_blank_area,
                        b.kept_blank_area, a.outlines.size(), b.outlines.size(), desc.str().c_str());
        }
      }
      CutPattern p = cut_pattern(m.x, x, m.triangles, trims, margin);
      if (!p.fallback.empty()) ++fallbacks;
      double sa = 0;
      for (auto& o : p.outlines) sa += sarea(o);
      // The outlines' points are joined within 1e-9 of the blank's size
      // (0.14 m here): their area may differ from the pattern's by that
      // times the outlines' length, some 1e-10 m^2 at most; a piece left
      // out or an outline that does not close differs by an element's
      // worth (1e-6 m^2 and more).
      bool ok = p.kept_blank_area <= p.blank_area * (1 + 1e-12) && p.kept_blank_area >= 0 &&
                std::abs(sa - p.kept_blank_area) <= 1e-8 * p.blank_area;
      if (std::abs(sa - p.kept_blank_area) > 1e-12 * p.blank_area) ++joined;
      if (!ok) {
        ++bad;
        if (bad < 15)
          std::printf(
              "BAD it %d kind %d nx %d ny %d crossed %d amp %g margin %g kept %.17g outlines %.17g (%zu) trims %s\n",
              it, kind, nx, ny, crossed, amp, margin, p.kept_blank_area, sa, p.outlines.size(), desc.str().c_str());
      }
    } catch (const std::exception& e) {
      ++thrown;
      if (thrown < 15)
        std::printf("THROW it %d kind %d: %s trims %s margin %g\n", it, kind, e.what(), desc.str().c_str(), margin);
    }
  }
  std::printf("%d cases, %d bad, %d thrown, %d by the distance, %d outline areas off by 1e-12 to 1e-8 of the blank's\n",
              N, bad, thrown, fallbacks, joined);
  return bad + thrown > 0 ? 1 : 0;
}
