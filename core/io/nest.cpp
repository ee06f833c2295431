#include "io/nest.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <tuple>
#include <stdexcept>
#include <utility>

namespace ts {
namespace {

using Interval = std::pair<double, double>;
using Set = std::vector<Interval>;  // sorted by their start

// Joins intervals that overlap (closed sets: those that touch too).
void merge_closed(Set& s) {
  std::sort(s.begin(), s.end());
  Set out;
  for (const Interval& i : s)
    if (!out.empty() && i.first <= out.back().second)
      out.back().second = std::max(out.back().second, i.second);
    else
      out.push_back(i);
  s = std::move(out);
}

// Joins open intervals that overlap; two that only touch stay apart (the
// point between them is not in the set).
void merge_open(Set& s) {
  std::sort(s.begin(), s.end());
  Set out;
  for (const Interval& i : s)
    if (!out.empty() && i.first < out.back().second)
      out.back().second = std::max(out.back().second, i.second);
    else
      out.push_back(i);
  s = std::move(out);
}

// The extent in x of the region (inside an odd number of rings) within the
// strip a <= y <= b: the x-ranges of its edges' pieces in the strip and its
// spans on the strip's two lines. Each piece of the region in the strip is
// connected, so its extent is that of its boundary, made of those.
Set strip_extent(const std::vector<Ring2>& rings, double a, double b) {
  Set out;
  std::vector<double> on_a, on_b;
  for (const Ring2& r : rings)
    for (std::size_t k = 0; k < r.size(); ++k) {
      const auto& p = r[k];
      const auto& q = r[(k + 1) % r.size()];
      const double lo = std::min(p[1], q[1]), hi = std::max(p[1], q[1]);
      if (hi >= a && lo <= b) {
        if (p[1] == q[1]) {
          out.emplace_back(std::min(p[0], q[0]), std::max(p[0], q[0]));
        } else {
          const double ta = (a - p[1]) / (q[1] - p[1]), tb = (b - p[1]) / (q[1] - p[1]);
          const double t0 = std::clamp(std::min(ta, tb), 0.0, 1.0), t1 = std::clamp(std::max(ta, tb), 0.0, 1.0);
          const double x0 = p[0] + t0 * (q[0] - p[0]), x1 = p[0] + t1 * (q[0] - p[0]);
          out.emplace_back(std::min(x0, x1), std::max(x0, x1));
        }
      }
      for (auto [y, xs] : {std::pair<double, std::vector<double>*>{a, &on_a}, {b, &on_b}})
        if ((p[1] <= y) != (q[1] <= y)) xs->push_back(p[0] + (y - p[1]) / (q[1] - p[1]) * (q[0] - p[0]));
    }
  for (std::vector<double>* xs : {&on_a, &on_b}) {
    std::sort(xs->begin(), xs->end());
    for (std::size_t k = 0; k + 1 < xs->size(); k += 2) out.emplace_back((*xs)[k], (*xs)[k + 1]);
  }
  merge_closed(out);
  return out;
}

// The pattern in `count` bands of height `step` from `y0` up, each band
// by the extent along the roll of the points within `r` of the pattern and
// level with it (a disc of radius r about each point of the pattern). A
// band's own part of the pattern is taken by its extent (strip_extent, the
// strip drawn in by `eps` so that a band whose edge lies along an edge of
// the pattern takes none of the region beyond), and a part j bands away
// grown by sqrt(r^2 - d^2), d = (j - 1) step its least distance across the
// roll from the band: the set holds every point within r of the pattern
// and none beyond r + 2 step (a point of a band's part of the pattern lies
// at most a step across the roll from the band).
std::vector<Set> grown_bands(const std::vector<Ring2>& rings, double y0, double step, int count, double r,
                             double eps) {
  std::vector<Set> own(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k)
    own[static_cast<std::size_t>(k)] = strip_extent(rings, y0 + k * step + eps, y0 + (k + 1) * step - eps);
  if (!(r > 0)) return own;
  std::vector<Set> out(static_cast<std::size_t>(count));
  const int reach = 1 + static_cast<int>(std::ceil(r / step));
  for (int k = 0; k < count; ++k) {
    Set s;
    for (int j = std::max(0, k - reach); j <= std::min(count - 1, k + reach); ++j) {
      const double d = std::max(0, std::abs(j - k) - 1) * step;
      if (d >= r) continue;
      const double a = std::sqrt(r * r - d * d);
      for (const auto& [lo, hi] : own[static_cast<std::size_t>(j)]) s.emplace_back(lo - a, hi + a);
    }
    merge_closed(s);
    out[static_cast<std::size_t>(k)] = std::move(s);
  }
  return out;
}

double signed_area(const Ring2& r) {
  double s = 0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    const auto& p = r[k];
    const auto& q = r[(k + 1) % r.size()];
    s += p[0] * q[1] - q[0] * p[1];
  }
  return s / 2;
}

// The area inside an odd number of rings: each ring's area, counted
// against the region where it lies inside an odd number of the others (a
// hole's), whichever way round it runs. Rings neither cross nor touch.
double region_area(const std::vector<Ring2>& rings) {
  double area = 0;
  for (std::size_t k = 0; k < rings.size(); ++k) {
    if (rings[k].size() < 3) continue;
    int depth = 0;
    for (std::size_t j = 0; j < rings.size(); ++j)
      if (j != k && rings[j].size() >= 3 && ring_contains(rings[j], rings[k][0][0], rings[k][0][1])) ++depth;
    area += (depth % 2 ? -1 : 1) * std::abs(signed_area(rings[k]));
  }
  return area;
}

// The open set `f` taken modulo p, within [0, p).
Set fold(const Set& f, double p) {
  Set out;
  for (const auto& [lo, hi] : f) {
    if (hi - lo >= p) return {{-1.0, p + 1}};  // every place
    const double k = std::floor(lo / p);
    const double a = lo - k * p, b = hi - k * p;
    if (b <= p) {
      out.emplace_back(a, b);
    } else {
      // Across the place p, which is also the place 0: both ends taken.
      out.emplace_back(a, p + 1);
      out.emplace_back(-1.0, b - p);
    }
  }
  merge_open(out);
  return out;
}

// The closed complement of the open set `f` within [0, p].
Set complement(const Set& f, double p) {
  Set out;
  double from = 0;
  for (const auto& [lo, hi] : f) {
    if (lo > from) out.emplace_back(from, std::min(lo, p));
    from = std::max(from, hi);
    if (from >= p) break;
  }
  if (from <= p) out.emplace_back(from, p);
  return out;
}

Set intersect(const Set& a, const Set& b) {
  Set out;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const double lo = std::max(a[i].first, b[j].first), hi = std::min(a[i].second, b[j].second);
    if (lo <= hi) out.emplace_back(lo, hi);
    if (a[i].second < b[j].second)
      ++i;
    else
      ++j;
  }
  return out;
}

}  // namespace

