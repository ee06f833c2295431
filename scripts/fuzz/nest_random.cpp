// Random patterns on a roll (scripts/fuzz_blank.py): star polygons of 3 to
// 24 points, one or two pieces, a hole in some, turned at random, gaps from
// 0 to a tenth of their size, rolls from narrower than the pattern to ten
// times it; a tenth of them laid out with pairs turned by 180 degrees tried
// (lay_on_roll), half of those with a quarter turn too, whose copies and
// turned copies are checked alike. Every
// layout must keep its copies apart by the gap (the exact distance between
// the polygons, over 7 lanes x 9 copies; 1e-9 of the size allowed for
// round-off), the copy along a lane that sets the pitch no further than
// four bands beyond it, its lanes within the roll, and its figures
// consistent (utilisation, roll per pattern, area by the shoelace sum).
// Each layout with a lane also gives a batch of 1 to 40 patterns
// (lay_batch): its copies must lie on the roll within its stretch, the gap
// apart, and no stretch of the lanes a little shorter (from any piece's
// start, the places counted one by one) may hold as many.
// Usage: nest_random CASES SEED [CASE]   (CASE: only that one, to look at it)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "io/nest.hpp"
using namespace ts;
using Pt = std::array<double, 2>;

static double cross(const Pt& o, const Pt& a, const Pt& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
static bool crosses(const Pt& a, const Pt& b, const Pt& c, const Pt& d) {
  const double d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}
static double point_segment(const Pt& p, const Pt& a, const Pt& b) {
  const double ux = b[0] - a[0], uy = b[1] - a[1];
  const double t = std::clamp(((p[0] - a[0]) * ux + (p[1] - a[1]) * uy) / (ux * ux + uy * uy), 0.0, 1.0);
  return std::hypot(p[0] - a[0] - t * ux, p[1] - a[1] - t * uy);
}
static bool in_region(const std::vector<Ring2>& rs, const Pt& p) {
  bool in = false;
  for (const Ring2& r : rs)
    for (std::size_t k = 0, j = r.size() - 1; k < r.size(); j = k++)
      if ((r[k][1] > p[1]) != (r[j][1] > p[1]) &&
          p[0] < (r[j][0] - r[k][0]) * (p[1] - r[k][1]) / (r[j][1] - r[k][1]) + r[k][0])
        in = !in;
  return in;
}
static double off_sides(const std::vector<Ring2>& rs, const Pt& p) {
  double m = 1e300;
  for (const Ring2& r : rs)
    for (std::size_t k = 0; k < r.size(); ++k) m = std::min(m, point_segment(p, r[k], r[(k + 1) % r.size()]));
  return m;
}
// The distance between two regions; -1 where they overlap by more than tol.
static double distance(const std::vector<Ring2>& a, const std::vector<Ring2>& b, double tol) {
  double d = 1e300;
  for (const Ring2& p : a)
    for (const Ring2& q : b)
      for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = 0; j < q.size(); ++j) {
          const Pt &u = p[i], &v = p[(i + 1) % p.size()], &w = q[j], &x = q[(j + 1) % q.size()];
          d = std::min({d, point_segment(u, w, x), point_segment(w, u, v)});
          if (crosses(u, v, w, x) && std::min({point_segment(u, w, x), point_segment(v, w, x), point_segment(w, u, v),
                                                point_segment(x, u, v)}) > tol)
            return -1;
        }
  for (const Ring2& p : a)
    for (const Pt& v : p)
      if (in_region(b, v) && off_sides(b, v) > tol) return -1;
  for (const Ring2& q : b)
    for (const Pt& v : q)
      if (in_region(a, v) && off_sides(a, v) > tol) return -1;
  return d;
}
static std::vector<Ring2> moved(const std::vector<Ring2>& rs, double dx, double dy) {
  std::vector<Ring2> out = rs;
  for (Ring2& r : out)
    for (Pt& v : r) v = {v[0] + dx, v[1] + dy};
  return out;
}

