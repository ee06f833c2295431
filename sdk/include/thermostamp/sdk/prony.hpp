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

// Per-branch factors of the update for a step dt: decay = exp(-dt/tau),
// ramp = (1 - decay) / (dt/tau) (1 for dt = 0), from 1 / tau_i (at most
// 16 branches). Compute once per temperature and step, reuse for every
// point that shares them.
// For x = dt / tau < 1e-2 (explicit steps are far shorter than the
// relaxation times) both factors come from their Taylor series, to x^4
// below x = 1e-3 and to x^6 above: the first omitted term is below 1e-17,
// under the rounding of a double, and no exponential is evaluated. The
// powers are formed first so that the terms do not wait on each other.
inline void prony_factors_inv(int branches, const double* inv_tau, double dt, double* decay, double* ramp) {
  for (int i = 0; i < branches; ++i) {
    const double x = dt * inv_tau[i];
    // exp(-x) = sum (-x)^k / k!,  (1 - exp(-x)) / x = sum (-x)^k / (k + 1)!
    if (x < 1e-3) {
      const double x2 = x * x, x4 = x2 * x2;
      decay[i] = (1 - x) + x2 * (1.0 / 2 - x * (1.0 / 6)) + x4 * (1.0 / 24);
      ramp[i] = (1 - x * (1.0 / 2)) + x2 * (1.0 / 6 - x * (1.0 / 24)) + x4 * (1.0 / 120);
    } else if (x < 1e-2) {
      const double x2 = x * x, x4 = x2 * x2;
      decay[i] = (1 - x) + x2 * (1.0 / 2 - x * (1.0 / 6)) + x4 * ((1.0 / 24 - x * (1.0 / 120)) + x2 * (1.0 / 720));
      ramp[i] = (1 - x * (1.0 / 2)) + x2 * (1.0 / 6 - x * (1.0 / 24)) +
                x4 * ((1.0 / 120 - x * (1.0 / 720)) + x2 * (1.0 / 5040));
    } else {
      decay[i] = std::exp(-x);
      ramp[i] = -std::expm1(-x) / x;
    }
  }
}
// The same from the relaxation times.
inline void prony_factors(int branches, const double* tau, double dt, double* decay, double* ramp) {
  double inv_tau[16];
  for (int i = 0; i < branches; ++i) inv_tau[i] = 1.0 / tau[i];
  prony_factors_inv(branches, inv_tau, dt, decay, ramp);
}
// Advances the branch states h (3 per branch, Voigt) for the change s0_new -
// s0_old and returns the relaxed stress in s.
inline void prony_step(int branches, const double* g, const double* decay, const double* ramp,
                       const double s0_old[3], const double s0_new[3], double* h, double s[3]) {
  double g_sum = 0;
  for (int i = 0; i < branches; ++i) g_sum += g[i];
  const double g_inf = 1.0 - g_sum;
  for (int k = 0; k < 3; ++k) s[k] = g_inf * s0_new[k];
  for (int i = 0; i < branches; ++i)
    for (int k = 0; k < 3; ++k) {
      h[3 * i + k] = decay[i] * h[3 * i + k] + g[i] * ramp[i] * (s0_new[k] - s0_old[k]);
      s[k] += h[3 * i + k];
    }
}

// Both in one call. dt = 0 gives the instantaneous response (H_i += g_i dS0).
inline void prony_update(int branches, const double* g, const double* tau, double dt, const double s0_old[3],
                         const double s0_new[3], double* h, double s[3]) {
  double decay[16], ramp[16];
  prony_factors(branches, tau, dt, decay, ramp);
  prony_step(branches, g, decay, ramp, s0_old, s0_new, h, s);
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