bool ring_contains(const Ring2& p, double x, double y) {
  bool inside = false;
  const std::size_t n = p.size();
  for (std::size_t k = 0, j = n - 1; k < n; j = k++) {
    const auto& a = p[j];
    const auto& b = p[k];
    if ((a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])) inside = !inside;
  }
  return inside;
}

namespace {

// nest_on_roll of a pattern whose area is known (a pair, whose two copies
// may touch: where a vertex of one lies on the other, which of the two it
// lies within is a matter of round-off).
RollNest nest_with_area(const std::vector<Ring2>& rings, double area, double roll_width, double gap, int bands) {
  if (!(std::isfinite(roll_width) && roll_width >= 0))
    throw std::invalid_argument("a roll width not finite or below 0");
  if (!(std::isfinite(gap) && gap >= 0)) throw std::invalid_argument("a gap not finite or below 0");
  if (bands < 1) throw std::invalid_argument("fewer than one band");
  RollNest n;
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (const Ring2& r : rings)
    for (const auto& v : r)
      for (int c = 0; c < 2; ++c) {
        if (!std::isfinite(v[static_cast<std::size_t>(c)])) throw std::invalid_argument("a vertex not finite");
        lo[c] = std::min(lo[c], v[static_cast<std::size_t>(c)]);
        hi[c] = std::max(hi[c], v[static_cast<std::size_t>(c)]);
      }
  n.area = area;
  if (!(n.area > 0)) throw std::invalid_argument("a pattern without area");
  n.length = hi[0] - lo[0];
  n.width = hi[1] - lo[1];
  const int K = bands;
  const double step = (n.width + gap) / K;  // the bands' height
  n.resolution = step;
  const double eps = 1e-9 * (n.length + n.width + gap);  // round-off allowance
  // Each band of the pattern grown by gap / 2 all round: two copies whose
  // grown bands keep apart are at least the gap apart.
  const std::vector<Set> band = grown_bands(rings, lo[1] - gap / 2, step, K, gap / 2, eps);
  // The shifts along the roll at which a copy m bands higher overlaps the
  // pattern (open intervals: copies may touch), each grown by the round-off
  // allowance, so that copies never overlap by round-off.
  std::vector<Set> over(static_cast<std::size_t>(K));
  std::vector<bool> done(static_cast<std::size_t>(K), false);
  auto overlap = [&](int m) -> const Set& {
    const auto mm = static_cast<std::size_t>(m);
    if (!done[mm]) {
      Set s;
      for (int k = 0; k + m < K; ++k)
        for (const Interval& i : band[static_cast<std::size_t>(k)])
          for (const Interval& j : band[static_cast<std::size_t>(k + m)]) {
            s.emplace_back(j.first - i.second - eps, j.second - i.first + eps);
          }
      merge_open(s);
      over[mm] = std::move(s);
      done[mm] = true;
    }
    return over[mm];
  };
  // The pitch: the smallest p for which no copy k p along the lane
  // overlaps the pattern.
  const Set& along = overlap(0);
  double p = 0;
  for (const Interval& i : along)
    if (i.first < 0 && 0 < i.second) p = i.second;
  if (!(p > 0)) p = n.length + gap;  // a pattern with no band (cannot be: it has area)
  const double far = along.empty() ? 0.0 : along.back().second;
  for (bool moved = true; moved;) {
    moved = false;
    for (int k = 1; k * p < far && !moved; ++k)
      for (const Interval& i : along)
        if (i.first < k * p && k * p < i.second) {
          // The least p with k p at the interval's end (k p rounds below
          // it for p = end / k at times).
          double q = i.second / k;
          while (k * q < i.second) q = std::nextafter(q, 2 * q);
          p = q;
          moved = true;
          break;
        }
  }
  n.pitch = p;
  // The lanes: the smallest step of m bands with a shift s along the roll
  // for which no copy of lane j (j s + k p along, j m bands across)
  // overlaps the pattern.
  int m_best = K;
  double s_best = 0;
  for (int m = 1; m < K; ++m) {
    Set allowed{{0.0, p}};
    for (int j = 1; j * m < K && !allowed.empty(); ++j) {
      const Set free = complement(fold(overlap(j * m), p), p);
      Set sj;  // the shifts s with j s (mod p) free
      for (int r = 0; r < j; ++r)
        for (const auto& [a, b] : free) sj.emplace_back((a + r * p) / j, (b + r * p) / j);
      merge_closed(sj);
      allowed = intersect(allowed, sj);
    }
    if (!allowed.empty()) {
      const Interval* widest = &allowed.front();
      for (const Interval& i : allowed)
        if (i.second - i.first > widest->second - widest->first) widest = &i;
      m_best = m;
      s_best = (widest->first + widest->second) / 2;
      if (s_best >= p) s_best -= p;
      break;
    }
  }
  n.lane_step = m_best * step;
  n.lane_shift = s_best;
  const double across = n.width + gap;  // a lane's height on the roll
  n.lanes =
      roll_width + eps >= across ? 1 + static_cast<int>(std::floor((roll_width - across + eps) / n.lane_step)) : 0;
  if (n.lanes > 0) {
    n.roll_per_pattern = n.pitch / n.lanes;
    n.utilisation = roll_width > 0 ? n.lanes * n.area / (roll_width * n.pitch) : 0.0;
  }
  n.origin = {gap / 2 - lo[0], gap / 2 - lo[1]};
  return n;
}

}  // namespace

