#pragma once
// Invariants of the membrane right Cauchy-Green tensor C for fibre
// families, and their derivatives (physics.md section 2). C and every
// tensor here are 2x2 symmetric in the material frame of the initial
// configuration (axis 1 along L1), Voigt order [11, 22, 12] with the tensor
// shear component (math.hpp).
//
//   I41 = C : L1 (x) L1, I42 = C : L2 (x) L2, I412 = C : sym(L1 (x) L2), I3 = det C
//   I_e1 = 1/2 ln I41, I_e2 = 1/2 ln I42, I_sh = I412 / sqrt(I41 I42),
//   I_lt = 1/2 ln(I3 / I41)
//
// Stress from an energy w(I_k) per unit initial area: S = kStressFactor *
// dw/dC = 2 sum_k w_k'(I_k) dI_k/dC (the paper prints 1/2 dw/dC in Eqs. 7-8;
// 2 is right, checked against finite differences).
#include <array>
#include <cmath>

namespace ts::sdk {

inline constexpr double kStressFactor = 2.0;  // S = 2 dw/dC

using Sym2 = std::array<double, 3>;  // Voigt [11, 22, 12]

// ln y. Near y = 1 (the small elongations of nearly inextensible fibres)
// by the series of ln(1 + x), x = y - 1 (exact for y in [0.5, 2]), to x^8:
// for |x| < 1e-2 the first omitted term is below 2e-17 of the value,
// under the rounding of a double, and no library call is made.
inline double log_near_one(double y) {
  const double x = y - 1.0;
  if (std::abs(x) < 1e-2)
    return x * (1 - x * (1.0 / 2 - x * (1.0 / 3 - x * (1.0 / 4 - x * (1.0 / 5 - x * (1.0 / 6 - x * (1.0 / 7 - x * (1.0 / 8))))))));
  return std::log(y);
}

// Double contraction A : B of two symmetric tensors in Voigt storage.
inline double ddot(const Sym2& a, const Sym2& b) { return a[0] * b[0] + a[1] * b[1] + 2 * a[2] * b[2]; }

struct FibreFrame {
  // L1 = (1, 0) in the material frame; L2 = (c, s) (weft / transverse).
  double c = 0.0, s = 1.0;
  Sym2 l11() const { return {1.0, 0.0, 0.0}; }
  Sym2 l22() const { return {c * c, s * s, c * s}; }
  Sym2 l12sym() const { return {c, 0.0, 0.5 * s}; }  // sym(L1 (x) L2)
};

struct Invariants {
  double i41 = 1, i42 = 1, i412 = 0, i3 = 1;
  double e1 = 0, e2 = 0, sh = 0, lt = 0;     // I_e1, I_e2, I_sh, I_lt
  Sym2 de1{}, de2{}, dsh{}, dlt{};           // dI/dC
};

enum InvariantSet : unsigned { kE1 = 1, kE2 = 2, kSh = 4, kLt = 8, kAll = 15 };

// Computes the invariants asked for in `which` (and I41, I42, I412, I3).
inline Invariants invariants(const Sym2& C, const FibreFrame& f = {}, unsigned which = kAll) {
  Invariants v;
  const Sym2 l11 = f.l11(), l22 = f.l22(), l12 = f.l12sym();
  v.i41 = ddot(C, l11);
  v.i42 = ddot(C, l22);
  v.i412 = ddot(C, l12);
  v.i3 = C[0] * C[1] - C[2] * C[2];
  if (which & kE1) {
    v.e1 = 0.5 * log_near_one(v.i41);
    for (int k = 0; k < 3; ++k) v.de1[k] = l11[k] / (2 * v.i41);
  }
  if (which & kE2) {
    v.e2 = 0.5 * log_near_one(v.i42);
    for (int k = 0; k < 3; ++k) v.de2[k] = l22[k] / (2 * v.i42);
  }
  if (which & kSh) {
    // One division: 1 / r = sqrt(I41 I42) / (I41 I42), 1 / I41 = I42 / (I41 I42).
    const double p = v.i41 * v.i42, inv = 1.0 / p, ir = std::sqrt(p) * inv;
    v.sh = v.i412 * ir;
    for (int k = 0; k < 3; ++k) v.dsh[k] = l12[k] * ir - 0.5 * v.sh * (l11[k] * (v.i42 * inv) + l22[k] * (v.i41 * inv));
  }
  if (which & kLt) {
    v.lt = 0.5 * log_near_one(v.i3 / v.i41);
    const Sym2 cinv = {C[1] / v.i3, C[0] / v.i3, -C[2] / v.i3};  // C^-1 in Voigt storage
    for (int k = 0; k < 3; ++k) v.dlt[k] = 0.5 * (cinv[k] - l11[k] / v.i41);
  }
  return v;
}

// Adds kStressFactor * dw_dI * dI/dC to S.
inline void add_stress(Sym2& S, double dw_dI, const Sym2& dI) {
  for (int k = 0; k < 3; ++k) S[k] += kStressFactor * dw_dI * dI[k];
}

// Polynomial sum_{i=1..n} k_i x^(2i) and its derivative.
inline void even_polynomial(const double* k, int n, double x, double* value, double* derivative) {
  double v = 0, d = 0, x2 = x * x, p = 1;  // p = x^(2(i-1))
  for (int i = 1; i <= n; ++i) {
    d += 2 * i * k[i - 1] * p * x;
    p *= x2;
    v += k[i - 1] * p;
  }
  *value = v;
  *derivative = d;
}

}  // namespace ts::sdk
