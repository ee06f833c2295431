// ud_hyperelastic: w = k_fibre I_e1^2 + p_ct I_lt^2 + sum_i k_sh_i I_sh^(2i),
// with the transverse invariant I_lt = 1/2 ln(I3 / I41), independent of the
// in-plane shear (Bigot et al. 2022). L2 = n x L1. Energy per unit initial
// area (J/m^2), stiffnesses in N/m. A temperature-dependent, viscoelastic
// shear is added by listing `viscoelastic_shear` next to this law.
#include <algorithm>
#include <cmath>
#include <vector>

#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace {

using namespace ts::sdk;

// Per-thread buffers of a block: points to evaluate again, energies when
// the caller wants none; the points of the wide pass (their indices, C,
// S, W, and which of them are beyond its range too).
struct Scratch {
  std::vector<double> redo;  // 0 or 1 (a double: a narrower type would widen the vector loops)
  std::vector<double> energy;
  std::vector<int> idx;
  std::vector<double> wc, ws, ww, wredo;
};
Scratch& scratch(std::size_t n) {
  thread_local Scratch s;
  if (s.redo.size() < n) {
    s.redo.resize(n);
    s.energy.resize(n);
    s.idx.resize(n);
    s.wc.resize(3 * n);
    s.ws.resize(3 * n);
    s.ww.resize(n);
    s.wredo.resize(n);
  }
  return s;
}

// ln(1 + x) by its series to x^8, exact to rounding for |x| < 1e-2 (as
// log_near_one, without the branch).
inline double log1p_series(double x) {
  return x * (1 - x * (1.0 / 2 - x * (1.0 / 3 - x * (1.0 / 4 - x * (1.0 / 5 - x * (1.0 / 6 - x * (1.0 / 7 - x * (1.0 / 8))))))));
}

// The range of log1p_wide: |x| < kWideRange.
constexpr double kWideRange = 0.25;
// ln(1 + f) for |f| < kWideRange, as the library's logarithm does it
// (fdlibm): with s = f / (2 + f), ln(1 + f) = 2 atanh(s) = 2 s + s R,
// R = 2/3 s^2 + 2/5 s^4 + ..., and 2 s = f - s f, so
// ln(1 + f) = f - (f^2 / 2 - s (f^2 / 2 + R)). The exact f leads and the
// rounding of the rest counts at most |f| / 4 as much: within 0.7 units in
// the last place of the exact value over the range (20 million points;
// the library's own: 0.52). R by its series to s^18 (|s| < 1/7: the first
// term left out is below 1e-18 of the result).
inline double log1p_wide(double f) {
  const double s = f / (2.0 + f), z = s * s, hfsq = 0.5 * f * f;
  const double q = 2.0 / 11 + z * (2.0 / 13 + z * (2.0 / 15 + z * (2.0 / 17 + z * (2.0 / 19))));
  const double R = z * (2.0 / 3 + z * (2.0 / 5 + z * (2.0 / 7 + z * (2.0 / 9 + z * q))));
  return f - (hfsq - s * (hfsq + R));
}

