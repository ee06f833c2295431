// shell_rf_t3: three-node shell triangle, translational dofs only
// (physics.md section 1). Membrane: total-Lagrangian constant-strain
// triangle; F = sum_a x_a (x) grad0 N_a maps the material frame of the
// initial element (axis 1 along the initial fibre direction, axis 2 =
// N x axis 1) to the current configuration, C = F^T F, the laws return S
// (N/m) and the nodal forces are f_a = A0 F S grad0 N_a (f = A0 B^T S).
//
// Bending, rotation-free (S3/BST family, 6-node patch), with the curvature
// of Morley's constant-curvature triangle: the mean curvature of an element
// is the boundary integral of the slopes at its mid-edges,
//   K = (1 / A0) sum_k l_k s_k nu_k (x) nu_k,
// s_k the outward normal slope at the middle of edge k relative to the
// element's plane, l_k and nu_k the length and in-plane outward normal of
// the edge in the initial configuration, K in the element's material
// frame. The slopes come from the bending angles theta (between the element
// and its neighbour across an edge, minus their initial values; positive
// when the surface turns towards the element's normal):
// - each element with three neighbours (or held edges) has the quadratic
//   through the six nodes of its patch; its slopes at the element's own
//   mid-edges are r = L theta_e, L a 3 x 3 map fixed at set-up (in the
//   initial configuration, the neighbours unfolded into the element's plane);
// - the slope of an interior edge is shared by its two elements:
//   s = omega r + (1 - omega) (theta - r'), r' the neighbour's slope of the
//   same edge, omega = 1/2, or 1 / 0 where only one of them has a quadratic
//   (1/2 with r = r' = 0 where neither has one: s = theta / 2). So the two
//   slopes add up to the angle between the elements, as in Morley's element
//   (the shared mid-edge slope makes the element converge), and a field of
//   constant curvature is exact on any mesh;
// - at a clamped edge the slope is the rotation of the element about the
//   edge from its initial orientation (the angle to a mirrored ghost is
//   twice that), at a symmetry edge half the angle to the element mirrored
//   in the symmetry plane; at a free edge the slope that makes the normal
//   moment zero (with the law's rigidities at the part's initial
//   temperature), folded into the coefficients of the other edges.
// The law returns the moments M (N m/m) and the energy w; the forces are
// the derivatives of sum A0 w through d theta / dx on the four nodes of each
// hinge, which splits into one part per element of the hinge along that
// element's normal (membrane_body). An element's curvature reads its
// neighbours' angles, so a step takes four passes over the blocks: angles
// and own slopes; slopes, curvatures, moments and dW/ds; each element's
// share of dW/dtheta of its hinges (which reads the neighbours' dW/ds);
// membrane and bending forces (which read the neighbours' shares).
//
// In-plane bending of the fibres (optional, ElementSetup::in_plane_bending):
// the same Morley curvature, of the displacement across the fibres in the
// ply's plane. Across edge k of element e the slope jump is
// phi_k = m . (F_j - F_e) nu_k (F in 3D over the initial plane, nu_k the
// edge's outward normal, m = n x f across the current fibre f = F a0 /
// |F a0|, n the element's normal), from the element's three nodes and the
// neighbour's fourth; the mid-edge slopes s = omega r + (1 - omega)
// (phi - r') with r = L phi the slopes of the element's own quadratic (the
// quadratic through its patch's six nodes), as for the bending; the
// fibres' in-plane curvature is K11 = (1 / A0) sum_k l_k s_k (nu_k . a0)^2,
// exact for any quadratic field. The law gets chi = (K11, 0, 0); its M11
// and w give dW/ds_k = A0 M11 l_k (nu_k . a0)^2 / A0 and the energy A0 w,
// and the forces follow through the same four passes as the bending, at
// every evaluation (whatever the bending weight: an impulse every few
// steps on the in-plane motion, which the membrane already holds at its
// stable step, is not stable). Boundary edges: on a symmetry plane the
// neighbour is the element mirrored in the plane (J = -(I + P) F_e nu,
// P the mirror) and s = phi / 2, the fibre's angle to the plane's normal;
// at a clamped edge it is the held grip (F = I: J = nu - F_e nu) and
// s = phi, the fibre's rotation from its initial direction. A free edge
// has a free mid-edge slope, and the energy's minimum over it is K11 = 0
// unless the edge runs along the fibres: such elements carry no term (the
// fibres' free ends take no moment).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <vector>

#include <unistd.h>

#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/memory.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace {

using namespace ts::sdk;

// Leading dimension of a structure of arrays with n entries per array: a
// whole number of cache lines with an odd line count, so that the arrays
// of one entry fall in different cache sets (n a multiple of 512 would put
// all of them in one set, and their loads behind each other's stores).
inline int padded_ld(int n) {
  int ld = (n + 7) / 8 * 8;
  if ((ld / 8) % 2 == 0) ld += 8;
  return ld;
}

// Per-thread buffers for the values of one block of elements (indexed from
// the block's first element); they grow to the largest block once.
struct BlockScratch {
  // stress and curv: the stresses and curvatures of a step after which the
  // kernel writes no fields (ElementForceInput::fields_due).
  std::vector<double> strain, ff, mf, mb, bslots, law_stress, energy_tmp, energy, moment, benergy, stress, curv;
  // The angle changes of the block's hinges in pass 0 (ShellRfT3::block_angles).
  std::vector<double> dth;
};

BlockScratch& block_scratch(int n) {
  thread_local BlockScratch s;
  const std::size_t m = static_cast<std::size_t>(n), ld = static_cast<std::size_t>(padded_ld(n));
  if (s.energy.size() < m || s.ff.size() < 6 * ld) {
    s.strain.resize(3 * m);
    s.ff.resize(6 * ld);
    s.mf.resize(9 * ld);
    s.mb.resize(9 * ld);
    s.law_stress.resize(3 * m);
    s.stress.resize(3 * m);
    s.curv.resize(3 * m);
    s.dth.resize(3 * m);
    s.energy_tmp.resize(m);
    s.energy.resize(m);
    s.moment.resize(3 * m);
    s.benergy.resize(m);
  }
  return s;
}

// What one block keeps between the passes of a step (see
// ShellRfT3::block_angles): per ghost hinge of the block (clamped and
// symmetry edges, in the order of ShellRfT3::gstart_), its gradient on
// (c, p, q) (ghost_grad, 12 values each); per element and edge, the ghost
// hinges' dW/dtheta (ghost_m, from pass 2).
struct BlockAngles {
  std::vector<double> ghost_grad, ghost_m;
  double bending_energy = 0;  // sum of A0 w over the block's elements (pass 1, for pass 3)
  // Time stepped since the block's last evaluation with bending, before this
  // evaluation's step (ElementForceInput::bending_weight 0 in between): the
  // bending law's history step is in.dt plus it.
  double elapsed = 0;
  // Where one evaluation carries the bending of several steps
  // (ElementForceInput::bending_weight > 1): the held part h of the
  // bending's nodal forces, xyz of the block's node slot i (as
  // ElementForceOutput::node_force numbers them) at 3 i .. 3 i + 2,
  // applied at every step; empty until the first such evaluation (see
  // ShellRfT3::hold_bending).
  std::vector<double> held;
};

// The size of the processor's per-core (level 2) cache, bytes: the
// environment's THERMOSTAMP_CACHE_BYTES where set, otherwise what the system
// says, 1 MB where it does not.
std::size_t level2_cache_bytes() {
  if (const char* s = std::getenv("THERMOSTAMP_CACHE_BYTES")) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end != s && v >= 0 && v < 1e18) return static_cast<std::size_t>(v);
  }
  const long v = sysconf(_SC_LEVEL2_CACHE_SIZE);
  return v > 0 ? static_cast<std::size_t>(v) : std::size_t{1} << 20;
}

// The geometry of hinge (c, p, q, o) at positions x (offsets 3 x node),
// the operations of ShellRfT3::hinge_angle (sub, dot, cross of math.hpp) in
// their order: the edge e = q - p, c - p, o - p and the unnormalised normals
// Ne = e x (c - p), Nn = (o - p) x e.
struct HingeGeometry {
  double e0, e1, e2, l2, len, c0, c1, c2, o0, o1, o2, ne0, ne1, ne2, nn0, nn1, nn2;
};
[[gnu::always_inline]] inline HingeGeometry hinge_geometry(const double* __restrict x, int c, int p, int q, int o) {
  HingeGeometry g;
  const double P0 = x[p], P1 = x[p + 1], P2 = x[p + 2];
  g.e0 = x[q] - P0, g.e1 = x[q + 1] - P1, g.e2 = x[q + 2] - P2;
  g.l2 = g.e0 * g.e0 + g.e1 * g.e1 + g.e2 * g.e2, g.len = std::sqrt(g.l2);
  g.c0 = x[c] - P0, g.c1 = x[c + 1] - P1, g.c2 = x[c + 2] - P2;
  g.o0 = x[o] - P0, g.o1 = x[o + 1] - P1, g.o2 = x[o + 2] - P2;
  g.ne0 = g.e1 * g.c2 - g.e2 * g.c1, g.ne1 = g.e2 * g.c0 - g.e0 * g.c2, g.ne2 = g.e0 * g.c1 - g.e1 * g.c0;  // edge x cp
  g.nn0 = g.o1 * g.e2 - g.o2 * g.e1, g.nn1 = g.o2 * g.e0 - g.o0 * g.e2, g.nn2 = g.o0 * g.e1 - g.o1 * g.e0;  // op x edge
  return g;
}

// Bending angles (minus their initial values theta0) of h hinges, as
// ShellRfT3::hinge_angle with the same operations in the same order. Hinge
// j has its nodes (c, p, q, o) at x[ic[j]], x[ip[j]], ... (offsets 3 x
// node). Where the angle is beyond atan2_small's range, dtheta[j] is NaN
// (the caller evaluates it with the library); returns how many are (a
// sum rather than a maximum: Clang vectorises the one, not the other).
TS_VECTOR_CLONES
double hinge_angle_block(int h, const int* __restrict ic, const int* __restrict ip, const int* __restrict iq,
                         const int* __restrict io, const double* __restrict x, const double* __restrict theta0,
                         double* __restrict dtheta) {
  double beyond = 0.0;
#pragma omp simd reduction(+ : beyond)
  for (int j = 0; j < h; ++j) {
    const HingeGeometry g = hinge_geometry(x, ic[j], ip[j], iq[j], io[j]);
    const double y = g.len * (g.o0 * g.ne0 + g.o1 * g.ne1 + g.o2 * g.ne2),
                 xx = g.ne0 * g.nn0 + g.ne1 * g.nn1 + g.ne2 * g.nn2;
    const double d = atan2_small_approx(y, xx) - theta0[j];
    const bool in_range = (xx > 0) & (std::abs(y) <= 0.66 * xx);
    dtheta[j] = in_range ? d : std::numeric_limits<double>::quiet_NaN();
    beyond += in_range ? 0.0 : 1.0;
  }
  return beyond;
}
// Indices kept in 16 bits are widened into int in pieces of kWidenPiece
// before a vector pass reads them: the compiler's vector code loads
// through int indices as cheaply as ever, through 16-bit ones with extra
// shuffles.
inline constexpr int kWidenPiece = 256;
TS_VECTOR_CLONES
void widen(int n, const std::uint16_t* __restrict a, int* __restrict b) {
#pragma omp simd
  for (int j = 0; j < n; ++j) b[j] = a[j];
}
// Rows r < rows of 16-bit values (row r at src + r stride), entries j ..
// j + m - 1, into w (row r at w + r kWidenPiece).
void widen_rows(int rows, const std::uint16_t* src, int stride, int j, int m, int* w) {
  for (int r = 0; r < rows; ++r) widen(m, src + static_cast<std::size_t>(r) * stride + j, w + r * kWidenPiece);
}
// hinge_angle_block with 16-bit node offsets (from x, which points at the
// offset they are relative to): row r of h16 (c, p, q, o) at h16 + r h.
double hinge_angle_block16(int h, const std::uint16_t* h16, const double* x, const double* theta0, double* dtheta) {
  alignas(64) int w[4 * kWidenPiece];
  double beyond = 0.0;
  for (int j = 0; j < h; j += kWidenPiece) {
    const int m = std::min(kWidenPiece, h - j);
    widen_rows(4, h16, h, j, m, w);
    beyond = std::max(beyond, hinge_angle_block(m, w, w + kWidenPiece, w + 2 * kWidenPiece, w + 3 * kWidenPiece, x,
                                                theta0 + j, dtheta + j));
  }
  return beyond;
}

typedef double V4d __attribute__((vector_size(32)));

// Sum of a[q] b[q] over q < n (b null: of a[q]) in four lanes, value q in
// lane q mod 4, the lanes added as (l0 + l1) + (l2 + l3): a fixed order
// (the same for any thread count), and four independent chains of
// additions instead of one.
TS_VECTOR_CLONES
double lane_dot(int n, const double* __restrict a, const double* __restrict b) {
  V4d s = {0.0, 0.0, 0.0, 0.0};
  int q = 0;
  for (; q + 4 <= n; q += 4) {
    V4d av, bv = {1.0, 1.0, 1.0, 1.0};
    __builtin_memcpy(&av, a + q, sizeof av);
    if (b) __builtin_memcpy(&bv, b + q, sizeof bv);
    s += av * bv;
  }
  for (int l = 0; q < n; ++q, ++l) s[l] += a[q] * (b ? b[q] : 1.0);
  return (s[0] + s[1]) + (s[2] + s[3]);
}

// The smallest of lo and the steps dte[q] (times scale[q] where scale is
// not null) over q < n.
TS_VECTOR_CLONES
double smallest_step(int n, const double* __restrict dte, const double* __restrict scale, double lo) {
  if (scale) {
#pragma omp simd reduction(min : lo)
    for (int q = 0; q < n; ++q) {
      const double v = dte[q] * scale[q];
      lo = v < lo ? v : lo;
    }
  } else {
#pragma omp simd reduction(min : lo)
    for (int q = 0; q < n; ++q) lo = dte[q] < lo ? dte[q] : lo;
  }
  return lo;
}

// The bending steps d2[q] c of n elements: lowers dte[q] to them and
// returns the smallest of them times scale[q] (where scale is not null).
TS_VECTOR_CLONES
double bending_steps(int n, const double* __restrict d2, double c, const double* __restrict scale,
                     double* __restrict dte) {
  double lo = std::numeric_limits<double>::infinity();
  if (scale) {
#pragma omp simd reduction(min : lo)
    for (int q = 0; q < n; ++q) {
      const double dtb = d2[q] * c, v = dtb * scale[q];
      lo = v < lo ? v : lo;
      dte[q] = dtb < dte[q] ? dtb : dte[q];
    }
  } else {
#pragma omp simd reduction(min : lo)
    for (int q = 0; q < n; ++q) {
      const double dtb = d2[q] * c;
      lo = dtb < lo ? dtb : lo;
      dte[q] = dtb < dte[q] ? dtb : dte[q];
    }
  }
  return lo;
}

// a[q] += b[q] for q < n.
TS_VECTOR_CLONES
void add_into(int n, double* __restrict a, const double* __restrict b) {
#pragma omp simd
  for (int q = 0; q < n; ++q) a[q] += b[q];
}

// Lowers lo and raises hi to the smallest and largest of v[0, n).
TS_VECTOR_CLONES
void value_range(int n, const double* __restrict v, double& lo, double& hi) {
  double a = lo, b = hi;
#pragma omp simd reduction(min : a) reduction(max : b)
  for (int q = 0; q < n; ++q) {
    a = v[q] < a ? v[q] : a;
    b = v[q] > b ? v[q] : b;
  }
  lo = a;
  hi = b;
}

// Strains of n elements: F e1 = sum_a x_a g1_a and F e2 = sum_a x_a g2_a,
// formed as F e1 = (x_1 - x_0) g1_1 + (x_2 - x_0) g1_2 (the three corners'
// gradients sum to zero: g_0 = -(g_1 + g_2)), so that the terms are of the
// element's size whatever the distance of the part from the origin
// (component d of element q at ff[d ld + q] and ff[(3 + d) ld + q];
// g1_1, g1_2, g2_1, g2_2 of element q at g[r gld + q], r = 0 .. 3, the
// offset 3 i of its node a in x at off[a ols + q]) and
// C = (F e1 . F e1, F e2 . F e2, F e1 . F e2) at C[3 q ..]. Returns the
// number of elements whose det C is <= 1e-12 or not a number (collapsed
// or inverted). One vector pass; fields() forms F the same way.
TS_VECTOR_CLONES
double strain_block(int n, int ld, const int* __restrict off, int ols, const double* __restrict x,
                    const double* __restrict g, int gld, double* __restrict ff, double* __restrict C) {
  double bad = 0.0;
#pragma omp simd reduction(+ : bad)
  for (int q = 0; q < n; ++q) {
    const int i0 = off[q], i1 = off[ols + q], i2 = off[2 * ols + q];
    const double gb = g[q], gc = g[gld + q], hb = g[2 * gld + q], hc = g[3 * gld + q];
    const double x0 = x[i0], x1 = x[i0 + 1], x2 = x[i0 + 2];
    const double y0 = x[i1] - x0, y1 = x[i1 + 1] - x1, y2 = x[i1 + 2] - x2;
    const double z0 = x[i2] - x0, z1 = x[i2 + 1] - x1, z2 = x[i2 + 2] - x2;
    const double f10 = y0 * gb + z0 * gc, f11 = y1 * gb + z1 * gc, f12 = y2 * gb + z2 * gc;
    const double f20 = y0 * hb + z0 * hc, f21 = y1 * hb + z1 * hc, f22 = y2 * hb + z2 * hc;
    ff[q] = f10, ff[ld + q] = f11, ff[2 * ld + q] = f12;
    ff[3 * ld + q] = f20, ff[4 * ld + q] = f21, ff[5 * ld + q] = f22;
    const double c0 = f10 * f10 + f11 * f11 + f12 * f12;
    const double c1 = f20 * f20 + f21 * f21 + f22 * f22;
    const double c2 = f10 * f20 + f11 * f21 + f12 * f22;
    C[3 * q] = c0;
    C[3 * q + 1] = c1;
    C[3 * q + 2] = c2;
    const double det = c0 * c1 - c2 * c2;
    bad += det > 1e-12 ? 0.0 : 1.0;
  }
  return bad;
}

