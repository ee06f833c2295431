// The cost of a cut pattern (thermostamp blank's core): a flat plate of
// 0.3 m in N x N crossed cells, not moved, trimmed by a cylinder of
// radius 0.1 m, by a polygon of V vertices on the same circle, and by
// that polygon and a plane through its centre (a corner where they
// meet), and by the polygon with a margin of 5 mm out and in (its outline
// moved, then cut). Prints one line per trim: seconds (best of 3), the
// pattern's area; and the time the moved outline takes alone, with its area.
// Usage: blank_patterns N V POLYGON_CSV
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "io/blank.hpp"
#include "mesh/shell_mesh.hpp"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: blank_patterns N V POLYGON_CSV\n");
    return 2;
  }
  const int n = std::atoi(argv[1]), v = std::atoi(argv[2]);
  const std::string csv = argv[3];
  {
    std::ofstream f(csv);
    f.precision(17);
    for (int k = 0; k < v; ++k)
      f << 0.15 + 0.1 * std::cos(2 * M_PI * k / v) << "," << 0.15 + 0.1 * std::sin(2 * M_PI * k / v) << "\n";
  }
  const ts::ShellMesh m = ts::rectangle_mesh({0, 0, 0}, {0.3, 0.3}, {n, n}, true);
  struct Case {
    std::string name;
    std::vector<ts::TrimSurface> trims;
    double margin = 0;
  };
  const std::vector<Case> cases = {
      {"cylinder", {ts::parse_trim("cylinder:0.15,0.15,0,0,0,1,0.1")}},
      {"polygon", {ts::parse_trim("polygon:" + csv)}},
      {"polygon+plane", {ts::parse_trim("polygon:" + csv), ts::parse_trim("plane:0.15,0.15,0,1,1,0")}},
      {"polygon,+5mm", {ts::parse_trim("polygon:" + csv)}, 0.005},
      {"polygon,-5mm", {ts::parse_trim("polygon:" + csv)}, -0.005},
  };
  std::printf("%zu triangles, %zu nodes, polygon of %d vertices\n", m.triangles.size() / 3, m.x.size() / 3, v);
  for (const Case& c : cases) {
    double best = 1e300, area = 0;
    for (int r = 0; r < 3; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const ts::CutPattern p = ts::cut_pattern(m.x, m.x, m.triangles, c.trims, c.margin);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      best = std::min(best, s);
      area = p.kept_blank_area;
    }
    std::printf("%-14s %.4f s  area %.9f m^2\n", c.name.c_str(), best, area);
  }
  for (const double margin : {0.005, -0.005}) {  // the moved outline alone
    double best = 1e300, area = 0;
    for (int r = 0; r < 3; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const auto rings = ts::polygon_margin_rings(cases[1].trims[0], margin);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      best = std::min(best, s);
      area = 0;
      for (const auto& q : rings)
        for (std::size_t k = 0; k < q.size(); ++k)
          area += 0.5 * (q[k][0] * q[(k + 1) % q.size()][1] - q[(k + 1) % q.size()][0] * q[k][1]);
    }
    std::printf("%-14s %.4f s  area %.9f m^2\n", margin > 0 ? "outline,+5mm" : "outline,-5mm", best, area);
  }
  return 0;
}
