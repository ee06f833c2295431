// shell_rf_t3: three-node shell triangle, translational dofs only
// (physics.md section 1). Membrane: total-Lagrangian constant-strain
// triangle; F = sum_a x_a (x) grad0 N_a maps the material frame of the
// initial element (axis 1 along the initial fibre direction, axis 2 =
// N x axis 1) to the current configuration, C = F^T F, the laws return S
// (N/m) and the nodal forces are f_a = A0 F S grad0 N_a (f = A0 B^T S).
//
// Bending, rotation-free (S3/BST family, 6-node patch): the curvature of an
// element is the boundary integral of the slope jumps at its edges,
//   K = (1 / 2 A0) sum_i l_i (theta_i - theta0_i) nu_i (x) nu_i,
// theta_i the bending angle between the element and its neighbour across
// edge i (positive when the surface turns towards the element's normal),
// l_i and nu_i the length and in-plane outward normal of the edge in the
// initial configuration, K in the element's material frame. The law
// returns the moments M (N m/m) and the energy; the forces are the
// derivatives of sum A0 w through d theta_i / dx on the four nodes of each
// hinge. A free edge carries no slope jump (zero normal moment for edges
// along the material axes). At a clamped edge the slope jump is the
// rotation of the element about the edge from its initial orientation
// (the hinge angle to a mirrored ghost is twice that). At a symmetry edge
// the ghost is the element mirrored in the symmetry plane.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace {

using namespace ts::sdk;

// Per-thread buffers for the values of one block of elements (indexed from
// the block's first element); they grow to the largest block once.
constexpr int kHingeChunk = 128;

struct BlockScratch {
  std::vector<double> temp, ff, law_stress, energy_tmp, energy, hgrad, hth, moment, benergy;
  // A chunk of interior hinges in structure-of-arrays form: node
  // positions (c, p, q, o) x xyz, angle, gradients.
  std::vector<double> hx = std::vector<double>(12 * kHingeChunk), hg = std::vector<double>(12 * kHingeChunk),
                      ht = std::vector<double>(kHingeChunk), hredo = std::vector<double>(kHingeChunk);
  std::vector<int> hdest = std::vector<int>(2 * kHingeChunk);
};

BlockScratch& block_scratch(int n) {
  thread_local BlockScratch s;
  const std::size_t m = static_cast<std::size_t>(n);
  if (s.temp.size() < m) {
    s.temp.resize(m);
    s.ff.resize(6 * m);
    s.law_stress.resize(3 * m);
    s.energy_tmp.resize(m);
    s.energy.resize(m);
    s.hgrad.resize(36 * m);
    s.hth.resize(3 * m);
    s.moment.resize(3 * m);
    s.benergy.resize(m);
  }
  return s;
}