// The mean of the nodes' temperatures of element q (tri: its block's
// triangles).
[[gnu::always_inline]] inline double mean_temperature(const int* __restrict tri, const double* __restrict node_temp,
                                                      int q) {
  return node_temp[tri[3 * q]] / 3.0 + node_temp[tri[3 * q + 1]] / 3.0 + node_temp[tri[3 * q + 2]] / 3.0;
}
// The mean of the nodes' temperatures of n elements.
TS_VECTOR_CLONES
void element_temperature_block(int n, const int* __restrict tri, const double* __restrict node_temp,
                               double* __restrict temp) {
#pragma omp simd
  for (int q = 0; q < n; ++q) temp[q] = mean_temperature(tri, node_temp, q);
}

// Membrane forces of n elements (F e1, F e2 of element q at ff[d ld + q],
// ff[(3 + d) ld + q]), f_a = A0 (c1 F e1 + c2 F e2) with c1 = S11 g1_a +
// S12 g2_a, c2 = S12 g1_a + S22 g2_a (component d of node a of element q
// at mf[(3 a + d) ld + q]; g1_a, g2_a of corners 1 and 2 as strain_block
// reads them, those of corner 0 minus their sums), and
// each element's stable step: smallest height
// (2 area / longest edge) times inv_c (infinite when has_stiffness is
// false). The height comes from C (C[3 q ..], Voigt): the current edge
// opposite node a is F E_a with E_a = 2 A0 (g2_a, -g1_a) in the element's
// material frame, so |F E_a|^2 = 4 A0^2 Q_a with Q_a = C11 g2_a^2 -
// 2 C12 g1_a g2_a + C22 g1_a^2, the area is A0 sqrt(det C), and the
// height is sqrt(det C / max_a Q_a). One vector pass without gathers.
//
// With kBend, the bending forces of the element's side of its hinges are
// added: edge k (opposite corner k, from corner k + 1 = p to k + 2 = q)
// with dW/dtheta m_k = hm[k hld + q] + hm_all[nidx[k nld + q]] (the two
// elements' shares; zero where the edge has no neighbour). The gradient of
// the hinge angle on the element's corners is along its normal n:
// n / h on corner k (h its height over the edge) and -(1 - s) n / h, -s n / h
// on p and q (s the position of corner k's foot along the edge from p, over
// the edge's length); the neighbour adds its side likewise. In terms of C:
// h = sqrt(det C / Q_k), s = -P_k / Q_k with P_k = (R g_(k+2))^T C (R g_k),
// R g = (g2, -g1), and n = N / sqrt(det C) with N = F e1 x F e2, so the
// forces on corners k, k + 2 and k + 1 are m_k sqrt(Q_k) N / det C,
// m_k P_k N / (sqrt(Q_k) det C) and minus their sum.
//
// With kSteps the elements' steps go to dte[q] and the result is infinite;
// without, nothing is written to dte and the result is the smallest step,
// taken from the smallest det C / max_a Q_a (the square root and the
// product with inv_c, rounding included, keep the order: the same bits as
// the smallest of the elements' steps, with one square root per block).
template <bool kBend, bool kSteps, bool kSplit = false>
[[gnu::always_inline]] inline double membrane_body(int n, int ld, const double* __restrict C,
                                                   const double* __restrict ff, const double* __restrict S,
                                                   const double* __restrict area, const double* __restrict g, int gld,
                                                   double cmul, const double* __restrict hm,
                                                   const int* __restrict nidx, int nld,
                                                   const double* __restrict hm_all, int hld, double* __restrict mf,
                                                   double* __restrict dte, double* __restrict mb = nullptr) {
  double rmin = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : rmin)
  for (int q = 0; q < n; ++q) {
    const double f10 = ff[q], f11 = ff[ld + q], f12 = ff[2 * ld + q];
    const double f20 = ff[3 * ld + q], f21 = ff[4 * ld + q], f22 = ff[5 * ld + q];
    const double S11 = S[3 * q], S22 = S[3 * q + 1], S12 = S[3 * q + 2], A0 = area[q];
    const double C11 = C[3 * q], C22 = C[3 * q + 1], C12 = C[3 * q + 2];
    const double a1 = g[q], a2 = g[gld + q], b1 = g[2 * gld + q], b2 = g[3 * gld + q];
    const double a0 = -(a1 + a2), b0 = -(b1 + b2);
    const double Q0 = C11 * b0 * b0 - 2 * C12 * a0 * b0 + C22 * a0 * a0;
    const double Q1 = C11 * b1 * b1 - 2 * C12 * a1 * b1 + C22 * a1 * a1;
    const double Q2 = C11 * b2 * b2 - 2 * C12 * a2 * b2 + C22 * a2 * a2;
    const double detc = C11 * C22 - C12 * C12;
    double w1 = 0, w2 = 0;  // the bending forces on corners 1 and 2 along N (corner 0: minus their sum)
    if (kBend) {
      const double m0 = hm[q] + hm_all[nidx[q]], m1 = hm[hld + q] + hm_all[nidx[nld + q]],
                   m2 = hm[2 * hld + q] + hm_all[nidx[2 * nld + q]];
      // P_k = (R g_(k+2))^T C (R g_k), R g = (g2, -g1)
      const double P0 = C11 * b2 * b0 - C12 * (b2 * a0 + a2 * b0) + C22 * a2 * a0;
      const double P1 = C11 * b0 * b1 - C12 * (b0 * a1 + a0 * b1) + C22 * a0 * a1;
      const double P2 = C11 * b1 * b2 - C12 * (b1 * a2 + a1 * b2) + C22 * a1 * a2;
      // t_k = m_k / (sqrt(Q_k) det C), with one division
      const double r0 = std::sqrt(Q0), r1 = std::sqrt(Q1), r2 = std::sqrt(Q2);
      const double id = 1.0 / (detc * (r0 * r1 * r2));
      const double t0 = m0 * (id * (r1 * r2)), t1 = m1 * (id * (r0 * r2)), t2 = m2 * (id * (r0 * r1));
      // edge k: corner k t_k Q_k, corner k + 2 t_k P_k, corner k + 1 minus both
      const double u0 = t0 * Q0, v0 = t0 * P0, u1 = t1 * Q1, v1 = t1 * P1, u2 = t2 * Q2, v2 = t2 * P2;
      w1 = (u1 + v2) - (u0 + v0);
      w2 = (u2 + v0) - (u1 + v1);
    }
    const double N0 = f11 * f22 - f12 * f21, N1 = f12 * f20 - f10 * f22, N2 = f10 * f21 - f11 * f20;
    // Corners 1 and 2; corner 0 takes minus their sum (the membrane
    // gradients and the bending weights w_k sum to zero), so that the
    // element's forces add up to zero to the last bit.
    double sum0 = 0, sum1 = 0, sum2 = 0;
    for (int a = 1; a < 3; ++a) {
      const double ga = a == 1 ? a1 : a2, gb = a == 1 ? b1 : b2;
      const double c1 = A0 * (S11 * ga + S12 * gb), c2 = A0 * (S12 * ga + S22 * gb);
      const double w = a == 1 ? w1 : w2;
      const double m0 = kBend ? (c1 * f10 + c2 * f20) + w * N0 : c1 * f10 + c2 * f20;
      const double m1 = kBend ? (c1 * f11 + c2 * f21) + w * N1 : c1 * f11 + c2 * f21;
      const double m2 = kBend ? (c1 * f12 + c2 * f22) + w * N2 : c1 * f12 + c2 * f22;
      mf[(3 * a) * ld + q] = m0;
      mf[(3 * a + 1) * ld + q] = m1;
      mf[(3 * a + 2) * ld + q] = m2;
      sum0 += m0, sum1 += m1, sum2 += m2;
    }
    mf[q] = -sum0;
    mf[ld + q] = -sum1;
    mf[2 * ld + q] = -sum2;
    if (kSplit) {  // the bending's share of the corner forces alone
      const double w0 = -(w1 + w2);
      mb[q] = w0 * N0, mb[ld + q] = w0 * N1, mb[2 * ld + q] = w0 * N2;
      mb[3 * ld + q] = w1 * N0, mb[4 * ld + q] = w1 * N1, mb[5 * ld + q] = w1 * N2;
      mb[6 * ld + q] = w2 * N0, mb[7 * ld + q] = w2 * N1, mb[8 * ld + q] = w2 * N2;
    }
    double qmax = Q0;
    qmax = qmax < Q1 ? Q1 : qmax;
    qmax = qmax < Q2 ? Q2 : qmax;
    const double r = detc / qmax;
    if (kSteps) dte[q] = std::sqrt(r) * cmul;
    rmin = r < rmin ? r : rmin;
  }
  return kSteps ? std::numeric_limits<double>::infinity() : std::sqrt(rmin) * cmul;
}
// The membrane forces and steps (see membrane_body; dte null: the
// smallest step only).
TS_VECTOR_CLONES
double membrane_block(int n, int ld, const double* C, const double* ff, const double* S, const double* area,
                      const double* g, int gld, double inv_c, bool has_stiffness, double* mf, double* dte) {
  // h > 0 (det C > 1e-12 here): h times infinity is infinity.
  const double cmul = has_stiffness ? inv_c : std::numeric_limits<double>::infinity();
  if (!dte)
    return membrane_body<false, false>(n, ld, C, ff, S, area, g, gld, cmul, nullptr, nullptr, 0, nullptr, 0, mf, dte);
  return membrane_body<false, true>(n, ld, C, ff, S, area, g, gld, cmul, nullptr, nullptr, 0, nullptr, 0, mf, dte);
}
// The membrane and bending forces (see membrane_body); mb, if not null,
// receives the bending's share of the corner forces alone.
TS_VECTOR_CLONES
double membrane_bending_block(int n, int ld, const double* C, const double* ff, const double* S, const double* area,
                              const double* g, int gld, double inv_c, bool has_stiffness, const double* hm,
                              const int* nidx, int nld, const double* hm_all, int hld, double* mf, double* dte,
                              double* mb) {
  const double cmul = has_stiffness ? inv_c : std::numeric_limits<double>::infinity();
  if (mb) {
    if (!dte)
      return membrane_body<true, false, true>(n, ld, C, ff, S, area, g, gld, cmul, hm, nidx, nld, hm_all, hld, mf, dte,
                                              mb);
    return membrane_body<true, true, true>(n, ld, C, ff, S, area, g, gld, cmul, hm, nidx, nld, hm_all, hld, mf, dte, mb);
  }
  if (!dte)
    return membrane_body<true, false>(n, ld, C, ff, S, area, g, gld, cmul, hm, nidx, nld, hm_all, hld, mf, dte);
  return membrane_body<true, true>(n, ld, C, ff, S, area, g, gld, cmul, hm, nidx, nld, hm_all, hld, mf, dte);
}

// Per element q of a block and edge k (values of the block's elements
// from their first one): theta_k = dth[loc[k ls + q]], rho = L theta (entry
// (k, i) of element q's L at L[(3 k + i) ld + q]), eq = rho + a theta (a_k
// at a[k ld + q]; rho_k and eq_k at rho[k sld + q] and eq[k sld + q]).
TS_VECTOR_CLONES
void slope_block(int n, int ls, int ld, const int* __restrict loc, const double* __restrict dth,
                 const float* __restrict L, const float* __restrict a, int sld, double* __restrict eq,
                 double* __restrict rho) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double t0 = dth[loc[q]], t1 = dth[loc[ls + q]], t2 = dth[loc[2 * ls + q]];
    const float* l = L + q;
    const double r0 = l[0] * t0 + l[ld] * t1 + l[2 * ld] * t2, r1 = l[3 * ld] * t0 + l[4 * ld] * t1 + l[5 * ld] * t2,
                 r2 = l[6 * ld] * t0 + l[7 * ld] * t1 + l[8 * ld] * t2;
    rho[q] = r0;
    rho[sld + q] = r1;
    rho[2 * sld + q] = r2;
    eq[q] = r0 + a[q] * t0;
    eq[sld + q] = r1 + a[ld + q] * t1;
    eq[2 * sld + q] = r2 + a[2 * ld + q] * t2;
  }
}

// Curvatures of n elements, K = sum_k c_k s_k with the shared slopes
// s_k = eq_k - rho[nidx_k] (c_k = dK/ds_k, value r of edge k of element q at
// c[(3 k + r) ld + q]; nidx_k at [k ld + q], eq_k at eq[k sld + q], rho
// indexed over the whole part or ring), and with kTemp the elements' mean
// temperatures from their nodes' (tri: the block's triangles).
template <bool kTemp>
[[gnu::always_inline]] inline void curvature_body(int n, int ld, const float* __restrict c, const int* __restrict nidx,
                                                  int sld, const double* __restrict eq, const double* __restrict rho,
                                                  const int* __restrict tri, const double* __restrict node_temp,
                                                  double* __restrict K, double* __restrict temp) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double s0 = eq[q] - rho[nidx[q]], s1 = eq[sld + q] - rho[nidx[ld + q]],
                 s2 = eq[2 * sld + q] - rho[nidx[2 * ld + q]];
    const float* cq = c + q;
    K[3 * q] = cq[0] * s0 + cq[3 * ld] * s1 + cq[6 * ld] * s2;
    K[3 * q + 1] = cq[ld] * s0 + cq[4 * ld] * s1 + cq[7 * ld] * s2;
    K[3 * q + 2] = cq[2 * ld] * s0 + cq[5 * ld] * s1 + cq[8 * ld] * s2;
    if (kTemp) temp[q] = mean_temperature(tri, node_temp, q);
  }
}
TS_VECTOR_CLONES
void curvature_block(int n, int ld, const float* __restrict c, const int* __restrict nidx, int sld,
                     const double* __restrict eq, const double* __restrict rho, const int* __restrict tri,
                     const double* __restrict node_temp, double* __restrict K, double* __restrict temp) {
  curvature_body<true>(n, ld, c, nidx, sld, eq, rho, tri, node_temp, K, temp);
}
// The curvatures alone (the elements' temperatures kept from an earlier
// evaluation at the same node temperatures).
TS_VECTOR_CLONES
void curvature_only_block(int n, int ld, const float* __restrict c, const int* __restrict nidx, int sld,
                          const double* __restrict eq, const double* __restrict rho, double* __restrict K) {
  curvature_body<false>(n, ld, c, nidx, sld, eq, rho, nullptr, nullptr, K, nullptr);
}

// dW/ds_k = A0 M : c_k per element and edge (c laid out as for
// curvature_block; edge k of element q at em[k sld + q]), and A0 w.
TS_VECTOR_CLONES
void moment_block(int n, int ld, const double* __restrict area, const float* __restrict c, const double* __restrict M,
                  const double* __restrict w, int sld, double* __restrict em, double* __restrict ew) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double A0 = area[q], M0 = M[3 * q], M1 = M[3 * q + 1], M2 = 2 * M[3 * q + 2];
    const float* cq = c + q;
    em[q] = A0 * (M0 * cq[0] + M1 * cq[ld] + M2 * cq[2 * ld]);
    em[sld + q] = A0 * (M0 * cq[3 * ld] + M1 * cq[4 * ld] + M2 * cq[5 * ld]);
    em[2 * sld + q] = A0 * (M0 * cq[6 * ld] + M1 * cq[7 * ld] + M2 * cq[8 * ld]);
    ew[q] = A0 * w[q];
  }
}

// Each element's share of dW/dtheta of its hinges, g_i = a_i m_i +
// sum_k L_ki (m_k - m_all[nidx_k]) (L with its rows scaled by omega, laid
// out as for slope_block; nidx as for curvature_block; m_k of the block's
// element q at m[k sld + q], g_i at g[i sld + q]; m_all over the whole part
// or ring).
TS_VECTOR_CLONES
void hinge_moment_block(int n, int ld, const float* __restrict L, const float* __restrict a,
                        const int* __restrict nidx, int sld, const double* __restrict m,
                        const double* __restrict m_all, double* __restrict g) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double m_0 = m[q], m_1 = m[sld + q], m_2 = m[2 * sld + q];
    const double u0 = m_0 - m_all[nidx[q]], u1 = m_1 - m_all[nidx[ld + q]], u2 = m_2 - m_all[nidx[2 * ld + q]];
    const float* l = L + q;
    g[q] = a[q] * m_0 + l[0] * u0 + l[3 * ld] * u1 + l[6 * ld] * u2;
    g[sld + q] = a[ld + q] * m_1 + l[ld] * u0 + l[4 * ld] * u1 + l[7 * ld] * u2;
    g[2 * sld + q] = a[2 * ld + q] * m_2 + l[2 * ld] * u0 + l[5 * ld] * u1 + l[8 * ld] * u2;
  }
}

