// viscoelastic_shear: in-plane shear with a temperature-dependent scale and
// a generalised Maxwell (Prony) relaxation (physics.md section 2):
//   S0_sh = 2 d/dC [ omega(T) sum_i k_sh_i I_sh^(2i) ],
//   S_sh(t) = int G(t - s) d/ds[S0_sh] ds, G = g_inf + sum_i g_i exp(-t/tau_i).
// omega, g_i and tau_i are piecewise linear in T with a break at t_break
// (270 degC in the reference data). Out of range values are clamped:
// omega >= 0, g_i >= 0, sum g_i <= 1, tau_i >= 1e-9 s. Listed next to
// ud_hyperelastic or woven_hyperelastic, its stress adds to theirs.
#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/prony.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace {

using namespace ts::sdk;

// Branches handled by the vector pass (more: point by point).
constexpr int kVectorBranches = 4;

// Per-thread buffers of a block.
struct Scratch {
  std::vector<double> redo;  // 0 or 1 (a double: a narrower type would widen the vector loops)
  std::vector<double> energy;
};
Scratch& scratch(std::size_t n) {
  thread_local Scratch s;
  if (s.redo.size() < n) {
    s.redo.resize(n);
    s.energy.resize(n);
  }
  return s;
}

// Unrelaxed shear stress S0 = 2 omega w_sh'(I_sh) dI_sh/dC and energy
// omega w_sh of one point (C, weft direction (c, s)), written out as
// invariants(C, {c, s}, kSh), even_polynomial() and add_stress() compute
// them (same operations, same order, so the same bits); inlined into the
// vector passes below.
struct ShearStress {
  double s0, s1, s2, w;
};
// The stress and energy from I_sh and dI_sh/dC (dsh0-2):
// even_polynomial() and add_stress() written out.
[[gnu::always_inline]] inline ShearStress shear_polynomial(double sh, double dsh0, double dsh1, double dsh2, double k1,
                                                           double k2, double k3, double omega) {
  const double x2 = sh * sh;
  double v = 0, d = 0, p = 1;
  d += 2 * 1 * k1 * p * sh;
  p *= x2;
  v += k1 * p;
  d += 2 * 2 * k2 * p * sh;
  p *= x2;
  v += k2 * p;
  d += 2 * 3 * k3 * p * sh;
  p *= x2;
  v += k3 * p;
  const double dw = kStressFactor * (omega * d);
  return {0.0 + dw * dsh0, 0.0 + dw * dsh1, 0.0 + dw * dsh2, omega * v};
}
// I_sh and dI_sh/dC for the frame (c, s), as invariants() forms them.
[[gnu::always_inline]] inline ShearStress shear_stress(double C0, double C1, double C2, double c, double s, double k1,
                                                       double k2, double k3, double omega) {
  const double l22_0 = c * c, l22_1 = s * s, l22_2 = c * s;
  const double l12_0 = c, l12_1 = 0.0, l12_2 = 0.5 * s;
  const double i41 = C0 * 1.0 + C1 * 0.0 + 2 * C2 * 0.0;
  const double i42 = C0 * l22_0 + C1 * l22_1 + 2 * C2 * l22_2;
  const double i412 = C0 * l12_0 + C1 * l12_1 + 2 * C2 * l12_2;
  const double pp = i41 * i42, inv = 1.0 / pp, ir = std::sqrt(pp) * inv, sh = i412 * ir;
  const double a41 = i42 * inv, a42 = i41 * inv;  // 1 / I41, 1 / I42
  const double dsh0 = l12_0 * ir - 0.5 * sh * (1.0 * a41 + l22_0 * a42);
  const double dsh1 = l12_1 * ir - 0.5 * sh * (0.0 * a41 + l22_1 * a42);
  const double dsh2 = l12_2 * ir - 0.5 * sh * (0.0 * a41 + l22_2 * a42);
  return shear_polynomial(sh, dsh0, dsh1, dsh2, k1, k2, k3, omega);
}

