#pragma once
// A conductivity that depends on the temperature, k(T), given as rows
// [T (degC), k11, k22, k33 (W/(m K))]: linear between the rows, held beyond
// the first and the last. The kernel evaluates it at every temperature value
// at the start of each thermal step and hands the values to the splitter
// (sdk::ThermalStepInput::conductivity): the coefficients of a step are
// those of its start (lagged), which is first order in time like the
// splitters' backward Euler.
#include <algorithm>
#include <array>
#include <vector>

namespace ts {

class ConductivityTable {
 public:
  ConductivityTable() = default;
  explicit ConductivityTable(const std::vector<std::array<double, 4>>& rows) : rows_(rows) {}
  bool empty() const { return rows_.empty(); }
  // k11, k22, k33 at T into k[0..2].
  void value(double T, double* k) const {
    const std::size_t n = rows_.size();
    if (!(T > rows_.front()[0])) {
      std::copy(rows_.front().begin() + 1, rows_.front().end(), k);
      return;
    }
    if (T >= rows_.back()[0]) {
      std::copy(rows_.back().begin() + 1, rows_.back().end(), k);
      return;
    }
    std::size_t r = 1;
    while (r + 1 < n && T >= rows_[r][0]) ++r;
    const auto& a = rows_[r - 1];
    const auto& b = rows_[r];
    const double s = (T - a[0]) / (b[0] - a[0]);
    for (int d = 1; d < 4; ++d) k[d - 1] = a[d] + s * (b[d] - a[d]);
  }

 private:
  std::vector<std::array<double, 4>> rows_;
};

}  // namespace ts