// Adds the forces of n elements, component d of corner a of element q at
// mf[(3 a + d) ld + q], into their corners' node slots (slot[6 q + a], the
// kernel's patch_slot).
// The fibres' in-plane bending (see the head of this file) in vector
// passes over n elements. Per element q: its corners' offsets 3 i in x at
// off[a mld + q], its g_1 row at g[q] and g[mld + q]; per edge k (rows of
// stride ld): the offset of the node across it at oo[k ld + q] (corner 0's
// where there is none), the coefficients of J_k on x1 - x0, x2 - x0 and
// xo - x0 at B[(3 k + j) ld + q], L at L[(3 k + i) ld + q]. The frame:
// f = g / |g|, g = g_1 x10 + g_2 x20 (the current fibre), n = N / |N|,
// N = x10 x x20, m = n x f.
struct InPlaneFrameV {
  double a0, a1, a2, c0, c1, c2;  // x10, x20
  double f0, f1, f2, n0, n1, n2, m0, m1, m2, inv_glen, inv_nlen;
};
[[gnu::always_inline]] inline InPlaneFrameV in_plane_frame_v(const double* __restrict x, int i0, int i1, int i2,
                                                            double gb, double gc) {
  InPlaneFrameV r;
  const double X0 = x[i0], X1 = x[i0 + 1], X2 = x[i0 + 2];
  r.a0 = x[i1] - X0, r.a1 = x[i1 + 1] - X1, r.a2 = x[i1 + 2] - X2;
  r.c0 = x[i2] - X0, r.c1 = x[i2 + 1] - X1, r.c2 = x[i2 + 2] - X2;
  const double G0 = gb * r.a0 + gc * r.c0, G1 = gb * r.a1 + gc * r.c1, G2 = gb * r.a2 + gc * r.c2;
  r.inv_glen = 1.0 / std::sqrt(G0 * G0 + G1 * G1 + G2 * G2);
  r.f0 = G0 * r.inv_glen, r.f1 = G1 * r.inv_glen, r.f2 = G2 * r.inv_glen;
  const double N0 = r.a1 * r.c2 - r.a2 * r.c1, N1 = r.a2 * r.c0 - r.a0 * r.c2, N2 = r.a0 * r.c1 - r.a1 * r.c0;
  r.inv_nlen = 1.0 / std::sqrt(N0 * N0 + N1 * N1 + N2 * N2);
  r.n0 = N0 * r.inv_nlen, r.n1 = N1 * r.inv_nlen, r.n2 = N2 * r.inv_nlen;
  r.m0 = r.n1 * r.f2 - r.n2 * r.f1, r.m1 = r.n2 * r.f0 - r.n0 * r.f2, r.m2 = r.n0 * r.f1 - r.n1 * r.f0;
  return r;
}

// The step's values (phi, r, mv, ... below) are in rows of stride sld,
// the set-up's (oo, B, L, c, w, mask) and nidx in rows of stride ld.
//
// Pass 0: the slope jumps phi_k = m . J_k (phi[k sld + q]), the own
// quadratic's slopes r = L phi (r[k sld + q]) and m (mv[d sld + q]).
TS_VECTOR_CLONES
void in_plane_angle_block(int n, const int* __restrict off, const double* __restrict g, int mld,
                          const int* __restrict oo, const double* __restrict B, const double* __restrict L, int ld,
                          const double* __restrict x, int sld, double* __restrict phi, double* __restrict r,
                          double* __restrict mv) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const int i0 = off[q];
    const InPlaneFrameV fr = in_plane_frame_v(x, i0, off[mld + q], off[2 * mld + q], g[q], g[mld + q]);
    mv[q] = fr.m0, mv[sld + q] = fr.m1, mv[2 * sld + q] = fr.m2;
    double p[3];
    for (int k = 0; k < 3; ++k) {
      const int io = oo[k * ld + q];
      const double o0 = x[io] - x[i0], o1 = x[io + 1] - x[i0 + 1], o2 = x[io + 2] - x[i0 + 2];
      const double b0 = B[3 * k * ld + q], b1 = B[(3 * k + 1) * ld + q], b2 = B[(3 * k + 2) * ld + q];
      const double J0 = b0 * fr.a0 + b1 * fr.c0 + b2 * o0, J1 = b0 * fr.a1 + b1 * fr.c1 + b2 * o1,
                   J2 = b0 * fr.a2 + b1 * fr.c2 + b2 * o2;
      p[k] = fr.m0 * J0 + fr.m1 * J1 + fr.m2 * J2;
      phi[k * sld + q] = p[k];
    }
    for (int k = 0; k < 3; ++k)
      r[k * sld + q] = L[3 * k * ld + q] * p[0] + L[(3 * k + 1) * ld + q] * p[1] + L[(3 * k + 2) * ld + q] * p[2];
  }
}

// Pass 1, before the law: K11 = sum_k c_k (w_k r_k + (1 - w_k) (phi_k -
// r'_k)) into chi[3 q] (chi[3 q + 1], chi[3 q + 2] zero), r' the
// neighbour's own slope of the same edge (r_all[nidx[k ld + q]]; the entry
// past the arrays, zero, where there is none).
TS_VECTOR_CLONES
void in_plane_curvature_block(int n, int ld, const double* __restrict c, const double* __restrict w, int sld,
                              const double* __restrict phi, const double* __restrict r, const int* __restrict nidx,
                              const double* __restrict r_all, double* __restrict chi) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    double kappa = 0.0;
    for (int k = 0; k < 3; ++k) {
      const int i = k * ld + q, j = k * sld + q;
      kappa += c[i] * (w[i] * r[j] + (1.0 - w[i]) * (phi[j] - r_all[nidx[i]]));
    }
    chi[3 * q] = kappa;
    chi[3 * q + 1] = 0.0;
    chi[3 * q + 2] = 0.0;
  }
}

// Pass 2: each element's dW/dphi_i = (1 - w_i) m_i + sum_k L_ki w_k (m_k -
// m'_k) into gs[i ld + q] (m = dW/ds, mm[k ld + q], m' the neighbour's of
// the same edge, m_all[nidx[..]]), and for the node across each edge its
// force g_k B_k2 m (og0/og1/og2[k ld + q], components of m at mv[d ld +
// q]), which the neighbour adds to its corner in pass 3.
TS_VECTOR_CLONES
void in_plane_share_block(int n, int ld, const double* __restrict w, const double* __restrict L,
                          const int* __restrict nidx, const double* __restrict B, int sld, const double* __restrict mm,
                          const double* __restrict m_all, const double* __restrict mv, double* __restrict gs,
                          double* __restrict og0, double* __restrict og1, double* __restrict og2) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    double d[3];
    for (int k = 0; k < 3; ++k) {
      const int i = k * ld + q;
      d[k] = w[i] * (mm[k * sld + q] - m_all[nidx[i]]);
    }
    for (int i = 0; i < 3; ++i) {
      const int e = i * ld + q, j = i * sld + q;
      const double gi =
          (1.0 - w[e]) * mm[j] + L[i * ld + q] * d[0] + L[(3 + i) * ld + q] * d[1] + L[(6 + i) * ld + q] * d[2];
      gs[j] = gi;
      const double t = gi * B[(3 * i + 2) * ld + q];
      og0[j] = t * mv[q], og1[j] = t * mv[sld + q], og2[j] = t * mv[2 * sld + q];
    }
  }
}

// Pass 3: the forces sum_i g_i dphi_i/dx on the element's corners, with
// dphi_i = m . dJ_i + J_i . dm and J . dm = dn . (f x J) + df . (J x n),
// df = (I - f f^T) dg / |g|, dn = (I - n n^T) dN / |N|, g_i taken times
// mask[i ld + q] (zero at ghost edges, which the caller adds apart); and
// each corner k the force of the neighbour across edge k on it (og*_all at
// nidx[k ld + q]). Added into mf (component d of corner a at
// mf[(3 a + d) mld_f + q]).
TS_VECTOR_CLONES
void in_plane_force_block(int n, const int* __restrict off, const double* __restrict g, int mld,
                          const int* __restrict oo, const double* __restrict B, int ld, int sld,
                          const double* __restrict gs, const double* __restrict mask, const int* __restrict nidx,
                          const double* __restrict og0,
                          const double* __restrict og1, const double* __restrict og2, const double* __restrict x,
                          double* __restrict mf, int fld) {
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const int i0 = off[q];
    const double gb = g[q], gc = g[mld + q];
    const InPlaneFrameV fr = in_plane_frame_v(x, i0, off[mld + q], off[2 * mld + q], gb, gc);
    double S1 = 0.0, S2 = 0.0, S3 = 0.0, Jg0 = 0.0, Jg1 = 0.0, Jg2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double gk = gs[k * sld + q] * mask[k * ld + q];
      const int io = oo[k * ld + q];
      const double o0 = x[io] - x[i0], o1 = x[io + 1] - x[i0 + 1], o2 = x[io + 2] - x[i0 + 2];
      const double b0 = gk * B[3 * k * ld + q], b1 = gk * B[(3 * k + 1) * ld + q], b2 = gk * B[(3 * k + 2) * ld + q];
      S1 += b0, S2 += b1, S3 += b2;
      Jg0 += b0 * fr.a0 + b1 * fr.c0 + b2 * o0;
      Jg1 += b0 * fr.a1 + b1 * fr.c1 + b2 * o1;
      Jg2 += b0 * fr.a2 + b1 * fr.c2 + b2 * o2;
    }
    // kn = (I - f f^T)(Jg x n) / |g|, v = (I - n n^T)(f x Jg) / |N|
    double k0 = Jg1 * fr.n2 - Jg2 * fr.n1, k1 = Jg2 * fr.n0 - Jg0 * fr.n2, k2 = Jg0 * fr.n1 - Jg1 * fr.n0;
    const double fk = fr.f0 * k0 + fr.f1 * k1 + fr.f2 * k2;
    k0 = (k0 - fr.f0 * fk) * fr.inv_glen, k1 = (k1 - fr.f1 * fk) * fr.inv_glen, k2 = (k2 - fr.f2 * fk) * fr.inv_glen;
    double v0 = fr.f1 * Jg2 - fr.f2 * Jg1, v1 = fr.f2 * Jg0 - fr.f0 * Jg2, v2 = fr.f0 * Jg1 - fr.f1 * Jg0;
    const double nv = fr.n0 * v0 + fr.n1 * v1 + fr.n2 * v2;
    v0 = (v0 - fr.n0 * nv) * fr.inv_nlen, v1 = (v1 - fr.n1 * nv) * fr.inv_nlen, v2 = (v2 - fr.n2 * nv) * fr.inv_nlen;
    // t1 = x20 x v, t2 = v x x10
    const double t10 = fr.c1 * v2 - fr.c2 * v1, t11 = fr.c2 * v0 - fr.c0 * v2, t12 = fr.c0 * v1 - fr.c1 * v0;
    const double t20 = v1 * fr.a2 - v2 * fr.a1, t21 = v2 * fr.a0 - v0 * fr.a2, t22 = v0 * fr.a1 - v1 * fr.a0;
    const double c1 = gb, c2 = gc, c0 = -(gb + gc), s0 = -(S1 + S2 + S3);
    const int n0 = nidx[q], n1 = nidx[ld + q], n2 = nidx[2 * ld + q];
    mf[q] += fr.m0 * s0 + k0 * c0 - (t10 + t20) + og0[n0];
    mf[fld + q] += fr.m1 * s0 + k1 * c0 - (t11 + t21) + og1[n0];
    mf[2 * fld + q] += fr.m2 * s0 + k2 * c0 - (t12 + t22) + og2[n0];
    mf[3 * fld + q] += fr.m0 * S1 + k0 * c1 + t10 + og0[n1];
    mf[4 * fld + q] += fr.m1 * S1 + k1 * c1 + t11 + og1[n1];
    mf[5 * fld + q] += fr.m2 * S1 + k2 * c1 + t12 + og2[n1];
    mf[6 * fld + q] += fr.m0 * S2 + k0 * c2 + t20 + og0[n2];
    mf[7 * fld + q] += fr.m1 * S2 + k1 * c2 + t21 + og1[n2];
    mf[8 * fld + q] += fr.m2 * S2 + k2 * c2 + t22 + og2[n2];
  }
}

void corner_forces(int n, int ld, const double* __restrict mf, const int* __restrict slot, double* __restrict nf) {
  for (int q = 0; q < n; ++q)
    for (int a = 0; a < 3; ++a) {
      double* f = nf + 3 * slot[6 * q + a];
      for (int d = 0; d < 3; ++d) f[d] += mf[(3 * a + d) * ld + q];
    }
}

// The same sums as corner_forces, node by node: node slot slots[i] adds,
// in this order, the corner forces at mf[e], mf[e + ld], mf[e + 2 ld] for
// the k entries e = ent[k i + j], j < k, which list its corners by
// ascending element, as corner_forces visits them: the same sums in the
// same order, the same bits. Each node's sum stays in registers instead of
// going through memory once per corner (where consecutive elements share
// a node, each addition then waits for the one before).
// K > 0: k = K corners per node, known to the compiler (0: k as given).
template <int K>
void node_forces_of(int k, int count, int ld, const double* __restrict mf, const std::uint16_t* __restrict slots,
                    const std::uint16_t* __restrict ent, double* __restrict nf) {
  const int kk = K > 0 ? K : k;
  for (int i = 0; i < count; ++i) {
    double* f = nf + 3 * static_cast<int>(slots[i]);
    double f0 = f[0], f1 = f[1], f2 = f[2];
    const std::uint16_t* e = ent + static_cast<std::size_t>(kk) * i;
    for (int j = 0; j < kk; ++j) {
      const double* m = mf + e[j];
      f0 += m[0];
      f1 += m[ld];
      f2 += m[2 * ld];
    }
    f[0] = f0;
    f[1] = f1;
    f[2] = f2;
  }
}
void node_forces(int k, int count, int ld, const double* mf, const std::uint16_t* slots, const std::uint16_t* ent,
                 double* nf) {
  switch (k) {
    case 1: return node_forces_of<1>(k, count, ld, mf, slots, ent, nf);
    case 2: return node_forces_of<2>(k, count, ld, mf, slots, ent, nf);
    case 3: return node_forces_of<3>(k, count, ld, mf, slots, ent, nf);
    case 4: return node_forces_of<4>(k, count, ld, mf, slots, ent, nf);
    case 5: return node_forces_of<5>(k, count, ld, mf, slots, ent, nf);
    case 6: return node_forces_of<6>(k, count, ld, mf, slots, ent, nf);
    case 7: return node_forces_of<7>(k, count, ld, mf, slots, ent, nf);
    case 8: return node_forces_of<8>(k, count, ld, mf, slots, ent, nf);
    default: return node_forces_of<0>(k, count, ld, mf, slots, ent, nf);
  }
}

// Largest entry of an element's map L from angle changes to the slopes of
// its own quadratic; a patch whose map is larger (nearly on a conic) uses
// its neighbours' quadratics instead.
constexpr double kMaxSlopeMap = 4.0;

class ShellRfT3 final : public ElementKernel {
 public:
  Status configure(const Params&, const ElementSetup& s) override {
    return guarded([&]() -> Status {
      part_ = s.part;
      laws_.assign(s.membrane.begin(), s.membrane.end());
      bending_ = s.bending;
      in_plane_ = s.in_plane_bending;
      if (in_plane_ && !bending_) return Status::failure("an in-plane bending law needs a bending law");
      if (in_plane_ && (in_plane_->state_size() != 0 || in_plane_->uses_strain_old()))
        return Status::failure("the in-plane bending law must keep no history (no state, no previous strains)");
      edge_condition_.assign(s.edge_condition.begin(), s.edge_condition.end());
      areal_mass_ = s.density * part_->thickness;
      const int ne = part_->num_elements;
      mld_ = padded_ld(ne);
      g_.assign(4 * static_cast<std::size_t>(mld_), 0.0);
      off_.assign(3 * static_cast<std::size_t>(mld_), 0);
      for (int e = 0; e < ne; ++e)
        for (int a = 0; a < 3; ++a) off_[a * mld_ + e] = 3 * part_->triangles[3 * e + a];
      area0_.resize(ne);
      e1_.resize(3 * ne);
      e2_.resize(3 * ne);
      for (int e = 0; e < ne; ++e) {
        const int* t = &part_->triangles[3 * e];
        const Vec3 X[3] = {load3(part_->x0.data(), t[0]), load3(part_->x0.data(), t[1]), load3(part_->x0.data(), t[2])};
        const Vec3 nn = cross(sub(X[1], X[0]), sub(X[2], X[0]));
        const double two_a = norm(nn);
        if (!(two_a > 0)) return Status::failure("element " + std::to_string(e) + " has zero initial area");
        const Vec3 n = scale(nn, 1.0 / two_a);
        Vec3 f = load3(part_->fibre.data(), e);
        f = normalized(sub(f, scale(n, dot(f, n))));
        const Vec3 m = cross(n, f);
        area0_[e] = 0.5 * two_a;
        for (int d = 0; d < 3; ++d) {
          e1_[3 * e + d] = f[d];
          e2_[3 * e + d] = m[d];
        }
        // grad0 N_a = n x (X_c - X_b) / (2 A0), components on (f, m), of
        // corners 1 and 2 (corner 0's is minus their sum).
        for (int a = 1; a < 3; ++a) {
          const Vec3 g = scale(cross(n, sub(X[(a + 2) % 3], X[(a + 1) % 3])), 1.0 / two_a);
          g_[(a - 1) * mld_ + e] = dot(g, f);
          g_[(a + 1) * mld_ + e] = dot(g, m);
        }
      }
      if (bending_) {
        setup_bending();
        if (auto st = setup_slopes(s.temperature); !st) return st;
      }
      if (in_plane_) {
        setup_in_plane();
        ip_step_.assign(3 * static_cast<std::size_t>(gld_));  // rows of gld_ per edge
      }
      // The previous strains are kept only for laws that read them.
      keep_old_ = std::any_of(laws_.begin(), laws_.end(), [](const MaterialLaw* l) { return l->uses_strain_old(); });
      strain_old_.assign(keep_old_ ? 3 * ne : 0, 0.0);
      for (std::size_t e = 0; 3 * e < strain_old_.size(); ++e) {
        strain_old_[3 * e] = 1.0;
        strain_old_[3 * e + 1] = 1.0;
      }
      stress_.assign(3 * ne, 0.0);
      etemp_.assign(ne, 0.0);
      etemp_version_.assign(ne + 1, 0);
      etemp_end_.assign(ne + 1, -1);
      range_index_.clear();
      range_index_.resize(ne + 1);
      states_.clear();
      for (const auto* l : laws_) states_.emplace_back(static_cast<std::size_t>(l->state_size()) * ne, 0.0);
      // The laws' caches (MaterialLaw::cache_size()) are kept where all of
      // them fit in half the per-core cache.
      std::size_t cache_values = 0;
      for (const auto* l : laws_) cache_values += static_cast<std::size_t>(l->cache_size()) * ne;
      const bool keep_caches = sizeof(double) * cache_values <= level2_cache_bytes() / 2;
      caches_.clear();
      for (const auto* l : laws_)
        caches_.emplace_back(keep_caches ? static_cast<std::size_t>(l->cache_size()) * ne : 0,
                             std::numeric_limits<double>::quiet_NaN());
      return Status::success();
    });
  }

