#pragma once
// The crystallisation of a semi-crystalline matrix on cooling, by
// Nakamura's non-isothermal extension of the Avrami law:
//   X(t) = 1 - exp(-theta(t)^n),  theta(t) = int_0^t K(T(s)) ds,
// X the relative crystallinity (0: amorphous melt, 1: as crystalline as the
// matrix gets), n the Avrami exponent and K(T) (1/s) the rate: rows
// [T (degC), K] (linear between them, held beyond), or Ziabicki's Gaussian
// K = k_max exp(-4 ln 2 (T - t_max)^2 / half_width^2) (zero beyond four
// half widths from t_max, where it is below 2^-64 k_max). The crystallisation
// releases latent_heat (J/kg of ply) from X = 0 to 1.
//
// Each value of a ply's thickness carries theta. After a thermal step the
// kernel adds K((T_old + T_new) / 2) dt to it (the midpoint rule) and gives
// the value the heat latent_heat (X_new - X_old) (see Simulation::
// finish_thermal_step).
//
// Melting (optional): rows [T, s] give the share s(T) of the crystals still
// solid at T (1 at the first row, 0 at the last; linear between, held
// beyond), the cumulative endotherm of a DSC heating run. The melting is
// taken as instantaneous: a value never holds more than s(T), and one that
// does melts down to it, taking the heat latent_heat (X_old - X_new), at
// the temperature that heat leaves it (X_new = s(T_new)); theta follows X,
// so that a value cooled again crystallises on from what is left. Without
// rows X never decreases.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace ts {

