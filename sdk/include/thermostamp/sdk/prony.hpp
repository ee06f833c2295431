#pragma once
// Generalised Maxwell (Prony series) relaxation of a stress-like tensor:
//   S(t) = int G(t - s) d/ds[S0] ds,  G(t) = g_inf + sum_i g_i exp(-t / tau_i),
//   g_inf = 1 - sum g_i.
// Recursive update per branch over a step dt, exact when S0 varies linearly
// within the step (physics.md section 2):
//   H_i <- exp(-dt/tau_i) H_i + g_i (1 - exp(-dt/tau_i)) / (dt/tau_i) (S0^{n+1} - S0^n)
//   S = g_inf S0^{n+1} + sum_i H_i
#include <cmath>

namespace ts::sdk {

// Advances the branch states h (3 per branch, Voigt) for the change s0_new -
// s0_old and returns the relaxed stress in s. dt = 0 gives the instantaneous
// response (H_i += g_i dS0).
inline void prony_update(int branches, const double* g, const double* tau, double dt, const double s0_old[3],
                         const double s0_new[3], double* h, double s[3]) {
  double g_sum = 0;
  for (int i = 0; i < branches; ++i) g_sum += g[i];
  const double g_inf = 1.0 - g_sum;
  for (int k = 0; k < 3; ++k) s[k] = g_inf * s0_new[k];
  for (int i = 0; i < branches; ++i) {
    const double x = dt / tau[i];
    const double decay = std::exp(-x);
    const double ramp = x > 1e-8 ? (1.0 - decay) / x : 1.0 - 0.5 * x;
    for (int k = 0; k < 3; ++k) {
      h[3 * i + k] = decay * h[3 * i + k] + g[i] * ramp * (s0_new[k] - s0_old[k]);
      s[k] += h[3 * i + k];
    }
  }
}

// A value piecewise-linear in temperature with one break: slope_below
// below t_break, slope_above above, value_at_break at the break.
struct BrokenLine {
  double t_break = 270.0, value_at_break = 0.0, slope_below = 0.0, slope_above = 0.0;
  double operator()(double T) const {
    return value_at_break + (T < t_break ? slope_below : slope_above) * (T - t_break);
  }
};

}  // namespace ts::sdk