// shear_stress() for a UD law's frame (c, s) = (0, 1): l22 = (0, 1, 0),
// l12 = (0, 0, 1/2). Every product with those zeros is a signed zero that
// the sums and differences of shear_stress() drop without a trace (C11,
// C22 > 0 and all values finite), so i41 = C0, i42 = C1, i412 = C2 and the
// terms below are the same bits, without the products by 0 and 1 and
// without a direction read.
[[gnu::always_inline]] inline ShearStress ud_shear_stress(double C0, double C1, double C2, double k1, double k2,
                                                          double k3, double omega) {
  const double i41 = C0, i42 = C1, i412 = C2;
  const double pp = i41 * i42, inv = 1.0 / pp, ir = std::sqrt(pp) * inv, sh = i412 * ir;
  const double dsh0 = 0.0 - 0.5 * sh * (i42 * inv);
  const double dsh1 = 0.0 - 0.5 * sh * (i41 * inv);
  const double dsh2 = 0.5 * ir;
  return shear_polynomial(sh, dsh0, dsh1, dsh2, k1, k2, k3, omega);
}
// The shear stress of a point with right Cauchy-Green tensor (C0, C1, C2):
// UD (kUd, no directions) or with the weft direction (d0, d1).
template <bool kUd>
[[gnu::always_inline]] inline ShearStress point_shear(double C0, double C1, double C2, double d0, double d1, double k1,
                                                      double k2, double k3, double omega) {
  if constexpr (kUd) return ud_shear_stress(C0, C1, C2, k1, k2, k3, omega);
  return shear_stress(C0, C1, C2, d0, d1, k1, k2, k3, omega);
}

// One Maxwell branch over a step (prony_step()'s update, same order):
// H <- decay H + g ramp (S0_new - S0_old), h the branch's 3 values, ds the
// change of S0.
struct Branch {
  double h0, h1, h2;
};
[[gnu::always_inline]] inline Branch maxwell_branch(double decay, double g, double ramp, const double* h, double ds0,
                                                    double ds1, double ds2) {
  return {decay * h[0] + g * ramp * ds0, decay * h[1] + g * ramp * ds1, decay * h[2] + g * ramp * ds2};
}

// A branch's new values h stored at out[0, 3) and added to the stress o.
[[gnu::always_inline]] inline void take_branch(const Branch& h, double* __restrict out, double& o0, double& o1,
                                               double& o2) {
  out[0] = h.h0;
  out[1] = h.h1;
  out[2] = h.h2;
  o0 += h.h0;
  o1 += h.h1;
  o2 += h.h2;
}

