#pragma once
// Copies of one cut pattern laid on a roll of prepreg (`thermostamp blank
// --roll W`): in lanes along the roll, each copy turned as the first (the
// fibres of every copy along the roll), the copies of a lane at the
// smallest pitch that keeps them apart, each lane against the one before
// at the smallest step across the roll that keeps them apart, with the
// shift along the roll that allows it. The figures a cutting plan asks
// for: how many lanes fit across the roll, the roll's length per pattern
// and the share of the roll the patterns take.
#include <array>
#include <vector>

namespace ts {

using Ring2 = std::vector<std::array<double, 2>>;

// Whether (x, y) lies inside a ring (crossings of a ray along +x).
bool ring_contains(const Ring2& ring, double x, double y);

struct RollNest {
  double length = 0, width = 0;  // m: the pattern's extent along and across the roll
  double area = 0;               // m^2: the pattern's
  double pitch = 0;              // m: from copy to copy along a lane
  double lane_step = 0;          // m: across the roll, from lane to lane
  double lane_shift = 0;         // m: along the roll, each lane against the one before (0 <= it < pitch)
  int lanes = 0;                 // across the roll's width; 0 where the pattern is wider than the roll
  double roll_per_pattern = 0;   // m of roll per pattern: pitch / lanes (0 where no lane fits)
  double utilisation = 0;        // the patterns' share of the roll: lanes area / (roll width pitch)
  double resolution = 0;         // m: the lane step is a multiple of it
  // The copy in lane j (from 0, at the roll's edge y = 0), place i along
  // the lane, lies at its pattern coordinates plus
  // origin + (i pitch + (j lane_shift mod pitch), j lane_step).
  std::array<double, 2> origin{};
};

// Nests the pattern `rings` (closed polygons, the region inside an odd
// number of them; in the roll's axes: x along the roll, y across it; m) on
// a roll `roll_width` m wide, with at least `gap` m between copies
// (Euclidean distance; a copy is kept gap / 2 from the roll's edges). The
// pattern is taken in `bands` bands across the roll, each band by the
// extent along the roll of the points level with it within gap / 2 of the
// pattern, so that no two copies come nearer than the gap (the bands are
// drawn over the pattern: the copy along a lane that sets the pitch, for
// most patterns the next, stands at most four bands further than the gap);
// the lane step is the smallest multiple of the band's height
// (width + gap) / bands with which some shift along the roll keeps the
// lanes apart, and the pitch exact for that banding.
// Throws std::invalid_argument for a pattern without area, a width or gap
// not finite or below 0, or bands below 1.
RollNest nest_on_roll(const std::vector<Ring2>& rings, double roll_width, double gap, int bands = 1000);

// The layout a cutting plan takes: every copy alike (nest_on_roll of the
// pattern), or, where that saves at least half a per cent of the roll,
// pairs of a copy and one turned by 180 degrees in the roll's plane (the
// fibres still along the roll), the pair nested as one unit. A pair
// places the turned copy beside the first along the roll, as near as the
// gap allows, at each of 41 offsets across the roll from one above the
// other to one below it, and on either side; each pair is nested with 250
// bands to choose, the best three again with `bands`. With
// `try_quarter_turn` (a balanced woven roll, whose weft may run along the
// roll as well as its warp), the pattern turned by 90 degrees is laid out
// the same way, and taken where it saves at least half a per cent of the
// roll, or fits where the pattern as given does not.
struct RollLayout {
  RollNest nest;                 // of the unit: the pattern, or the pair
  std::vector<Ring2> unit;       // its rings: the pattern's (turned by 90 degrees with turned_90), and with pairs
                                 // the turned copy's
  bool pairs = false;            // the unit is a pair
  bool turned_90 = false;        // every copy turned by +90 degrees first: v -> (-v_y, v_x)
  std::array<double, 2> turned{};  // pairs: the turned copy's vertex of the (first) copy's v lies at turned - v
  double area = 0;               // m^2: the pattern's
  double length = 0, width = 0;  // m: the (first) copy's extent along and across the roll
  double roll_per_pattern = 0;   // m of roll per pattern (0 where no lane fits)
  double single_roll_per_pattern = 0;  // m: every copy alike as given, for comparison (0 where no lane fits)
};
RollLayout lay_on_roll(const std::vector<Ring2>& rings, double roll_width, double gap, bool try_pairs = true,
                       int bands = 1000, bool try_quarter_turn = false);

// The extent along the roll (min x, max x) of each of a unit's `pieces`
// patterns (the unit's rings in as many groups of as many rings each).
std::vector<std::array<double, 2>> piece_extents(const std::vector<Ring2>& unit, int pieces);

// A batch of `count` patterns cut from the layout's lanes: the stretch of
// roll that holds `count` whole patterns of the lanes (the copies of every
// lane at the pitch, the lanes at their step and shift across the roll,
// as nested) and is the shortest along the roll over every start, with
// the gap before its first pattern and after its last. Its copies are
// moved along the roll so that the stretch starts at x = 0: each copy is
// the unit's rings of `piece` (0 the pattern, 1 a pair's turned copy)
// moved by `offset`. The lanes are not changed for the batch: a shorter
// stretch may exist with other shifts between the lanes (few patterns on
// a wide roll) or more copies of the pattern turned.
// Throws std::invalid_argument for a count below 1 or above 10 000, or a
// layout without a lane.
struct RollCopy {
  int piece = 0;                   // 0 the pattern, 1 the turned copy of a pair
  std::array<double, 2> offset{};  // m, added to the unit's rings of the piece
};
struct RollBatch {
  double length = 0;             // m of roll: from gap / 2 before the first pattern to gap / 2 beyond the last
  std::vector<RollCopy> copies;  // count of them, by their end along the roll
};
RollBatch lay_batch(const RollLayout& layout, double gap, int count);

}  // namespace ts
