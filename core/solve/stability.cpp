#include "solve/stability.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

namespace ts {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Voigt index of the tensor component (a, b): 0 for 11, 1 for 22, 2 for 12 and 21.
constexpr int voigt(int a, int b) { return a == b ? a : 2; }

// The coefficients of Q(n) = c^2 P + s^2 R + c s X (n = (c, s)), each
// 2 x 2 row-major, from F, S and D (see acoustic_minimum).
struct AcousticCoefficients {
  double P[4], R[4], X[4];
};

AcousticCoefficients coefficients(const double F[4], const double S[3], const double D[9]) {
  // CC_MJNL = dS_MJ / dE_NL with the minor symmetries: a column of D for a
  // shear strain moves E12 and E21 together, so each of them takes half.
  auto cc = [&](int M, int J, int N, int L) { return D[3 * voigt(M, J) + voigt(N, L)] * (N != L ? 0.5 : 1.0); };
  auto s = [&](int J, int L) { return S[voigt(J, L)]; };
  auto a = [&](int i, int J, int k, int L) {
    double v = i == k ? s(J, L) : 0.0;
    for (int M = 0; M < 2; ++M)
      for (int N = 0; N < 2; ++N) v += F[2 * i + M] * F[2 * k + N] * cc(M, J, N, L);
    return v;
  };
  AcousticCoefficients c{};
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k) {
      c.P[2 * i + k] = a(i, 0, k, 0);
      c.R[2 * i + k] = a(i, 1, k, 1);
      c.X[2 * i + k] = a(i, 0, k, 1) + a(i, 1, k, 0);
    }
  return c;
}

void tensor_at(const AcousticCoefficients& c, double theta, double Q[3]) {
  const double cs = std::cos(theta), sn = std::sin(theta);
  double q[4];
  for (int r = 0; r < 4; ++r) q[r] = cs * cs * c.P[r] + sn * sn * c.R[r] + cs * sn * c.X[r];
  Q[0] = q[0];
  Q[1] = q[3];
  Q[2] = 0.5 * (q[1] + q[2]);  // the quadratic form sees the symmetric part only
}

// The smallest eigenvalue of Q as a function of phi = 2 theta:
//   f = m - sqrt(d^2 + o^2), m = (Q11 + Q22) / 2, d = (Q11 - Q22) / 2, o = Q12,
// each of m, d, o of the form v0 + v1 cos phi + v2 sin phi.
struct EigenCurve {
  double m[3], d[3], o[3];
  explicit EigenCurve(const AcousticCoefficients& c) {
    // c^2 = (1 + cos phi) / 2, s^2 = (1 - cos phi) / 2, c s = sin phi / 2.
    auto entry = [&](int r, double v[3]) {
      v[0] = 0.5 * (c.P[r] + c.R[r]);
      v[1] = 0.5 * (c.P[r] - c.R[r]);
      v[2] = 0.5 * c.X[r];
    };
    double q11[3], q22[3], q12[3], q21[3];
    entry(0, q11);
    entry(3, q22);
    entry(1, q12);
    entry(2, q21);
    for (int k = 0; k < 3; ++k) {
      m[k] = 0.5 * (q11[k] + q22[k]);
      d[k] = 0.5 * (q11[k] - q22[k]);
      o[k] = 0.5 * (q12[k] + q21[k]);
    }
  }
  double at(double cs, double sn) const {
    const double mv = m[0] + m[1] * cs + m[2] * sn, dv = d[0] + d[1] * cs + d[2] * sn, ov = o[0] + o[1] * cs + o[2] * sn;
    return mv - std::sqrt(dv * dv + ov * ov);
  }
  // f, f' and f'' at phi.
  void derivatives(double phi, double& f, double& f1, double& f2) const {
    const double cs = std::cos(phi), sn = std::sin(phi);
    auto val = [&](const double v[3], double& v0, double& v1, double& v2) {
      v0 = v[0] + v[1] * cs + v[2] * sn;
      v1 = -v[1] * sn + v[2] * cs;
      v2 = -v[1] * cs - v[2] * sn;
    };
    double m0, m1, m2, d0, d1, d2, o0, o1, o2;
    val(m, m0, m1, m2);
    val(d, d0, d1, d2);
    val(o, o0, o1, o2);
    const double r = std::sqrt(d0 * d0 + o0 * o0);
    f = m0 - r;
    if (!(r > 0)) {  // a double eigenvalue: no slope of the root to follow
      f1 = m1;
      f2 = m2;
      return;
    }
    const double g = d0 * d1 + o0 * o1;
    f1 = m1 - g / r;
    f2 = m2 - ((d1 * d1 + d0 * d2 + o1 * o1 + o0 * o2) / r - g * g / (r * r * r));
  }
};