// BrokenLine::operator() of a line given as (t_break, value at the break,
// slope below, slope above): the same operations, so the same bits.
[[gnu::always_inline]] inline double broken_line(const double* l, double T) {
  return l[1] + (T < l[0] ? l[2] : l[3]) * (T - l[0]);
}
// The parameters' lines as the vector passes read them (`lines`: t_min,
// t_max, then (t_break, value at the break, slope below, slope above) for
// omega, each g_i and each tau_i), unpacked.
template <int NB>
struct Lines {
  double t_min, t_max, lo[4], lg[NB][4], lt[NB][4];
  Lines() = default;
  explicit Lines(const double* lines) {
    t_min = lines[0];
    t_max = lines[1];
    for (int k = 0; k < 4; ++k) {
      lo[k] = lines[2 + k];
      for (int i = 0; i < NB; ++i) {
        lg[i][k] = lines[6 + 4 * i + k];
        lt[i][k] = lines[6 + 4 * NB + 4 * i + k];
      }
    }
  }
};
// at() at temperature T0: omega, the weights g_i (scaled to sum 1 where
// they sum to more), 1 / tau_i and g_inf = 1 - sum g_i.
template <int NB>
struct Parameters {
  double omega, g_inf, g[NB], inv_tau[NB];
  double decay[NB], ramp[NB];  // the Prony factors, where given for the block (kGiven in visco_values)
};
template <int NB>
[[gnu::always_inline]] inline Parameters<NB> parameters(const Lines<NB>& l, double T0) {
  Parameters<NB> p;
  const double T = T0 < l.t_min ? l.t_min : (l.t_max < T0 ? l.t_max : T0);  // std::clamp
  const double ov = broken_line(l.lo, T);
  p.omega = 0.0 < ov ? ov : 0.0;  // std::max(0.0, ov)
  double g_raw_sum = 0;
  for (int i = 0; i < NB; ++i) {
    const double gv = broken_line(l.lg[i], T), tv = broken_line(l.lt[i], T);
    p.g[i] = 0.0 < gv ? gv : 0.0;
    const double tau = 1e-9 < tv ? tv : 1e-9;
    p.inv_tau[i] = 1.0 / tau;
    g_raw_sum += p.g[i];
  }
  for (int i = 0; i < NB; ++i) p.g[i] = g_raw_sum > 1.0 ? p.g[i] / g_raw_sum : p.g[i];
  // prony_step(nb, g, decay, ramp, S0_old, s0, H, s)
  double g_sum = 0;
  for (int i = 0; i < NB; ++i) g_sum += p.g[i];
  p.g_inf = 1.0 - g_sum;
  return p;
}
// The law at one point with parameters p; with parameters(), each step of
// the scalar path (ViscoelasticShear::at(), invariants(), even_polynomial(),
// add_stress(), prony_factors_inv(), prony_step()) written out in the same
// order so that the results are the same bits. In: the point's C (c0, c1,
// c2), its weft direction (d0, d1; not read for UD) and its state st (S0,
// then H_i: 3 + 3 NB values). Out: the new state nx, the stress (s0, s1,
// s2), the energy w, and rq = 1 where dt / tau_i >= 1e-2 for some branch
// (the point is evaluated again by the scalar path, the state left as it
// was), else 0. With kGiven the factors are p.decay and p.ramp (computed
// once for a block at one temperature) and no point is to be redone. It
// works on values only; visco_point or the loop (see there) does the loads
// and stores of the block's arrays.
template <int NB>
struct PointIn {
  double c0, c1, c2, d0, d1, st[3 + 3 * NB];
};
template <int NB>
struct PointOut {
  double nx[3 + 3 * NB], s0, s1, s2, w, rq;
};
template <int NB, bool kUd, bool kGiven = false>
[[gnu::always_inline]] inline PointOut<NB> visco_values(const PointIn<NB> in, const Parameters<NB>& p, double dt,
                                                      double k1, double k2, double k3) {
  PointOut<NB> out;
  const double* st = in.st;
  double* nx = out.nx;
  const ShearStress ss = point_shear<kUd>(in.c0, in.c1, in.c2, in.d0, in.d1, k1, k2, k3, p.omega);
  const double s00 = ss.s0, s01 = ss.s1, s02 = ss.s2;
  double o0 = p.g_inf * s00, o1 = p.g_inf * s01, o2 = p.g_inf * s02;
  nx[0] = s00;
  nx[1] = s01;
  nx[2] = s02;
  bool ok = true;
  for (int i = 0; i < NB; ++i) {
    if constexpr (kGiven) {
      take_branch(maxwell_branch(p.decay[i], p.g[i], p.ramp[i], st + 3 + 3 * i, s00 - st[0], s01 - st[1], s02 - st[2]),
                  nx + 3 + 3 * i, o0, o1, o2);
      continue;
    }
    const double x = dt * p.inv_tau[i];
    // prony_factors_inv: the series (x < 1e-3 and x < 1e-2 forms)
    const double xx2 = x * x, x4 = xx2 * xx2;
    const double decay_a = (1 - x) + xx2 * (1.0 / 2 - x * (1.0 / 6)) + x4 * (1.0 / 24);
    const double ramp_a = (1 - x * (1.0 / 2)) + xx2 * (1.0 / 6 - x * (1.0 / 24)) + x4 * (1.0 / 120);
    const double decay_b =
        (1 - x) + xx2 * (1.0 / 2 - x * (1.0 / 6)) + x4 * ((1.0 / 24 - x * (1.0 / 120)) + xx2 * (1.0 / 720));
    const double ramp_b = (1 - x * (1.0 / 2)) + xx2 * (1.0 / 6 - x * (1.0 / 24)) +
                          x4 * ((1.0 / 120 - x * (1.0 / 720)) + xx2 * (1.0 / 5040));
    const double decay = x < 1e-3 ? decay_a : decay_b, ramp = x < 1e-3 ? ramp_a : ramp_b;
    ok = ok & (x < 1e-2);
    take_branch(maxwell_branch(decay, p.g[i], ramp, st + 3 + 3 * i, s00 - st[0], s01 - st[1], s02 - st[2]),
                nx + 3 + 3 * i, o0, o1, o2);
  }
  out.s0 = o0;
  out.s1 = o1;
  out.s2 = o2;
  out.w = ss.w;
  out.rq = ok ? 0.0 : 1.0;
  return out;
}
// One point's loads, law and stores (q of n points, rows n apart); returns
// its redo flag. GCC vectorises the loop below with the point's arrays
// inside this inlined function (in the loop's own body its `omp simd`
// lowering gives them a copy per lane, and the loop stays scalar). Clang
// 14 does not carry the loop's independence into the loads and stores of
// a function it inlines there (it then checks the arrays' overlap at run
// time, the checks fail and the loop runs scalar), so for Clang the loop
// does them itself: the same operations, the same bits.
template <int NB, bool kUd, bool kGiven>
[[gnu::always_inline]] inline double visco_point(std::size_t q, std::size_t n, const double* __restrict C,
                                               const double* __restrict dir2, const Parameters<NB>& p, double dt,
                                               double k1, double k2, double k3, double* __restrict state,
                                               double* __restrict S, double* __restrict W, double* __restrict redo) {
  PointIn<NB> in;
  in.c0 = C[3 * q];
  in.c1 = C[3 * q + 1];
  in.c2 = C[3 * q + 2];
  in.d0 = 0.0;
  in.d1 = 0.0;
  if constexpr (!kUd) {
    in.d0 = dir2[2 * q];
    in.d1 = dir2[2 * q + 1];
  }
  for (int k = 0; k < 3 + 3 * NB; ++k) in.st[k] = state[k * n + q];
  const PointOut<NB> out = visco_values<NB, kUd, kGiven>(in, p, dt, k1, k2, k3);
  redo[q] = out.rq;
  for (int k = 0; k < 3 + 3 * NB; ++k) state[k * n + q] = out.rq == 0.0 ? out.nx[k] : in.st[k];
  S[3 * q] = out.s0;
  S[3 * q + 1] = out.s1;
  S[3 * q + 2] = out.s2;
  W[q] = out.w;
  return out.rq;
}
// Where a pass takes each point's parameters: evaluated at its
// temperature from the lines, read from the cache (MaterialBlock::cache,
// see visco_parameters), or given for the whole block (one temperature).
enum class ParamSource { kEvaluated, kCached, kGiven };
// The law over n points; returns 1 if some point is to be evaluated again,
// else 0. State of a block: row k (value k of every point, n apart) holds
// S0 (rows 0-2), then H_i (rows 3 + 3 i to 5 + 3 i). The new S0 and H_i
// replace the old ones, except where redo[q] = 1 (a store in every case:
// contiguous rows, a select and a vector store). Per source: temp and
// lines (kEvaluated), cache (kCached: 3 + 2 NB rows, ld = n: the
// temperature, omega, g_inf, g_i, 1 / tau_i), given (kGiven).
template <int NB, bool kUd, ParamSource kSource>
[[gnu::always_inline]] inline double visco_loop(std::size_t n, const double* __restrict C,
                                              const double* __restrict dir2, const double* __restrict temp,
                                              const double* lines, const double* __restrict cache,
                                              const Parameters<NB>& given, double dt, const double* ksh,
                                              double* __restrict state, double* __restrict S, double* __restrict W,
                                              double* __restrict redo) {
  const double k1 = ksh[0], k2 = ksh[1], k3 = ksh[2];
  Lines<NB> l;  // read only by kEvaluated
  if constexpr (kSource == ParamSource::kEvaluated) l = Lines<NB>(lines);
  double any = 0.0;
#pragma omp simd reduction(+ : any)
  for (std::size_t q = 0; q < n; ++q) {
    Parameters<NB> p;
    if constexpr (kSource == ParamSource::kEvaluated) {
      p = parameters<NB>(l, temp[q]);
    } else if constexpr (kSource == ParamSource::kCached) {
      p.omega = cache[n + q];
      p.g_inf = cache[2 * n + q];
      for (int i = 0; i < NB; ++i) {
        p.g[i] = cache[(3 + i) * n + q];
        p.inv_tau[i] = cache[(3 + NB + i) * n + q];
      }
    } else {
      p = given;
    }
#if defined(__clang__)
    PointIn<NB> in;
    in.c0 = C[3 * q];
    in.c1 = C[3 * q + 1];
    in.c2 = C[3 * q + 2];
    in.d0 = 0.0;
    in.d1 = 0.0;
    if constexpr (!kUd) {
      in.d0 = dir2[2 * q];
      in.d1 = dir2[2 * q + 1];
    }
    for (int k = 0; k < 3 + 3 * NB; ++k) in.st[k] = state[k * n + q];
    const PointOut<NB> out = visco_values<NB, kUd, kSource == ParamSource::kGiven>(in, p, dt, k1, k2, k3);
    redo[q] = out.rq;
    for (int k = 0; k < 3 + 3 * NB; ++k) state[k * n + q] = out.rq == 0.0 ? out.nx[k] : in.st[k];
    S[3 * q] = out.s0;
    S[3 * q + 1] = out.s1;
    S[3 * q + 2] = out.s2;
    W[q] = out.w;
    any += out.rq;
#else
    any += visco_point<NB, kUd, kSource == ParamSource::kGiven>(q, n, C, dir2, p, dt, k1, k2, k3, state, S, W, redo);
#endif
  }
  return any;
}

