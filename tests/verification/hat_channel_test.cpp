// The hat-channel example (examples/hat_channel/hat_channel.json) as a user
// runs it: tools from CAD as STL files in millimetres, in their closed
// position, the punch opened by the first row of its displacement table,
// a force-controlled blank holder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace ts::test {
namespace {

// The die's section of examples/hat_channel/make_tools.py (mm): depth,
// wall angle from the vertical, fillet radii (valley, crest).
constexpr double kDepth = 20.0, kDraft = 20.0 * std::numbers::pi / 180.0, kRValley = 5.0, kRCrest = 5.0;

// How much longer than its width the section is, along any curve at a
// constant offset from it (mm): the arc of an offset curve is longer at
// the crest by what it is shorter in the valley, so the offset drops out.
double excess_length() {
  const double turn = std::numbers::pi / 2 - kDraft;  // at each fillet
  const double tangent = std::tan(turn / 2);          // tangent length over radius
  const double wall = kDepth / std::cos(kDraft) - (kRValley + kRCrest) * tangent;  // its straight part
  return wall + (kRValley + kRCrest) * turn - (kDepth * std::tan(kDraft) + (kRValley + kRCrest) * tangent);
}

// Probe values by (probe, quantity) at time t, from probes.csv (probe,
// quantity, time, z, value; z empty for the values that are not profiles).
std::map<std::pair<std::string, std::string>, double> probe_values(const std::filesystem::path& file, double t) {
  std::map<std::pair<std::string, std::string>, double> v;
  const auto rows = csv_rows(file);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const auto& row = rows[k];
    if (row.size() == 5 && row[3].empty() && std::abs(std::stod(row[2]) - t) < 1e-9) v[{row[0], row[1]}] = std::stod(row[4]);
  }
  return v;
}

}  // namespace

