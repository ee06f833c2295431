#pragma once
// Storage conventions used everywhere in ThermoStamp (kernel and plugins).
//
//  * Node coordinates, displacements, velocities, forces, normals: flat
//    arrays of doubles, node-major, xyz interleaved: v[3*i + d], d = 0,1,2.
//  * Triangles: flat int array, tri[3*e + a], a = 0,1,2, counter-clockwise
//    seen from the ply's top face (element normal (x1-x0) x (x2-x0) points
//    to the top face, +h/2).
//  * Edge k of a triangle is the edge opposite its node k; neighbour[3*e+k]
//    is the element across that edge, or -1.
//  * Through-thickness fields: node-major, bottom to top:
//    T[nz*i + k], k = 0 (z = -h/2) ... nz-1 (z = +h/2).
//  * Symmetric 2x2 membrane tensors (C, S, strain): Voigt order
//    [11, 22, 12] with the 12 entry stored once (tensor component, not the
//    engineering shear): v = {A(0,0), A(1,1), A(0,1)}.
//  * 2x2 matrices that are not symmetric (F): row-major {F00, F01, F10, F11}.
//  * Temperatures in degrees Celsius, everything else SI.
#include <array>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ts::sdk {

using Vec3 = std::array<double, 3>;

inline constexpr int kVoigt11 = 0;
inline constexpr int kVoigt22 = 1;
inline constexpr int kVoigt12 = 2;

inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(const Vec3& a) {
  const double n = norm(a);
  return n > 0 ? scale(a, 1.0 / n) : a;
}
inline Vec3 load3(const double* p, int i) { return {p[3 * i], p[3 * i + 1], p[3 * i + 2]}; }

// Cubic cells of a bucket grid over the box [lo, hi]: starts from `cell`
// and grows it by half until the grid has at most max_cells cells; writes
// the cells per axis to n and returns the cell size. A box or cell that
// is not finite (positions beyond the range of doubles) gets one cell of
// infinite size.
inline double bucket_grid(const Vec3& lo, const Vec3& hi, double cell, int n[3], long long max_cells = 4'000'000) {
  bool finite = std::isfinite(cell) && cell > 0;
  for (int d = 0; d < 3; ++d) finite = finite && std::isfinite(hi[d] - lo[d]);
  if (!finite) {
    n[0] = n[1] = n[2] = 1;
    return std::numeric_limits<double>::infinity();
  }
  for (;;) {
    double cells = 1;  // a double: three counts of up to 1e9 overflow a long long
    for (int d = 0; d < 3; ++d) {
      const double span = std::max(0.0, hi[d] - lo[d]);
      n[d] = 1 + static_cast<int>(std::min(std::ceil(span / cell), 1e9));
      cells *= n[d];
    }
    if (cells <= static_cast<double>(max_cells)) return cell;
    cell *= 1.5;
  }
}

// Cell coordinate t (in cells from the grid's origin) as the index of one
// of n cells along an axis, clamped to [0, n - 1] as a double, so that a
// point far outside (or NaN) never reaches the int conversion out of its
// range.
inline int bucket_cell(double t, int n) {
  const double top = n - 1;
  return static_cast<int>(!(t >= 0) ? 0.0 : t > top ? top : t);
}
// The cell along one axis of a bucket grid (origin lo, cells of size
// `cell`, n of them) that holds coordinate v.
inline int bucket_index(double v, double lo, double cell, int n) { return bucket_cell((v - lo) / cell, n); }

// atan2(y, x). For x > 0 and |y| <= 0.66 x (|angle| < 33.4 degrees: the
// small angles between neighbouring elements of a shell) by the rational
// approximation of atan(r), r = y / x, of the Cephes library,
// atan r = r + r^3 P(r^2) / Q(r^2) (relative error below 2e-16 on that
// range); elsewhere by std::atan2.
// atan2_small_range(y, x) says whether (y, x) is on that range;
// atan2_small_approx(y, x) is the approximation alone (no branch, for
// vector loops; meaningless off the range).
inline bool atan2_small_range(double y, double x) { return x > 0 && std::abs(y) <= 0.66 * x; }
inline double atan2_small_approx(double y, double x) {
  const double r = y / x, z = r * r;
  const double p = (((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z - 7.500855792314704667340e1) * z -
                    1.228866684490136173410e2) * z - 6.485021904942025371773e1;
  const double q = ((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z + 4.328810604912902668951e2) * z +
                    4.853903996359136964868e2) * z + 1.945506571482613964425e2;
  return r + r * (z * p / q);
}
inline double atan2_small(double y, double x) {
  return atan2_small_range(y, x) ? atan2_small_approx(y, x) : std::atan2(y, x);
}

// Closest point to p on the triangle (a, b, c) and its barycentric weights
// (Ericson, Real-Time Collision Detection, 5.1.5).
inline Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                                      double* w = nullptr) {
  auto out = [&](double u, double v, double t) {
    if (w) {
      w[0] = u;
      w[1] = v;
      w[2] = t;
    }
    return add(add(scale(a, u), scale(b, v)), scale(c, t));
  };
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return out(1, 0, 0);
  const Vec3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return out(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return out(1 - v, v, 0);
  }
  const Vec3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return out(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return out(1 - t, 0, t);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return out(0, 1 - t, t);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, t = vc * denom;
  return out(1 - v - t, v, t);
}

}  // namespace ts::sdk