// The per-point parameters kept in MaterialBlock::cache, one value after
// the other (ld = n apart): the temperature they are for, omega, g_inf,
// g_i, 1 / tau_i (3 + 2 NB rows). visco_parameters writes them for the
// temperatures temp; visco_cached is visco_block with them read instead of
// evaluated (the same bits).
template <int NB>
[[gnu::always_inline]] inline void parameters_body(std::size_t n, const double* __restrict temp,
                                                   const double* lines, double* __restrict cache) {
  const Lines<NB> l(lines);
#pragma omp simd
  for (std::size_t q = 0; q < n; ++q) {
    const Parameters<NB> p = parameters<NB>(l, temp[q]);
    cache[q] = temp[q];
    cache[n + q] = p.omega;
    cache[2 * n + q] = p.g_inf;
    for (int i = 0; i < NB; ++i) {
      cache[(3 + i) * n + q] = p.g[i];
      cache[(3 + NB + i) * n + q] = p.inv_tau[i];
    }
  }
}
// Whether all n temperatures are temp[0] (one vector pass).
TS_VECTOR_CLONES
bool all_the_same(std::size_t n, const double* __restrict temp) {
  const double t0 = temp[0];
  double differ = 0;
#pragma omp simd reduction(+ : differ)
  for (std::size_t q = 0; q < n; ++q) differ += temp[q] == t0 ? 0.0 : 1.0;
  return differ == 0;
}
// Whether the cache's temperatures are those of temp (NaN at the start: no).
TS_VECTOR_CLONES
bool same_temperatures(std::size_t n, const double* __restrict temp, const double* __restrict cached) {
  double differ = 0;
#pragma omp simd reduction(+ : differ)
  for (std::size_t q = 0; q < n; ++q) differ += temp[q] == cached[q] ? 0.0 : 1.0;
  return differ == 0;
}

