// The cost of laying patterns on a roll (thermostamp blank --roll): a disc
// of 720 vertices (r = 100 mm) and an ellipse of 5 000 (150 x 50 mm) on a
// roll 0.6 m wide, gaps 0, 5 and 20 mm: nest_on_roll (copies alike),
// lay_on_roll (pairs tried) and lay_batch of the latter for batches of 10,
// 1 000 and 10 000 patterns. One line per case: the pattern, the gap (m),
// then seconds (best of 3) for alike, pairs and the three batches, and the
// batches' lengths (m).
// Usage: nest_roll
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "io/nest.hpp"

namespace {

ts::Ring2 ellipse(double a, double b, int n) {
  ts::Ring2 r;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n;
    r.push_back({a * std::cos(t), b * std::sin(t)});
  }
  return r;
}

double best_of_3(const std::function<void()>& f) {
  double best = 1e300;
  for (int k = 0; k < 3; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace

int main() {
  const double width = 0.6;
  for (const auto& [name, ring] : {std::pair{"disc", ellipse(0.1, 0.1, 720)},
                                   std::pair{"ellipse", ellipse(0.15, 0.05, 5000)}})
    for (const double gap : {0.0, 0.005, 0.02}) {
      const double alike = best_of_3([&] { ts::nest_on_roll({ring}, width, gap); });
      ts::RollLayout l;
      const double pairs = best_of_3([&] { l = ts::lay_on_roll({ring}, width, gap); });
      std::printf("%s %g %.4f %.4f", name, gap, alike, pairs);
      std::vector<double> lengths;
      for (const int count : {10, 1000, 10000}) {
        ts::RollBatch b;
        std::printf(" %.7f", best_of_3([&] { b = ts::lay_batch(l, gap, count); }));
        lengths.push_back(b.length);
      }
      for (const double len : lengths) std::printf(" %.6g", len);
      std::printf("\n");
    }
  return 0;
}