class CrystallisationKinetics {
 public:
  CrystallisationKinetics() = default;
  // Rows with increasing temperatures and rates >= 0, or (rows empty) the
  // Gaussian's k_max > 0 and half_width > 0 (checked by the job reader).
  // Melting rows: temperatures increasing, shares non-increasing from 1 to
  // 0 (checked by the job reader), or empty.
  CrystallisationKinetics(double latent_heat, double exponent, std::vector<std::array<double, 2>> rows,
                          double k_max, double t_max, double half_width,
                          std::vector<std::array<double, 2>> melting = {})
      : on_(true), latent_(latent_heat), n_(exponent), rows_(std::move(rows)), k_max_(k_max), t_max_(t_max),
        a_(half_width > 0 ? 4.0 * std::log(2.0) / (half_width * half_width) : 0.0),
        whole_(exponent == 1.0 || exponent == 2.0 || exponent == 3.0 || exponent == 4.0 ? static_cast<int>(exponent)
                                                                                         : 0),
        melting_(std::move(melting)),
        melt_onset_(melting_.empty() ? std::numeric_limits<double>::infinity() : melting_.front()[0]) {}
  bool empty() const { return !on_; }
  bool melts() const { return !melting_.empty(); }
  // Below this temperature (degC) every crystal is solid (infinity without melting).
  double melting_onset() const { return melt_onset_; }
  double melting_end() const { return melting_.empty() ? melt_onset_ : melting_.back()[0]; }
  // s(T): the share of the crystals still solid at T (1 without melting).
  double solid_share(double T) const { return T <= melt_onset_ ? 1.0 : along_rows(melting_, T); }
  // The temperature (degC) at which the share still solid falls to s in
  // (0, 1) (the first, where s(T) holds it over a range).
  double melting_temperature(double share) const {
    for (std::size_t k = 1; k < melting_.size(); ++k) {
      const auto &a = melting_[k - 1], &b = melting_[k];
      if (b[1] <= share) return a[1] == b[1] ? a[0] : a[0] + (a[1] - share) / (a[1] - b[1]) * (b[0] - a[0]);
    }
    return melting_end();
  }
  // A value at T holding X > s(T) melts down to x = s(T'), T' the
  // temperature the heat latent_heat (X - x) leaves it at:
  //   F(T') = H(T') - H(T) + latent_heat (X - s(T')) = 0,
  // H the value's enthalpy per kg (c T for a constant c), after(x) the
  // temperature H gives after the heat latent_heat (X - x) is taken. F rises
  // with T' (H rises, s falls), F(T) > 0 and F(after(s(T))) <= 0: one root
  // between. The rows inside that bracket narrow it to a piece where s is
  // linear (F then linear for a constant c: the secant step is the root),
  // and the Illinois variant of regula falsi ends there, at |F| below 1e-14
  // of the heats (a few steps for the quadratic pieces of a specific heat
  // table). Returns x = s(T') (kept
  // between s(T) and X) and after(x): the heat is that of the crystals
  // melted, to round-off.
  template <class Enthalpy, class After>
  std::pair<double, double> melt(double X, double T, Enthalpy enthalpy, After after) const {
    const double h0 = enthalpy(T), s0 = solid_share(T);
    auto F = [&](double t) { return enthalpy(t) - h0 + latent_ * (X - solid_share(t)); };
    double lo = after(s0), hi = T;
    double f_lo = F(lo), f_hi = F(hi);
    for (std::size_t k = melting_.size(); k-- > 0;) {  // from the top: the last row below hi decides
      const double r = melting_[k][0];
      if (!(r > lo && r < hi)) continue;
      const double f = F(r);
      if (f > 0) {
        hi = r;
        f_hi = f;
      } else {
        lo = r;
        f_lo = f;
        break;
      }
    }
    // A root to 1e-14 of the heats involved (1e-12 K and below in T').
    const double tol = 1e-14 * (std::abs(h0) + latent_);
    double t = hi;
    int side = 0;  // the end kept by the last two steps (Illinois: halve its value)
    for (int it = 0; it < 100 && f_lo < 0 && f_hi > 0; ++it) {
      t = lo - f_lo * (hi - lo) / (f_hi - f_lo);
      if (!(t > lo && t < hi)) break;  // the bracket is as narrow as the doubles allow
      const double f = F(t);
      if (std::abs(f) <= tol) break;
      if (f < 0) {
        lo = t;
        f_lo = f;
        if (side == -1) f_hi *= 0.5;
        side = -1;
      } else {
        hi = t;
        f_hi = f;
        if (side == 1) f_lo *= 0.5;
        side = 1;
      }
    }
    if (f_lo == 0) t = lo;
    const double x = std::clamp(solid_share(t), s0, X);
    return {x, after(x)};
  }
  double latent_heat() const { return latent_; }
  double exponent() const { return n_; }
  // K(T), 1/s.
  double rate(double T) const {
    if (rows_.empty()) {
      // Zero beyond four half widths, where K is below 2^-64 of its peak:
      // values there skip the kinetics.
      const double d = T - t_max_, ad2 = a_ * d * d;
      return ad2 > kCut ? 0.0 : k_max_ * std::exp(-ad2);
    }
    return along_rows(rows_, T);
  }
  // Cooling at a constant rate (K/s) from `from` (degC; at most 2000): the
  // temperature at which X reaches x (degC; -infinity if it never does
  // above -273.15). For a comparison with a DSC run at that rate.
  double temperature_at(double x, double cooling_rate, double from) const {
    const double target = integral(x) * cooling_rate, step = 0.01;
    double sum = 0, T = std::min(from, 2000.0), k = rate(T);
    while (T > -273.15) {
      const double k1 = rate(T - step);
      const double add = 0.5 * (k + k1) * step;
      if (sum + add >= target) return T - step * (target - sum) / add;
      sum += add;
      T -= step;
      k = k1;
    }
    return -std::numeric_limits<double>::infinity();
  }
  // The temperature above which K is negligible: the last row, or four half
  // widths above the Gaussian's peak (K there is 2^-64 of its peak).
  double upper_temperature() const { return rows_.empty() ? t_max_ + 4.0 * half_width() : rows_.back()[0]; }
  double half_width() const { return a_ > 0 ? std::sqrt(4.0 * std::log(2.0) / a_) : 0.0; }
  // X from theta, and theta from X (infinite for X = 1: a value that
  // crystallises no further until it melts).
  double crystallinity(double theta) const {
    if (!(theta > 0)) return 0.0;
    double p;  // theta^n, by products for the usual whole exponents
    switch (whole_) {
      case 1: p = theta; break;
      case 2: p = theta * theta; break;
      case 3: p = theta * theta * theta; break;
      case 4: p = (theta * theta) * (theta * theta); break;
      default: p = std::pow(theta, n_);
    }
    return -std::expm1(-p);
  }
  double integral(double X) const { return X > 0 ? std::pow(-std::log1p(-X), 1.0 / n_) : 0.0; }

 private:
  // The value of rows [T, v] at T: linear between the rows, held beyond them.
  static double along_rows(const std::vector<std::array<double, 2>>& rows, double T) {
    if (T <= rows.front()[0]) return rows.front()[1];
    if (T >= rows.back()[0]) return rows.back()[1];
    std::size_t k = 1;
    while (rows[k][0] < T) ++k;
    const auto &a = rows[k - 1], &b = rows[k];
    return a[1] + (T - a[0]) / (b[0] - a[0]) * (b[1] - a[1]);
  }
  static constexpr double kCut = 64.0 * 0.6931471805599453;  // a d^2 at four half widths: 4 ln 2 x 16
  bool on_ = false;
  double latent_ = 0, n_ = 1;
  std::vector<std::array<double, 2>> rows_;
  double k_max_ = 0, t_max_ = 0, a_ = 0;
  int whole_ = 0;  // n when it is 1, 2, 3 or 4, else 0
  std::vector<std::array<double, 2>> melting_;  // [T, share still solid]
  double melt_onset_ = std::numeric_limits<double>::infinity();
};

}  // namespace ts