// Each vector pass for 1 to 4 branches, with the weft directions (V) and
// for UD (U, no directions read); the tables below are indexed [ud][NB].
#define TS_VISCO_VARIANTS(M) \
  M(1, V, false) M(2, V, false) M(3, V, false) M(4, V, false) M(1, U, true) M(2, U, true) M(3, U, true) M(4, U, true)
#define TS_VISCO_TABLE(f) \
  { {nullptr, f##V1, f##V2, f##V3, f##V4}, {nullptr, f##U1, f##U2, f##U3, f##U4} }
#define TS_VISCO_BLOCK(NB, V, UD)                                                                                \
  TS_VECTOR_CLONES double visco_block##V##NB(std::size_t n, const double* C, const double* dir2, const double* temp, \
                                             double dt, const double* ksh, const double* lines, double* state,      \
                                             double* S, double* W, double* redo) {                                  \
    return visco_loop<NB, UD, ParamSource::kEvaluated>(n, C, dir2, temp, lines, nullptr, Parameters<NB>{}, dt, ksh, \
                                                       state, S, W, redo);                                          \
  }
TS_VISCO_VARIANTS(TS_VISCO_BLOCK)
#undef TS_VISCO_BLOCK
using ViscoBlock = double (*)(std::size_t, const double*, const double*, const double*, double, const double*,
                            const double*, double*, double*, double*, double*);
constexpr ViscoBlock kViscoBlock[2][kVectorBranches + 1] = TS_VISCO_TABLE(visco_block);
#define TS_VISCO_PARAMETERS(NB)                                                                      \
  TS_VECTOR_CLONES void visco_parameters##NB(std::size_t n, const double* temp, const double* lines, \
                                             double* cache) {                                       \
    parameters_body<NB>(n, temp, lines, cache);                                                      \
  }
TS_VISCO_PARAMETERS(1)
TS_VISCO_PARAMETERS(2)
TS_VISCO_PARAMETERS(3)
TS_VISCO_PARAMETERS(4)
#undef TS_VISCO_PARAMETERS
#define TS_VISCO_CACHED(NB, V, UD)                                                                            \
  TS_VECTOR_CLONES double visco_cached##V##NB(std::size_t n, const double* C, const double* dir2,               \
                                              const double* cache, double dt, const double* ksh, double* state, \
                                              double* S, double* W, double* redo) {                            \
    return visco_loop<NB, UD, ParamSource::kCached>(n, C, dir2, nullptr, nullptr, cache, Parameters<NB>{}, dt, ksh, \
                                                    state, S, W, redo);                                         \
  }
TS_VISCO_VARIANTS(TS_VISCO_CACHED)
#undef TS_VISCO_CACHED
using ViscoParameters = void (*)(std::size_t, const double*, const double*, double*);
constexpr ViscoParameters kViscoParameters[kVectorBranches + 1] = {nullptr, visco_parameters1, visco_parameters2,
                                                                   visco_parameters3, visco_parameters4};
