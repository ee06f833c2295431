#include "solve/heat_capacity.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ts {

HeatCapacityTable::HeatCapacityTable(const std::vector<std::array<double, 2>>& rows) {
  for (const auto& r : rows) {
    t_.push_back(r[0]);
    c_.push_back(r[1]);
  }
  h_.assign(t_.size(), 0.0);
  for (std::size_t j = 1; j < t_.size(); ++j) h_[j] = h_[j - 1] + 0.5 * (c_[j - 1] + c_[j]) * (t_[j] - t_[j - 1]);
  c_min_ = c_.empty() ? 0.0 : *std::min_element(c_.begin(), c_.end());
  const double inf = std::numeric_limits<double>::infinity();
  const std::size_t n = t_.size();
  regions_.clear();
  for (std::size_t r = 0; r <= n && n > 0; ++r) {
    Region g;
    if (r == 0) {
      g = {t_[0], -inf, t_[0], c_[0], c_[0], 0.0};
    } else if (r == n) {
      g = {t_[n - 1], t_[n - 1], inf, c_[n - 1], c_[n - 1], 0.0};
    } else {
      g = {t_[r - 1], t_[r - 1], t_[r], c_[r - 1], c_[r], (c_[r] - c_[r - 1]) / (t_[r] - t_[r - 1])};
    }
    regions_.push_back(g);
  }
  h_zero_ = 0.0;
  if (!t_.empty()) {
    const double h0 = enthalpy(0.0);  // with h_zero_ = 0: int_{t_0}^{0} c
    h_zero_ = h0;
  }
}

double HeatCapacityTable::value(double T) const {
  const int n = static_cast<int>(t_.size());
  const int r = region(T);
  if (r == 0) return c_.front();
  if (r == n) return c_.back();
  const double s = (T - t_[r - 1]) / (t_[r] - t_[r - 1]);
  return c_[r - 1] + s * (c_[r] - c_[r - 1]);
}

double HeatCapacityTable::enthalpy(double T) const {
  const int n = static_cast<int>(t_.size());
  const int r = region(T);
  double h;
  if (r == 0) {
    h = c_.front() * (T - t_.front());
  } else if (r == n) {
    h = h_.back() + c_.back() * (T - t_.back());
  } else {
    h = h_[r - 1] + 0.5 * (c_[r - 1] + value(T)) * (T - t_[r - 1]);
  }
  return h - h_zero_;
}

}  // namespace ts