  // With bending, four passes: the angle changes and the slopes of the
  // elements' own quadratics; the mid-edge slopes, curvatures and moments;
  // each element's share of its hinges' dW/dtheta (which reads the
  // neighbours' moments); the forces (which read the neighbours' shares).
  int passes() const override { return bending_ ? 4 : 1; }
  // Pass 1 reads the own-quadratic slopes of the neighbours across the
  // edges (pass 0), pass 2 their dW/ds (pass 1), pass 3 their shares of
  // dW/dtheta (pass 2); nothing further.
  int pass_reach() const override { return 1; }

  Status internal_forces(const ElementForceInput& in, ElementForceOutput& out) override {
    return guarded([&]() -> Status {
      // Bending in this evaluation (ElementForceInput::bending_weight): 0
      // skips its passes, w > 0 scales its forces by w.
      const bool bend = bending_ && in.bending_weight > 0;
      // An evaluation without bending that a frame follows (fields_due)
      // still forms the curvatures of its positions for fields(): passes 0
      // and 1 up to the curvatures, with no moments, history or forces.
      const bool curvatures_only = bending_ && !bend && in.fields_due;
      if (bending_ && in.pass == 0) {
        if (bend || curvatures_only) slope_angles(in, in.range.begin, in.range.end);
        if (in_plane_) in_plane_angles(in, in.range.begin, in.range.end);
        return Status::success();
      }
      if (bending_ && in.pass == 1) {
        if (curvatures_only) {
          const StepValues sv = step_values(in);
          curvature_only_block(in.range.end - in.range.begin, gld_, cs_.data() + in.range.begin, sv.nidx, sv.ld,
                               sv.eq, sv.rho_all, curv_.data() + 3 * static_cast<std::size_t>(in.range.begin));
        }
        if (in_plane_ && !bend && !temperatures_kept(in, in.range.begin, in.range.end)) {
          // (with the bending, slope_moments forms them)
          element_temperature_block(in.range.end - in.range.begin, &part_->triangles[3 * in.range.begin],
                                    in.node_temperature.data(), etemp_.data() + in.range.begin);
          keep_temperatures(in, in.range.begin, in.range.end);
        }
        if (bend)
          if (auto st = slope_moments(in, in.range.begin, in.range.end); !st) return st;
        if (in_plane_)
          if (auto st = in_plane_moments(in, in.range.begin, in.range.end); !st) return st;
        if (!bend) return Status::success();
        if (in.bending_weight != 1.0) {  // dW/ds times w: every hinge moment and bending force follows
          const StepValues sv = step_values(in);
          for (int k = 0; k < 3; ++k)
            for (int q = 0; q < in.range.end - in.range.begin; ++q) sv.em[k * sv.ld + q] *= in.bending_weight;
        }
        return Status::success();
      }
      if (bending_ && in.pass == 2) {
        if (bend) hinge_moments(in, in.range.begin, in.range.end);
        if (in_plane_) in_plane_shares(in, in.range.begin, in.range.end);
        return Status::success();
      }
      const int b = in.range.begin, n = in.range.end - in.range.begin;
      const double* x = part_->x.data();
      // Values needed only while this block is evaluated live in a buffer of
      // the calling thread (indexed from the block's first element), so that
      // they stay in cache instead of streaming through per-element arrays.
      BlockScratch& sc = block_scratch(n);
      const int ld = padded_ld(n);  // of ff and mf
      double* C = sc.strain.data();  // C of the block's elements (the fields compute it again from x)
      double* ff = sc.ff.data();
      // 1. Strains and temperatures of the block (with bending in this
      // evaluation, pass 1 has formed the temperatures).
      const double* temp = etemp_.data() + b;
      if (!bend && !temperatures_kept(in, b, in.range.end)) {
        element_temperature_block(n, &part_->triangles[3 * b], in.node_temperature.data(), etemp_.data() + b);
        keep_temperatures(in, b, in.range.end);
      }
      const RangeIndex& ri = range_index(in, b, in.range.end);
      if (strains(ri, b, in.range.end, ld, x, ff, C) != 0.0)
        for (int q = 0; q < n; ++q) {
          const double* c = C + 3 * q;
          if (!(c[0] * c[1] - c[2] * c[2] > 1e-12)) {
            out.failed_element = b + q;
            return Status::success();
          }
        }
      // 2. The laws, one call per law for the whole block; stresses add (the
      // first law writes straight into the block's stresses and energies).
      // The stresses are kept for fields() only where the kernel asks
      // (fields_due); otherwise they live in the thread's block buffer.
      double* energy_e = sc.energy.data();
      double* S = in.fields_due ? stress_.data() + 3 * b : sc.stress.data();
      for (std::size_t k = 0; k < laws_.size(); ++k) {
        const int ns = laws_[k]->state_size();
        MaterialBlock blk;
        blk.n = n;
        blk.strain = std::span<const double>(C, 3 * n);
        if (keep_old_) blk.strain_old = std::span<const double>(strain_old_.data() + 3 * b, 3 * n);
        blk.temperature = std::span<const double>(temp, n);
        blk.dt = in.dt;
        blk.state = std::span<double>(states_[k].data() + static_cast<std::size_t>(ns) * b, static_cast<std::size_t>(ns) * n);
        if (!caches_[k].empty()) {
          const std::size_t nc = static_cast<std::size_t>(laws_[k]->cache_size());
          blk.cache = std::span<double>(caches_[k].data() + nc * b, nc * n);
        }
        blk.stress = std::span<double>(k == 0 ? S : sc.law_stress.data(), 3 * n);
        blk.energy = std::span<double>(k == 0 ? energy_e : sc.energy_tmp.data(), n);
        if (auto s = laws_[k]->evaluate(blk); !s) return s;
        if (k == 0) continue;
        add_into(3 * n, S, sc.law_stress.data());
        add_into(n, energy_e, sc.energy_tmp.data());
      }
      if (laws_.empty()) {
        std::fill(S, S + 3 * n, 0.0);
        std::fill(energy_e, energy_e + n, 0.0);
      }
      // 3. Nodal forces, energy, stable step. The largest tangent stiffness
      // is taken over the block's temperature range (one call per law).
      double t_lo = temp[0], t_hi = temp[0];
      value_range(n, temp, t_lo, t_hi);
      double kmax = 0;
      for (const auto* l : laws_) kmax += std::max(l->max_stiffness(t_lo), l->max_stiffness(t_hi));
      const double inv_c = kmax > 0 ? 1.0 / std::sqrt(kmax / areal_mass_) : 0.0;
      double energy = 0, dt_min = std::numeric_limits<double>::infinity();
      // The elements' own steps are formed only where they are scaled or
      // asked for; otherwise the passes give the block's smallest.
      const bool steps = !in.dt_scale.empty() || !out.element_dt.empty();
      double* dte = steps ? sc.energy_tmp.data() : nullptr;  // free again after the laws
      double* mf = sc.mf.data();
      BlockAngles* held_eval = nullptr;  // a block whose held part this evaluation updates
      const double* held_add = nullptr;   // a held part to add (evaluations without bending)
      if (bend) {  // the membrane forces with the bending ones
        const StepValues sv = step_values(in);
        BlockAngles& ba = *block_angles_[b];
        // With a held part, the bending's corner forces (times the weight)
        // also apart, into mb, and their node sums into the block's slots
        // (sc.bslots).
        double* mb = in.bending_weight > 1.0 || !ba.held.empty() ? sc.mb.data() : nullptr;
        dt_min = membrane_bending_block(n, ld, C, ff, S, area0_.data() + b, g_.data() + b, mld_, inv_c, kmax > 0,
                                        sv.hm, sv.nidx, gld_, sv.hm_all, sv.ld, mf, dte, mb);
        energy += bending_forces(in, b, in.range.end, dte, t_lo, t_hi, mf, mb, ld, ri, out, dt_min);
        if (mb) {
          const std::size_t ns = out.node_force.size();
          if (sc.bslots.size() < ns) sc.bslots.resize(ns);
          std::fill(sc.bslots.begin(), sc.bslots.begin() + static_cast<std::ptrdiff_t>(ns), 0.0);
          add_node_forces(in, ri, n, ld, mb, sc.bslots.data());
          held_eval = &ba;
        }
      } else {
        dt_min = membrane_block(n, ld, C, ff, S, area0_.data() + b, g_.data() + b, mld_, inv_c, kmax > 0, mf, dte);
        if (bending_ && block_angles_[b] && block_angles_[b]->held.size() == out.node_force.size())
          held_add = block_angles_[b]->held.data();
        if (bending_ && block_angles_[b]) {
          energy += block_angles_[b]->bending_energy;  // of the last one with bending
          if (in.commit) block_angles_[b]->elapsed += in.dt;
        }
      }
      // The fibres' in-plane bending, at every evaluation.
      if (in_plane_) energy += in_plane_forces(in, b, in.range.end, dte, t_lo, t_hi, mf, ld, dt_min);
      add_node_forces(in, ri, n, ld, mf, out.node_force.data());
      if (held_eval)
        hold_bending(*held_eval, in.bending_weight, in.commit, sc.bslots.data(), out.node_force);
      else if (held_add)
        add_into(static_cast<int>(out.node_force.size()), out.node_force.data(), held_add);
      energy += lane_dot(n, area0_.data() + b, energy_e);
      if (steps) dt_min = smallest_step(n, dte, in.dt_scale.empty() ? nullptr : in.dt_scale.data() + b, dt_min);
      if (!out.element_dt.empty()) std::copy(dte, dte + n, out.element_dt.begin() + b);
      if (in.commit && keep_old_)
        std::copy(C, C + 3 * n, strain_old_.begin() + 3 * b);
      out.energy += energy;
      out.stable_dt = dt_min;
      return Status::success();
    });
  }

  Status fields(ElementFields& out) const override {
    const int ne = part_->num_elements;
    for (int e = 0; e < ne; ++e) {
      // F e1 and F e2, as internal_forces forms them (shear angle, strain, fibre).
      const int* t = &part_->triangles[3 * e];
      const Vec3 x0 = load3(part_->x.data(), t[0]);
      const Vec3 d1 = sub(load3(part_->x.data(), t[1]), x0), d2 = sub(load3(part_->x.data(), t[2]), x0);
      const Vec3 f1 = add(scale(d1, g_[e]), scale(d2, g_[mld_ + e]));
      const Vec3 f2 = add(scale(d1, g_[2 * mld_ + e]), scale(d2, g_[3 * mld_ + e]));
      const double c11 = dot(f1, f1), c22 = dot(f2, f2), c12 = dot(f1, f2);
      if (!out.shear_angle.empty()) {  // gamma = asin(I_sh), I_sh = C12 / sqrt(C11 C22)
        const double ish = c12 / std::sqrt(c11 * c22);
        out.shear_angle[e] = std::asin(std::clamp(ish, -1.0, 1.0)) * 180.0 / M_PI;
      }
      if (!out.strain.empty()) {  // E = (C - I) / 2
        out.strain[3 * e] = 0.5 * (c11 - 1.0);
        out.strain[3 * e + 1] = 0.5 * (c22 - 1.0);
        out.strain[3 * e + 2] = 0.5 * c12;
      }
      if (!out.stress.empty())
        for (int k = 0; k < 3; ++k) out.stress[3 * e + k] = stress_[3 * e + k];
      if (!out.curvature.empty() && bending_)
        for (int k = 0; k < 3; ++k) out.curvature[3 * e + k] = curv_[3 * e + k];
      if (!out.fibre.empty()) {
        const Vec3 u = normalized(f1);
        for (int d = 0; d < 3; ++d) out.fibre[3 * e + d] = u[d];
      }
    }
    return Status::success();
  }

  // What a step leaves for the next: the laws' history and previous
  // strains, the bending's (curvatures, history), the stresses and
  // curvatures fields() shows, and per block the time since its last
  // evaluation with bending and that evaluation's energy.
  Status save_state(StateWriter& out) const override {
    out.put_vector(strain_old_);
    out.put_vector(stress_);
    out.put(static_cast<std::uint64_t>(states_.size()));
    for (const auto& s : states_) out.put_vector(s);
    out.put_vector(curv_);
    out.put_vector(curv_old_);
    out.put_vector(bstate_);
    std::vector<double> blocks;  // (first element, elapsed, bending energy) per block evaluated so far
    for (std::size_t b = 0; b < block_angles_.size(); ++b)
      if (block_angles_[b])
        blocks.insert(blocks.end(), {static_cast<double>(b), block_angles_[b]->elapsed, block_angles_[b]->bending_energy});
    out.put_vector(blocks);
    std::vector<double> held;  // per block with a held part: its first element, their count, then the values
    for (std::size_t b = 0; b < block_angles_.size(); ++b)
      if (block_angles_[b] && !block_angles_[b]->held.empty()) {
        held.push_back(static_cast<double>(b));
        held.push_back(static_cast<double>(block_angles_[b]->held.size()));
        held.insert(held.end(), block_angles_[b]->held.begin(), block_angles_[b]->held.end());
      }
    out.put_vector(held);
    return Status::success();
  }
  Status load_state(StateReader& in) override {
    const auto mismatch = [] { return Status::failure("shell_rf_t3: the checkpoint does not fit this part"); };
    std::uint64_t nlaws = 0;
    if (!in.get_array(std::span<double>(strain_old_)) || !in.get_array(std::span<double>(stress_)) ||
        !in.get(nlaws) || nlaws != states_.size())
      return mismatch();
    for (auto& s : states_)
      if (!in.get_array(std::span<double>(s))) return mismatch();
    std::vector<double> blocks;
    if (!in.get_array(std::span<double>(curv_)) || !in.get_array(std::span<double>(curv_old_)) ||
        !in.get_array(std::span<double>(bstate_)) || !in.get_vector(blocks) || blocks.size() % 3 != 0)
      return mismatch();
    for (std::size_t k = 0; k < blocks.size(); k += 3) {
      const double b = blocks[k];
      if (!(b >= 0 && b < static_cast<double>(block_angles_.size()))) return mismatch();
      auto& slot = block_angles_[static_cast<std::size_t>(b)];
      if (!slot) slot = std::make_unique<BlockAngles>();
      slot->elapsed = blocks[k + 1];
      slot->bending_energy = blocks[k + 2];
    }
    if (in.done()) return Status::success();  // (written before the held parts were kept)
    std::vector<double> held;
    if (!in.get_vector(held)) return mismatch();
    for (std::size_t k = 0; k < held.size();) {
      const double b = held[k];
      if (!(b >= 0 && b < static_cast<double>(block_angles_.size())) || !block_angles_[static_cast<std::size_t>(b)])
        return mismatch();
      if (held.size() - k < 2) return mismatch();
      const double count = held[k + 1];
      if (!(count >= 1 && count <= static_cast<double>(held.size() - k - 2))) return mismatch();
      const std::size_t m = static_cast<std::size_t>(count);
      const auto from = held.begin() + static_cast<std::ptrdiff_t>(k + 2);
      block_angles_[static_cast<std::size_t>(b)]->held.assign(from, from + static_cast<std::ptrdiff_t>(m));
      k += 2 + m;
    }
    return Status::success();
  }

 private:
  // Bending angle of hinge k of element e at positions x (edge nodes p, q in
  // the element's counter-clockwise order, c opposite in e, o in the
  // neighbour); hinge_angle_block evaluates it for many hinges.
  double hinge_angle(const double* x, int c, int p, int q, int o) const {
    const Vec3 C = load3(x, c), P = load3(x, p), Q = load3(x, q), O = load3(x, o);
    const Vec3 edge = sub(Q, P);
    const double len = std::sqrt(dot(edge, edge));
    const Vec3 cp = sub(C, P), op = sub(O, P);
    // Unnormalised normals: element e (p, q, c) and the neighbour (q, p, o),
    // both counter-clockwise; |N| = len * height of c (of o) over the edge.
    const Vec3 Ne = cross(edge, cp);
    const Vec3 Nn = cross(op, edge);
    // (Nn x Ne) . edge = |Ne| |Nn| len sin theta and Ne . Nn = |Ne| |Nn|
    // cos theta; (Nn x Ne) = (op . Ne) edge (as Nn = op x edge and
    // Ne = edge x cp), and atan2 is invariant to scaling both arguments by
    // len > 0.
    return atan2_small(len * dot(op, Ne), dot(Ne, Nn));
  }