using ViscoCached = double (*)(std::size_t, const double*, const double*, const double*, double, const double*,
                             double*, double*, double*, double*);
constexpr ViscoCached kViscoCached[2][kVectorBranches + 1] = TS_VISCO_TABLE(visco_cached);

// The same for n points at one temperature: omega, g_i and the factors
// decay_i, ramp_i given (computed once for the block); the new S0 and H_i
// are written to the state in place (no point needs evaluating again).
template <int NB, bool kUd>
[[gnu::always_inline]] inline void visco_uniform_body(std::size_t n, const double* __restrict C,
                                                      const double* __restrict dir2, double omega, const double* g,
                                                      const double* decay, const double* ramp, const double* ksh,
                                                      double* __restrict state, double* __restrict S,
                                                      double* __restrict W, double* __restrict redo) {
  Parameters<NB> p;
  p.omega = omega;
  double g_sum = 0;
  for (int i = 0; i < NB; ++i) {
    p.g[i] = g[i];
    p.inv_tau[i] = 0.0;  // not read
    p.decay[i] = decay[i];
    p.ramp[i] = ramp[i];
    g_sum += g[i];
  }
  p.g_inf = 1.0 - g_sum;
  visco_loop<NB, kUd, ParamSource::kGiven>(n, C, dir2, nullptr, nullptr, nullptr, p, 0.0, ksh, state, S, W, redo);
}
#define TS_VISCO_UNIFORM(NB, V, UD)                                                                               \
  TS_VECTOR_CLONES void visco_uniform##V##NB(std::size_t n, const double* C, const double* dir2, double omega, \
                                             const double* g, const double* decay, const double* ramp,          \
                                             const double* ksh, double* state, double* S, double* W,            \
                                             double* redo) {                                                     \
    visco_uniform_body<NB, UD>(n, C, dir2, omega, g, decay, ramp, ksh, state, S, W, redo);                       \
  }
TS_VISCO_VARIANTS(TS_VISCO_UNIFORM)
#undef TS_VISCO_UNIFORM
using ViscoUniform = void (*)(std::size_t, const double*, const double*, double, const double*, const double*,
                              const double*, const double*, double*, double*, double*, double*);
constexpr ViscoUniform kViscoUniform[2][kVectorBranches + 1] = TS_VISCO_TABLE(visco_uniform);
#undef TS_VISCO_TABLE
#undef TS_VISCO_VARIANTS

class ViscoelasticShear final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&]() -> Status {
      const auto& ks = p.list("k_sh");
      for (int i = 0; i < 3; ++i) k_sh_[i] = ks[i];
      const double tb = p.real("t_break");
      t_min_ = p.real("t_min");
      t_max_ = p.real("t_max");
      if (!(t_max_ > t_min_)) return Status::failure("t_max must be above t_min");
      omega_ = {tb, p.real("omega_at_break"), p.real("omega_slope_below"), p.real("omega_slope_above")};
      const auto& g = p.list("g");
      const auto& tau = p.list("tau");
      const auto& gb = p.list("g_slope_below");
      const auto& ga = p.list("g_slope_above");
      const auto& tb_ = p.list("tau_slope_below");
      const auto& ta = p.list("tau_slope_above");
      n_ = static_cast<int>(g.size());
      if (n_ > 16) return Status::failure("at most 16 Maxwell branches, found " + std::to_string(n_));
      if (tau.size() != g.size())
        return Status::failure("tau has " + std::to_string(tau.size()) + " entries, g has " + std::to_string(g.size()));
      auto slopes = [&](const std::vector<double>& v, const char* name) -> std::vector<double> {
        if (v.empty()) return std::vector<double>(n_, 0.0);
        if (static_cast<int>(v.size()) != n_)
          throw std::invalid_argument(std::string(name) + " needs one entry per branch (" + std::to_string(n_) + ")");
        return v;
      };
      const auto gb2 = slopes(gb, "g_slope_below"), ga2 = slopes(ga, "g_slope_above");
      const auto tb2 = slopes(tb_, "tau_slope_below"), ta2 = slopes(ta, "tau_slope_above");
      double sum = 0;
      for (int i = 0; i < n_; ++i) {
        if (!(tau[i] > 0))
          return Status::failure("tau[" + std::to_string(i) + "] must be > 0 s, found " + std::to_string(tau[i]));
        sum += g[i];
        g_.push_back({tb, g[i], gb2[i], ga2[i]});
        tau_.push_back({tb, tau[i], tb2[i], ta2[i]});
      }
      if (sum > 1.0)
        return Status::failure("the Maxwell weights g sum to " + std::to_string(sum) + " at t_break; it must be <= 1");
      // The lines as the vector pass reads them (see visco_loop).
      lines_ = {t_min_, t_max_, omega_.t_break, omega_.value_at_break, omega_.slope_below, omega_.slope_above};
      for (const auto* set : {&g_, &tau_})
        for (const BrokenLine& l : *set) lines_.insert(lines_.end(), {l.t_break, l.value_at_break, l.slope_below, l.slope_above});
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  bool uses_strain_old() const override { return false; }
  // Per point: S0 at the previous step (3), the branch states H_i (3 per
  // branch); a block's values row by row (value k of point q at k n + q).
  int state_size() const override { return 3 + 3 * n_; }
  // Per point, for the vector pass at varying temperatures: the
  // temperature, omega, g_inf, g_i and 1 / tau_i there (parameters_body).
  int cache_size() const override { return n_ >= 1 && n_ <= kVectorBranches ? 3 + 2 * n_ : 0; }
  std::pair<double, double> temperature_range() const override { return {t_min_, t_max_}; }