int main(int argc, char** argv) {
  const int N = argc > 1 ? std::atoi(argv[1]) : 1000;
  const unsigned seed0 = argc > 2 ? static_cast<unsigned>(std::atoi(argv[2])) : 1;
  const int only = argc > 3 ? std::atoi(argv[3]) : -1;
  int bad = 0, none = 0, pairs_taken = 0, quarters_taken = 0;
  double worst_excess = 0;  // the distance over the gap of the copy that sets the pitch, in bands
  for (int it = 0; it < N; ++it) {
    if (only >= 0 && it != only) continue;
    std::mt19937 rng(seed0 * 1000003u + static_cast<unsigned>(it));
    std::uniform_real_distribution<double> u(0, 1);
    auto star = [&](double cx, double cy, double r0, bool reverse) {
      const int n = 3 + static_cast<int>(u(rng) * 22);
      std::vector<double> t(static_cast<std::size_t>(n));
      for (double& a : t) a = 2 * M_PI * u(rng);
      std::sort(t.begin(), t.end());
      Ring2 r;
      for (const double a : t) {
        const double rr = r0 * (0.3 + 0.7 * u(rng));
        r.push_back({cx + rr * std::cos(a), cy + rr * std::sin(a)});
      }
      if (reverse) std::reverse(r.begin(), r.end());
      return r;
    };
    std::vector<Ring2> rings{star(0, 0, 0.1, false)};
    const double kind = u(rng);
    if (kind < 0.3) rings.push_back(star(0.25 * (u(rng) - 0.5) + 0.3, 0.3 * (u(rng) - 0.5), 0.06, false));
    const bool hole = kind >= 0.3 && kind < 0.5 && in_region(rings, {0, 0}) && off_sides(rings, {0, 0}) > 0.026;
    if (hole) rings.push_back(star(0, 0, 0.025, true));  // a hole about the centre, within the star
    const double turn = 2 * M_PI * u(rng), c = std::cos(turn), s = std::sin(turn);
    for (Ring2& r : rings)
      for (Pt& v : r) v = {c * v[0] - s * v[1], s * v[0] + c * v[1]};
    double area = 0;  // the pieces' areas less the hole's
    for (std::size_t k = 0; k < rings.size(); ++k) {
      const Ring2& r = rings[k];
      double a = 0;
      for (std::size_t i = 0; i < r.size(); ++i)
        a += 0.5 * (r[i][0] * r[(i + 1) % r.size()][1] - r[(i + 1) % r.size()][0] * r[i][1]);
      area += (k > 0 && hole ? -1 : 1) * std::abs(a);
    }
    double lo = 1e300, hi = -1e300, size = 0;
    for (const Ring2& r : rings)
      for (const Pt& v : r) {
        lo = std::min(lo, v[1]);
        hi = std::max(hi, v[1]);
        size = std::max({size, std::abs(v[0]), std::abs(v[1])});
      }
    const double gap = u(rng) < 0.3 ? 0.0 : 0.02 * u(rng);
    const double width = (hi - lo) * (0.8 + 9 * u(rng));
    RollNest n;
    const int bands = 200 + static_cast<int>(u(rng) * 800);
    const bool try_pairs = u(rng) < 0.1;
    const bool try_quarter = try_pairs && u(rng) < 0.5;  // half of those also turned by 90 degrees
    if (only >= 0)
      std::printf("width %.17g, gap %.17g, bands %d%s%s\n", width, gap, bands, try_pairs ? ", pairs" : "",
                  try_quarter ? ", a quarter turn" : "");
    std::vector<Ring2> unit = rings;
    bool paired = false, quartered = false;
    try {
      if (try_pairs) {
        const RollLayout l = lay_on_roll(rings, width, gap, true, bands, try_quarter);
        n = l.nest;
        unit = l.unit;
        paired = l.pairs;
        quartered = l.turned_90;
        pairs_taken += paired;
        quarters_taken += quartered;
        if (!(l.roll_per_pattern <= l.single_roll_per_pattern || l.single_roll_per_pattern == 0)) {
          std::printf("case %d: pairs take more roll than copies alike\n", it);
          ++bad;
        }
        for (std::size_t k = 0; quartered && k < rings.size(); ++k)  // the pattern turned by +90 degrees
          for (std::size_t i = 0; i < rings[k].size(); ++i)
            if (unit[k][i] != Pt{-rings[k][i][1], rings[k][i][0]}) {
              std::printf("case %d: the first copy is not the pattern turned by 90 degrees\n", it);
              ++bad;
              k = rings.size();
              break;
            }
      } else {
        n = nest_on_roll(rings, width, gap, bands);
      }
    } catch (const std::exception& e) {
      std::printf("case %d: threw %s\n", it, e.what());
      ++bad;
      continue;
    }
    bool ok = std::abs(n.area - (paired ? 2 : 1) * area) <= 1e-12 * area;
    if (paired || quartered) {  // the unit's extent across
      lo = 1e300;
      hi = -1e300;
      for (const Ring2& r : unit)
        for (const Pt& v : r) {
          lo = std::min(lo, v[1]);
          hi = std::max(hi, v[1]);
        }
    }
    const double across = hi - lo + gap;
    const int fit = width + 1e-9 * size >= across ? 1 + static_cast<int>(std::floor((width - across) / n.lane_step + 1e-9)) : 0;
    ok = ok && n.lanes == fit;
    if (n.lanes > 0)
      ok = ok && std::abs(n.utilisation - n.lanes * n.area / (width * n.pitch)) <= 1e-12 &&
           std::abs(n.roll_per_pattern - n.pitch / n.lanes) <= 1e-15;  // of the unit
    else
      ++none;
    // The first lane from gap / 2 to the last within width - gap / 2.
    if (n.lanes > 0) {
      const double bottom = lo + n.origin[1], top = hi + n.origin[1] + (n.lanes - 1) * n.lane_step;
      ok = ok && std::abs(bottom - gap / 2) < 1e-12 && top <= width - gap / 2 + 1e-9 * size;
    }
    double nearest = 1e300;
    for (int j = -3; j <= 3 && nearest >= 0; ++j)
      for (int i = -4; i <= 4 && nearest >= 0; ++i)
        if (i != 0 || j != 0)
          nearest = std::min(nearest, distance(unit, moved(unit, i * n.pitch + j * n.lane_shift, j * n.lane_step),
                                               1e-9 * size));
    if (paired)  // the pattern and its turned copy in the unit
      nearest = std::min(nearest, distance({unit.begin(), unit.begin() + static_cast<long>(rings.size())},
                                           {unit.begin() + static_cast<long>(rings.size()), unit.end()}, 1e-9 * size));
    ok = ok && nearest >= gap - 1e-9 * size;
    // The copy along the lane that sets the pitch within four bands of the
    // gap (each banded copy reaches at most two bands beyond the points
    // within gap / 2 of it): the nearest of those the pitch keeps clear.
    double along = 1e300;
    for (int i = 1; n.lanes > 0 && (i - 1) * n.pitch <= 4 * size + gap; ++i)
      along = std::min(along, distance(unit, moved(unit, i * n.pitch, 0), 1e-9 * size));
    ok = ok && (n.lanes == 0 || along <= gap + 4 * n.resolution + 1e-9 * size);
    if (n.lanes > 0 && along >= 0) worst_excess = std::max(worst_excess, (along - gap) / n.resolution);
    if (n.lanes > 0) {  // a batch
      RollLayout l;
      l.nest = n;
      l.unit = unit;
      l.pairs = paired;
      const int count = 1 + static_cast<int>(u(rng) * 40);
      const RollBatch b = lay_batch(l, gap, count);
      const std::size_t per = paired ? rings.size() : unit.size();
      auto piece = [&](int k) { return std::vector<Ring2>(unit.begin() + k * per, unit.begin() + (k + 1) * per); };
      std::vector<std::vector<Ring2>> placed;
      bool inside = b.copies.size() == static_cast<std::size_t>(count);
      for (const RollCopy& c : b.copies) {
        placed.push_back(moved(piece(c.piece), c.offset[0], c.offset[1]));
        for (const Ring2& r : placed.back())
          for (const Pt& v : r)
            inside = inside && v[0] >= gap / 2 - 1e-9 * size && v[0] <= b.length - gap / 2 + 1e-9 * size &&
                     v[1] >= gap / 2 - 1e-9 * size && v[1] <= width - gap / 2 + 1e-9 * size;
      }
      double apart = 1e300;
      for (std::size_t i = 0; i < placed.size(); ++i)
        for (std::size_t j = i + 1; j < placed.size(); ++j)
          apart = std::min(apart, distance(placed[i], placed[j], 1e-9 * size));
      std::vector<std::array<double, 2>> slots;  // every place of the lanes by its extent along the roll
      const int pieces = paired ? 2 : 1, units = (count + pieces * n.lanes - 1) / (pieces * n.lanes);
      const int places = 4 * units + 8 + 3 * static_cast<int>(std::ceil(n.length / n.pitch));
      for (int j = 0; j < n.lanes; ++j)
        for (int i = 0; i < places; ++i)
          for (int k = 0; k < pieces; ++k) {
            const double x = n.origin[0] + i * n.pitch + std::fmod(j * n.lane_shift, n.pitch);
            double a = 1e300, z = -1e300;
            for (const Ring2& r : piece(k))
              for (const Pt& v : r) {
                a = std::min(a, v[0] + x);
                z = std::max(z, v[0] + x);
              }
            slots.push_back({a, z});
          }
      int most = 0;
      for (const auto& st : slots) {
        int within = 0;
        for (const auto& t : slots) within += t[0] >= st[0] && t[1] <= st[0] + b.length - gap - 1e-9 * size;
        most = std::max(most, within);
      }
      if (!inside || apart < gap - 1e-9 * size || most >= count) {
        std::printf("case %d: a batch of %d: %s, copies %.9g apart, %d within a shorter stretch  FAILED\n", it, count,
                    inside ? "on the roll" : "off the roll or its stretch", apart, most);
        ok = false;
      }
    }
    if (only >= 0)
      for (const Ring2& r : rings) {
        std::printf("ring:");
        for (const Pt& v : r) std::printf(" {%.17g, %.17g},", v[0], v[1]);
        std::printf("\n");
      }
    if (!ok || only >= 0)
      std::printf("case %d: %zu rings, gap %g, width %g: pitch %.9g, step %.9g, shift %.9g, lanes %d (fit %d), "
                  "area %.9g (%.9g), nearest copy %.9g%s\n",
                  it, rings.size(), gap, width, n.pitch, n.lane_step, n.lane_shift, n.lanes, fit, n.area,
                  area, nearest, ok ? "" : "  FAILED");
    if (!ok) ++bad;
  }
  std::printf("%d cases, %d failed, %d with a roll too narrow, %d in pairs turned by 180 deg, %d turned by 90 deg; the "
              "copy that sets the pitch at most %.3g bands beyond the gap\n",
              only >= 0 ? 1 : N, bad, none, pairs_taken, quarters_taken, worst_excess);
  return bad ? 1 : 0;
}
