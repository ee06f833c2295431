#pragma once
// A specific heat that depends on the temperature, c(T), given as rows
// [T (degC), c (J/(kg K))]: linear between the rows, held beyond the first
// and the last. Measured on cooling (DSC), such a table carries the latent
// heat of crystallisation of a semi-crystalline matrix as a peak: the
// apparent specific heat.
//
// The thermal splitters advance the temperatures with the table's smallest
// value c_min (their step is then at most as long as c(T) would allow);
// the kernel then gives every value the heat the splitter gave it:
//   H(T_new) - H(T_old) = c_min (T* - T_old),  H(T) = int_0^T c(theta) dtheta,
// T* the splitter's result (the enthalpy method with the heat flows of the
// step taken at T*). Heat is conserved exactly against the splitter's
// fluxes, and T_new lies between T_old and T*, so no value leaves the range
// the splitter kept it in.
#include <array>
#include <cmath>
#include <vector>

namespace ts {

class HeatCapacityTable {
 public:
  HeatCapacityTable() = default;
  // Rows with increasing temperatures and positive values (checked by the job reader).
  explicit HeatCapacityTable(const std::vector<std::array<double, 2>>& rows);
  bool empty() const { return t_.empty(); }
  double c_min() const { return c_min_; }
  // c(T), J/(kg K).
  double value(double T) const;
  // H(T) = int_0^T c, J/kg (c held beyond the rows, so H is defined for any T).
  double enthalpy(double T) const;
  // The temperature reached from T0 by adding e J/kg: T with int_{T0}^{T} c = e.
  double advance(double T0, double e) const {
    if (e == 0.0) return T0;
    int r = region(T0);
    double T = T0;
    for (;;) {
      // Region r: c = c_lo + slope (T - lo) between lo and hi (+-infinity
      // beyond the rows, where c is held).
      const Region& g = regions_[r];
      const double c = g.c_lo + g.slope * (T - g.lo);
      const double edge = e > 0 ? g.hi : g.lo_edge;
      const double c_edge = e > 0 ? g.c_hi : g.c_lo;
      const double to_edge = 0.5 * (c + c_edge) * (edge - T);  // heat to reach the edge (infinite beyond the rows)
      if (e > 0 ? to_edge < e : to_edge > e) {
        e -= to_edge;
        T = edge;
        r += e > 0 ? 1 : -1;
        continue;
      }
      // Within the region: c tau + slope tau^2 / 2 = e.
      const double disc = c * c + 2.0 * g.slope * e;
      return T + 2.0 * e / (c + std::sqrt(disc > 0 ? disc : 0.0));
    }
  }

 private:
  // 0: below the first row, r: between rows r-1 and r, n: above the last.
  int region(double T) const {
    int r = 0;
    const int n = static_cast<int>(t_.size());
    while (r < n && t_[r] <= T) ++r;
    return r;
  }
  struct Region {
    double lo, lo_edge, hi;  // lo: the point c_lo is taken at; lo_edge, hi: the region's ends (+-infinity)
    double c_lo, c_hi, slope;
    double h_lo;  // int_{t_0}^{lo} c
  };
  std::vector<double> t_;        // the rows' temperatures
  std::vector<Region> regions_;  // n + 1
  double h_zero_ = 0;              // int_{t_0}^{0} c
  double c_min_ = 0;
};

}  // namespace ts