// The law at one point, L1 = (1, 0), L2 = (0, 1): I_e1 = 1/2 ln C11,
// I_lt = 1/2 ln(det C / C11), I_sh = C12 / sqrt(C11 C22),
//   S = 2 [2 k_f I_e1 dI_e1/dC + 2 p_ct I_lt dI_lt/dC + w_sh' dI_sh/dC],
//   dI_e1/dC = (1 / 2 C11, 0, 0), dI_lt/dC = 1/2 (C22 / I3 - 1 / C11, C11 / I3, -C12 / I3),
//   dI_sh/dC = (-I_sh / 2 C11, -I_sh / 2 C22, 1 / 2 sqrt(C11 C22)),
// with C^-1 as C22 / I3 = C22 (1 / I3) (one division). The logarithms
// (kLog): kSmall, by log1p_series (vector loops; the result is right where
// C11 - 1 and det C / C11 - 1 are within 1e-2, and *in_range says whether
// they are); kWide, by log1p_wide (within kWideRange, likewise); kLibrary,
// as log_near_one() (the library's beyond 1e-2).
// Without kShear (k_sh all +0) the shear terms are left out: each of them
// is then a zero, -0 in S11 and S22 and in S12 a zero of the sign of C12,
// which the sums below keep (the same bits as with them).
enum LogForm { kLibrary, kSmall, kWide };
template <LogForm kLog, bool kShear = true>
[[gnu::always_inline]] inline void ud_point(const double* __restrict C, double kf, double pct, double k1, double k2,
                                            double k3, double* __restrict S, double* __restrict W, double* in_range) {
  const double a = C[0], b = C[1], c = C[2];
  const double inv_a = 1.0 / a, i3 = a * b - c * c, inv_3 = 1.0 / i3;
  const double xa = a - 1.0, xt = i3 / a - 1.0;  // as the SDK forms I3 / I41
  double e1, lt;
  if (kLog == kSmall) {
    *in_range = (static_cast<int>(std::abs(xa) < 1e-2) & static_cast<int>(std::abs(xt) < 1e-2)) ? 1.0 : 0.0;
    e1 = 0.5 * log1p_series(xa);
    lt = 0.5 * log1p_series(xt);
  } else if (kLog == kWide) {
    *in_range = (static_cast<int>(std::abs(xa) < kWideRange) & static_cast<int>(std::abs(xt) < kWideRange)) ? 1.0 : 0.0;
    e1 = 0.5 * log1p_wide(xa);
    lt = 0.5 * log1p_wide(xt);
  } else {
    e1 = 0.5 * log_near_one(a);
    lt = 0.5 * log_near_one(i3 / a);
  }
  const double fe = 2 * (2 * kf * e1), fl = 2 * (2 * pct * lt);
  if (!kShear) {
    S[0] = fe * (0.5 * inv_a) + fl * (0.5 * (b * inv_3 - inv_a));
    S[1] = fl * (0.5 * (a * inv_3));
    S[2] = fl * (0.5 * (-c * inv_3)) + c * 0.0;
    *W = kf * e1 * e1 + pct * lt * lt + 0.0;  // + w_sh, which is +0
    return;
  }
  const double inv_r = 1.0 / std::sqrt(a * b), sh = c * inv_r, x2 = sh * sh;
  const double wsh = x2 * (k1 + x2 * (k2 + x2 * k3)), dwsh = sh * (2 * k1 + x2 * (4 * k2 + x2 * 6 * k3));
  const double fs = 2 * dwsh;
  S[0] = fe * (0.5 * inv_a) + fl * (0.5 * (b * inv_3 - inv_a)) + fs * (-0.5 * sh * inv_a);
  S[1] = fl * (0.5 * (a * inv_3)) + fs * (-0.5 * sh * (a * inv_r * inv_r));
  S[2] = fl * (0.5 * (-c * inv_3)) + fs * (0.5 * inv_r);
  *W = kf * e1 * e1 + pct * lt * lt + wsh;
}

// The law over n points by the series (kLog kSmall or kWide); redo[q] = 1
// where C11 - 1 or det C / C11 - 1 is beyond the series' range.
// Returns the number of points to evaluate again (a sum, not a maximum:
// Clang vectorises the one and not the other).
template <LogForm kLog, bool kShear>
[[gnu::always_inline]] inline double ud_body(std::size_t n, const double* __restrict C, double kf, double pct,
                                             const double* ksh, double* __restrict S, double* __restrict W,
                                             double* __restrict redo) {
  const double k1 = ksh[0], k2 = ksh[1], k3 = ksh[2];
  double any = 0.0;
#pragma omp simd reduction(+ : any)
  for (std::size_t q = 0; q < n; ++q) {
    double in_range;
    ud_point<kLog, kShear>(C + 3 * q, kf, pct, k1, k2, k3, S + 3 * q, W + q, &in_range);
    redo[q] = 1.0 - in_range;
    any += 1.0 - in_range;
  }
  return any;
}
// The vector passes, by series (kSmall) and for the points beyond its
// range (kWide), with and without the shear terms: kUdBlock[wide][shear].
#define TS_UD_BLOCK(NAME, LOG, SHEAR)                                                                              \
  TS_VECTOR_CLONES double NAME(std::size_t n, const double* C, double kf, double pct, const double* ksh, double* S, \
                               double* W, double* redo) {                                                        \
    return ud_body<LOG, SHEAR>(n, C, kf, pct, ksh, S, W, redo);                                                  \
  }