// Bending angles and their gradients of h hinges (as
// ShellRfT3::hinge_angle, the same operations in the same order, so the
// same bits): X holds the positions of the nodes (c, p, q, o), component
// 3 i + d of node i at X[(3 i + d) cap + j]; the gradients on (c, o, p, q)
// go to G likewise. redo[j] = 1 (0 otherwise) where the angle is beyond atan2_small's
// range (the caller evaluates it with the library).
TS_VECTOR_CLONES
void hinge_block(int h, int cap, const double* __restrict X, double* __restrict theta, double* __restrict G,
                 double* __restrict redo) {
#pragma omp simd
  for (int j = 0; j < h; ++j) {
    // Written out component by component (sub, dot, cross, scale, add of
    // math.hpp, in their order), so that the compiler sees plain scalars.
    const double C0 = X[0 * cap + j], C1 = X[1 * cap + j], C2 = X[2 * cap + j];
    const double P0 = X[3 * cap + j], P1 = X[4 * cap + j], P2 = X[5 * cap + j];
    const double Q0 = X[6 * cap + j], Q1 = X[7 * cap + j], Q2 = X[8 * cap + j];
    const double O0 = X[9 * cap + j], O1 = X[10 * cap + j], O2 = X[11 * cap + j];
    const double e0 = Q0 - P0, e1 = Q1 - P1, e2 = Q2 - P2;
    const double l2 = e0 * e0 + e1 * e1 + e2 * e2, len = std::sqrt(l2);
    const double c0 = C0 - P0, c1 = C1 - P1, c2 = C2 - P2;
    const double o0 = O0 - P0, o1 = O1 - P1, o2 = O2 - P2;
    const double ne0 = e1 * c2 - e2 * c1, ne1 = e2 * c0 - e0 * c2, ne2 = e0 * c1 - e1 * c0;  // edge x cp
    const double nn0 = o1 * e2 - o2 * e1, nn1 = o2 * e0 - o0 * e2, nn2 = o0 * e1 - o1 * e0;  // op x edge
    const double m0 = nn1 * ne2 - nn2 * ne1, m1 = nn2 * ne0 - nn0 * ne2, m2 = nn0 * ne1 - nn1 * ne0;  // Nn x Ne
    const double y = m0 * e0 + m1 * e1 + m2 * e2, x = len * (ne0 * nn0 + ne1 * nn1 + ne2 * nn2);
    redo[j] = (x > 0) & (std::abs(y) <= 0.66 * x) ? 0.0 : 1.0;
    theta[j] = atan2_small_approx(y, x);
    const double sc = (c0 * e0 + c1 * e1 + c2 * e2) / l2, so = (o0 * e0 + o1 * e1 + o2 * e2) / l2;
    const double se = len / (ne0 * ne0 + ne1 * ne1 + ne2 * ne2), sn = len / (nn0 * nn0 + nn1 * nn1 + nn2 * nn2);
    const double g0[3] = {ne0 * se, ne1 * se, ne2 * se};
    const double g1[3] = {nn0 * sn, nn1 * sn, nn2 * sn};
    const double a2 = -(1 - sc), b2 = -(1 - so), a3 = -sc, b3 = -so;
    for (int d = 0; d < 3; ++d) {
      G[(0 + d) * cap + j] = g0[d];
      G[(3 + d) * cap + j] = g1[d];
      G[(6 + d) * cap + j] = g0[d] * a2 + g1[d] * b2;
      G[(9 + d) * cap + j] = g0[d] * a3 + g1[d] * b3;
    }
  }
}

// Membrane forces of n elements, f_a = A0 (c1 F e1 + c2 F e2) with c1 =
// S11 g1_a + S12 g2_a, c2 = S12 g1_a + S22 g2_a (slots 0-8 of each
// element's 18), and each element's stable step: smallest height (2 area /
// longest edge) times inv_c (infinite when has_stiffness is false). One
// vector pass; the operations of the scalar form in its order, so the
// same bits.
TS_VECTOR_CLONES
void membrane_block(int n, const int* __restrict tri, const double* __restrict x, const double* __restrict ff,
                    const double* __restrict S, const double* __restrict area, const double* __restrict g1,
                    const double* __restrict g2, double inv_c, bool has_stiffness, double* __restrict ef,
                    double* __restrict dte) {
  const double inf = std::numeric_limits<double>::infinity();
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double f10 = ff[6 * q], f11 = ff[6 * q + 1], f12 = ff[6 * q + 2];
    const double f20 = ff[6 * q + 3], f21 = ff[6 * q + 4], f22 = ff[6 * q + 5];
    const double S11 = S[3 * q], S22 = S[3 * q + 1], S12 = S[3 * q + 2], A0 = area[q];
    for (int a = 0; a < 3; ++a) {
      const double ga = g1[3 * q + a], gb = g2[3 * q + a];
      const double c1 = A0 * (S11 * ga + S12 * gb), c2 = A0 * (S12 * ga + S22 * gb);
      ef[18 * q + 3 * a] = c1 * f10 + c2 * f20;
      ef[18 * q + 3 * a + 1] = c1 * f11 + c2 * f21;
      ef[18 * q + 3 * a + 2] = c1 * f12 + c2 * f22;
    }
    const int i0 = 3 * tri[3 * q], i1 = 3 * tri[3 * q + 1], i2 = 3 * tri[3 * q + 2];
    const double a0 = x[i0], a1 = x[i0 + 1], a2 = x[i0 + 2];
    const double u0 = x[i1] - a0, u1 = x[i1 + 1] - a1, u2 = x[i1 + 2] - a2;  // e01
    const double v0 = x[i2] - a0, v1 = x[i2 + 1] - a1, v2 = x[i2 + 2] - a2;  // e02
    const double w0 = x[i2] - x[i1], w1 = x[i2 + 1] - x[i1 + 1], w2 = x[i2 + 2] - x[i1 + 2];  // e12
    const double n0 = u1 * v2 - u2 * v1, n1 = u2 * v0 - u0 * v2, n2 = u0 * v1 - u1 * v0;
    const double l01 = u0 * u0 + u1 * u1 + u2 * u2, l02 = v0 * v0 + v1 * v1 + v2 * v2, l12 = w0 * w0 + w1 * w1 + w2 * w2;
    double l2max = l01;
    l2max = l2max < l02 ? l02 : l2max;
    l2max = l2max < l12 ? l12 : l2max;
    const double h = std::sqrt((n0 * n0 + n1 * n1 + n2 * n2) / l2max);
    dte[q] = has_stiffness ? h * inv_c : inf;
  }
}