  // Clamped parameters at temperature T.
  void at(double T, double* omega, double* g, double* tau) const {
    T = std::clamp(T, t_min_, t_max_);
    *omega = std::max(0.0, omega_(T));
    double sum = 0;
    for (int i = 0; i < n_; ++i) {
      g[i] = std::max(0.0, g_[i](T));
      tau[i] = std::max(1e-9, tau_[i](T));
      sum += g[i];
    }
    if (sum > 1.0)
      for (int i = 0; i < n_; ++i) g[i] /= sum;
  }

  Status evaluate(const MaterialBlock& b) const override {
    if (b.n == 0) return Status::success();
    // One temperature for the whole block (an isothermal run)?
    const bool uniform = all_the_same(b.n, b.temperature.data());
    if (n_ < 1 || n_ > kVectorBranches) {
      double g[16], decay[16], ramp[16], omega = 0;
      if (uniform) factors(b.temperature[0], b.dt, &omega, g, decay, ramp);
      for (std::size_t q = 0; q < b.n; ++q) {
        if (uniform)
          shared_point(b, q, omega, g, decay, ramp);
        else
          point(b, q);
      }
      return Status::success();
    }
    Scratch& sc = scratch(b.n);
    const int ud = b.dir2.empty() ? 1 : 0;  // UD: the passes that read no directions
    const double* dir2 = ud ? nullptr : b.dir2.data();
    double* W = b.energy.empty() ? sc.energy.data() : b.energy.data();
    if (uniform) {
      // The parameters and factors at the block's temperature, shared by
      // every point in one vector pass.
      double g[16], decay[16], ramp[16], omega = 0;
      factors(b.temperature[0], b.dt, &omega, g, decay, ramp);
      kViscoUniform[ud][n_](b.n, b.strain.data(), dir2, omega, g, decay, ramp, k_sh_, b.state.data(), b.stress.data(),
                            W, sc.redo.data());
      return Status::success();
    }
    // Otherwise one vector pass over the block, the parameters evaluated
    // at each point's temperature (or read from the cache, evaluated there
    // when the temperatures changed), for the points whose dt / tau_i are
    // in the factors' series range; the other points are evaluated one by
    // one. All give the same bits.
    double any = 0.0;  // some point to evaluate again
    if (b.cache.size() == static_cast<std::size_t>(cache_size()) * b.n) {
      if (!same_temperatures(b.n, b.temperature.data(), b.cache.data()))
        kViscoParameters[n_](b.n, b.temperature.data(), lines_.data(), b.cache.data());
      any = kViscoCached[ud][n_](b.n, b.strain.data(), dir2, b.cache.data(), b.dt, k_sh_, b.state.data(),
                                 b.stress.data(), W, sc.redo.data());
    } else {
      any = kViscoBlock[ud][n_](b.n, b.strain.data(), dir2, b.temperature.data(), b.dt, k_sh_, lines_.data(),
                                b.state.data(), b.stress.data(), W, sc.redo.data());
    }
    if (any == 0.0) return Status::success();
    for (std::size_t q = 0; q < b.n; ++q)
      if (sc.redo[q] != 0) point(b, q);
    return Status::success();
  }

  // The parameters at temperature T and the Prony factors of a step dt
  // (16 values each at most).
  void factors(double T, double dt, double* omega, double* g, double* decay, double* ramp) const {
    double tau[16], inv_tau[16];
    at(T, omega, g, tau);
    for (int i = 0; i < n_; ++i) inv_tau[i] = 1.0 / tau[i];
    prony_factors_inv(n_, inv_tau, dt, decay, ramp);
  }