TS_UD_BLOCK(ud_block, kSmall, true)
TS_UD_BLOCK(ud_block_no_shear, kSmall, false)
TS_UD_BLOCK(ud_block_wide, kWide, true)
TS_UD_BLOCK(ud_block_wide_no_shear, kWide, false)
#undef TS_UD_BLOCK
using UdBlock = double (*)(std::size_t, const double*, double, double, const double*, double*, double*, double*);
constexpr UdBlock kUdBlock[2][2] = {{ud_block_no_shear, ud_block}, {ud_block_wide_no_shear, ud_block_wide}};
// The indices q < n with redo[q] != 0, in order, to idx (branch-free);
// returns their count.
std::size_t redo_points(std::size_t n, const double* __restrict redo, int* __restrict idx) {
  std::size_t m = 0;
  for (std::size_t q = 0; q < n; ++q) {
    idx[m] = static_cast<int>(q);
    m += redo[q] != 0 ? 1 : 0;
  }
  return m;
}

class UdHyperelastic final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&] {
      k_fibre_ = p.real("k_fibre");
      p_ct_ = p.real("p_ct");
      const auto& ks = p.list("k_sh");
      for (int i = 0; i < 3; ++i) k_sh_[i] = ks[i];
      // The shear terms are left out where they are all +0 (see ud_point).
      shear_ = !std::all_of(k_sh_, k_sh_ + 3, [](double k) { return k == 0.0 && !std::signbit(k); });
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  bool uses_strain_old() const override { return false; }
  Status evaluate(const MaterialBlock& b) const override {
    // Vector pass over the block; the points whose logarithms fall outside
    // the series' range (strains beyond about 0.5 %, common across the
    // fibres in forming) are gathered and evaluated again in a second
    // vector pass by log1p_wide, and those beyond its range too one by one
    // with the library's logarithm.
    Scratch& sc = scratch(b.n);
    double* redo = sc.redo.data();
    double* W = b.energy.empty() ? sc.energy.data() : b.energy.data();
    if (kUdBlock[0][shear_](b.n, b.strain.data(), k_fibre_, p_ct_, k_sh_, b.stress.data(), W, redo) == 0.0)
      return Status::success();
    const std::size_t m = redo_points(b.n, redo, sc.idx.data());
    const int* idx = sc.idx.data();
    double *wc = sc.wc.data(), *ws = sc.ws.data(), *ww = sc.ww.data(), *wredo = sc.wredo.data();
    for (std::size_t j = 0; j < m; ++j)
      for (int k = 0; k < 3; ++k) wc[3 * j + k] = b.strain[3 * idx[j] + k];
    const double beyond = kUdBlock[1][shear_](m, wc, k_fibre_, p_ct_, k_sh_, ws, ww, wredo);
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t q = idx[j];
      if (beyond != 0.0 && wredo[j] != 0) {
        // (With k_sh all +0 the full form gives the same bits as the one
        // without shear terms: see ud_point.)
        ud_point<kLibrary>(&b.strain[3 * q], k_fibre_, p_ct_, k_sh_[0], k_sh_[1], k_sh_[2], &b.stress[3 * q], &W[q],
                           nullptr);
        continue;
      }
      for (int k = 0; k < 3; ++k) b.stress[3 * q + k] = ws[3 * j + k];
      W[q] = ww[j];
    }
    return Status::success();
  }
  double max_stiffness(double) const override { return 2 * std::max(k_fibre_, p_ct_); }

 private:
  double k_fibre_ = 0, p_ct_ = 0, k_sh_[3] = {0, 0, 0};
  bool shear_ = false;
};

MaterialLaw* create() { return new UdHyperelastic(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "ud_hyperelastic";
  d.version = "1.1.1";
  d.summary = "UD membrane: fibre elongation, transverse elongation I_lt = 1/2 ln(I3/I41), optional elastic shear";
  const ParamSpec ksh = list_param("k_sh", "[0, 0, 0]", "N/m",
                                   "elastic shear coefficients of w_sh = sum k_sh^i I_sh^(2i) (zero when viscoelastic_shear carries the shear)", 3);
  d.params = {real_param("k_fibre", "", "N/m", "fibre stiffness: w_e1 = k_fibre I_e1^2, I_e1 = 1/2 ln I41", 0.0, 1e15, true),
              real_param("p_ct", "", "N/m", "transverse stiffness: w_lt = p_ct I_lt^2", 0.0, 1e15, true), ksh};
  d.example = R"({ "law": "ud_hyperelastic", "k_fibre": 5.0e6, "p_ct": 50.0 })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_ud_hyperelastic", "1.1.1", register_all)