  // Hinge angle between element (c, p, q) and a ghost neighbour across its
  // edge (p, q) whose normal is g = G n (G = 0 with g = n0 fixed: a clamp;
  // G = reflection: the mirror image in a symmetry plane), with the gradient
  // on (c, p, q) when grad is given: theta = atan2((g x n) . e, n . g).
  double ghost_angle(const double* x, int c, int p, int q, const Vec3& n0, int mirror_axis, Vec3* grad) const {
    const Vec3 C = load3(x, c), P = load3(x, p), Q = load3(x, q);
    const Vec3 edge = sub(Q, P);
    const double len = norm(edge);
    const Vec3 eh = scale(edge, 1.0 / len);
    const Vec3 N = cross(sub(Q, P), sub(C, P));
    const double nlen = norm(N);
    const Vec3 n = scale(N, 1.0 / nlen);
    Vec3 g = n0;  // the ghost's normal: fixed (clamp) or n mirrored
    if (mirror_axis >= 0) {
      g = n;
      g[mirror_axis] = -g[mirror_axis];
    }
    const double y = dot(cross(g, n), eh), z = dot(n, g);
    const double theta = atan2_small(y, z);
    if (!grad) return theta;
    // The gradient, for either ghost: for a flat triangle dn = -sum_k
    // (n . dx_k) grad N_k, and de = (I - e e^T)(dQ - dP) / |Q - P|, so it is
    // s_k n on corner k, plus wq on Q and minus wq on P.
    const Vec3 xs[3] = {C, P, Q};
    Vec3 gk[3];  // grad N_k
    for (int k = 0; k < 3; ++k) gk[k] = scale(cross(n, sub(xs[(k + 2) % 3], xs[(k + 1) % 3])), 1.0 / nlen);
    double s[3];
    Vec3 wq;
    if (mirror_axis >= 0) {
      // Mirror ghost (edge in the symmetry plane, e_a its normal): with
      // m = n x e, theta = 2 atan2(-n_a, m_a), d theta = 2 (-m_a dn_a +
      // n_a dm_a), dm = dn x e + n x de.
      const int a = mirror_axis;
      const Vec3 m = cross(n, eh);
      Vec3 ea{0, 0, 0};
      ea[a] = 1.0;
      const Vec3 exa = cross(eh, ea);
      Vec3 w = cross(ea, n);
      w = sub(w, scale(eh, dot(w, eh)));
      for (int k = 0; k < 3; ++k) s[k] = 2 * (m[a] * gk[k][a] - n[a] * dot(gk[k], exa));
      wq = scale(w, 2 * n[a] / len);
    } else {
      // Clamp (g = n0 fixed): d theta = (z dy - y dz) / (y^2 + z^2) with
      // dy = dn . (e x g) + (g x n) . de and dz = dn . g, where
      // (g x n) . de = w . (dQ - dP) / |Q - P| with w = g x n - y e.
      const double r2 = y * y + z * z;
      const Vec3 exg = cross(eh, g);
      for (int k = 0; k < 3; ++k) s[k] = (y * dot(gk[k], g) - z * dot(gk[k], exg)) / r2;
      wq = scale(sub(cross(g, n), scale(eh, y)), z / (len * r2));
    }
    for (int k = 0; k < 3; ++k) grad[k] = scale(n, s[k]);
    grad[2] = add(grad[2], wq);
    grad[1] = sub(grad[1], wq);
    return theta;
  }

