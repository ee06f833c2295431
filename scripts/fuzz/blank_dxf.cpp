// Mutated DXF trim outlines (scripts/fuzz_blank.py): two DXF files (a slot
// with bulges and a circle in a tilted plane; a 3D polyline and a circle)
// with 1 to 4 lines replaced, removed, inserted or swapped. Each must be
// read and cut, or refused with an input error in one line; anything else
// is counted.
// Usage: blank_dxf CASES [CASE]
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
static int fallbacks = 0;
int main(int argc, char** argv) {
  const std::vector<std::string> seeds = {
      "0\nSECTION\n2\nHEADER\n9\n$"
      "INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nLWPOLYLINE\n8\nTRIM\n90\n4\n70\n1\n10\n25.0\n20\n25."
      "0\n10\n75.0\n20\n25.0\n42\n1.0\n10\n75.0\n20\n55.0\n10\n25.0\n20\n55.0\n42\n1.0\n210\n0.3\n220\n-0.2\n230\n0."
      "93\n0\nCIRCLE\n8\nTRIM\n10\n50.0\n20\n40.0\n30\n0.0\n40\n5.0\n210\n0.3\n220\n-0.2\n230\n0."
      "93\n0\nENDSEC\n0\nEOF\n",
      "0\nSECTION\n2\nHEADER\n9\n$"
      "INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nPOLYLINE\n8\nTRIM\n66\n1\n70\n9\n10\n0.0\n20\n0."
      "0\n30\n0."
      "0\n0\nVERTEX\n8\nTRIM\n10\n10\n20\n10\n30\n3\n0\nVERTEX\n8\nTRIM\n10\n90\n20\n10\n30\n3\n0\nVERTEX\n8\nTRIM\n10"
      "\n50\n20\n80\n30\n3\n0\nSEQEND\n8\nTRIM\n0\nCIRCLE\n8\nT\n10\n50\n20\n30\n40\n5\n0\nENDSEC\n0\nEOF\n",
  };
  const std::vector<std::string> junk = {"",           "0",      "-1",     "1e308",    "nan",    "inf",     "CIRCLE",
                                         "LWPOLYLINE", "SEQEND", "VERTEX", "POLYLINE", "70",     "42",      "210",
                                         "230",        "40",     "x",      "1e-300",   "ENDSEC", "SECTION", "  7 ",
                                         "\r",         "1e9",    "-1e9",   "0.5"};
  const int N = std::atoi(argv[1]);
  const ShellMesh m = rectangle_mesh({0, 0, 0}, {0.1, 0.1}, {10, 10}, true);
  int ok = 0, refused = 0, other = 0;
  const int only = argc > 2 ? std::atoi(argv[2]) : -1;
  for (int it = 0; it < N; ++it) {
    if (only >= 0 && it != only) continue;
    std::mt19937 rng(it);
    std::vector<std::string> lines;
    std::istringstream in(seeds[it % seeds.size()]);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    const int muts = 1 + rng() % 4;
    for (int k = 0; k < muts; ++k) {
      const size_t i = rng() % lines.size();
      switch (rng() % 4) {
        case 0:
          lines[i] = junk[rng() % junk.size()];
          break;
        case 1:
          lines.erase(lines.begin() + i);
          break;
        case 2:
          lines.insert(lines.begin() + i, junk[rng() % junk.size()]);
          break;
        case 3:
          std::swap(lines[i], lines[rng() % lines.size()]);
          break;
      }
    }
    const std::string fz = (std::filesystem::temp_directory_path() / "thermostamp_fuzz.dxf").string();
    {
      std::ofstream f(fz);
      for (auto& l : lines) f << l << "\n";
    }
    try {
      TrimSurface t = parse_trim("polygon:" + fz);
      if (only >= 0)
        for (auto& r : t.rings) {
          std::printf("ring %zu:", r.size());
          for (auto& v : r) std::printf(" (%.6g,%.6g)", v[0], v[1]);
          std::printf("\n");
        }
      if (only >= 0)
        std::printf("u %g %g %g v %g %g %g\n", t.plan_u[0], t.plan_u[1], t.plan_u[2], t.plan_v[0], t.plan_v[1],
                    t.plan_v[2]);
      CutPattern p = cut_pattern(m.x, m.x, m.triangles, {t});
      if (!p.fallback.empty()) ++fallbacks;
      ++ok;
    } catch (const ExportInputError& e) {
      ++refused;
      std::string w = e.what();
      if (w.find('\n') != std::string::npos) std::printf("NEWLINE in message: %s\n", w.c_str());
    } catch (const std::exception& e) {
      ++other;
      if (other < 5) std::printf("OTHER it %d: %s\n", it, e.what());
    }
  }
  std::printf("%d ok (%d by the distance), %d refused, %d other\n", ok, fallbacks, refused, other);
  return other > 0 ? 1 : 0;
}