RollNest nest_on_roll(const std::vector<Ring2>& rings, double roll_width, double gap, int bands) {
  return nest_with_area(rings, region_area(rings), roll_width, gap, bands);
}

namespace {

// lay_on_roll of the pattern as given.
RollLayout lay_as_given(const std::vector<Ring2>& rings, double roll_width, double gap, bool try_pairs, int bands) {
  RollLayout best;
  best.nest = nest_on_roll(rings, roll_width, gap, bands);
  best.unit = rings;
  best.area = best.nest.area;
  best.length = best.nest.length;
  best.width = best.nest.width;
  auto per_metre = [](const RollNest& n, int copies) { return n.lanes > 0 ? copies * n.lanes / n.pitch : 0.0; };
  best.roll_per_pattern = best.nest.lanes > 0 ? best.nest.pitch / best.nest.lanes : 0.0;
  best.single_roll_per_pattern = best.roll_per_pattern;
  if (!try_pairs) return best;
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (const Ring2& r : rings)
    for (const auto& v : r)
      for (std::size_t c = 0; c < 2; ++c) {
        lo[c] = std::min(lo[c], v[c]);
        hi[c] = std::max(hi[c], v[c]);
      }
  const double H = hi[1] - lo[1], eps = 1e-9 * (hi[0] - lo[0] + H + gap);
  constexpr int kFine = 250;  // bands to choose with
  const double pick = (hi[1] - lo[1] + gap) / kFine;
  // The turned copy q(v) = t - v beside the pattern: for an offset t_y
  // across, the shifts t_x at which the two (each grown by gap / 2 all
  // round) overlap, band by band over their common height; the turned copy
  // then lies just beyond them, to the right or to the left.
  const double need = 1.005 * per_metre(best.nest, 1);  // patterns per metre of roll a pair must beat
  // The pattern and its copy turned by 180 degrees whose vertex of v lies at t - v.
  auto pair_at = [&rings](const std::array<double, 2>& t) {
    std::vector<Ring2> pair = rings;
    for (Ring2 r : rings) {
      for (auto& v : r) v = {t[0] - v[0], t[1] - v[1]};
      pair.push_back(std::move(r));
    }
    return pair;
  };
  std::vector<std::pair<double, std::array<double, 2>>> found;  // patterns per metre, and the offset t
  for (int o = 0; o <= 40; ++o) {
    const double ty = (lo[1] + hi[1]) + H * (o - 20) / 20.0;
    std::vector<Ring2> turned = rings;
    for (Ring2& r : turned)
      for (auto& v : r) v = {-v[0], ty - v[1]};
    const double y_lo = std::max(lo[1], ty - hi[1]) - gap, y_hi = std::min(hi[1], ty - lo[1]) + gap;
    Set forbid;
    if (y_hi > y_lo) {
      const int count = static_cast<int>(std::ceil((y_hi - y_lo) / pick));
      // Closed strips (not drawn in): every point of either copy counts,
      // also on a band's edge, and the turned copy keeps clear of the
      // first by the round-off allowance.
      const std::vector<Set> a = grown_bands(rings, y_lo, pick, count, gap / 2, 0.0);
      const std::vector<Set> b = grown_bands(turned, y_lo, pick, count, gap / 2, 0.0);
      for (std::size_t k = 0; k < a.size(); ++k)
        for (const Interval& i : a[k])
          for (const Interval& j : b[k]) forbid.emplace_back(i.first - j.second - eps, i.second - j.first + eps);
    }
    merge_open(forbid);
    if (forbid.empty()) continue;  // one above the other: no nearer than the single layout's lanes
    for (const double tx : {forbid.back().second, forbid.front().first}) {
      const RollNest n = nest_with_area(pair_at({tx, ty}), 2 * best.area, roll_width, gap, kFine);
      if (const double rate = per_metre(n, 2); rate > need) found.emplace_back(rate, std::array<double, 2>{tx, ty});
    }
  }
  // The best few pairs again with the bands asked for (the choice with
  // fewer bands may differ by a lane or a band's step); the best of them
  // kept where it still saves.
  constexpr std::size_t kKept = 3;
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  double best_rate = need;
  for (std::size_t k = 0; k < std::min(kKept, found.size()); ++k) {
    const std::array<double, 2> t = found[k].second;
    std::vector<Ring2> pair = pair_at(t);
    const RollNest n = nest_with_area(pair, 2 * best.area, roll_width, gap, bands);
    if (const double rate = per_metre(n, 2); rate > best_rate) {
      best_rate = rate;
      best.nest = n;
      best.unit = std::move(pair);
      best.pairs = true;
      best.turned = t;
      best.roll_per_pattern = n.pitch / (2.0 * n.lanes);
    }
  }
  return best;
}

}  // namespace

