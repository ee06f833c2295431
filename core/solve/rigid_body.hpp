#pragma once
// The velocity of a body of nodes that move rigidly (a gripper's swivelling
// jaws), from their momentum, under linear constraints.
#include <array>
#include <cmath>

namespace ts {

// Generalised velocity q = (V, L w) of the rigid velocity field
// v_j = V + w x y_j (y_j a node's position from the body's origin, L a
// length that makes both halves of q alike in size): the matrix G (6 x 6,
// row-major) with q = G p for
//
//     q = argmin (1/2 q^T M q - p^T q)  subject to  C q = 0,
//
// M = sum_j m_j a_j a_j^T (6 x 6, row-major) over the free dofs, a_j their
// rows (e_d, y_j x e_d / L), p a generalised momentum sum_j a_j p_j;
// C = sum a a^T over the held rows, symmetric positive semi-definite.
// Directions in which M vanishes (rotation about the line of collinear
// nodes, which moves none of them) take no velocity.
void constrained_rigid_inverse(const double* M, const double* C, double* G);

// The rotation R (3 x 3, row-major) that best carries the points a_j onto
// the points b_j (both about their weighted centres), from
// H = sum_j w_j a_j b_j^T (row-major): R maximises sum_j w_j b_j . R a_j
// (Kabsch; a proper rotation, det R = 1).
void best_fit_rotation(const double* H, double* R);

// Row a (6) of dof d of a node at y from the origin, for a length scale L:
// (e_d, y x e_d / L).
inline void rigid_row(const double* y, int d, double inv_length, double* a) {
  a[0] = a[1] = a[2] = 0.0;
  a[d] = 1.0;
  const int d1 = (d + 1) % 3, d2 = (d + 2) % 3;
  a[3 + d] = 0.0;  // (y x e_d)_d = 0
  a[3 + d1] = y[d2] * inv_length;
  a[3 + d2] = -y[d1] * inv_length;
}

// The rotation R by the vector phi (Rodrigues, exact for any angle), as
// the factors of (R - I) y = f1 phi x y + f2 phi x (phi x y).
struct Rotation {
  double phi[3];
  double f1, f2;  // sin(t) / t, (1 - cos t) / t^2, t = |phi|
  explicit Rotation(const double* p) : phi{p[0], p[1], p[2]}, f1(1.0), f2(0.5) {
    const double th = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (th > 0) {
      const double s = std::sin(0.5 * th) / (0.5 * th);
      f1 = std::sin(th) / th;
      f2 = 0.5 * s * s;
    }
  }
  // The displacement (R - I) y of a point at y from the origin.
  void increment(const double* y, double* out) const {
    const double wy[3] = {phi[1] * y[2] - phi[2] * y[1], phi[2] * y[0] - phi[0] * y[2], phi[0] * y[1] - phi[1] * y[0]};
    const double wwy[3] = {phi[1] * wy[2] - phi[2] * wy[1], phi[2] * wy[0] - phi[0] * wy[2],
                           phi[0] * wy[1] - phi[1] * wy[0]};
    for (int d = 0; d < 3; ++d) out[d] = f1 * wy[d] + f2 * wwy[d];
  }
};

}  // namespace ts
