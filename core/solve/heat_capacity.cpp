#include "solve/heat_capacity.hpp"

#include <algorithm>
#include <limits>

namespace ts {

HeatCapacityTable::HeatCapacityTable(const std::vector<std::array<double, 2>>& rows) {
  const std::size_t n = rows.size();
  if (n == 0) return;
  const double inf = std::numeric_limits<double>::infinity();
  c_min_ = rows[0][1];
  for (const auto& r : rows) {
    t_.push_back(r[0]);
    c_min_ = std::min(c_min_, r[1]);
  }
  // Region r runs from row r-1 to row r; below the first row and above the
  // last, c is held.
  double h = 0;  // int_{t_0}^{row r-1} c
  regions_.push_back({rows[0][0], -inf, rows[0][0], rows[0][1], rows[0][1], 0.0, 0.0});
  for (std::size_t r = 1; r < n; ++r) {
    const auto &a = rows[r - 1], &b = rows[r];
    regions_.push_back({a[0], a[0], b[0], a[1], b[1], (b[1] - a[1]) / (b[0] - a[0]), h});
    h += 0.5 * (a[1] + b[1]) * (b[0] - a[0]);
  }
  regions_.push_back({rows[n - 1][0], rows[n - 1][0], inf, rows[n - 1][1], rows[n - 1][1], 0.0, h});
  h_zero_ = enthalpy(0.0);  // with h_zero_ = 0: int_{t_0}^{0} c
}

double HeatCapacityTable::value(double T) const {
  const Region& g = regions_[region(T)];
  return g.c_lo + g.slope * (T - g.lo);
}

double HeatCapacityTable::enthalpy(double T) const {
  const Region& g = regions_[region(T)];
  return g.h_lo + 0.5 * (g.c_lo + value(T)) * (T - g.lo) - h_zero_;
}

}  // namespace ts