// The section's geometry first: the die file's vertices at one end, walked
// in x from 0, give the excess length of the analytic section less what
// its 16 facets per fillet cut off the arcs (under 0.01 mm).
//
// The top ply's fibres cross the channel and barely stretch, so its edge
// is drawn in by the excess length of the path of its mid-surface: 12.217
// mm at any offset from the die (excess_length()). The run gives a little
// less: the ply's nodes follow the fillets on chords of 1.25 mm, which are
// shorter than their arcs (by 0.035 mm over the two fillets at the ply's
// radii 4.25 and 5.75 mm), its fibres stretch (the run's largest fibre
// strain, 3e-4, over 70 mm: 0.02 mm) and the facets shorten the path (under
// 0.01 mm). Required: the draw-in under the excess length and within
// 0.08 mm of it (0.7 %; measured 0.044 mm). The bottom ply's fibres run
// along the channel: across, it is drawn in less, as its soft transverse
// direction stretches instead.
//
// The run takes the mass scaling of target_dt 1.4e-5 s, four times the
// job's step (a quarter of the run time): the draw-in is geometric, 12.172
// against 12.178 mm at the job's 3.5e-6 s.
//
// At the end the stack lies on the closed tools: every node of the lower
// ply within 0.1 mm (a fifth of a ply) of the die, every node of the upper
// one within 0.1 mm of the punch (measured 0.05 mm), and both plies down
// 20 mm at the channel's bottom (within 0.05 mm, the penalty's
// penetration). The job draws no warning (a punch left in its closed
// position at the start would have had 93 nodes of the plies behind it)
// but the material stability ones, and the energy balance error stays
// under 1e-4.
//
// Material stability: the lower ply crosses the channel across its
// fibres and is drawn in by 4.3 of the section's 12.2 mm excess length;
// the rest, about 8 mm over the 37 mm of its path in the channel (x < 30
// mm, 43 % of its area), stretches it across the fibres by some 20 %, far
// beyond the 5.3 % at which the card's long-term response at 300 degC
// loses its stability (docs/mechanics-method.md). Required: the lower
// ply's unstable share at the end above 0.4 (measured 0.54: the channel and
// the flange next to the die's radius), the upper ply's, whose fibres take
// the excess length by drawing in, under 0.05 (measured 0.018).
//
// Cut pattern (thermostamp blank): the part trimmed at x = 45 mm on its
// flange; the upper ply's trim line lies in the blank at 45 mm plus its
// draw-in, within the same 0.08 mm below the excess length (measured
// 12.168-12.172 mm along the whole line), the lower ply's at 45 mm plus
// 4.7-4.8 mm.
TEST(HatChannel, FibresAcrossTheChannelDrawInByTheSectionsExcessLength) {
  const auto example = source_dir() / "examples" / "hat_channel";
  {
    std::ifstream stl(example / "die.stl");
    std::vector<std::pair<double, double>> section;  // (x, z) at y = -60 mm, x >= 0
    std::string word;
    while (stl >> word)
      if (word == "vertex") {
        double x, y, z;
        stl >> x >> y >> z;
        if (y == -60.0 && x >= 0.0) section.emplace_back(x, z);
      }
    std::sort(section.begin(), section.end());
    section.erase(std::unique(section.begin(), section.end()), section.end());
    ASSERT_GT(section.size(), 30u);
    double length = 0;
    for (std::size_t k = 1; k < section.size(); ++k)
      length += std::hypot(section[k].first - section[k - 1].first, section[k].second - section[k - 1].second);
    const double facets = length - section.back().first;
    EXPECT_LT(facets, excess_length());
    EXPECT_GT(facets, excess_length() - 0.01);
  }
  const auto out = temp_dir("hat_channel");
  const auto r = thermostamp("run " + q(example / "hat_channel.json") + " --out " + q(out) +
                             " --threads 2 --quiet --set solvers.mechanics.mass_scaling.target_dt=1.4e-5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream log(out / "log.txt");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  for (std::size_t at = text.find("[warning]"); at != std::string::npos; at = text.find("[warning]", at + 1)) {
    const std::string line = text.substr(at, text.find('\n', at) - at);
    EXPECT_NE(line.find("(user guide, \"Material stability\")"), std::string::npos) << line;
  }
  EXPECT_NE(text.find("part 'ply_0': the long-term (relaxed) response of its membrane law is unstable"),
            std::string::npos)
      << text;
  const json summary = json::parse(std::ifstream(out / "summary.json"));
  for (const auto& ply : summary["parts"]) {
    const double share = ply["fraction_unstable"].get<double>();
    if (ply["name"] == "ply_0") {
      EXPECT_GT(share, 0.4);
    } else {
      EXPECT_LT(share, 0.05);
    }
    std::printf("%s: long-term response unstable in %.3f of the area at the end, from t = %s s\n",
                ply["name"].get<std::string>().c_str(), share, ply["unstable_from_s"].dump().c_str());
  }
  EXPECT_LT(std::abs(summary["energy"]["balance_error"].get<double>()), 1e-4) << summary["energy"].dump();

  const auto v = probe_values(out / "probes.csv", 0.7);
  const double drawn = -1e3 * v.at({"edge_90", "displacement_x"});
  EXPECT_LT(drawn, excess_length());
  EXPECT_GT(drawn, excess_length() - 0.08);
  EXPECT_LT(-1e3 * v.at({"edge_0", "displacement_x"}), drawn - 1.0);
  for (const char* p : {"bottom_0", "bottom_90"}) EXPECT_NEAR(v.at({p, "displacement_z"}), -0.020, 5e-5) << p;

  const hid_t file = H5Fopen((out / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  char last[32];
  std::snprintf(last, sizeof last, "frames/%06d/", frame_count(file) - 1);
  for (const char* ply : {"ply_0", "ply_90"}) {
    const std::vector<double> gap = read_dataset<double>(file, last + std::string(ply) + "/tool_gap");
    double worst = 0;
    for (const double g : gap) worst = std::max(worst, std::abs(g));
    EXPECT_LT(worst, 1e-4) << ply;
  }
  H5Fclose(file);

  // The cut pattern of the part trimmed on its flange at x = 45 mm: the
  // upper ply's fibres carry the section's path into the part, so its
  // trim line lies in the blank at 45 mm plus the excess length, less the
  // same chords, stretch and facets as its draw-in (within 0.08 mm); the
  // lower ply's lies closer (it stretches across the channel instead).
  const auto b = thermostamp("blank " + q(out) + " --trim plane:0.045,0,0,-1,0,0");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  for (const std::string ply : {"ply_90", "ply_0"}) {
    const auto rows = csv_rows(out / "blank" / (ply + ".csv"));
    int on_trim = 0;
    double lo = 1e9, hi = -1e9;
    for (std::size_t k = 1; k < rows.size(); ++k) {
      if (rows[k][0] != "pattern" || rows[k][3] != "1") continue;
      ++on_trim;
      EXPECT_NEAR(std::stod(rows[k][7]), 0.045, 1e-12) << ply << ": on the trim plane";
      const double beyond = 1e3 * std::stod(rows[k][4]) - 45.0;
      lo = std::min(lo, beyond);
      hi = std::max(hi, beyond);
    }
    EXPECT_GT(on_trim, 20) << ply;
    std::printf("%s: the trim line at x = 45 mm lies at 45 + %.4f to %.4f mm in the blank (excess length %.4f mm)\n",
                ply.c_str(), lo, hi, excess_length());
    if (ply == "ply_90") {
      EXPECT_LT(hi, excess_length());
      EXPECT_GT(lo, excess_length() - 0.08);
    } else {
      EXPECT_LT(hi, excess_length() - 5.0);
    }
  }
}

// The bending evaluated at most every 8th step (bending_subcycles 8, as
// the hemisphere jobs set it; on this scene the bending's own step allows
// all 8) against every step, over the first 0.25 s of the stroke (the
// punch 10 mm down) at the mass scaling of the test above. The plies are bent round the die's
// 5 mm radii and pressed between stiff contacts, where the contact holds
// the bending forces in balance at every step. Delivered as one impulse
// per evaluation, those forces shook the plies: the internal work at 0.25
// s came out 24 % low (0.00152 J against 0.00201 J) and the lower ply's
// largest shear angle 4.7 deg against 9.6 deg (shell_rf_t3 before 0.10.0).
// With the slowly varying part of the bending forces applied at every step
// and the impulse carrying the rest (docs/mechanics-method.md), required:
// the internal work within 1 % (measured 0.34 %), the shear extrema of both
// plies within 0.5 deg (measured 0.11 deg), the punch's largest force
// within 1 % (measured 0.08 %) and the energy balance under 1e-4.
TEST(HatChannel, BendingSubcyclesKeepTheAnswer) {
  const auto example = source_dir() / "examples" / "hat_channel";
  struct Run {
    double internal = 0, balance = 0, punch = 0;
    std::vector<double> shear;  // min, max of ply_0, then of ply_90
    long long evaluations = 0, largest = 0;
  };
  const auto run = [&](int subcycles) {
    const auto out = temp_dir("hat_channel_subcycles" + std::to_string(subcycles));
    const auto r = thermostamp("run " + q(example / "hat_channel.json") + " --out " + q(out) +
                               " --threads 2 --quiet --set time.end=0.25"
                               " --set solvers.mechanics.mass_scaling.target_dt=1.4e-5"
                               " --set solvers.mechanics.bending_subcycles=" +
                               std::to_string(subcycles));
    Run x;
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const json summary = json::parse(std::ifstream(out / "summary.json"));
    x.internal = summary["energy"]["internal"].get<double>();
    x.balance = std::abs(summary["energy"]["balance_error"].get<double>());
    for (const auto& ply : summary["parts"]) {
      x.shear.push_back(ply["shear_angle_min_deg"].get<double>());
      x.shear.push_back(ply["shear_angle_max_deg"].get<double>());
    }
    if (summary.contains("bending_subcycles")) {
      x.evaluations = summary["bending_subcycles"]["evaluations"].get<long long>();
      x.largest = summary["bending_subcycles"]["largest"].get<long long>();
    }
    const auto rows = csv_rows(out / "tools.csv");  // time, tool, ux, uy, uz, fx, fy, fz
    for (std::size_t k = 1; k < rows.size(); ++k)
      if (rows[k].size() >= 8 && rows[k][1] == "punch") x.punch = std::max(x.punch, std::abs(std::stod(rows[k][7])));
    return x;
  };
  const Run a = run(1), b = run(8);
  ASSERT_EQ(a.shear.size(), 4u);
  ASSERT_EQ(b.shear.size(), 4u);
  EXPECT_EQ(b.largest, 8);
  double shear = 0;
  for (std::size_t k = 0; k < 4; ++k) shear = std::max(shear, std::abs(a.shear[k] - b.shear[k]));
  std::printf("bending every step / at most every 8th (%lld evaluations): internal work %.6g / %.6g J, shear extrema "
              "%.3f deg apart, punch's largest force %.4g / %.4g N, energy balance %.2e / %.2e\n",
              b.evaluations, a.internal, b.internal, shear, a.punch, b.punch, a.balance, b.balance);
  EXPECT_NEAR(b.internal, a.internal, 0.01 * a.internal);
  EXPECT_LT(shear, 0.5);
  EXPECT_NEAR(b.punch, a.punch, 0.01 * a.punch);
  EXPECT_GT(a.punch, 1.0);
  EXPECT_LT(b.balance, 1e-4);
}

}  // namespace ts::test
