// Copies of a cut pattern on a roll (`blank --roll`): lanes against the
// closed forms of shapes whose best lanes are known (a rectangle, a
// staircase that tiles the roll, a disc's and an ellipse's hexagonal
// lanes), and on a star with a notch, copies checked by their exact
// geometry: never nearer than the gap, and no lane step three bands
// smaller that any shift allows.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <tuple>

#include "io/nest.hpp"

namespace {

using ts::Ring2;
using Pt = std::array<double, 2>;

Ring2 ellipse(double a, double b, int n) {
  Ring2 r;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * std::numbers::pi * k / n;
    r.push_back({a * std::cos(t), b * std::sin(t)});
  }
  return r;
}

double cross(const Pt& o, const Pt& a, const Pt& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

bool segments_cross(const Pt& a, const Pt& b, const Pt& c, const Pt& d) {
  const double d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

double point_segment(const Pt& p, const Pt& a, const Pt& b) {
  const double ux = b[0] - a[0], uy = b[1] - a[1];
  const double t = std::clamp(((p[0] - a[0]) * ux + (p[1] - a[1]) * uy) / (ux * ux + uy * uy), 0.0, 1.0);
  return std::hypot(p[0] - a[0] - t * ux, p[1] - a[1] - t * uy);
}

bool inside(const Ring2& r, const Pt& p) {
  bool in = false;
  for (std::size_t k = 0, j = r.size() - 1; k < r.size(); j = k++)
    if ((r[k][1] > p[1]) != (r[j][1] > p[1]) &&
        p[0] < (r[j][0] - r[k][0]) * (p[1] - r[k][1]) / (r[j][1] - r[k][1]) + r[k][0])
      in = !in;
  return in;
}

Ring2 moved(const Ring2& r, double dx, double dy) {
  Ring2 out = r;
  for (auto& v : out) v = {v[0] + dx, v[1] + dy};
  return out;
}

// The distance between two simple polygons' regions; -1 where they
// overlap (sides that cross, or a vertex of one inside the other and off
// its sides), 0 where they only touch.
double distance(const Ring2& p, const Ring2& q) {
  double d = 1e300;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = 0; j < q.size(); ++j) {
      const Pt &a = p[i], &b = p[(i + 1) % p.size()], &c = q[j], &e = q[(j + 1) % q.size()];
      if (segments_cross(a, b, c, e)) return -1;
      d = std::min({d, point_segment(a, c, e), point_segment(c, a, b)});
    }
  auto off_sides = [](const Ring2& r, const Pt& v) {
    double m = 1e300;
    for (std::size_t k = 0; k < r.size(); ++k) m = std::min(m, point_segment(v, r[k], r[(k + 1) % r.size()]));
    return m > 1e-12;
  };
  for (const Pt& v : p)
    if (inside(q, v) && off_sides(q, v)) return -1;
  for (const Pt& v : q)
    if (inside(p, v) && off_sides(p, v)) return -1;
  return d;
}

// The nearest copy of a lane layout to the one at the origin: over the
// lanes -3..3 and places -4..4 along them.
double nearest_copy(const Ring2& r, double pitch, double shift, double step) {
  double d = 1e300;
  for (int j = -3; j <= 3; ++j)
    for (int i = -4; i <= 4; ++i)
      if (i != 0 || j != 0) d = std::min(d, distance(r, moved(r, i * pitch + j * shift, j * step)));
  return d;
}

TEST(Nest, RectangleLanes) {
  const Ring2 rect{{0, 0}, {0.3, 0}, {0.3, 0.2}, {0, 0.2}};
  const ts::RollNest n = ts::nest_on_roll({rect}, 1.0, 0.005);
  EXPECT_NEAR(n.pitch, 0.305, 1e-9);  // copies 1e-9 of the size apart against round-off
  EXPECT_NEAR(n.lane_step, 0.205, 1e-12);
  EXPECT_EQ(n.lanes, 4);  // 0.205 + 3 x 0.205 = 0.82 m of the 1 m
  EXPECT_NEAR(n.area, 0.06, 1e-15);
  EXPECT_NEAR(n.utilisation, 4 * 0.06 / 0.305, 1e-8);
  EXPECT_NEAR(n.roll_per_pattern, 0.305 / 4, 1e-9);
  EXPECT_NEAR(n.origin[0], 0.0025, 1e-15);
  EXPECT_NEAR(n.origin[1], 0.0025, 1e-15);
  // A roll narrower than the pattern and its gap takes none; one just wide
  // enough takes one lane.
  EXPECT_EQ(ts::nest_on_roll({rect}, 0.2, 0.005).lanes, 0);
  EXPECT_EQ(ts::nest_on_roll({rect}, 0.205, 0.005).lanes, 1);
  EXPECT_EQ(ts::nest_on_roll({rect}, 0.205 * 5, 0.005).lanes, 5);
}

// A tab thinner than a band, wholly within one, still sets the pitch: a
// band takes the extent of the pattern's edges within it, not only that
// along its two lines.
TEST(Nest, TabThinnerThanABandSetsThePitch) {
  const Ring2 tabbed{{0, 0}, {1, 0}, {1, 0.5003}, {1.5, 0.5003}, {1.5, 0.5006}, {1, 0.5006}, {1, 1}, {0, 1}};
  const ts::RollNest n = ts::nest_on_roll({tabbed}, 3.0, 0.0);
  EXPECT_NEAR(n.resolution, 1e-3, 1e-15);  // the tab lies within the band from 0.5 to 0.501
  EXPECT_NEAR(n.pitch, 1.5, 1e-8);
  EXPECT_GE(nearest_copy(tabbed, n.pitch, n.lane_shift, n.lane_step), 0.0);
  EXPECT_LT(distance(tabbed, moved(tabbed, n.pitch - 1e-3, 0)), 0.0) << "a pitch a little smaller overlaps";
}

// A staircase of two unit steps (its rows [1, 3] and [0, 2]) is 3 long, but
// its copies fit 2 apart along the lane, and lanes 2 apart tile the roll.
TEST(Nest, StaircaseTilesTheRoll) {
  const Ring2 z{{1, 0}, {3, 0}, {3, 1}, {2, 1}, {2, 2}, {0, 2}, {0, 1}, {1, 1}};
  const ts::RollNest n = ts::nest_on_roll({z}, 8.0, 0.0);
  EXPECT_NEAR(n.length, 3.0, 1e-15);
  EXPECT_NEAR(n.pitch, 2.0, 1e-8);
  EXPECT_NEAR(n.lane_step, 2.0, 1e-12);
  EXPECT_EQ(n.lanes, 4);
  EXPECT_NEAR(n.utilisation, 1.0, 1e-8);
  EXPECT_GE(nearest_copy(z, n.pitch, n.lane_shift, n.lane_step), 0.0);
}

// Two unit squares 1.5 apart in a row: a pitch of 1 or 1.25 keeps the next
// copy clear but not the one after (at 2 or 2.5, on the second square);
// 3.5 is the smallest that keeps every copy clear.
TEST(Nest, EveryCopyOfALaneKeepsClearNotOnlyTheNext) {
  const Ring2 left{{0, 0}, {1, 0}, {1, 1}, {0, 1}}, right{{2.5, 0}, {3.5, 0}, {3.5, 1}, {2.5, 1}};
  const ts::RollNest n = ts::nest_on_roll({left, right}, 1.0, 0.0);
  EXPECT_NEAR(n.pitch, 3.5, 1e-8);
  EXPECT_EQ(n.lanes, 1);
  EXPECT_NEAR(n.utilisation, 2.0 / 3.5, 1e-8);
}

// A pattern of two unit squares, one 3 above the other: lanes 1 apart
// would keep clear of the next lane and the one after, but the third
// lane's lower square would meet the first lane's upper one; 2 apart every
// lane keeps clear of every other.
TEST(Nest, EveryLaneKeepsClearNotOnlyTheNext) {
  const Ring2 low{{0, 0}, {1, 0}, {1, 1}, {0, 1}}, high{{0, 3}, {1, 3}, {1, 4}, {0, 4}};
  const ts::RollNest n = ts::nest_on_roll({low, high}, 10.0, 0.0);
  EXPECT_NEAR(n.area, 2.0, 1e-15);
  EXPECT_NEAR(n.pitch, 1.0, 1e-8);
  EXPECT_GE(n.lane_step, 2.0 - 1e-9);
  EXPECT_LE(n.lane_step, 2.0 + n.resolution);
  EXPECT_EQ(n.lanes, 4);  // lanes from 0, 2, 4 and 6 to 10 m
  EXPECT_NEAR(n.utilisation, 4 * 2.0 / 10.0, 1e-8);
}

// Discs and ellipses: their lanes are the hexagonal packing (a disc
// touches two in its lane and two in each next lane), pitch 2a, step
// sqrt(3) b, shift a. The polygon of 720 sides lies within 1e-5 of its
// circle. The banding keeps the step within three bands above the exact
// one: each banded copy reaches at most a band beyond the ellipse, and
// the step is a whole number of bands (1.97 bands above it here).
TEST(Nest, DiscsAndEllipsesPackHexagonally) {
  for (const auto& [a, b] : {std::pair{0.1, 0.1}, std::pair{0.15, 0.05}}) {
    const Ring2 e = ellipse(a, b, 720);
    const ts::RollNest n = ts::nest_on_roll({e}, 1.0, 0.0);
    const double band = 2 * b / 1000;
    EXPECT_NEAR(n.resolution, band, 1e-15);
    EXPECT_NEAR(n.pitch, 2 * a, 1e-5 * a) << a << " x " << b;
    EXPECT_GE(n.lane_step, std::sqrt(3.0) * b * (1 - 1e-4)) << a << " x " << b;
    EXPECT_LE(n.lane_step, std::sqrt(3.0) * b + 3 * band) << a << " x " << b;
    EXPECT_NEAR(n.lane_shift, a, 0.02 * a) << a << " x " << b;
    EXPECT_NEAR(n.area, std::numbers::pi * a * b, 1e-4 * a * b);
    EXPECT_GE(nearest_copy(e, n.pitch, n.lane_shift, n.lane_step), 0.0);
  }
  // With a gap g, discs lie as discs of radius a + g / 2 do: pitch 2 a + g,
  // step sqrt(3) (a + g / 2), every copy g from its six neighbours. Each
  // banded copy reaches at most two bands beyond the points within g / 2 of
  // the disc, and the step is a whole number of bands: within five bands
  // (3.97 here; grown by a square of side g instead, 38 bands above, and
  // four lanes instead of five).
  const double a = 0.1, g = 0.02, R = a + g / 2;
  const Ring2 disc = ellipse(a, a, 720);
  const ts::RollNest n = ts::nest_on_roll({disc}, 1.0, g);
  const double band = (2 * a + g) / 1000;
  EXPECT_NEAR(n.resolution, band, 1e-15);
  EXPECT_NEAR(n.pitch, 2 * R, 1e-5 * a);
  EXPECT_GE(n.lane_step, std::sqrt(3.0) * R * (1 - 1e-4));
  EXPECT_LE(n.lane_step, std::sqrt(3.0) * R + 5 * band);
  EXPECT_NEAR(n.lane_shift, R, 0.02 * R);
  EXPECT_GE(nearest_copy(disc, n.pitch, n.lane_shift, n.lane_step), g * (1 - 1e-9));
  EXPECT_EQ(n.lanes, 1 + static_cast<int>((1.0 - 2 * R) / n.lane_step));
}

// A star with a notch to its centre: copies never nearer than the gap (exact distance
// between the polygons), the copies along a lane touching within the
// gap's allowance, and a lane step three bands smaller taking no shift.
TEST(Nest, CopiesOfAStarKeepTheGapAndNoSmallerStepFits) {
  Ring2 star;
  for (int k = 0; k < 14; ++k) {
    const double t = 2 * std::numbers::pi * k / 14 + 0.1, r = k % 2 ? 0.04 : 0.1 + 0.01 * (k % 3);
    star.push_back({r * std::cos(t), 0.8 * r * std::sin(t)});
  }
  star.insert(star.begin() + 3, {0.0, 0.0});  // a notch to the centre
  for (const double gap : {0.0, 0.004}) {
    const ts::RollNest n = ts::nest_on_roll({star}, 1.0, gap);
    const double near = nearest_copy(star, n.pitch, n.lane_shift, n.lane_step);
    EXPECT_GE(near, gap * (1 - 1e-9)) << "gap " << gap;
    // Along the lane: the next copy, which sets the pitch, within four
    // bands of the gap (each banded copy reaches at most two bands beyond
    // the points within gap / 2 of it).
    const double along = distance(star, moved(star, n.pitch, 0));
    EXPECT_LE(along, gap + 4 * n.resolution) << "gap " << gap;
    if (gap > 0) continue;
    // No shift (in steps of pitch / 4000) lets lanes three bands closer.
    const double closer = n.lane_step - 3 * n.resolution;
    int fits = 0;
    for (int k = 0; k < 4000; ++k)
      if (nearest_copy(star, n.pitch, n.pitch * k / 4000, closer) >= 0) ++fits;
    EXPECT_EQ(fits, 0);
  }
}

// A pattern of two pieces (found by scripts/fuzz/nest_random.cpp, seed 1,
// case 1879) on which the pitch's search once ran for ever: for
// p = end / k of an interval, k p rounded below the end and landed in it
// again. The search ends, and the copies keep clear of each other.
TEST(Nest, PitchSearchEndsWhereTheProductRoundsDown) {
  const std::vector<Ring2> rings{
      {{-0.042608521065617314, -0.0030829860300912197}, {-0.071531852544931912, -0.049529199468145053},
       {-0.025848328190254788, -0.018541688710920667}, {-0.037874557080898638, -0.089248152982033799},
       {-0.01446241371948863, -0.080250500422243742}, {0.0078328219533916957, -0.080988991701031771},
       {0.053664400979107588, -0.079194542923024788}, {0.055306318535430457, -0.077598940347678308},
       {0.052510245395089881, -0.067334684874976805}, {0.0660483320406825, -0.017887419636852774},
       {0.062474345595414184, 0.016751137675418866}, {0.012828976043366525, 0.042062150053208396},
       {0.013462309460956504, 0.060389720487719248}, {-0.0040690252018852841, 0.069791005476027498},
       {-0.018090328520691559, 0.035351846471946634}, {-0.05690406599248686, 0.049766312669559318},
       {-0.043267333443965154, 0.0053556998161862386}},
      {{-0.42914945328577647, 0.11270989449804329}, {-0.39738546016006504, 0.10938086325351457},
       {-0.40213121954193592, 0.10814692876055512}, {-0.40379541351378267, 0.065319542515098791},
       {-0.38102216247432497, 0.069971512726060697}, {-0.37735663338410746, 0.074002017109720819},
       {-0.3748560020274514, 0.093417028258768714}, {-0.3732868357834237, 0.075392337461939074},
       {-0.37079927557970799, 0.073074870131290326}, {-0.35928221075372857, 0.077257874421457345},
       {-0.35220903690784372, 0.072487614539866727}, {-0.34952910539740162, 0.068119411841743333},
       {-0.36096920496642604, 0.089629737408288362}, {-0.34027967820248006, 0.079454533404597766},
       {-0.34382175430978323, 0.085552927738532097}, {-0.34715286331373868, 0.105263602961368},
       {-0.34746892069028112, 0.11000876022076267}, {-0.34511101229334307, 0.12034388470950344},
       {-0.345987929194712, 0.13641229316817924}, {-0.36461106604592136, 0.13403933996603723},
       {-0.38673459821124606, 0.1617025246233724}, {-0.38278175991099578, 0.13991524113788062},
       {-0.41087704281098997, 0.14088065859620788}, {-0.40386613263875087, 0.12827971010102926}}};
  const ts::RollNest n = ts::nest_on_roll(rings, 1.1996061941259308, 0.0, 333);
  EXPECT_EQ(n.lanes, 5);
  double nearest = 1e300;
  for (int j = -3; j <= 3; ++j)
    for (int i = -4; i <= 4; ++i)
      if (i != 0 || j != 0)
        for (const Ring2& a : rings)
          for (const Ring2& b : rings)
            nearest = std::min(nearest, distance(a, moved(b, i * n.pitch + j * n.lane_shift, j * n.lane_step)));
  EXPECT_GE(nearest, 0.0);
}

// The copies of the units of a layout (the pattern, or the pair) around the
// first: the nearest distance between any two of their pieces, over 7
// lanes x 9 units; -1 where two overlap.
double nearest_unit(const std::vector<Ring2>& unit, const ts::RollNest& n) {
  double d = 1e300;
  for (int j = -3; j <= 3; ++j)
    for (int i = -4; i <= 4; ++i)
      for (std::size_t a = 0; a < unit.size(); ++a)
        for (std::size_t b = 0; b < unit.size(); ++b) {
          if (i == 0 && j == 0 && a >= b) continue;  // a piece against itself, each pair once
          d = std::min(d, distance(unit[a], moved(unit[b], i * n.pitch + j * n.lane_shift, j * n.lane_step)));
        }
  return d;
}

// A balanced woven roll's weft may run along the roll (try_quarter_turn):
// a rectangle 300 x 200 mm on a roll 310 mm wide takes one lane either
// way, a copy every 300 mm as given and every 200 mm turned by 90 degrees;
// one 100 x 400 mm fits only turned (three lanes, a copy every 400 mm); a
// square gains nothing from the turn and stays as given.
TEST(Nest, AQuarterTurnLaysTheWeftAlongTheRoll) {
  const Ring2 rect{{0, 0}, {0.3, 0}, {0.3, 0.2}, {0, 0.2}};
  const ts::RollLayout given = ts::lay_on_roll({rect}, 0.31, 0.0, true, 1000, false);
  EXPECT_FALSE(given.turned_90);
  EXPECT_NEAR(given.roll_per_pattern, 0.3, 1e-8);
  const ts::RollLayout l = ts::lay_on_roll({rect}, 0.31, 0.0, true, 1000, true);
  ASSERT_TRUE(l.turned_90);
  EXPECT_FALSE(l.pairs);
  EXPECT_EQ(l.nest.lanes, 1);
  EXPECT_NEAR(l.roll_per_pattern, 0.2, 1e-8);
  EXPECT_NEAR(l.single_roll_per_pattern, 0.3, 1e-8);  // as given, for comparison
  EXPECT_NEAR(l.length, 0.2, 1e-15);
  EXPECT_NEAR(l.width, 0.3, 1e-15);
  ASSERT_EQ(l.unit.size(), 1u);
  for (std::size_t k = 0; k < rect.size(); ++k) {  // turned by +90 degrees: (x, y) -> (-y, x)
    EXPECT_EQ(l.unit[0][k][0], -rect[k][1]);
    EXPECT_EQ(l.unit[0][k][1], rect[k][0]);
  }
  const Ring2 tall{{0, 0}, {0.1, 0}, {0.1, 0.4}, {0, 0.4}};
  EXPECT_EQ(ts::lay_on_roll({tall}, 0.3, 0.0, true, 1000, false).nest.lanes, 0);
  const ts::RollLayout t = ts::lay_on_roll({tall}, 0.3, 0.0, true, 1000, true);
  ASSERT_TRUE(t.turned_90);
  EXPECT_EQ(t.nest.lanes, 3);
  EXPECT_NEAR(t.roll_per_pattern, 0.4 / 3, 1e-8);
  EXPECT_EQ(t.single_roll_per_pattern, 0.0);  // as given none fits
  const Ring2 square{{0, 0}, {0.2, 0}, {0.2, 0.2}, {0, 0.2}};
  const ts::RollLayout sq = ts::lay_on_roll({square}, 0.5, 0.01, true, 1000, true);
  EXPECT_FALSE(sq.turned_90);
  EXPECT_EQ(sq.unit[0], square);
}

// Two patterns (found by scripts/fuzz/nest_random.cpp, seed 2, cases 903
// and 1980) whose turned copy, without a gap, comes to touch the first at
// a vertex. The pair's area was once summed by which copy that vertex lay
// within, a matter of round-off: it came to naught (thrown as a pattern
// without area), and the turned copy overlapped the first by 1e-10 m where
// it was placed by bands drawn in against round-off. The pair keeps its
// area and its copies apart.
TEST(Nest, TurnedCopiesThatTouchTheFirstKeepClearAndTheirArea) {
  const Ring2 quad{{0.037537964487592508, -0.03045732904389982},
                   {0.033395802044937209, 0.021107511874026},
                   {0.05557786134237052, 0.04488759685386022},
                   {0.013336600023049733, 0.082204410381730916}};
  const Ring2 star{{-0.062452590542463313, -0.0011709338903875439}, {0.065933800138064103, -0.062876433789538985},
                   {0.032317388699057766, -0.010339881449167898}, {0.086287821656172575, 0.040103314049788813},
                   {0.059922846265753553, 0.031095754258948609},  {0.0510825589464559, 0.05392360288010755},
                   {0.054094830065684066, 0.08084011376569257}};
  for (const auto& [r, width, bands] : {std::tuple{quad, 0.84215788494421484, 957},
                                        std::tuple{star, 0.58943736402283686, 749}}) {
    const ts::RollLayout l = ts::lay_on_roll({r}, width, 0.0, true, bands);
    ASSERT_TRUE(l.pairs) << r.size();
    EXPECT_NEAR(l.nest.area, 2 * l.area, 1e-15) << r.size();
    EXPECT_GT(l.area, 0.0);
    EXPECT_GE(distance(l.unit[0], l.unit[1]), 0.0) << r.size();
    EXPECT_GE(nearest_unit(l.unit, l.nest), 0.0) << r.size();
  }
}

// Right triangles pair with their copies turned by 180 degrees into
// squares that fill the roll, where copies all alike fill at most 2/3 of
// it (the densest lattice of a triangle's translates); discs on a wide roll
// gain nothing from pairs and stay alike.
TEST(Nest, TrianglesPairIntoSquaresDiscsStayAlike) {
  const Ring2 tri{{0, 0}, {0.2, 0}, {0, 0.2}};
  for (const double gap : {0.0, 0.01}) {
    const ts::RollLayout l = ts::lay_on_roll({tri}, 1.0, gap);
    ASSERT_TRUE(l.pairs) << "gap " << gap;
    ASSERT_EQ(l.unit.size(), 2u);
    EXPECT_NEAR(l.area, 0.02, 1e-15);
    // The pair: the square 0.2 + gap (the diagonal cut a band wider), lanes of them.
    const double side = 0.2 + gap;
    const int lanes = 1 + static_cast<int>((1.0 - side) / side);
    EXPECT_EQ(l.nest.lanes, lanes) << "gap " << gap;
    EXPECT_NEAR(l.roll_per_pattern, side / (2 * lanes), 0.01 * side / (2 * lanes)) << "gap " << gap;
    EXPECT_GT(l.single_roll_per_pattern, 1.45 * l.roll_per_pattern) << "gap " << gap;
    if (gap == 0) {
      EXPECT_GT(l.nest.utilisation, 0.99);
    }
    EXPECT_GE(nearest_unit(l.unit, l.nest), gap * (1 - 1e-9)) << "gap " << gap;
    // The turned copy is the pattern turned: its vertex of v at turned - v.
    for (std::size_t k = 0; k < tri.size(); ++k)
      for (std::size_t c = 0; c < 2; ++c) EXPECT_NEAR(l.unit[1][k][c], l.turned[c] - tri[k][c], 1e-15);
    EXPECT_FALSE(ts::lay_on_roll({tri}, 1.0, gap, false).pairs);
  }
  // Discs on a roll 20 m wide: the hexagonal lanes are the densest packing,
  // which no pair beats. On a roll 1 m wide a pair may fit the width
  // better; whichever is taken keeps the copies apart.
  const ts::RollLayout disc = ts::lay_on_roll({ellipse(0.1, 0.1, 360)}, 20.0, 0.0);
  EXPECT_FALSE(disc.pairs);
  EXPECT_EQ(disc.roll_per_pattern, disc.single_roll_per_pattern);
  const ts::RollLayout narrow = ts::lay_on_roll({ellipse(0.1, 0.1, 360)}, 1.0, 0.0);
  EXPECT_LE(narrow.roll_per_pattern, narrow.single_roll_per_pattern);
  EXPECT_GE(nearest_unit(narrow.unit, narrow.nest), 0.0);
}

// A batch of patterns: the shortest stretch of the lanes that holds them.
// Against closed forms where the lanes are known (one lane of rectangles:
// count pitches; three hexagonal lanes of discs: 1.5 and 2.5 diameters
// for 3 and 6 discs, the lanes' shifts moving it by at most twice their
// difference from a radius), and on a star in pairs with a gap, the
// copies checked by their exact geometry (on the roll, never nearer than
// the gap) and against every start of the lanes' places taken one by one
// (no stretch a little shorter holds as many).
TEST(Nest, ABatchTakesTheShortestStretchOfTheLanes) {
  const Ring2 rect{{0, 0}, {0.3, 0}, {0.3, 0.2}, {0, 0.2}};
  const ts::RollLayout one = ts::lay_on_roll({rect}, 0.205, 0.005);
  ASSERT_EQ(one.nest.lanes, 1);
  const ts::RollBatch seven = ts::lay_batch(one, 0.005, 7);
  EXPECT_NEAR(seven.length, 7 * 0.305, 1e-8);  // the pitch is 1e-9 of the size above 0.305
  ASSERT_EQ(seven.copies.size(), 7u);
  for (std::size_t c = 0; c < 7; ++c) {
    EXPECT_NEAR(seven.copies[c].offset[0], 0.0025 + 0.305 * c, 1e-8) << c;
    EXPECT_NEAR(seven.copies[c].offset[1], 0.0025, 1e-15) << c;
  }

  const double a = 0.1;
  const ts::RollLayout discs = ts::lay_on_roll({ellipse(a, a, 720)}, 0.55, 0.0, false);
  ASSERT_EQ(discs.nest.lanes, 3);
  const double off = 2 * std::abs(discs.nest.lane_shift - a) + 1e-4 * a;  // the shifts' difference, the pitch's
  EXPECT_NEAR(ts::lay_batch(discs, 0.0, 1).length, 2 * a, 1e-12);
  EXPECT_NEAR(ts::lay_batch(discs, 0.0, 3).length, 3 * a, off);
  EXPECT_NEAR(ts::lay_batch(discs, 0.0, 6).length, 5 * a, off);

  Ring2 star;
  for (int k = 0; k < 14; ++k) {
    const double t = 2 * std::numbers::pi * k / 14 + 0.1, r = k % 2 ? 0.04 : 0.1 + 0.01 * (k % 3);
    star.push_back({r * std::cos(t), 0.8 * r * std::sin(t)});
  }
  star.insert(star.begin() + 3, {0.0, 0.0});
  const double gap = 0.004, width = 0.7;
  const ts::RollLayout l = ts::lay_on_roll({star}, width, gap);
  ASSERT_TRUE(l.pairs);
  const ts::RollNest& n = l.nest;
  const int count = 25;
  const ts::RollBatch b = ts::lay_batch(l, gap, count);
  ASSERT_EQ(b.copies.size(), static_cast<std::size_t>(count));
  std::vector<Ring2> placed;
  for (const ts::RollCopy& c : b.copies) {
    placed.push_back(moved(l.unit[static_cast<std::size_t>(c.piece)], c.offset[0], c.offset[1]));
    for (const Pt& v : placed.back()) {
      EXPECT_GE(v[0], gap / 2 - 1e-12);
      EXPECT_LE(v[0], b.length - gap / 2 + 1e-12);
      EXPECT_GE(v[1], gap / 2 - 1e-12);
      EXPECT_LE(v[1], width - gap / 2 + 1e-12);
    }
  }
  for (std::size_t i = 0; i < placed.size(); ++i)
    for (std::size_t j = i + 1; j < placed.size(); ++j)
      EXPECT_GE(distance(placed[i], placed[j]), gap * (1 - 1e-9)) << i << " " << j;
  EXPECT_GE(b.length * width, count * l.area);
  const int units = (count + 2 * n.lanes - 1) / (2 * n.lanes);
  EXPECT_LE(b.length, (units + 1) * n.pitch + n.length + gap);
  // Every place of the lanes, each piece by its extent along the roll; no
  // stretch from any piece's start 1e-9 m shorter than the batch's (less
  // the gap) holds count of them.
  std::vector<std::array<double, 2>> slots;
  for (int j = 0; j < n.lanes; ++j)
    for (int i = 0; i < 4 * units + 20; ++i)
      for (std::size_t k = 0; k < 2; ++k) {
        const double x = n.origin[0] + i * n.pitch + std::fmod(j * n.lane_shift, n.pitch);
        double lo = 1e300, hi = -1e300;
        for (const Pt& v : l.unit[k]) {
          lo = std::min(lo, v[0] + x);
          hi = std::max(hi, v[0] + x);
        }
        slots.push_back({lo, hi});
      }
  int most = 0;
  for (const auto& s : slots) {
    int within = 0;
    for (const auto& t : slots)
      if (t[0] >= s[0] && t[1] <= s[0] + b.length - gap - 1e-9) ++within;
    most = std::max(most, within);
  }
  EXPECT_LT(most, count);

  EXPECT_THROW(ts::lay_batch(l, gap, 0), std::invalid_argument);
  EXPECT_THROW(ts::lay_batch(l, gap, 10001), std::invalid_argument);
  EXPECT_THROW(ts::lay_batch(ts::lay_on_roll({rect}, 0.1, 0.0), 0.0, 1), std::invalid_argument);  // no lane
}

TEST(Nest, RefusesWhatIsNoPattern) {
  const Ring2 line{{0, 0}, {1, 0}, {2, 0}};
  EXPECT_THROW(ts::nest_on_roll({line}, 1.0, 0.0), std::invalid_argument);
  const Ring2 sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_THROW(ts::nest_on_roll({sq}, -1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(ts::nest_on_roll({sq}, 1.0, std::nan("")), std::invalid_argument);
  EXPECT_THROW(ts::nest_on_roll({sq}, 1.0, 0.0, 0), std::invalid_argument);
}

}  // namespace