RollLayout lay_on_roll(const std::vector<Ring2>& rings, double roll_width, double gap, bool try_pairs, int bands,
                       bool try_quarter_turn) {
  RollLayout best = lay_as_given(rings, roll_width, gap, try_pairs, bands);
  if (!try_quarter_turn) return best;
  std::vector<Ring2> quarter = rings;
  for (Ring2& r : quarter)
    for (auto& v : r) v = {-v[1], v[0]};
  RollLayout turned = lay_as_given(quarter, roll_width, gap, try_pairs, bands);
  // Taken where it saves at least half a per cent of the roll (or fits
  // where the pattern as given does not).
  const bool fits = turned.roll_per_pattern > 0;
  if (fits && (best.roll_per_pattern == 0 || turned.roll_per_pattern * 1.005 < best.roll_per_pattern)) {
    turned.turned_90 = true;
    turned.single_roll_per_pattern = best.single_roll_per_pattern;  // the pattern as given, all alike
    return turned;
  }
  return best;
}

std::vector<std::array<double, 2>> piece_extents(const std::vector<Ring2>& unit, int pieces) {
  const std::size_t per = unit.size() / static_cast<std::size_t>(pieces);
  std::vector<std::array<double, 2>> extent;
  for (std::size_t k = 0; k < static_cast<std::size_t>(pieces); ++k) {
    std::array<double, 2> e{1e300, -1e300};
    for (std::size_t r = k * per; r < (k + 1) * per; ++r)
      for (const auto& v : unit[r]) e = {std::min(e[0], v[0]), std::max(e[1], v[0])};
    extent.push_back(e);
  }
  return extent;
}