  // In-plane bending of the fibres (see the head of this file), set-up:
  // per element e and edge k (rows of stride gld_: [k gld_ + e]) the
  // coefficients of the slope jump J_k = (F_j - F_e) nu_k on x1 - x0,
  // x2 - x0 and xo - x0 (ipb_, row 3 k + j; xo the neighbour's other node,
  // at offset ipo_), the weight omega of the element's own quadratic (ipw_)
  // and dK11/ds_k = l_k (nu_k . a0)^2 / A0 (ipc_, zero for every edge of an
  // element that carries no term); per element the map L from its slope
  // jumps to the slopes of its own quadratic at its mid-edges (ipl_, row
  // 3 k + i, zero without one). At a ghost edge (clamped, symmetry) ipb_
  // holds the coefficients of F_e nu (none on xo), ipmask_ is zero and the
  // edge is listed in ipghost_ (by element, from ipgstart_), the passes
  // adding its terms apart.
  void setup_in_plane() {
    const int ne = part_->num_elements;
    const std::size_t gld = static_cast<std::size_t>(gld_);
    const double* x0 = part_->x0.data();
    ipb_.assign(9 * gld, 0.0);
    ipl_.assign(9 * gld, 0.0);
    ipw_.assign(3 * gld, 0.5);
    ipc_.assign(3 * gld, 0.0);
    ipmask_.assign(3 * gld, 1.0);
    ipo_.assign(3 * gld, 0);
    ipk_.assign(3 * static_cast<std::size_t>(ne), static_cast<char>(kEdgeFree));
    ipnu_.assign(9 * static_cast<std::size_t>(ne), 0.0);
    ipghost_.clear();
    ipgstart_.assign(ne + 1, 0);
    std::vector<char> quad(ne, 0);
    const auto grads = [&](int e, Vec3 gr[3], Vec3& n) {  // grad0 N_a (3D, in the initial plane)
      const int* t = &part_->triangles[3 * e];
      const Vec3 X[3] = {load3(x0, t[0]), load3(x0, t[1]), load3(x0, t[2])};
      const Vec3 nn = cross(sub(X[1], X[0]), sub(X[2], X[0]));
      const double two_a = norm(nn);
      n = scale(nn, 1.0 / two_a);
      for (int a = 0; a < 3; ++a) gr[a] = scale(cross(n, sub(X[(a + 2) % 3], X[(a + 1) % 3])), 1.0 / two_a);
    };
    for (int e = 0; e < ne; ++e) {
      ipgstart_[e] = static_cast<int>(ipghost_.size());
      const int* t = &part_->triangles[3 * e];
      Vec3 ge[3], n;
      grads(e, ge, n);
      const Vec3 f = load3(e1_.data(), e);
      bool off = false;
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        const std::size_t ek = static_cast<std::size_t>(k) * gld + e;
        ipo_[ek] = 3 * t[0];
        const Vec3 P = load3(x0, t[(k + 1) % 3]), Q = load3(x0, t[(k + 2) % 3]);
        const Vec3 nu = normalized(cross(sub(Q, P), n));  // outward in the element's plane
        const double l = norm(sub(Q, P)), nf = dot(nu, f);
        const int nb = part_->neighbours[3 * e + k];
        // bk: the coefficients of J on the element's three nodes and xo.
        double bk[4] = {0, 0, 0, 0};
        if (nb < 0) {
          const int ec = edge_condition_.empty() ? kEdgeFree : edge_condition_[3 * e + k];
          if (ec == kEdgeFree) {
            // The mid-edge slope is free, and the energy's minimum over it
            // makes K11 zero unless the edge runs along the fibres.
            if (nf * nf > 1e-6) off = true;
            continue;
          }
          // A ghost: the mirrored element (s = phi / 2, omega 1/2 with no
          // quadratic on either side) or the held grip (s = phi). bk: the
          // coefficients of F_e nu on the element's nodes.
          ipk_[3 * e + k] = static_cast<char>(ec);
          ipc_[ek] = l * nf * nf / area0_[e];
          ipw_[ek] = ec == kEdgeClamped ? 0.0 : 0.5;
          ipmask_[ek] = 0.0;
          ipghost_.push_back(3 * e + k);
          for (int a = 0; a < 3; ++a) bk[a] = dot(ge[a], nu);
          for (int d = 0; d < 3; ++d) ipnu_[9 * static_cast<std::size_t>(e) + 3 * k + d] = nu[d];
        } else {
          ++count;
          ipc_[ek] = l * nf * nf / area0_[e];
          Vec3 gj[3], nj;
          grads(nb, gj, nj);
          for (int a = 0; a < 3; ++a) bk[a] = -dot(ge[a], nu);
          for (int j = 0; j < 3; ++j) {
            const int node = part_->triangles[3 * nb + j];
            const double v = dot(gj[j], nu);
            if (node == t[(k + 1) % 3]) bk[(k + 1) % 3] += v;
            else if (node == t[(k + 2) % 3]) bk[(k + 2) % 3] += v;
            else bk[3] = v;
          }
          ipo_[ek] = 3 * opp_[3 * e + k];
        }
        // Relative to corner 0 (the four coefficients sum to zero).
        for (int j = 0; j < 3; ++j) ipb_[(3 * k + j) * gld + e] = bk[j + 1];
      }
      if (off)
        for (int k = 0; k < 3; ++k) ipc_[k * gld + e] = 0.0;
      if (count == 3) {
        double L[9];
        quad[e] = in_plane_quadratic(e, L) ? 1 : 0;
        if (quad[e])
          for (int j = 0; j < 9; ++j) ipl_[j * gld + e] = L[j];
      }
    }
    ipgstart_[ne] = static_cast<int>(ipghost_.size());
    for (int e = 0; e < ne; ++e)
      for (int k = 0; k < 3; ++k) {
        const int nb = part_->neighbours[3 * e + k];
        if (nb < 0) continue;
        ipw_[k * gld + e] = quad[e] && quad[nb] ? 0.5 : quad[e] ? 1.0 : quad[nb] ? 0.0 : 0.5;
      }
  }

  // L of element e (row k: the slope at mid-edge k of the quadratic through
  // the patch's six nodes, relative to the element's plane, per unit slope
  // jump across edge i): the quadratic with 1 at the node across edge i and
  // 0 at the other five has slope jump 1 / d_i across edge i (d_i that
  // node's distance from the edge) and none across the others. False where
  // the six nodes (nearly) lie on a conic.
  bool in_plane_quadratic(int e, double* L) const {
    const double* x0 = part_->x0.data();
    const int* t = &part_->triangles[3 * e];
    const Vec3 X0 = load3(x0, t[0]);
    const Vec3 n = normalized(cross(sub(load3(x0, t[1]), X0), sub(load3(x0, t[2]), X0)));
    const Vec3 f = load3(e1_.data(), e), m = cross(n, f);
    const double h = std::sqrt(area0_[e]);
    double P[6][2];
    int nodes[6] = {t[0], t[1], t[2], opp_[3 * e], opp_[3 * e + 1], opp_[3 * e + 2]};
    for (int sl = 0; sl < 6; ++sl) {
      const Vec3 d = sub(load3(x0, nodes[sl]), X0);
      P[sl][0] = dot(d, f) / h;
      P[sl][1] = dot(d, m) / h;
    }
    // Inverse of the 6 x 6 matrix V (row: a node, columns: 1, u, v, u^2,
    // uv, v^2), by Gauss-Jordan with partial pivoting.
    double A[6][12] = {};
    for (int r = 0; r < 6; ++r) {
      const double u = P[r][0], v = P[r][1];
      const double row[6] = {1, u, v, u * u, u * v, v * v};
      for (int c = 0; c < 6; ++c) A[r][c] = row[c];
      A[r][6 + r] = 1;
    }
    for (int c = 0; c < 6; ++c) {
      int piv = c;
      for (int r = c + 1; r < 6; ++r)
        if (std::abs(A[r][c]) > std::abs(A[piv][c])) piv = r;
      if (!(std::abs(A[piv][c]) > 1e-6)) return false;
      std::swap(A[piv], A[c]);
      const double inv = 1.0 / A[c][c];
      for (int j = 0; j < 12; ++j) A[c][j] *= inv;
      for (int r = 0; r < 6; ++r) {
        if (r == c || A[r][c] == 0.0) continue;
        const double fct = A[r][c];
        for (int j = 0; j < 12; ++j) A[r][j] -= fct * A[c][j];
      }
    }
    for (int i = 0; i < 3; ++i) {
      // Coefficients of the quadratic with 1 at node 3 + i: column 3 + i of
      // V^-1 (scaled coordinates).
      double a[6];
      for (int r = 0; r < 6; ++r) a[r] = A[r][6 + 3 + i];
      const int p = 3 + i;
      // d_i: the node's distance from edge i (scaled).
      const double* E1 = P[(i + 1) % 3];
      const double* E2 = P[(i + 2) % 3];
      const double ex = E2[0] - E1[0], ey = E2[1] - E1[1], el = std::hypot(ex, ey);
      const double di = std::abs((P[p][0] - E1[0]) * ey - (P[p][1] - E1[1]) * ex) / el;
      for (int k = 0; k < 3; ++k) {
        const double* Q1 = P[(k + 1) % 3];
        const double* Q2 = P[(k + 2) % 3];
        const double qx = Q2[0] - Q1[0], qy = Q2[1] - Q1[1], ql = std::hypot(qx, qy);
        const double nx = qy / ql, ny = -qx / ql;  // outward (counter-clockwise corners)
        const double u = 0.5 * (Q1[0] + Q2[0]), v = 0.5 * (Q1[1] + Q2[1]);
        const double du = a[1] + 2 * a[3] * u + a[4] * v, dv = a[2] + a[4] * u + 2 * a[5] * v;
        // Slope in scaled units times the jump's scale: L is dimensionless.
        L[3 * k + i] = (du * nx + dv * ny) * di;
      }
    }
    for (int j = 0; j < 9; ++j)
      if (!(std::abs(L[j]) <= kMaxSlopeMap)) {
        for (int q = 0; q < 9; ++q) L[q] = 0.0;
        return false;
      }
    return true;
  }

  // The element's current unit normal n, fibre f = F a0 / |F a0|, m = n x f,
  // |F a0|, |N| (N = x10 x x20) and x10, x20 (for the ghost edges, which
  // the passes add apart; in_plane_frame_v forms the same for the blocks).
  struct InPlaneFrame {
    Vec3 n, f, m, x10, x20;
    double glen, nlen;
  };
  InPlaneFrame in_plane_frame(const double* x, int e) const {
    InPlaneFrame fr;
    const int* t = &part_->triangles[3 * e];
    const Vec3 x0 = load3(x, t[0]);
    fr.x10 = sub(load3(x, t[1]), x0);
    fr.x20 = sub(load3(x, t[2]), x0);
    const Vec3 g = add(scale(fr.x10, g_[e]), scale(fr.x20, g_[mld_ + e]));
    fr.glen = norm(g);
    fr.f = scale(g, 1.0 / fr.glen);
    const Vec3 N = cross(fr.x10, fr.x20);
    fr.nlen = norm(N);
    fr.n = scale(N, 1.0 / fr.nlen);
    fr.m = cross(fr.n, fr.f);
    return fr;
  }
  // J_k at the ghost edge k of element e (ipk_ its kind) at positions x:
  // from F_e nu = sum of ipb_'s coefficients on x1 - x0 and x2 - x0.
  Vec3 ghost_jump(const InPlaneFrame& fr, int e, int k) const {
    const std::size_t gld = static_cast<std::size_t>(gld_);
    Vec3 J = add(scale(fr.x10, ipb_[3 * k * gld + e]), scale(fr.x20, ipb_[(3 * k + 1) * gld + e]));
    const int kind = ipk_[3 * e + k];
    if (kind == kEdgeClamped) return sub(load3(ipnu_.data(), 3 * e + k), J);
    J[kind - kEdgeSymmetryX] = 0.0;
    return scale(J, -2.0);
  }
  // d(m . J_k) / d(F_e nu) for a ghost edge of kind `kind`: -m at a clamp,
  // -(I + P) m = -2 m without its component normal to a symmetry plane.
  static Vec3 ghost_jump_row(int kind, Vec3 m) {
    if (kind == kEdgeClamped) return scale(m, -1.0);
    m[kind - kEdgeSymmetryX] = 0.0;
    return scale(m, -2.0);
  }

  // The in-plane term's values of the step for the range in.range (edge k
  // of its element q at [k ld + q], per element at [q]) and, through nidx
  // (rows of gld_ from the range's first element), the neighbours' same
  // edges in *_all: arrays over the whole part, or where the kernel
  // interleaves the passes the ring of block buffers (as step_values).
  struct InPlaneStep {
    double *phi, *r, *m, *g, *fm, *og0, *og1, *og2, *e;
    int ld;
    const int* nidx;
    const double *r_all, *m_all, *og0_all, *og1_all, *og2_all;
  };
  InPlaneStep in_plane_step(const ElementForceInput& in) {
    const int b = in.range.begin;
    if (in.pass_window > 0 && in.block_size > 0) {
      if (in.pass_window != ring_w_ || in.block_size != ring_bs_) set_up_ring(in.pass_window, in.block_size);
      return ring_ip_step_.view(static_cast<std::size_t>(in.block % ring_w_) * 3 * rld_, rld_, ring_nidx_.data() + b);
    }
    return ip_step_.view(b, gld_, nidx_.data() + b);
  }
  // The arrays behind InPlaneStep: m values each (r, m and each third of
  // og with a zero past them, read for edges without a neighbour).
  struct InPlaneStepArrays {
    std::vector<double> phi, r, m, g, fm, og, e;
    void assign(std::size_t n) {
      phi.assign(n, 0.0), r.assign(n + 1, 0.0), m.assign(n + 1, 0.0), g.assign(n, 0.0), fm.assign(n, 0.0);
      og.assign(3 * (n + 1), 0.0), e.assign(n, 0.0);
    }
    // From offset o, rows of ld, nidx into the *_all arrays.
    InPlaneStep view(std::size_t o, int ld, const int* nidx) {
      const std::size_t w = r.size();
      double* o3 = og.data();
      return {phi.data() + o, r.data() + o, m.data() + o, g.data() + o, fm.data() + o, o3 + o, o3 + w + o,
              o3 + 2 * w + o, e.data() + o, ld, nidx, r.data(), m.data(), o3, o3 + w, o3 + 2 * w};
    }
  };

  // Pass 0: the slope jumps phi_k = m . J_k and the own quadratic's slopes
  // r = L phi (an element with a ghost edge has no quadratic: r = 0).
  void in_plane_angles(const ElementForceInput& in, int b, int end) {
    const double* x = part_->x.data();
    const InPlaneStep st = in_plane_step(in);
    in_plane_angle_block(end - b, off_.data() + b, g_.data() + b, mld_, ipo_.data() + b, ipb_.data() + b, ipl_.data() + b,
                         gld_, x, st.ld, st.phi, st.r, st.fm);
    for (int h = ipgstart_[b]; h < ipgstart_[end]; ++h) {
      const int e = ipghost_[h] / 3, k = ipghost_[h] % 3;
      const InPlaneFrame fr = in_plane_frame(x, e);
      st.phi[k * st.ld + (e - b)] = dot(fr.m, ghost_jump(fr, e, k));
    }
  }

  // Pass 1: mid-edge slopes s_k = omega r_k + (1 - omega) (phi_k - r'_k),
  // K11 = sum_k c_k s_k, the law, and dW/ds_k = A0 M11 c_k and each
  // element's A0 w into the step's values.
  Status in_plane_moments(const ElementForceInput& in, int b, int end) {
    const int n = end - b;
    const std::size_t gld = static_cast<std::size_t>(gld_);
    const InPlaneStep st = in_plane_step(in);
    thread_local std::vector<double> chi, moment, w;
    if (chi.size() < 3 * static_cast<std::size_t>(n)) {
      chi.resize(3 * static_cast<std::size_t>(n));
      moment.resize(3 * static_cast<std::size_t>(n));
      w.resize(n);
    }
    in_plane_curvature_block(n, gld_, ipc_.data() + b, ipw_.data() + b, st.ld, st.phi, st.r, st.nidx, st.r_all,
                             chi.data());
    MaterialBlock blk;
    blk.n = n;
    blk.strain = std::span<const double>(chi.data(), 3 * static_cast<std::size_t>(n));
    blk.temperature = std::span<const double>(etemp_.data() + b, n);
    blk.dt = in.dt;
    blk.stress = std::span<double>(moment.data(), 3 * static_cast<std::size_t>(n));
    blk.energy = std::span<double>(w.data(), n);
    if (auto st = in_plane_->evaluate(blk); !st) return st;
    for (int k = 0; k < 3; ++k) {
      const double* c = ipc_.data() + k * gld + b;
      double* m = st.m + static_cast<std::size_t>(k) * st.ld;
      for (int q = 0; q < n; ++q) m[q] = area0_[b + q] * moment[3 * q] * c[q];
    }
    for (int q = 0; q < n; ++q) st.e[q] = area0_[b + q] * w[q];
    return Status::success();
  }

  // Pass 2: each element's dW/dphi_i = (1 - omega_i) m_i + sum_k L_ki
  // omega_k (m_k - m'_k), m' the neighbour's dW/ds of the same edge, and the
  // forces on the nodes across its edges.
  void in_plane_shares(const ElementForceInput& in, int b, int end) {
    const InPlaneStep st = in_plane_step(in);
    in_plane_share_block(end - b, gld_, ipw_.data() + b, ipl_.data() + b, st.nidx, ipb_.data() + b, st.ld, st.m,
                         st.m_all, st.fm, st.g, st.og0, st.og1, st.og2);
  }

  // Pass 3: the forces sum_i g_i dphi_i/dx into the block's corner forces mf
  // (component d of corner a of element q at mf[(3 a + d) ld + q]), the
  // ghost edges' apart; the range's energy; lowers the elements' steps dte
  // (where given) or dt_floor with the term's (the bending's formula for
  // rigidity R: it is evaluated at every step, also where the bending is
  // not).
  double in_plane_forces(const ElementForceInput& in, int b, int end, double* dte, double t_lo, double t_hi,
                         double* mf, int ld, double& dt_floor) {
    const double* x = part_->x.data();
    const std::size_t gld = static_cast<std::size_t>(gld_);
    const int n = end - b;
    const InPlaneStep st = in_plane_step(in);
    in_plane_force_block(n, off_.data() + b, g_.data() + b, mld_, ipo_.data() + b, ipb_.data() + b, gld_, st.ld, st.g,
                         ipmask_.data() + b, st.nidx, st.og0_all, st.og1_all, st.og2_all, x, mf, ld);
    for (int h = ipgstart_[b]; h < ipgstart_[end]; ++h) {
      const int e = ipghost_[h] / 3, i = ipghost_[h] % 3, q = e - b;
      const double gi = st.g[i * st.ld + q];
      if (gi == 0.0) continue;
      const InPlaneFrame fr = in_plane_frame(x, e);
      const Vec3 row = ghost_jump_row(ipk_[3 * e + i], fr.m);
      const double c1 = gi * ipb_[3 * i * gld + e], c2 = gi * ipb_[(3 * i + 1) * gld + e];
      Vec3 own[3] = {scale(row, -(c1 + c2)), scale(row, c1), scale(row, c2)};
      const Vec3 Jg = scale(ghost_jump(fr, e, i), gi);
      Vec3 kn = cross(Jg, fr.n);
      kn = scale(sub(kn, scale(fr.f, dot(fr.f, kn))), 1.0 / fr.glen);
      Vec3 v = cross(fr.f, Jg);
      v = scale(sub(v, scale(fr.n, dot(fr.n, v))), 1.0 / fr.nlen);
      const Vec3 t1 = cross(fr.x20, v), t2 = cross(v, fr.x10);
      const double b1 = g_[e], b2 = g_[mld_ + e], b0 = -(b1 + b2);
      own[0] = sub(add(own[0], scale(kn, b0)), add(t1, t2));
      own[1] = add(add(own[1], scale(kn, b1)), t1);
      own[2] = add(add(own[2], scale(kn, b2)), t2);
      for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 3; ++d) mf[(3 * a + d) * ld + q] += own[a][d];
    }
    const double energy = lane_dot(n, st.e, nullptr);
    const double rmax = std::max(in_plane_->max_stiffness(t_lo), in_plane_->max_stiffness(t_hi));
    if (rmax > 0) {
      // As the bending's: dt ~ d^2 sqrt(rho h / R) / 2.
      const double c = 0.5 * std::sqrt(areal_mass_ / rmax);
      const double* scale_f = in.dt_scale.empty() ? nullptr : in.dt_scale.data() + b;
      double lo = std::numeric_limits<double>::infinity();
      for (int q = 0; q < n; ++q) {
        const double dt = dmin2_[b + q] * c;
        lo = std::min(lo, scale_f ? dt * scale_f[q] : dt);
        if (dte) dte[q] = std::min(dte[q], dt);
      }
      if (!dte) dt_floor = std::min(dt_floor, lo);
    }
    return energy;
  }

  void setup_bending() {
    const int ne = part_->num_elements;
    opp_.assign(3 * ne, -1);
    partner_k_.assign(3 * ne, -1);
    clamped_.assign(3 * ne, 0);
    n0_.assign(3 * ne, 0.0);
    d_.assign(3 * ne, 1.0);
    theta0_.assign(3 * ne, 0.0);
    gld_ = padded_ld(ne);
    curv_.assign(3 * ne, 0.0);
    curv_old_.assign(bending_->uses_strain_old() ? 3 * ne : 0, 0.0);
    bstate_.assign(static_cast<std::size_t>(bending_->state_size()) * ne, 0.0);
    const double* x0 = part_->x0.data();
    for (int e = 0; e < ne; ++e) {
      const int* t = &part_->triangles[3 * e];
      const Vec3 X[3] = {load3(x0, t[0]), load3(x0, t[1]), load3(x0, t[2])};
      const Vec3 n = normalized(cross(sub(X[1], X[0]), sub(X[2], X[0])));
      for (int k = 0; k < 3; ++k) {
        const int p = t[(k + 1) % 3], q = t[(k + 2) % 3];
        const Vec3 P = load3(x0, p), Q = load3(x0, q);
        const int nb = part_->neighbours[3 * e + k];
        if (nb < 0) {
          const int ec = edge_condition_.empty() ? kEdgeFree : edge_condition_[3 * e + k];
          if (ec == kEdgeClamped) {
            clamped_[3 * e + k] = 1;
            for (int d = 0; d < 3; ++d) n0_[3 * e + d] = n[d];
          } else if (ec >= kEdgeSymmetryX) {
            clamped_[3 * e + k] = static_cast<char>(2 + (ec - kEdgeSymmetryX));  // 2, 3, 4: plane x, y, z
          }
          continue;
        }
        for (int j = 0; j < 3; ++j) {
          const int o = part_->triangles[3 * nb + j];
          if (o != p && o != q) opp_[3 * e + k] = o;
          if (part_->neighbours[3 * nb + j] == e) partner_k_[3 * e + k] = j;
        }
        const int o = opp_[3 * e + k];
        const Vec3 C = X[k], O = load3(x0, o);
        const Vec3 eh = normalized(sub(Q, P));
        auto height = [&](const Vec3& V) {
          const Vec3 v = sub(V, P);
          return norm(sub(v, scale(eh, dot(v, eh))));
        };
        d_[3 * e + k] = std::min(height(C), height(O));
        theta0_[3 * e + k] = hinge_angle(x0, t[k], p, q, o);
      }
    }
    // Interior hinges, each once, owned by the lower-numbered of its two
    // elements and numbered by owner: the hinges owned by the elements of
    // [b, end) are [hstart_[b], hstart_[end]).
    hstart_.assign(ne + 1, 0);
    hid_.assign(3 * ne, -1);
    hc_.clear(), hp_.clear(), hq_.clear(), ho_.clear(), htheta0_.clear();
    dmin2_.assign(ne, std::numeric_limits<double>::infinity());
    for (int e = 0; e < ne; ++e) {
      hstart_[e] = static_cast<int>(hc_.size());
      const int* t = &part_->triangles[3 * e];
      for (int k = 0; k < 3; ++k) {
        const int nb = part_->neighbours[3 * e + k];
        if (nb < 0) continue;
        dmin2_[e] = std::min(dmin2_[e], d_[3 * e + k] * d_[3 * e + k]);
        if (nb < e) continue;
        const int h = static_cast<int>(hc_.size());
        hid_[3 * e + k] = h;
        hid_[3 * nb + partner_k_[3 * e + k]] = h;
        hc_.push_back(3 * t[k]);
        hp_.push_back(3 * t[(k + 1) % 3]);
        hq_.push_back(3 * t[(k + 2) % 3]);
        ho_.push_back(3 * opp_[3 * e + k]);
        htheta0_.push_back(theta0_[3 * e + k]);
      }
    }
    hstart_[ne] = static_cast<int>(hc_.size());
    // Ghost hinges (clamped and symmetry edges) by element: those of the
    // elements of [b, end) are gedge_[gstart_[b] .. gstart_[end]) (3 e + k).
    gstart_.assign(ne + 1, 0);
    block_hinges_.clear();
    block_hinges_.resize(ne + 1);
    block_angles_.clear();
    block_angles_.resize(ne + 1);
    gedge_.clear();
    for (int e = 0; e < ne; ++e) {
      gstart_[e] = static_cast<int>(gedge_.size());
      for (int k = 0; k < 3; ++k)
        if (clamped_[3 * e + k]) gedge_.push_back(3 * e + k);
    }
    gstart_[ne] = static_cast<int>(gedge_.size());
  }

  // The law's small-curvature rigidities D (M = D K, Voigt (11, 22, 12)) at
  // temperature T, probed with three unit curvatures; false if the law
  // fails or returns a non-finite value.
  bool probe_rigidity(double T, double D[3][3]) const {
    const double eps = 1e-6;
    const int ns = bending_->state_size();
    std::vector<double> chi(9, 0.0), old(9, 0.0), temp(3, T), state(static_cast<std::size_t>(ns) * 3, 0.0), M(9, 0.0), W(3, 0.0);
    for (int j = 0; j < 3; ++j) chi[3 * j + j] = eps;
    MaterialBlock blk;
    blk.n = 3;
    blk.strain = chi;
    if (bending_->uses_strain_old()) blk.strain_old = old;
    blk.temperature = temp;
    blk.dt = 1e-3;
    blk.state = state;
    blk.stress = M;
    blk.energy = W;
    if (!bending_->evaluate(blk)) return false;
    for (int r = 0; r < 3; ++r)
      for (int j = 0; j < 3; ++j) {
        D[r][j] = M[3 * j + r] / eps;
        if (!std::isfinite(D[r][j])) return false;
      }
    return true;
  }

  // The mid-edge slopes of every element (see the header): the map L from
  // the element's three angle changes to the slopes of its own quadratic,
  // the weights omega per edge, and dK/ds with the free edges condensed
  // (zero normal moment there, with the law's rigidities at the part's
  // initial temperature T).
  Status setup_slopes(double T) {
    const int ne = part_->num_elements;
    const double* x0 = part_->x0.data();
    const int* nbr = part_->neighbours.data();
    cs_.assign(9 * static_cast<std::size_t>(gld_), 0.0);
    const std::size_t gld = static_cast<std::size_t>(gld_);
    lmap_.assign(9 * gld, 0.0f);
    acoef_.assign(3 * gld, 0.0f);
    nidx_.assign(3 * gld, static_cast<int>(3 * gld));
    eq_.assign(3 * gld, 0.0);
    erho_.assign(3 * gld + 1, 0.0);  // the last: zero, read for edges without a neighbour
    em_.assign(3 * gld + 1, 0.0);
    hm_.assign(3 * gld + 1, 0.0);
    std::vector<char> fit(ne, 0);
    // Gradient of the linear interpolant of values v at three points.
    auto grad_lin = [](const double P[3][2], const double v[3], double g[2]) {
      const double ax = P[1][0] - P[0][0], ay = P[1][1] - P[0][1], bx = P[2][0] - P[0][0], by = P[2][1] - P[0][1];
      const double det = ax * by - ay * bx, dv1 = v[1] - v[0], dv2 = v[2] - v[0];
      g[0] = (dv1 * by - dv2 * ay) / det;
      g[1] = (ax * dv2 - bx * dv1) / det;
    };
    // The quadratics x^2 / 2, y^2 / 2 and x y and their gradients.
    auto quad = [](int j, const double* p) { return j == 0 ? 0.5 * p[0] * p[0] : j == 1 ? 0.5 * p[1] * p[1] : p[0] * p[1]; };
    auto quad_grad = [](int j, const double* p, double* g) {
      g[0] = j == 0 ? p[0] : j == 1 ? 0.0 : p[1];
      g[1] = j == 0 ? 0.0 : j == 1 ? p[1] : p[0];
    };
    std::vector<double> nu2(6 * static_cast<std::size_t>(ne)), len(3 * static_cast<std::size_t>(ne));
    for (int e = 0; e < ne; ++e) {
      const int* t = &part_->triangles[3 * e];
      const Vec3 X[3] = {load3(x0, t[0]), load3(x0, t[1]), load3(x0, t[2])};
      const Vec3 cen = scale(add(add(X[0], X[1]), X[2]), 1.0 / 3.0);
      const Vec3 n = normalized(cross(sub(X[1], X[0]), sub(X[2], X[0])));
      const Vec3 f = load3(e1_.data(), e), m = load3(e2_.data(), e);
      double P[3][2];
      for (int a = 0; a < 3; ++a) {
        const Vec3 v = sub(X[a], cen);
        P[a][0] = dot(v, f);
        P[a][1] = dot(v, m);
      }
      double ge[3][2];  // gradients of the element's interpolants of the quadratics
      for (int j = 0; j < 3; ++j) {
        const double v[3] = {quad(j, P[0]), quad(j, P[1]), quad(j, P[2])};
        grad_lin(P, v, ge[j]);
      }
      double B[3][3], R[3][3];
      bool ok = true;
      for (int k = 0; k < 3; ++k) {
        const int a = (k + 1) % 3, c = (k + 2) % 3;
        const Vec3 Pp = X[a], Pq = X[c];
        const Vec3 nu = normalized(cross(sub(Pq, Pp), n));
        const double nx = dot(nu, f), ny = dot(nu, m);
        nu2[6 * e + 2 * k] = nx;
        nu2[6 * e + 2 * k + 1] = ny;
        len[3 * e + k] = norm(sub(Pq, Pp));
        const double mid[2] = {0.5 * (P[a][0] + P[c][0]), 0.5 * (P[a][1] + P[c][1])};
        for (int j = 0; j < 3; ++j) {
          double g[2];
          quad_grad(j, mid, g);
          R[k][j] = (g[0] - ge[j][0]) * nx + (g[1] - ge[j][1]) * ny;
        }
        if (nbr[3 * e + k] >= 0) {
          // The neighbour unfolded into the element's plane across the edge.
          const Vec3 O = load3(x0, opp_[3 * e + k]);
          const Vec3 eh = normalized(sub(Pq, Pp)), v = sub(O, Pp);
          const double along = dot(v, eh), h = norm(sub(v, scale(eh, along)));
          const double ex = (P[c][0] - P[a][0]) / len[3 * e + k], ey = (P[c][1] - P[a][1]) / len[3 * e + k];
          const double Q[3][2] = {{P[a][0], P[a][1]}, {P[c][0], P[c][1]},
                                  {P[a][0] + along * ex + h * nx, P[a][1] + along * ey + h * ny}};
          for (int j = 0; j < 3; ++j) {
            const double v3[3] = {quad(j, Q[0]), quad(j, Q[1]), quad(j, Q[2])};
            double gn[2];
            grad_lin(Q, v3, gn);
            B[k][j] = (gn[0] - ge[j][0]) * nx + (gn[1] - ge[j][1]) * ny;
          }
        } else if (clamped_[3 * e + k]) {
          for (int j = 0; j < 3; ++j) B[k][j] = -2 * (ge[j][0] * nx + ge[j][1] * ny);
        } else {
          ok = false;  // a free edge: no quadratic through the patch
        }
      }
      if (!ok) continue;
      // L = R B^-1, kept where B is well conditioned and L moderate.
      const double det = B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) -
                         B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                         B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0]);
      double bmax = 0;
      for (const auto& row : B)
        for (double v : row) bmax = std::max(bmax, std::abs(v));
      if (!(std::abs(det) > 1e-6 * bmax * bmax * bmax)) continue;
      double Bi[3][3];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
          Bi[r][c] = (B[r1][c1] * B[r2][c2] - B[r1][c2] * B[r2][c1]) / det;
        }
      double L[9], lmax = 0;
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) {
          L[3 * k + i] = R[k][0] * Bi[0][i] + R[k][1] * Bi[1][i] + R[k][2] * Bi[2][i];
          lmax = std::max(lmax, std::abs(L[3 * k + i]));
        }
      if (!(lmax < kMaxSlopeMap)) continue;
      for (int i = 0; i < 9; ++i) lmap_[i * gld + e] = static_cast<float>(L[i]);
      fit[e] = 1;
    }
    // Weights omega of the element's own slope per interior edge; the rows
    // of L scaled by them (zero for edges without a neighbour: no one reads
    // those slopes), and a = 1 - omega (1/2 at a held edge, 0 at a free one).
    for (int e = 0; e < ne; ++e)
      for (int k = 0; k < 3; ++k) {
        const int nb = nbr[3 * e + k], i = 3 * e + k;
        const double w = nb < 0 ? 0.0 : fit[e] && fit[nb] ? 0.5 : fit[e] ? 1.0 : fit[nb] ? 0.0 : 0.5;
        for (int c = 0; c < 3; ++c) {
          float& l = lmap_[(3 * k + c) * gld + e];
          l = static_cast<float>(w * l);
        }
        acoef_[k * gld + e] = static_cast<float>(nb >= 0 ? 1 - w : clamped_[i] ? 0.5 : 0.0);
        if (nb >= 0) nidx_[k * gld + e] = static_cast<int>(partner_k_[i] * gld + nb);
      }
    double D[3][3];
    const bool have_d = probe_rigidity(T, D);
    for (int e = 0; e < ne; ++e) {
      const double A0 = area0_[e];
      double c[3][3];  // dK/ds_k before condensation: l_k / A0 nu (x) nu
      int free_edges[3], nf = 0;
      for (int k = 0; k < 3; ++k) {
        const double nx = nu2[6 * e + 2 * k], ny = nu2[6 * e + 2 * k + 1], s = len[3 * e + k] / A0;
        c[k][0] = s * nx * nx;
        c[k][1] = s * ny * ny;
        c[k][2] = s * nx * ny;
        if (nbr[3 * e + k] < 0 && !clamped_[3 * e + k]) free_edges[nf++] = k;
      }
      // Free edges: the slope that makes the normal moment zero, M_nn = t . D K
      // with t = (nx^2, ny^2, 2 nx ny), solved for (s_f) and folded into the
      // other edges' coefficients.
      double cp[3][3];
      for (int k = 0; k < 3; ++k)
        for (int r = 0; r < 3; ++r) cp[k][r] = c[k][r];
      for (int i = 0; i < nf; ++i)
        for (int r = 0; r < 3; ++r) cp[free_edges[i]][r] = 0.0;
      if (have_d && nf > 0 && nf < 3) {
        auto tDc = [&](int f, const double* v) {
          const double nx = nu2[6 * e + 2 * f], ny = nu2[6 * e + 2 * f + 1];
          const double tv[3] = {nx * nx, ny * ny, 2 * nx * ny};
          double r = 0;
          for (int a = 0; a < 3; ++a)
            for (int bb = 0; bb < 3; ++bb) r += tv[a] * D[a][bb] * v[bb];
          return r;
        };
        double A[2][2] = {{0, 0}, {0, 0}};
        for (int i = 0; i < nf; ++i)
          for (int j = 0; j < nf; ++j) A[i][j] = tDc(free_edges[i], c[free_edges[j]]);
        double Ai[2][2];
        bool solvable;
        if (nf == 1) {
          solvable = std::abs(A[0][0]) > 0;
          Ai[0][0] = solvable ? 1.0 / A[0][0] : 0.0;
        } else {
          const double dA = A[0][0] * A[1][1] - A[0][1] * A[1][0];
          solvable = std::abs(dA) > 1e-12 * (std::abs(A[0][0] * A[1][1]) + std::abs(A[0][1] * A[1][0]));
          if (solvable) {
            Ai[0][0] = A[1][1] / dA, Ai[0][1] = -A[0][1] / dA;
            Ai[1][0] = -A[1][0] / dA, Ai[1][1] = A[0][0] / dA;
          }
        }
        if (solvable)
          for (int k = 0; k < 3; ++k) {
            if (nbr[3 * e + k] < 0 && !clamped_[3 * e + k]) continue;
            for (int i = 0; i < nf; ++i) {
              double si = 0;  // d s_f(i) / d s_k
              for (int j = 0; j < nf; ++j) si -= Ai[i][j] * tDc(free_edges[j], c[k]);
              for (int r = 0; r < 3; ++r) cp[k][r] += si * c[free_edges[i]][r];
            }
          }
      }
      for (int k = 0; k < 3; ++k)
        for (int r = 0; r < 3; ++r) cs_[(3 * k + r) * static_cast<std::size_t>(gld_) + e] = static_cast<float>(cp[k][r]);
    }
    return Status::success();
  }

  // Per range [b, end), formed at its first evaluation and kept in the
  // range's own object (slot b; a range with other bounds forms it again),
  // in 16 bits where they fit: the elements' node offsets relative to the
  // smallest of them (off16, row a of element q at a n + q; off_base -1
  // where they span 2^16 or more), and the corners by node (from the
  // first three of each element's ElementForceInput::patch_slot, the same
  // at every call for a range), for node_forces: the nodes with k corners
  // in the range form group (k, count), their slots nslot and their
  // corners' entries nent in the block's corner forces (3 a ld + q, ld =
  // padded_ld(n); k per node, by ascending element), group after group.
  // Empty where a slot or an entry does not fit in 16 bits: the corners
  // are then added one by one into the kernel's slots (corner_forces).
  struct RangeIndex {
    int end = -1, off_base = -1;
    std::vector<std::uint16_t> off16, nslot, nent;
    std::vector<std::array<int, 2>> ngroup;
    double d2min = 0;  // with bending: the smallest dmin2_ of the range
  };

  // What the bending passes need of the hinges of a block [b, end) that depends
  // only on the mesh and the block's bounds; built at the block's first
  // evaluation and kept (the kernel's blocks do not change during a run).
  // Slot b belongs to the block starting at element b: blocks evaluated at
  // the same time never share it, and a range with other bounds rebuilds it.
  struct BlockHinges {
    int end = -1, nforeign = 0;
    // Where the node offsets of the hinges the block's elements own span
    // less than 2^16: the smallest of them, and h16 holds them relative to
    // it (the nown c, then p, q and o); -1 otherwise.
    int base16 = -1;
    std::vector<std::uint16_t> h16;
    int nbound = 0;  // edges without a neighbour (their entries follow the hinges')
    // Per element and edge of the block: the edge's entry in the angle
    // changes (see bending_forces), edge k of the block's element q at
    // loc[3 q + k], and again for slope_block at loc_k[k n + q] (n
    // elements), in 16 bits (loc_k16) where 3 n entries fit.
    std::vector<int> loc, loc_k;
    std::vector<std::uint16_t> loc_k16;
    // The hinges owned by an element of an earlier block: node offsets c,
    // p, q, o (nforeign each), initial angles and hinge numbers.
    std::vector<int> fnode, fhinge;
    std::vector<double> ftheta0;
  };
  const BlockHinges& block_hinges(int b, int end) {
    std::unique_ptr<BlockHinges>& slot = block_hinges_[b];
    if (slot && slot->end == end) return *slot;
    auto bh = std::make_unique<BlockHinges>();
    const int* nbr = part_->neighbours.data();
    const int n = end - b, h0 = hstart_[b], nown = hstart_[end] - h0;
    bh->end = end;
    bh->loc.assign(3 * n, 0);
    std::vector<int> fc, fp, fq, fo;
    for (int e = b; e < end; ++e)
      for (int k = 0; k < 3; ++k) {
        const int h = hid_[3 * e + k], nb = nbr[3 * e + k], i = 3 * (e - b) + k;
        if (h < 0) continue;  // a ghost entry, numbered below (after the foreign hinges)
        if (nb >= b) {
          bh->loc[i] = h - h0;
        } else {
          bh->loc[i] = nown + bh->nforeign++;
          fc.push_back(hc_[h]);
          fp.push_back(hp_[h]);
          fq.push_back(hq_[h]);
          fo.push_back(ho_[h]);
          bh->ftheta0.push_back(htheta0_[h]);
          bh->fhinge.push_back(h);
        }
      }
    if (nown > 0) {
      int lo = hc_[h0], hi = hc_[h0];
      for (const auto* a : {&hc_, &hp_, &hq_, &ho_})
        for (int h = h0; h < h0 + nown; ++h) lo = std::min(lo, (*a)[h]), hi = std::max(hi, (*a)[h]);
      if (hi - lo <= 0xffff) {
        bh->base16 = lo;
        bh->h16.resize(4 * static_cast<std::size_t>(nown));
        int r = 0;
        for (const auto* a : {&hc_, &hp_, &hq_, &ho_}) {
          for (int h = h0; h < h0 + nown; ++h) bh->h16[r * nown + (h - h0)] = static_cast<std::uint16_t>((*a)[h] - lo);
          ++r;
        }
      }
    }
    const int nh = nown + bh->nforeign;
    for (int e = b; e < end; ++e)
      for (int k = 0; k < 3; ++k)
        if (hid_[3 * e + k] < 0) bh->loc[3 * (e - b) + k] = nh + bh->nbound++;
    if (3 * n - 1 <= 0xffff) {
      bh->loc_k16.resize(3 * n);
      for (int q = 0; q < n; ++q)
        for (int k = 0; k < 3; ++k) bh->loc_k16[k * n + q] = static_cast<std::uint16_t>(bh->loc[3 * q + k]);
    } else {
      bh->loc_k.resize(3 * n);
      for (int q = 0; q < n; ++q)
        for (int k = 0; k < 3; ++k) bh->loc_k[k * n + q] = bh->loc[3 * q + k];
    }
    bh->fnode = fc;
    bh->fnode.insert(bh->fnode.end(), fp.begin(), fp.end());
    bh->fnode.insert(bh->fnode.end(), fq.begin(), fq.end());
    bh->fnode.insert(bh->fnode.end(), fo.begin(), fo.end());
    slot = std::move(bh);
    return *slot;
  }

  // The interior hinges of block [b, end) as two lists: those its elements
  // own, then those owned by an element of an earlier block. Calls f(h, c,
  // p, q, o, theta0, j0) for each list of int node offsets: h hinges with
  // node offsets c[j] ... o[j] and initial angles theta0[j], entries j0 ..
  // j0 + h - 1 of the block's hinges; for the own hinges where
  // BlockHinges::base16 allows, f16(h, h16, theta0, j0, base) instead, the
  // offsets base + h16[r h + j] (rows r = c, p, q, o).
  template <class F, class F16>
  void hinge_lists(int b, int end, const BlockHinges& bh, F&& f, F16&& f16) const {
    const int h0 = hstart_[b], nown = hstart_[end] - h0, nf = bh.nforeign;
    const int* fnode = bh.fnode.data();
    if (bh.base16 >= 0)
      f16(nown, bh.h16.data(), htheta0_.data() + h0, 0, bh.base16);
    else
      f(nown, hc_.data() + h0, hp_.data() + h0, hq_.data() + h0, ho_.data() + h0, htheta0_.data() + h0, 0);
    f(nf, fnode, fnode + nf, fnode + 2 * nf, fnode + 3 * nf, bh.ftheta0.data(), nown);
  }

  // The angle changes of the hinges of block [b, end) into dth (at most
  // 3 (end - b) entries, read by pass 0 only): its interior hinges (those
  // owned by its elements, then those owned by an element of an earlier
  // block), then one entry per element and edge without a neighbour (the
  // ghost hinge's angle, zero at a free edge). The ghost hinges' gradients
  // are kept for pass 3 in the block's BlockAngles.
  BlockAngles& block_angles(int b, int end, const BlockHinges& bh, double* dth) {
    const double* x = part_->x.data();
    static_assert(sizeof(Vec3) == 3 * sizeof(double));
    const int h0 = hstart_[b], nown = hstart_[end] - h0;
    const int nforeign = bh.nforeign;
    const int nh = nown + nforeign;
    std::unique_ptr<BlockAngles>& slot = block_angles_[b];
    const std::size_t ng = static_cast<std::size_t>(gstart_[end] - gstart_[b]);
    if (!slot) slot = std::make_unique<BlockAngles>();
    BlockAngles& ba = *slot;
    if (ba.ghost_grad.size() < 12 * ng) ba.ghost_grad.resize(12 * ng);
    double beyond = 0.0;
    hinge_lists(
        b, end, bh,
        [&](int h, const int* c, const int* p, const int* q, const int* o, const double* t0, int j0) {
          beyond = std::max(beyond, hinge_angle_block(h, c, p, q, o, x, t0, dth + j0));
        },
        [&](int h, const std::uint16_t* h16, const double* t0, int j0, int base) {
          beyond = std::max(beyond, hinge_angle_block16(h, h16, x + base, t0, dth + j0));
        });
    for (int j = 0; j < (beyond != 0.0 ? nh : 0); ++j)
      if (dth[j] != dth[j]) {  // NaN: beyond the approximation's range, the library's atan2
        const int h = j < nown ? h0 + j : bh.fhinge[j - nown];
        dth[j] = hinge_angle(x, hc_[h] / 3, hp_[h] / 3, hq_[h] / 3, ho_[h] / 3) - htheta0_[h];
      }
    // Ghost hinges (clamped and symmetry edges), one by one.
    double* ggrad = ba.ghost_grad.data();  // per ghost hinge of the block: d theta / dx on (c, p, q)
    std::fill(dth + nh, dth + nh + bh.nbound, 0.0);
    for (int g = gstart_[b]; g < gstart_[end]; ++g) {
      const int e = gedge_[g] / 3, k = gedge_[g] % 3;
      const int* t = &part_->triangles[3 * e];
      Vec3* gr = reinterpret_cast<Vec3*>(&ggrad[12 * static_cast<std::size_t>(g - gstart_[b])]);
      dth[bh.loc[3 * (e - b) + k]] =
          clamped_[3 * e + k] == 1
              ? 2 * ghost_angle(x, t[k], t[(k + 1) % 3], t[(k + 2) % 3], load3(n0_.data(), e), -1, gr)
              : ghost_angle(x, t[k], t[(k + 1) % 3], t[(k + 2) % 3], Vec3{0, 0, 0}, clamped_[3 * e + k] - 2, gr);
    }
    return ba;
  }

  // Pass 0: per element and edge of the block, from the angle changes
  // theta: rho = omega r (r = L theta the slopes of the element's own
  // quadratic at its mid-edges) and q = rho + a theta; the shared slope of
  // an edge is then s = q - rho' (rho' the neighbour's of the same edge).
  void slope_angles(const ElementForceInput& in, int b, int end) {
    const BlockHinges& bh = block_hinges(b, end);
    double* dth = block_scratch(end - b).dth.data();  // stays in the thread's cache
    block_angles(b, end, bh, dth);
    const StepValues sv = step_values(in);
    const int n = end - b;
    if (bh.loc_k16.empty()) {
      slope_block(n, n, gld_, bh.loc_k.data(), dth, lmap_.data() + b, acoef_.data() + b, sv.ld, sv.eq, sv.rho);
      return;
    }
    alignas(64) int w[3 * kWidenPiece];  // the 16-bit entries widened (see kWidenPiece)
    for (int j = 0; j < n; j += kWidenPiece) {
      const int m = std::min(kWidenPiece, n - j);
      widen_rows(3, bh.loc_k16.data(), n, j, m, w);
      slope_block(m, kWidenPiece, gld_, w, dth, lmap_.data() + b + j, acoef_.data() + b + j, sv.ld, sv.eq + j,
                  sv.rho + j);
    }
  }

  // Pass 1: mid-edge slopes, curvatures, the law's moments and energies,
  // and per element and edge dW/ds_k = A0 M : dK/ds_k (em_).
  Status slope_moments(const ElementForceInput& in, int b, int end) {
    const int n = end - b;
    BlockScratch& sc = block_scratch(n);
    double* temp = etemp_.data() + b;  // read again by pass 3
    double* K = in.fields_due ? curv_.data() + 3 * b : sc.curv.data();  // kept for fields() only where asked
    const StepValues sv = step_values(in);
    if (temperatures_kept(in, b, end)) {
      curvature_only_block(n, gld_, cs_.data() + b, sv.nidx, sv.ld, sv.eq, sv.rho_all, K);
    } else {
      curvature_block(n, gld_, cs_.data() + b, sv.nidx, sv.ld, sv.eq, sv.rho_all, &part_->triangles[3 * b],
                      in.node_temperature.data(), K, temp);
      keep_temperatures(in, b, end);
    }
    MaterialBlock blk;
    blk.n = n;
    blk.strain = std::span<const double>(K, 3 * n);
    if (!curv_old_.empty()) blk.strain_old = std::span<const double>(curv_old_.data() + 3 * b, 3 * n);
    blk.temperature = std::span<const double>(temp, n);
    BlockAngles& ba = *block_angles_[b];
    blk.dt = in.dt + ba.elapsed;  // since the last evaluation with bending
    if (in.commit) ba.elapsed = 0;
    const int ns = bending_->state_size();
    blk.state = std::span<double>(bstate_.data() + static_cast<std::size_t>(ns) * b, static_cast<std::size_t>(ns) * n);
    blk.stress = std::span<double>(sc.moment.data(), 3 * n);
    blk.energy = std::span<double>(sc.benergy.data(), n);
    if (auto st = bending_->evaluate(blk); !st) return st;
    double* ew = sc.energy_tmp.data();
    moment_block(n, gld_, area0_.data() + b, cs_.data() + b, sc.moment.data(), sc.benergy.data(), sv.ld, sv.em, ew);
    block_angles_[b]->bending_energy = lane_dot(n, ew, nullptr);  // pass 3 adds the membrane energies to it
    if (in.commit && !curv_old_.empty()) std::copy(K, K + 3 * n, curv_old_.begin() + 3 * b);
    return Status::success();
  }

  // Pass 2: each element's share of dW/dtheta of its hinges,
  //   g_i = a_i m_i + sum_k omega_k L_ki (m_k - m'_k)
  // (m' the neighbour's dW/ds of the same edge), into hm_; the shares of
  // the ghost hinges (clamped and symmetry edges) go to the block's
  // ghost_m, and their entries in hm_ are zero (as are those of free
  // edges), so that pass 3 reads the two shares of interior hinges only.
  void hinge_moments(const ElementForceInput& in, int b, int end) {
    const int n = end - b;
    const StepValues sv = step_values(in);
    hinge_moment_block(n, gld_, lmap_.data() + b, acoef_.data() + b, sv.nidx, sv.ld, sv.em, sv.em_all, sv.hm);
    if (gstart_[b] == gstart_[end]) return;
    BlockAngles& ba = *block_angles_[b];
    if (ba.ghost_m.size() < 3 * static_cast<std::size_t>(n)) ba.ghost_m.resize(3 * static_cast<std::size_t>(n));
    for (int g = gstart_[b]; g < gstart_[end]; ++g) {
      const int e = gedge_[g] / 3, k = gedge_[g] % 3;
      double& h = sv.hm[k * sv.ld + (e - b)];
      ba.ghost_m[3 * (e - b) + k] = h;
      h = 0.0;
    }
  }

  // Pass 3, after membrane_bending_block has added the interior hinges'
  // forces to the membrane forces mf (laid out as membrane_block writes
  // them, leading dimension ld): the ghost hinges' forces into mf (and mb, if
  // not null: the bending's share of the corner forces alone); returns
  // the bending energy (from pass 1) and lowers the elements' stable steps
  // dte (the membrane's) with the bending ones, or, where dte is null (the
  // elements' own steps are not formed: see internal_forces), lowers
  // dt_floor (the block's stable step so far) with the block's smallest
  // bending step; [t_lo, t_hi] is the block's temperature range.
  double bending_forces(const ElementForceInput& in, int b, int end, double* dte, double t_lo, double t_hi,
                        double* mf, double* mb, int ld, const RangeIndex& ri, ElementForceOutput& out,
                        double& dt_floor) {
    const int n = end - b;
    const BlockAngles& ba = *block_angles_[b];  // from passes 0 to 2
    const double rmax = std::max(bending_->max_stiffness(t_lo), bending_->max_stiffness(t_hi));
    if (rmax > 0) {
      // Bending waves: dt ~ d^2 sqrt(rho h / R) / 2 (conservative), d the
      // smallest initial height over the element's interior edges.
      const double dtb_scale = 0.5 * std::sqrt(areal_mass_ / rmax);
      if (!dte) {
        // Without step factors the smallest bending step of the block is
        // its smallest d^2 times dtb_scale (a product with a positive
        // factor keeps the order, rounding included): the same bits as the
        // smallest of the elements' steps, without reading them.
        out.bending_dt = ri.d2min * dtb_scale;
        dt_floor = std::min(dt_floor, out.bending_dt);
      } else {
        const double* scale = in.dt_scale.empty() ? nullptr : in.dt_scale.data() + b;
        out.bending_dt = bending_steps(n, dmin2_.data() + b, dtb_scale, scale, dte);
      }
    }
    // Ghost hinges: gradient on the element's corners (c, p, q) = (k, k + 1,
    // k + 2); a clamp's theta is 2 x the rotation.
    const double* hgrad = ba.ghost_grad.data();
    for (int g = gstart_[b]; g < gstart_[end]; ++g) {
      const int e = gedge_[g] / 3, k = gedge_[g] % 3, q = e - b;
      const Vec3* gr = reinterpret_cast<const Vec3*>(&hgrad[12 * static_cast<std::size_t>(g - gstart_[b])]);
      const double m = (clamped_[3 * e + k] == 1 ? 2.0 : 1.0) * ba.ghost_m[3 * q + k];
      for (int j = 0; j < 3; ++j) {
        const int a = (k + j) % 3;
        for (int d = 0; d < 3; ++d) mf[(3 * a + d) * ld + q] += m * gr[j][d];
        if (mb)
          for (int d = 0; d < 3; ++d) mb[(3 * a + d) * ld + q] += m * gr[j][d];
      }
    }
    return ba.bending_energy;
  }

  // An evaluation that carries the bending of the next j steps
  // (ElementForceInput::bending_weight j > 1) delivers their impulse j f_b
  // in two parts: a held part h, applied at each of the j steps, and
  // j (f_b - h) at once. h follows f_b through a first-order filter per
  // evaluation, h += alpha (f_b - h) (alpha = kHeldAlpha, at committed
  // evaluations), so that it carries the slowly varying bending forces
  // (those that the contact or the membrane holds in balance) and the
  // impulse only their recent change: an impulse j f_b against a force
  // that balances f_b at every step would shake the nodes (the step's
  // contact or membrane takes the extra velocity back over the next steps)
  // and feed that vibration from the bending's impulses. Over the j steps
  // the momentum is j f_b either way (docs/mechanics-method.md). Per node
  // slot of the block: jfb = j f_b (the bending's share of the slot's
  // forces), and the slot's forces, which hold j f_b, become those of the
  // membrane + h + j (f_b - h), i.e. less (j - 1) h. An evaluation with
  // weight 1 after such evaluations (the bending's step has come to set
  // the run's) updates h and applies f_b.
  static constexpr double kHeldAlpha = 1.0 / 64.0;
  static void hold_bending(BlockAngles& ba, double j, bool commit, const double* jfb, std::span<double> node_force) {
    const std::size_t m = node_force.size();
    if (ba.held.size() != m) ba.held.assign(m, 0.0);
    double* __restrict h = ba.held.data();
    double* __restrict f = node_force.data();
    const double inv_j = 1.0 / j, keep = j - 1.0;
    if (commit)
      for (std::size_t v = 0; v < m; ++v) h[v] += kHeldAlpha * (jfb[v] * inv_j - h[v]);
    for (std::size_t v = 0; v < m; ++v) f[v] -= keep * h[v];
  }

  // Adds the corner forces mf (component d of corner a of element q at
  // mf[(3 a + d) ld + q]) of the range's n elements into the node slots nf.
  static void add_node_forces(const ElementForceInput& in, const RangeIndex& ri, int n, int ld, const double* mf,
                              double* nf) {
    if (!ri.ngroup.empty()) {
      const std::uint16_t *slots = ri.nslot.data(), *ent = ri.nent.data();
      for (const auto& [k, count] : ri.ngroup) {
        node_forces(k, count, ld, mf, slots, ent, nf);
        slots += count;
        ent += static_cast<std::size_t>(k) * count;
      }
    } else {
      corner_forces(n, ld, mf, in.patch_slot.data(), nf);
    }
  }

  // The per-step values of the elements' edges between the passes (eq,
  // rho, dW/ds, the shares of dW/dtheta) of the range in.range, edge k of
  // its element q at [k ld + q], and nidx (from the range's first element,
  // rows of gld_) into the arrays *_all for the neighbours' same edges: the
  // arrays over the whole part (eq_, erho_, em_, hm_, nidx_), or where the
  // kernel interleaves the passes (ElementForceInput::pass_window W > 0)
  // a ring of W block buffers that stays in cache, block b in buffer b mod W
  // (ring_*, ring_nidx_).
  struct StepValues {
    double *eq, *rho, *em, *hm;
    int ld;
    const int* nidx;
    const double *rho_all, *em_all, *hm_all;
  };
  StepValues step_values(const ElementForceInput& in) {
    const int b = in.range.begin;
    if (in.pass_window > 0 && in.block_size > 0) {
      if (in.pass_window != ring_w_ || in.block_size != ring_bs_) set_up_ring(in.pass_window, in.block_size);
      const std::size_t o = static_cast<std::size_t>(in.block % ring_w_) * 3 * rld_;
      return {ring_eq_.data() + o, ring_rho_.data() + o, ring_em_.data() + o, ring_hm_.data() + o, rld_,
              ring_nidx_.data() + b, ring_rho_.data(), ring_em_.data(), ring_hm_.data()};
    }
    return {eq_.data() + b, erho_.data() + b, em_.data() + b, hm_.data() + b, gld_, nidx_.data() + b,
            erho_.data(), em_.data(), hm_.data()};
  }
  // The ring for a window of w blocks of bs elements: w buffers of 3 rld_
  // values per array (and a zero entry at the end, for edges without a
  // neighbour), and nidx_ with the neighbours' edges in the ring.
  void set_up_ring(int w, int bs) {
    ring_w_ = w;
    ring_bs_ = bs;
    rld_ = padded_ld(bs);
    const std::size_t m = static_cast<std::size_t>(w) * 3 * rld_;
    ring_eq_.assign(m, 0.0);
    ring_rho_.assign(m + 1, 0.0);
    ring_em_.assign(m + 1, 0.0);
    ring_hm_.assign(m + 1, 0.0);
    if (in_plane_) ring_ip_step_.assign(m);  // the in-plane term's, alike
    const int ne = part_->num_elements;
    ring_nidx_.assign(nidx_.size(), static_cast<int>(m));
    for (int k = 0; k < 3; ++k)
      for (int e = 0; e < ne; ++e) {
        const int v = nidx_[static_cast<std::size_t>(k) * gld_ + e];
        if (v >= 3 * gld_) continue;  // no neighbour
        const int kp = v / gld_, nb = v % gld_, blk = nb / bs;
        ring_nidx_[static_cast<std::size_t>(k) * gld_ + e] =
            static_cast<int>(static_cast<std::size_t>(blk % w) * 3 * rld_ + static_cast<std::size_t>(kp) * rld_) +
            (nb - blk * bs);
      }
  }
  int ring_w_ = 0, ring_bs_ = 0, rld_ = 0;
  std::vector<double> ring_eq_, ring_rho_, ring_em_, ring_hm_;
  InPlaneStepArrays ring_ip_step_;
  large_vector<int> ring_nidx_;

  const MaterialLaw* bending_ = nullptr;
  const MaterialLaw* in_plane_ = nullptr;  // the fibres' in-plane bending (may be null)
  // See setup_in_plane; per step (rows of gld_): the slope jumps, own
  // slopes, dW/ds and dW/dphi per element and edge, m per element, the
  // forces on the nodes across the edges, and per element A0 w.
  std::vector<double> ipb_, ipw_, ipc_, ipl_, ipmask_;
  InPlaneStepArrays ip_step_;
  std::vector<int> ipo_;
  // Per element and edge (3 e + k): kEdgeFree (a neighbour or a free edge)
  // or the ghost's kind (kEdgeClamped, kEdgeSymmetryX + axis), and the
  // edge's initial outward normal nu at ghost edges (3 values); the ghost
  // edges (3 e + k) by element, those of element e from ipgstart_[e].
  std::vector<char> ipk_;
  std::vector<double> ipnu_;
  std::vector<int> ipghost_, ipgstart_;
  int gld_ = 0;
  std::vector<int> opp_, partner_k_, edge_condition_;  // partner_k_: the same edge's index in the neighbour
  std::vector<char> clamped_;
  std::vector<double> n0_;  // initial element normals (clamped elements)
  // ginv_: dK/dtheta_k, value r of edge k of element e at (3 k + r) gld_ + e.
  std::vector<double> d_, theta0_, curv_;
  large_vector<double> curv_old_, bstate_;
  // The element temperatures of the step (from the node temperatures), and
  // per block [b, end) at entry b the node temperatures' version they were
  // formed for and end (ElementForceInput::temperature_version; 0: none).
  large_vector<double> etemp_;
  std::vector<std::uint64_t> etemp_version_;
  std::vector<int> etemp_end_;
  // The ranges' RangeIndex (see there), by the range's first element.
  std::vector<std::unique_ptr<RangeIndex>> range_index_;
  const RangeIndex& range_index(const ElementForceInput& in, int b, int end) {
    std::unique_ptr<RangeIndex>& slot = range_index_[b];
    if (slot && slot->end == end) return *slot;
    auto ri = std::make_unique<RangeIndex>();
    const int n = end - b;
    ri->end = end;
    int lo = off_[b], hi = off_[b];
    for (int a = 0; a < 3; ++a)
      for (int e = b; e < end; ++e) lo = std::min(lo, off_[a * mld_ + e]), hi = std::max(hi, off_[a * mld_ + e]);
    if (hi - lo <= 0xffff) {
      ri->off_base = lo;
      ri->off16.resize(3 * static_cast<std::size_t>(n));
      for (int a = 0; a < 3; ++a)
        for (int q = 0; q < n; ++q) ri->off16[a * n + q] = static_cast<std::uint16_t>(off_[a * mld_ + b + q] - lo);
    }
    bool fit = true;
    for (int q = 0; q < n && fit; ++q)
      for (int a = 0; a < 3; ++a) fit = fit && in.patch_slot[6 * q + a] >= 0 && in.patch_slot[6 * q + a] <= 0xffff;
    if (fit && 7 * padded_ld(n) <= 0x10000) {
      // By node: corners by ascending element, nodes grouped by their count.
      const int ld = padded_ld(n);
      int nslots = 0;
      for (int q = 0; q < n; ++q)
        for (int a = 0; a < 3; ++a) nslots = std::max(nslots, in.patch_slot[6 * q + a] + 1);
      std::vector<int> count(nslots, 0), first(nslots + 1, 0);
      for (int q = 0; q < n; ++q)
        for (int a = 0; a < 3; ++a) ++count[in.patch_slot[6 * q + a]];
      for (int v = 0; v < nslots; ++v) first[v + 1] = first[v] + count[v];
      std::vector<std::uint16_t> by_node(first[nslots]);
      std::vector<int> fill(first.begin(), first.end() - 1);
      for (int q = 0; q < n; ++q)
        for (int a = 0; a < 3; ++a)
          by_node[fill[in.patch_slot[6 * q + a]]++] = static_cast<std::uint16_t>(3 * a * ld + q);
      const int kmax = nslots > 0 ? *std::max_element(count.begin(), count.end()) : 0;
      for (int k = 1; k <= kmax; ++k) {
        int c = 0;
        for (int v = 0; v < nslots; ++v) {
          if (count[v] != k) continue;
          ++c;
          ri->nslot.push_back(static_cast<std::uint16_t>(v));
          ri->nent.insert(ri->nent.end(), by_node.begin() + first[v], by_node.begin() + first[v + 1]);
        }
        if (c > 0) ri->ngroup.push_back({k, c});
      }
    }
    if (bending_)
      ri->d2min = *std::min_element(dmin2_.begin() + b, dmin2_.begin() + end);
    slot = std::move(ri);
    return *slot;
  }

  // strain_block over range [b, end) (ff with leading dimension ld), from
  // the range's 16-bit node offsets (widened into int in pieces, see
  // kWidenPiece) where it has them, otherwise from off_.
  double strains(const RangeIndex& ri, int b, int end, int ld, const double* x, double* ff, double* C) {
    const int n = end - b;
    if (ri.off_base < 0) return strain_block(n, ld, off_.data() + b, mld_, x, g_.data() + b, mld_, ff, C);
    alignas(64) int w[3 * kWidenPiece];
    double bad = 0.0;
    for (int j = 0; j < n; j += kWidenPiece) {
      const int m = std::min(kWidenPiece, n - j);
      widen_rows(3, ri.off16.data(), n, j, m, w);
      bad = std::max(bad, strain_block(m, ld, w, kWidenPiece, x + ri.off_base, g_.data() + b + j, mld_, ff + j,
                                       C + 3 * j));
    }
    return bad;
  }

  bool temperatures_kept(const ElementForceInput& in, int b, int end) const {
    return in.temperature_version != 0 && etemp_version_[b] == in.temperature_version && etemp_end_[b] == end;
  }
  void keep_temperatures(const ElementForceInput& in, int b, int end) {
    etemp_version_[b] = in.temperature_version;
    etemp_end_[b] = end;
  }
  // Mid-edge slopes (the set-up coefficients in single precision: the
  // forces stay the exact derivatives of the energy they define): cs_ dK/ds_k (value r of edge k of element e at
  // (3 k + r) gld_ + e, free edges condensed), lmap_ the 3 x 3 map L from
  // an element's angle changes to the slopes of its own quadratic (entry
  // (k, i) of element e at (3 k + i) gld_ + e; zero where the element has
  // no quadratic; its rows scaled by the weight omega of the element's own
  // slope per edge), acoef_ a per edge (edge k of element e at k gld_ + e;
  // see slope_angles), nidx_ per edge (edge k of element e at k gld_ + e)
  // the entry of the neighbour's same edge in erho_, em_ and hm_ (3 gld_,
  // a zero entry, where there is none); per step eq_, erho_ (slope_angles),
  // em_ (dW/ds), hm_ (the element's share of dW/dtheta, hinge_moments),
  // edge k of element e at k gld_ + e.
  large_vector<float> cs_, lmap_, acoef_;
  large_vector<double> eq_, erho_, em_, hm_;
  large_vector<int> nidx_;
  // Interior hinges: node offsets (3 x node) of (c, p, q, o) in the owner's
  // orientation and initial angle; hid_ per element and edge; hstart_ the
  // first hinge owned by each element; gstart_, gedge_ the ghost hinges
  // (3 e + k) by element; dmin2_ the squared smallest initial height over
  // an element's interior edges.
  std::vector<int> hstart_, hid_, gstart_, gedge_;
  large_vector<int> hc_, hp_, hq_, ho_;
  large_vector<double> htheta0_, dmin2_;
  std::vector<std::unique_ptr<BlockHinges>> block_hinges_;  // by the block's first element
  std::vector<std::unique_ptr<BlockAngles>> block_angles_;  // likewise
  const PartView* part_ = nullptr;
  std::vector<const MaterialLaw*> laws_;
  double areal_mass_ = 0;
  bool keep_old_ = true;
  // g_: the initial shape-function gradients grad0 N_a on the material
  // frame (f, m) of corners a = 1, 2: g1_a of element e at (a - 1) mld_ + e,
  // g2_a at (a + 1) mld_ + e (corner 0's: minus the sums, so that the three
  // sum to zero exactly and F depends on the positions relative to corner 0
  // only).
  // off_: the offset 3 i in x of node a of element e at a mld_ + e.
  int mld_ = 0;
  large_vector<int> off_;
  large_vector<double> g_, area0_, strain_old_, stress_;
  std::vector<double> e1_, e2_;
  std::vector<large_vector<double>> states_;
  std::vector<large_vector<double>> caches_;  // per membrane law: cache_size() per element, or none
};

ElementKernel* create() { return new ShellRfT3(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Element;
  d.name = "shell_rf_t3";
  d.version = "0.12.0";
  d.summary = "Three-node shell triangle, translational dofs: total-Lagrangian membrane, rotation-free bending (Morley mid-edge slopes from the 6-node patch), optional in-plane bending of the fibres (a material's in_plane_bending)";
  d.example = R"({ "element": "shell_rf_t3" })";
  r.add_element(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("element_shell_rf_t3", "0.12.0", register_all)