// cos and sin of phi_j = 2 pi j / kPhiSamples.
constexpr int kPhiSamples = 36;
struct PhiTable {
  double c[kPhiSamples], s[kPhiSamples];
  PhiTable() {
    for (int j = 0; j < kPhiSamples; ++j) {
      c[j] = std::cos(2 * kPi * j / kPhiSamples);
      s[j] = std::sin(2 * kPi * j / kPhiSamples);
    }
  }
};
const PhiTable& phi_table() {
  static const PhiTable t;
  return t;
}

}  // namespace

void stretch_of(const double C[3], double U[4]) {
  // For a 2 x 2 symmetric positive definite C: sqrt(C) = (C + sqrt(det C) I) / sqrt(tr C + 2 sqrt(det C)).
  const double r = std::sqrt(C[0] * C[1] - C[2] * C[2]);
  const double k = 1.0 / std::sqrt(C[0] + C[1] + 2 * r);
  U[0] = (C[0] + r) * k;
  U[1] = C[2] * k;
  U[2] = C[2] * k;
  U[3] = (C[1] + r) * k;
}

void acoustic_tensor(const double F[4], const double S[3], const double D[9], double theta, double Q[3]) {
  tensor_at(coefficients(F, S, D), theta, Q);
}

double acoustic_minimum(const double F[4], const double S[3], const double D[9], double* theta_min) {
  const EigenCurve curve(coefficients(F, S, D));
  // Sampled every 5 degrees of theta (phi = 2 theta every 10), then Newton's
  // method on the best sample's neighbourhood (f is smooth there; a step that
  // would leave it, or does not lower f, ends the search).
  const PhiTable& tab = phi_table();
  constexpr double h = 2 * kPi / kPhiSamples;
  double best = std::numeric_limits<double>::infinity();
  int jb = -1;
  for (int j = 0; j < kPhiSamples; ++j) {
    const double v = curve.at(tab.c[j], tab.s[j]);
    if (v < best) {
      best = v;
      jb = j;
    }
  }
  if (jb < 0) {
    if (theta_min) *theta_min = std::numeric_limits<double>::quiet_NaN();
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double phi0 = jb * h;
  double phi = phi0, f, f1, f2;
  curve.derivatives(phi, f, f1, f2);
  for (int it = 0; it < 8 && f2 > 0; ++it) {
    const double next = phi - f1 / f2;
    if (!(std::abs(next - phi0) <= h)) break;
    double g, g1, g2;
    curve.derivatives(next, g, g1, g2);
    if (!(g <= best)) break;
    best = g;
    const bool done = std::abs(next - phi) < 1e-12;
    phi = next;
    f1 = g1;
    f2 = g2;
    if (done) break;
  }
  if (theta_min) {
    const double theta = 0.5 * phi;
    *theta_min = theta - kPi * std::floor(theta / kPi);
  }
  return best;
}

std::string long_term_stability(std::span<const sdk::MaterialLaw* const> laws, std::size_t n, const double* C,
                                const double* T, double* q, StabilityScratch& s, double* theta, double* response) {
  constexpr int kVariants = 7;  // C, then C + 2h e_k and C - 2h e_k for k = 0, 1, 2
  const std::size_t m = kVariants * n;
  s.strain.resize(3 * m);
  s.temperature.resize(m);
  s.stress.resize(3 * m);
  s.sum.assign(3 * m, 0.0);
  const double h = kStabilityStrainStep;
  // Point p's variants are entries 7 p .. 7 p + 6, so that a run of points
  // at one temperature is one block at one temperature (a law may then
  // evaluate its temperature-dependent parameters once for the block).
  for (std::size_t p = 0; p < n; ++p)
    for (int v = 0; v < kVariants; ++v) {
      double* c = &s.strain[3 * (kVariants * p + v)];
      for (int k = 0; k < 3; ++k) c[k] = C[3 * p + k];
      if (v > 0) c[(v - 1) / 2] += (v % 2 ? 2 * h : -2 * h);  // dC = 2 dE
      s.temperature[kVariants * p + v] = T[p];
    }
  for (const sdk::MaterialLaw* law : laws) {
    const std::size_t ns = static_cast<std::size_t>(law->state_size());
    s.state.assign(ns * m, 0.0);
    for (std::size_t p0 = 0; p0 < n;) {
      std::size_t p1 = p0 + 1;
      while (p1 < n && T[p1] == T[p0]) ++p1;
      const std::size_t a = kVariants * p0, len = kVariants * (p1 - p0);
      sdk::MaterialBlock b;
      b.n = len;
      b.strain = std::span<const double>(&s.strain[3 * a], 3 * len);
      if (law->uses_strain_old()) b.strain_old = b.strain;
      b.temperature = std::span<const double>(&s.temperature[a], len);
      b.dt = kLongTermDt;
      b.state = std::span<double>(s.state.data() + ns * a, ns * len);  // empty for a law without history
      b.stress = std::span<double>(&s.stress[3 * a], 3 * len);
      // Called from the threads of ply_stability: nothing may escape.
      try {
        if (auto st = law->evaluate(b); !st) return st.message;
      } catch (const std::exception& e) {
        return e.what();
      } catch (...) {
        return "unknown error inside the law";
      }
      p0 = p1;
    }
    for (std::size_t k = 0; k < 3 * m; ++k) s.sum[k] += s.stress[k];
  }
  for (std::size_t p = 0; p < n; ++p) {
    const double* c = &C[3 * p];
    if (!(c[0] > 0 && c[0] * c[1] - c[2] * c[2] > 0)) {
      q[p] = std::numeric_limits<double>::quiet_NaN();
      if (theta) theta[p] = q[p];
      continue;
    }
    double D[9];
    for (int k = 0; k < 3; ++k) {
      const double* plus = &s.sum[3 * (kVariants * p + 1 + 2 * k)];
      const double* minus = &s.sum[3 * (kVariants * p + 2 + 2 * k)];
      for (int v = 0; v < 3; ++v) D[3 * v + k] = (plus[v] - minus[v]) / (2 * h);
    }
    if (response) {
      std::copy(&s.sum[3 * kVariants * p], &s.sum[3 * kVariants * p] + 3, response + 12 * p);
      std::copy(D, D + 9, response + 12 * p + 3);
    }
    double F[4];
    stretch_of(c, F);
    q[p] = acoustic_minimum(F, &s.sum[3 * kVariants * p], D, theta ? &theta[p] : nullptr);
  }
  return {};
}

double stability_tolerance(std::span<const sdk::MaterialLaw* const> laws, double T) {
  double k = 0;
  for (const sdk::MaterialLaw* law : laws) k += law->max_stiffness(T);
  return 1e-9 * k;
}

std::string ply_stability(std::span<const sdk::MaterialLaw* const> laws, std::span<const int> triangles,
                          std::span<const double> node_temperature, std::span<const double> strain,
                          std::vector<double>& q, std::vector<double>& tolerance, std::vector<double>* theta) {
  const int ne = static_cast<int>(triangles.size() / 3);
  q.assign(static_cast<std::size_t>(ne), std::numeric_limits<double>::quiet_NaN());
  if (theta) theta->assign(static_cast<std::size_t>(ne), std::numeric_limits<double>::quiet_NaN());
  tolerance.assign(static_cast<std::size_t>(ne), 0.0);
  constexpr int kBlock = 256;
  const int blocks = (ne + kBlock - 1) / kBlock;
  std::vector<std::string> errors(static_cast<std::size_t>(blocks));
#pragma omp parallel
  {
    StabilityScratch s;
    std::vector<double> C(3 * kBlock), T(kBlock);
#pragma omp for schedule(dynamic)
    for (int b = 0; b < blocks; ++b) {
      const int e0 = b * kBlock, n = std::min(kBlock, ne - e0);
      for (int i = 0; i < n; ++i) {
        const int e = e0 + i;
        const double* E = &strain[3 * static_cast<std::size_t>(e)];
        C[3 * i] = 1 + 2 * E[0];
        C[3 * i + 1] = 1 + 2 * E[1];
        C[3 * i + 2] = 2 * E[2];
        // The element's temperature as shell elements form it: the mean of its nodes'.
        const int* t = &triangles[3 * static_cast<std::size_t>(e)];
        T[i] = node_temperature[t[0]] / 3.0 + node_temperature[t[1]] / 3.0 + node_temperature[t[2]] / 3.0;
        tolerance[e] = stability_tolerance(laws, T[i]);
      }
      errors[b] = long_term_stability(laws, static_cast<std::size_t>(n), C.data(), T.data(), &q[e0], s,
                                      theta ? theta->data() + e0 : nullptr);
    }
  }
  for (const auto& e : errors)
    if (!e.empty()) return e;
  return {};
}

}  // namespace ts