RollBatch lay_batch(const RollLayout& layout, double gap, int count) {
  const RollNest& n = layout.nest;
  if (count < 1 || count > 10000) throw std::invalid_argument("a batch of fewer than 1 or more than 10000 patterns");
  if (n.lanes < 1 || !(n.pitch > 0)) throw std::invalid_argument("a layout without a lane");
  const int pieces = layout.pairs ? 2 : 1;
  const std::vector<std::array<double, 2>> extent = piece_extents(layout.unit, pieces);  // in the unit's coordinates
  // Every lane's places i = 0 .. last: the window of the shortest stretch
  // is at most (units + 1) pitches and a unit long (units of every lane
  // from any start), so places from m on, m pitches beyond the unit's
  // length, hold every window that starts in their first pitch.
  const long units = (count + static_cast<long>(n.lanes) * pieces - 1) / (static_cast<long>(n.lanes) * pieces);
  const long m = static_cast<long>(std::ceil(n.length / n.pitch)) + 1;
  const long last = units + 3 * m + 4;
  struct Slot {
    double lo, hi;  // the piece's extent along the roll
    int lane, piece;
    long place;
  };
  std::vector<Slot> slots;
  slots.reserve(static_cast<std::size_t>(n.lanes) * pieces * (last + 1));
  for (int j = 0; j < n.lanes; ++j) {
    const double shift = std::fmod(j * n.lane_shift, n.pitch);
    for (long i = 0; i <= last; ++i) {
      const double x = n.origin[0] + static_cast<double>(i) * n.pitch + shift;
      for (int k = 0; k < pieces; ++k) slots.push_back({x + extent[k][0], x + extent[k][1], j, k, i});
    }
  }
  // The starts from the last to the first: the count nearest ends of the
  // slots that start at or after each, kept in a heap of the largest.
  std::sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) { return a.lo > b.lo; });
  std::priority_queue<double> ends;
  double best = 1e300, start = 0, end = 0;
  for (std::size_t s = 0; s < slots.size();) {
    const double x0 = slots[s].lo;
    for (; s < slots.size() && slots[s].lo == x0; ++s) {
      if (ends.size() < static_cast<std::size_t>(count)) {
        ends.push(slots[s].hi);
      } else if (slots[s].hi < ends.top()) {
        ends.pop();
        ends.push(slots[s].hi);
      }
    }
    if (ends.size() == static_cast<std::size_t>(count) && ends.top() - x0 < best) {
      best = ends.top() - x0;
      start = x0;
      end = ends.top();
    }
  }
  std::vector<const Slot*> in;
  for (const Slot& s : slots)
    if (s.lo >= start && s.hi <= end) in.push_back(&s);
  std::sort(in.begin(), in.end(), [](const Slot* a, const Slot* b) {
    return std::tie(a->hi, a->lane, a->place, a->piece) < std::tie(b->hi, b->lane, b->place, b->piece);
  });
  RollBatch batch;
  batch.length = best + gap;
  for (std::size_t c = 0; c < static_cast<std::size_t>(count); ++c) {
    const Slot& s = *in[c];
    const double shift = std::fmod(s.lane * n.lane_shift, n.pitch);
    batch.copies.push_back({s.piece,
                            {n.origin[0] + static_cast<double>(s.place) * n.pitch + shift - start + gap / 2,
                             n.origin[1] + s.lane * n.lane_step}});
  }
  return batch;
}

}  // namespace ts