  // One point: parameters at its temperature, Prony step.
  void point(const MaterialBlock& b, std::size_t q) const {
    double g[16], decay[16], ramp[16], omega = 0;
    factors(b.temperature[q], b.dt, &omega, g, decay, ramp);
    shared_point(b, q, omega, g, decay, ramp);
  }

  // One point at the temperature of another (its parameters and factors
  // given).
  void shared_point(const MaterialBlock& b, std::size_t q, double omega, const double* g, const double* decay,
                    const double* ramp) const {
    FibreFrame fr;
    if (!b.dir2.empty()) {
      fr.c = b.dir2[2 * q];
      fr.s = b.dir2[2 * q + 1];
    }
    const Invariants v = invariants({b.strain[3 * q], b.strain[3 * q + 1], b.strain[3 * q + 2]}, fr, kSh);
    finish(b, q, v, omega, g, decay, ramp);
  }

  // Prony step of one point from its invariants and factors.
  void finish(const MaterialBlock& b, std::size_t q, const Invariants& v, double omega, const double* g,
              const double* decay, const double* ramp) const {
    // The point's values, row k of the block's state at k n + q.
    double st[3 + 3 * 16];
    const int ns = state_size();
    for (int k = 0; k < ns; ++k) st[k] = b.state[k * b.n + q];
    double wsh, dwsh;
    even_polynomial(k_sh_, 3, v.sh, &wsh, &dwsh);
    Sym2 s0{0, 0, 0};
    add_stress(s0, omega * dwsh, v.dsh);
    double s[3];
    prony_step(n_, g, decay, ramp, st, s0.data(), st + 3, s);
    for (int k = 0; k < 3; ++k) {
      st[k] = s0[k];
      b.stress[3 * q + k] = s[k];
    }
    for (int k = 0; k < ns; ++k) b.state[k * b.n + q] = st[k];
    if (!b.energy.empty()) b.energy[q] = omega * wsh;  // elastic (unrelaxed) energy
  }
  double max_stiffness(double T) const override {
    double omega, g[16], tau[16];
    at(T, &omega, g, tau);
    return 2 * omega * (2 * std::abs(k_sh_[0]) + 12 * std::abs(k_sh_[1]) + 30 * std::abs(k_sh_[2]));
  }

 private:
  double t_min_ = 200, t_max_ = 350;
  double k_sh_[3] = {0, 0, 0};
  BrokenLine omega_;
  std::vector<BrokenLine> g_, tau_;
  std::vector<double> lines_;
  int n_ = 0;
};

MaterialLaw* create() { return new ViscoelasticShear(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "viscoelastic_shear";
  d.version = "1.3.2";
  d.summary = "In-plane shear, temperature-dependent scale and Prony-series relaxation (adds to a membrane law)";
  d.params = {
      list_param("k_sh", "", "N/m", "shear coefficients of w_sh = omega(T) sum k_sh^i I_sh^(2i)", 3),
      real_param("t_break", "270.0", "degC", "temperature of the break of the piecewise-linear laws"),
      real_param("t_min", "200.0", "degC", "lowest temperature the parameters hold for; below it they are held at t_min (with a warning)"),
      real_param("t_max", "350.0", "degC", "highest temperature the parameters hold for; above it they are held at t_max (with a warning)"),
      real_param("omega_at_break", "1.0", "-", "shear scale omega at t_break"),
      real_param("omega_slope_below", "0.0", "1/degC", "d omega / dT below t_break"),
      real_param("omega_slope_above", "0.0", "1/degC", "d omega / dT above t_break"),
      list_param("g", "[]", "-", "Maxwell weights g_i at t_break (sum <= 1; g_inf = 1 - sum)", -1, 0.0),
      list_param("tau", "[]", "s", "relaxation times tau_i at t_break (> 0)", -1, 0.0),
      list_param("g_slope_below", "[]", "1/degC", "d g_i / dT below t_break (empty: 0)"),
      list_param("g_slope_above", "[]", "1/degC", "d g_i / dT above t_break (empty: 0)"),
      list_param("tau_slope_below", "[]", "s/degC", "d tau_i / dT below t_break (empty: 0)"),
      list_param("tau_slope_above", "[]", "s/degC", "d tau_i / dT above t_break (empty: 0)"),
  };
  d.example = R"({ "law": "viscoelastic_shear", "k_sh": [18.5, 46.4, -21.3], "omega_slope_below": -0.02, "omega_slope_above": -0.01, "g": [0.5, 0.3], "tau": [0.2, 2.0] })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_viscoelastic_shear", "1.3.2", register_all)