class ShellRfT3 final : public ElementKernel {
 public:
  Status configure(const Params&, const ElementSetup& s) override {
    return guarded([&]() -> Status {
      part_ = s.part;
      laws_.assign(s.membrane.begin(), s.membrane.end());
      bending_ = s.bending;
      edge_condition_.assign(s.edge_condition.begin(), s.edge_condition.end());
      areal_mass_ = s.density * part_->thickness;
      const int ne = part_->num_elements;
      g1_.resize(3 * ne);
      g2_.resize(3 * ne);
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
        // grad0 N_a = n x (X_c - X_b) / (2 A0), components on (f, m).
        for (int a = 0; a < 3; ++a) {
          const Vec3 g = scale(cross(n, sub(X[(a + 2) % 3], X[(a + 1) % 3])), 1.0 / two_a);
          g1_[3 * e + a] = dot(g, f);
          g2_[3 * e + a] = dot(g, m);
        }
      }
      if (bending_) setup_bending();
      strain_.assign(3 * ne, 0.0);
      strain_old_.assign(3 * ne, 0.0);
      for (int e = 0; e < ne; ++e) {
        strain_old_[3 * e] = 1.0;
        strain_old_[3 * e + 1] = 1.0;
      }
      stress_.assign(3 * ne, 0.0);
      states_.clear();
      for (const auto* l : laws_) states_.emplace_back(static_cast<std::size_t>(l->state_size()) * ne, 0.0);
      return Status::success();
    });
  }

  Status internal_forces(const ElementForceInput& in, ElementForceOutput& out) override {
    return guarded([&]() -> Status {
      const int b = in.range.begin, n = in.range.end - in.range.begin;
      const double* x = part_->x.data();
      // Values needed only while this block is evaluated live in a buffer of
      // the calling thread (indexed from the block's first element), so that
      // they stay in cache instead of streaming through per-element arrays.
      BlockScratch& sc = block_scratch(n);
      double* temp = sc.temp.data();
      double* ff = sc.ff.data();
      // 1. Strains and temperatures of the block.
      for (int e = b; e < in.range.end; ++e) {
        const int* t = &part_->triangles[3 * e];
        Vec3 f1{0, 0, 0}, f2{0, 0, 0};
        double T = 0;
        for (int a = 0; a < 3; ++a) {
          const Vec3 xa = load3(x, t[a]);
          f1 = add(f1, scale(xa, g1_[3 * e + a]));
          f2 = add(f2, scale(xa, g2_[3 * e + a]));
          T += in.node_temperature[t[a]] / 3.0;
        }
        for (int d = 0; d < 3; ++d) {
          ff[6 * (e - b) + d] = f1[d];
          ff[6 * (e - b) + 3 + d] = f2[d];
        }
        strain_[3 * e] = dot(f1, f1);
        strain_[3 * e + 1] = dot(f2, f2);
        strain_[3 * e + 2] = dot(f1, f2);
        temp[e - b] = T;
        const double det = strain_[3 * e] * strain_[3 * e + 1] - strain_[3 * e + 2] * strain_[3 * e + 2];
        if (!(det > 1e-12) && out.failed_element < 0) out.failed_element = e;
      }
      if (out.failed_element >= 0) return Status::success();
      // 2. The laws, one call per law for the whole block; stresses add.
      std::fill(stress_.begin() + 3 * b, stress_.begin() + 3 * (b + n), 0.0);
      double* energy_e = sc.energy.data();
      std::fill(energy_e, energy_e + n, 0.0);
      for (std::size_t k = 0; k < laws_.size(); ++k) {
        const int ns = laws_[k]->state_size();
        MaterialBlock blk;
        blk.n = n;
        blk.strain = std::span<const double>(strain_.data() + 3 * b, 3 * n);
        blk.strain_old = std::span<const double>(strain_old_.data() + 3 * b, 3 * n);
        blk.temperature = std::span<const double>(temp, n);
        blk.dt = in.dt;
        blk.state = std::span<double>(states_[k].data() + static_cast<std::size_t>(ns) * b, static_cast<std::size_t>(ns) * n);
        blk.stress = std::span<double>(sc.law_stress.data(), 3 * n);
        blk.energy = std::span<double>(sc.energy_tmp.data(), n);
        if (auto s = laws_[k]->evaluate(blk); !s) return s;
        for (int q = 0; q < 3 * n; ++q) stress_[3 * b + q] += sc.law_stress[q];
        for (int q = 0; q < n; ++q) energy_e[q] += sc.energy_tmp[q];
      }
      // 3. Nodal forces, energy, stable step. The largest tangent stiffness
      // is taken over the block's temperature range (one call per law).
      double t_lo = temp[0], t_hi = temp[0];
      for (int q = 0; q < n; ++q) {
        t_lo = std::min(t_lo, temp[q]);
        t_hi = std::max(t_hi, temp[q]);
      }
      double kmax = 0;
      for (const auto* l : laws_) kmax += std::max(l->max_stiffness(t_lo), l->max_stiffness(t_hi));
      const double inv_c = kmax > 0 ? 1.0 / std::sqrt(kmax / areal_mass_) : 0.0;
      double energy = 0, dt_min = std::numeric_limits<double>::infinity();
      double* dte = sc.energy_tmp.data();  // free again after the laws
      membrane_block(n, &part_->triangles[3 * b], x, ff, stress_.data() + 3 * b, area0_.data() + b, g1_.data() + 3 * b,
                     g2_.data() + 3 * b, inv_c, kmax > 0, out.element_force.data(), dte);
      for (int e = b; e < in.range.end; ++e) {
        if (!bending_)  // with bending, bending_forces writes these slots
          for (int q = 9; q < 18; ++q) out.element_force[18 * (e - b) + q] = 0.0;
        energy += area0_[e] * energy_e[e - b];
        dt_min = std::min(dt_min, dte[e - b]);
        if (!out.element_dt.empty()) out.element_dt[e] = dte[e - b];
      }
      if (bending_) {
        const double eb = bending_forces(in, b, in.range.end, sc, t_lo, t_hi, out, &dt_min);
        energy += eb;
      }
      if (in.commit) std::copy(strain_.begin() + 3 * b, strain_.begin() + 3 * (b + n), strain_old_.begin() + 3 * b);
      out.energy += energy;
      out.stable_dt = dt_min;
      return Status::success();
    });
  }

  Status fields(ElementFields& out) const override {
    const int ne = part_->num_elements;
    for (int e = 0; e < ne; ++e) {
      if (!out.shear_angle.empty()) {  // gamma = asin(I_sh), I_sh = C12 / sqrt(C11 C22)
        const double ish = strain_[3 * e + 2] / std::sqrt(strain_[3 * e] * strain_[3 * e + 1]);
        out.shear_angle[e] = std::asin(std::clamp(ish, -1.0, 1.0)) * 180.0 / M_PI;
      }
      if (!out.stress.empty())
        for (int k = 0; k < 3; ++k) out.stress[3 * e + k] = stress_[3 * e + k];
      if (!out.curvature.empty() && bending_)
        for (int k = 0; k < 3; ++k) out.curvature[3 * e + k] = curv_[3 * e + k];
      if (!out.fibre.empty()) {
        const int* t = &part_->triangles[3 * e];
        Vec3 f1{0, 0, 0};
        for (int a = 0; a < 3; ++a) f1 = add(f1, scale(load3(part_->x.data(), t[a]), g1_[3 * e + a]));
        const Vec3 u = normalized(f1);
        for (int d = 0; d < 3; ++d) out.fibre[3 * e + d] = u[d];
      }
    }
    return Status::success();
  }

 private:
  // Bending angle of hinge k of element e at positions x (edge nodes p, q in
  // the element's counter-clockwise order, c opposite in e, o in the
  // neighbour), with its gradient on (c, o, p, q) when grad is given.
  double hinge_angle(const double* x, int c, int p, int q, int o, Vec3* grad) const {
    const Vec3 C = load3(x, c), P = load3(x, p), Q = load3(x, q), O = load3(x, o);
    const Vec3 edge = sub(Q, P);
    const double l2 = dot(edge, edge), len = std::sqrt(l2);
    const Vec3 cp = sub(C, P), op = sub(O, P);
    // Unnormalised normals: element e (p, q, c) and the neighbour (q, p, o),
    // both counter-clockwise; |N| = len * height of c (of o) over the edge.
    const Vec3 Ne = cross(edge, cp);
    const Vec3 Nn = cross(op, edge);
    // atan2 is invariant to scaling both arguments by |Ne| |Nn| len.
    const double theta = atan2_small(dot(cross(Nn, Ne), edge), len * dot(Ne, Nn));
    if (grad) {
      // d theta / d c = n_e / h_c = Ne len / |Ne|^2 (and likewise for o).
      const double sc = dot(cp, edge) / l2, so = dot(op, edge) / l2;
      grad[0] = scale(Ne, len / dot(Ne, Ne));
      grad[1] = scale(Nn, len / dot(Nn, Nn));
      grad[2] = add(scale(grad[0], -(1 - sc)), scale(grad[1], -(1 - so)));
      grad[3] = add(scale(grad[0], -sc), scale(grad[1], -so));
    }
    return theta;
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
    auto ghost = [&](const Vec3& v, bool derivative) -> Vec3 {
      if (mirror_axis < 0) return derivative ? Vec3{0, 0, 0} : n0;
      Vec3 r = v;
      r[mirror_axis] = -r[mirror_axis];
      return r;
    };
    const Vec3 g = ghost(n, false);
    const double y = dot(cross(g, n), eh), z = dot(n, g);
    const double theta = atan2_small(y, z);
    if (grad && mirror_axis >= 0) {
      // Mirror ghost (edge in the symmetry plane, e_a its normal): with
      // m = n x e, theta = 2 atan2(-n_a, m_a), d theta = 2 (-m_a dn_a +
      // n_a dm_a). For a flat triangle dn = -sum_k (n . dx_k) grad N_k, and
      // dm = dn x e + n x de, de = (I - e e^T)(dQ - dP) / |Q - P|.
      const int a = mirror_axis;
      const Vec3 m = cross(n, eh);
      Vec3 ea{0, 0, 0};
      ea[a] = 1.0;
      const Vec3 exa = cross(eh, ea);
      Vec3 w = cross(ea, n);
      w = sub(w, scale(eh, dot(w, eh)));
      const Vec3 xs[3] = {C, P, Q};
      for (int k = 0; k < 3; ++k) {
        const Vec3 gk = scale(cross(n, sub(xs[(k + 2) % 3], xs[(k + 1) % 3])), 1.0 / nlen);  // grad N_k
        grad[k] = scale(n, 2 * (m[a] * gk[a] - n[a] * dot(gk, exa)));
      }
      grad[2] = add(grad[2], scale(w, 2 * n[a] / len));
      grad[1] = sub(grad[1], scale(w, 2 * n[a] / len));
    } else if (grad) {
      // Chain rule through N = (Q - P) x (C - P) and e = (Q - P) / |Q - P|.
      const double r2 = y * y + z * z;
      for (int v = 0; v < 3; ++v) grad[v] = {0, 0, 0};
      for (int d = 0; d < 3; ++d) {
        Vec3 u{0, 0, 0};
        u[d] = 1.0;
        const Vec3 dN[3] = {cross(sub(Q, P), u), add(scale(cross(u, sub(C, P)), -1.0), scale(cross(sub(Q, P), u), -1.0)),
                            cross(u, sub(C, P))};
        const Vec3 dE[3] = {{0, 0, 0}, scale(u, -1.0), u};
        for (int v = 0; v < 3; ++v) {
          const Vec3 dn = scale(sub(dN[v], scale(n, dot(n, dN[v]))), 1.0 / nlen);
          const Vec3 de = scale(sub(dE[v], scale(eh, dot(eh, dE[v]))), 1.0 / len);
          const Vec3 dg = ghost(dn, true);
          const double dy = dot(add(cross(dg, n), cross(g, dn)), eh) + dot(cross(g, n), de);
          const double dz = dot(dn, g) + dot(n, dg);
          grad[v][d] = (z * dy - y * dz) / r2;
        }
      }
    }
    return theta;
  }

  void setup_bending() {
    const int ne = part_->num_elements;
    opp_.assign(3 * ne, -1);
    partner_k_.assign(3 * ne, -1);
    clamped_.assign(3 * ne, 0);
    n0_.assign(3 * ne, 0.0);
    d_.assign(3 * ne, 1.0);
    theta0_.assign(3 * ne, 0.0);
    ginv_.assign(9 * ne, 0.0);
    curv_.assign(3 * ne, 0.0);
    curv_old_.assign(3 * ne, 0.0);
    bstate_.assign(static_cast<std::size_t>(bending_->state_size()) * ne, 0.0);
    const double* x0 = part_->x0.data();
    for (int e = 0; e < ne; ++e) {
      const int* t = &part_->triangles[3 * e];
      const Vec3 X[3] = {load3(x0, t[0]), load3(x0, t[1]), load3(x0, t[2])};
      const Vec3 n = normalized(cross(sub(X[1], X[0]), sub(X[2], X[0])));
      const Vec3 f = load3(e1_.data(), e), m = load3(e2_.data(), e);
      const double A0 = area0_[e];
      for (int k = 0; k < 3; ++k) {
        const int p = t[(k + 1) % 3], q = t[(k + 2) % 3];
        const Vec3 P = load3(x0, p), Q = load3(x0, q);
        const double len = norm(sub(Q, P));
        const Vec3 nu = normalized(cross(sub(Q, P), n));  // outward in-plane normal of edge k
        const double a = dot(nu, f), bb = dot(nu, m);
        // dK/dtheta_k = l_k / (2 A0) nu (x) nu, Voigt in the material frame.
        ginv_[9 * e + 3 * k] = len / (2 * A0) * a * a;
        ginv_[9 * e + 3 * k + 1] = len / (2 * A0) * bb * bb;
        ginv_[9 * e + 3 * k + 2] = len / (2 * A0) * a * bb;
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
        theta0_[3 * e + k] = hinge_angle(x0, t[k], p, q, o, nullptr);
      }
    }
  }

  // Bending curvatures, moments and forces of elements [b, end); returns the
  // bending energy and lowers *dt_min with the bending stable step; [t_lo,
  // t_hi] is the block's temperature range.
  double bending_forces(const ElementForceInput& in, int b, int end, BlockScratch& sc, double t_lo, double t_hi,
                        ElementForceOutput& out, double* dt_min) {
    double* hgrad = sc.hgrad.data();  // per element and edge of the block: d theta / dx on up to 4 nodes
    double* hth = sc.hth.data();      // per element and edge of the block: current hinge angle
    const double* temp = sc.temp.data();
    const double* x = part_->x.data();
    static_assert(sizeof(Vec3) == 3 * sizeof(double));
    // Hinge angles and their gradients. An interior edge is one hinge seen
    // from both of its elements (same angle, gradients permuted): when both
    // elements are in this block it is evaluated once. Interior hinges are
    // gathered into structure-of-arrays form, evaluated in one vector pass
    // and handed to their elements; ghost hinges (clamped and symmetry
    // edges) one by one.
    // Hinges go through the vector pass in chunks of kHingeChunk, so that
    // their arrays stay in the first-level cache.
    constexpr int cap = kHingeChunk;
    double* X = sc.hx.data();
    double* G = sc.hg.data();
    double* th = sc.ht.data();
    int* dest = sc.hdest.data();
    int h = 0;
    auto flush = [&]() {
      hinge_block(h, cap, X, th, G, sc.hredo.data());
      for (int j = 0; j < h; ++j) {
        const int slot = dest[2 * j];
        if (sc.hredo[j] != 0) {  // beyond the approximation's range: the library's atan2
          const int e = b + slot / 3, k = slot % 3;
          const int* t = &part_->triangles[3 * e];
          th[j] = hinge_angle(x, t[k], t[(k + 1) % 3], t[(k + 2) % 3], opp_[3 * e + k], nullptr);
        }
        hth[slot] = th[j];
        double* g = &hgrad[12 * slot];  // (c, o, p, q)
        for (int c = 0; c < 12; ++c) g[c] = G[c * cap + j];
        if (const int ps = dest[2 * j + 1]; ps >= 0) {  // the neighour's (c, o, p, q) are (o, c, q, p) here
          hth[ps] = th[j];
          double* gp = &hgrad[12 * ps];
          for (int d = 0; d < 3; ++d) {
            gp[d] = G[(3 + d) * cap + j];
            gp[3 + d] = G[(0 + d) * cap + j];
            gp[6 + d] = G[(9 + d) * cap + j];
            gp[9 + d] = G[(6 + d) * cap + j];
          }
        }
      }
      h = 0;
    };
    for (int e = b; e < end; ++e) {
      const int* t = &part_->triangles[3 * e];
      for (int k = 0; k < 3; ++k) {
        const int o = opp_[3 * e + k];
        if (o >= 0) {
          const int nb = part_->neighbours[3 * e + k];
          const bool shared = nb >= b && nb < end;
          if (shared && nb < e) continue;  // done from the neighbour
          const int nodes[4] = {t[k], t[(k + 1) % 3], t[(k + 2) % 3], o};
          for (int i = 0; i < 4; ++i)
            for (int d = 0; d < 3; ++d) X[(3 * i + d) * cap + h] = x[3 * nodes[i] + d];
          dest[2 * h] = 3 * (e - b) + k;
          dest[2 * h + 1] = shared ? 3 * (nb - b) + partner_k_[3 * e + k] : -1;
          if (++h == cap) flush();
        } else if (clamped_[3 * e + k]) {
          Vec3* g = reinterpret_cast<Vec3*>(&hgrad[36 * (e - b) + 12 * k]);
          hth[3 * (e - b) + k] =
              clamped_[3 * e + k] == 1
                  ? 2 * ghost_angle(x, t[k], t[(k + 1) % 3], t[(k + 2) % 3], load3(n0_.data(), e), -1, g)
                  : ghost_angle(x, t[k], t[(k + 1) % 3], t[(k + 2) % 3], Vec3{0, 0, 0}, clamped_[3 * e + k] - 2, g);
        }
      }
    }
    if (h > 0) flush();
    for (int e = b; e < end; ++e) {
      const double* c = &ginv_[9 * e];
      double K[3] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        double th;
        if (opp_[3 * e + k] >= 0) {
          th = hth[3 * (e - b) + k] - theta0_[3 * e + k];
        } else if (clamped_[3 * e + k]) {
          th = hth[3 * (e - b) + k];
        } else {
          continue;
        }
        for (int r = 0; r < 3; ++r) K[r] += c[3 * k + r] * th;
      }
      for (int r = 0; r < 3; ++r) curv_[3 * e + r] = K[r];
    }
    const int n = end - b;
    MaterialBlock blk;
    blk.n = n;
    blk.strain = std::span<const double>(curv_.data() + 3 * b, 3 * n);
    blk.strain_old = std::span<const double>(curv_old_.data() + 3 * b, 3 * n);
    blk.temperature = std::span<const double>(temp, n);
    blk.dt = in.dt;
    const int ns = bending_->state_size();
    blk.state = std::span<double>(bstate_.data() + static_cast<std::size_t>(ns) * b, static_cast<std::size_t>(ns) * n);
    blk.stress = std::span<double>(sc.moment.data(), 3 * n);
    blk.energy = std::span<double>(sc.benergy.data(), n);
    bending_->evaluate(blk);
    const double rmax = std::max(bending_->max_stiffness(t_lo), bending_->max_stiffness(t_hi));
    const double dtb_scale = rmax > 0 ? 0.5 * std::sqrt(areal_mass_ / rmax) : 0.0;  // once per block
    double energy = 0;
    for (int e = b; e < end; ++e) {
      const double A0 = area0_[e];
      const double* M = &sc.moment[3 * (e - b)];
      const double* gi = &ginv_[9 * e];
      energy += A0 * sc.benergy[e - b];
      double hmin = std::numeric_limits<double>::infinity();
      // Forces on the patch: the element's own nodes (slots 0-2, after the
      // membrane forces) summed in registers, the opposite node of hinge k
      // (slot 3 + k) written once. The hinges are unrolled so that every
      // slot index is a constant.
      double* fe = &out.element_force[18 * static_cast<std::size_t>(e - b)];
      double own[9];
      for (int q = 0; q < 9; ++q) own[q] = fe[q];
      auto hinge = [&]<int k>() {
        constexpr int p = (k + 1) % 3, q = (k + 2) % 3;
        const int o = opp_[3 * e + k];
        const char cl = clamped_[3 * e + k];
        const Vec3* g = reinterpret_cast<const Vec3*>(&hgrad[36 * (e - b) + 12 * k]);
        // dW/dtheta_k = A0 M : dK/dtheta_k = A0 (M11 c11 + M22 c22 + 2 M12 c12).
        const double mk = A0 * (M[0] * gi[3 * k] + M[1] * gi[3 * k + 1] + 2 * M[2] * gi[3 * k + 2]);
        if (o >= 0) {
          hmin = std::min(hmin, d_[3 * e + k]);
          for (int d = 0; d < 3; ++d) {
            own[3 * k + d] += mk * g[0][d];
            fe[9 + 3 * k + d] = mk * g[1][d];
            own[3 * p + d] += mk * g[2][d];
            own[3 * q + d] += mk * g[3][d];
          }
        } else {
          for (int d = 0; d < 3; ++d) fe[9 + 3 * k + d] = 0.0;
          if (cl) {  // ghost neighbour: gradient on (c, p, q)
            const double m = (cl == 1 ? 2.0 : 1.0) * mk;  // clamp: theta = 2 x the rotation
            for (int d = 0; d < 3; ++d) {
              own[3 * k + d] += m * g[0][d];
              own[3 * p + d] += m * g[1][d];
              own[3 * q + d] += m * g[2][d];
            }
          }
        }
      };
      hinge.template operator()<0>();
      hinge.template operator()<1>();
      hinge.template operator()<2>();
      for (int q = 0; q < 9; ++q) fe[q] = own[q];
      // Bending waves: dt ~ d^2 sqrt(rho h / R) / 2 (conservative).
      if (rmax > 0 && std::isfinite(hmin)) {
        const double dtb = hmin * hmin * dtb_scale;
        *dt_min = std::min(*dt_min, dtb);
        if (!out.element_dt.empty()) out.element_dt[e] = std::min(out.element_dt[e], dtb);
      }
    }
    if (in.commit) std::copy(curv_.begin() + 3 * b, curv_.begin() + 3 * end, curv_old_.begin() + 3 * b);
    return energy;
  }

  const MaterialLaw* bending_ = nullptr;
  std::vector<int> opp_, partner_k_, edge_condition_;  // partner_k_: the same edge's index in the neighbour
  std::vector<char> clamped_;
  std::vector<double> n0_;  // initial element normals (clamped elements)
  std::vector<double> d_, theta0_, ginv_, curv_, curv_old_, bstate_;
  const PartView* part_ = nullptr;
  std::vector<const MaterialLaw*> laws_;
  double areal_mass_ = 0;
  std::vector<double> g1_, g2_, area0_, e1_, e2_, strain_, strain_old_, stress_;
  std::vector<std::vector<double>> states_;
};

ElementKernel* create() { return new ShellRfT3(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Element;
  d.name = "shell_rf_t3";
  d.version = "0.2.0";
  d.summary = "Three-node shell triangle, translational dofs: total-Lagrangian membrane, rotation-free bending";
  d.example = R"({ "element": "shell_rf_t3" })";
  r.add_element(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("element_shell_rf_t3", "0.2.0", register_all)
