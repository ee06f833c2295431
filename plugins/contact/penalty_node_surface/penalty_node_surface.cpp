// penalty_node_surface: node-to-surface penalty contact with shell thickness
// (physics.md section 4).
//
// Mechanics: a node of the first body (a ply) whose contact face (mid-surface
// +- h/2) penetrates the second body (a tool surface, or the other ply's
// face at +- h/2 of its mid-surface) gets the normal force
//   f_n = penalty * A_i * penetration
// (A_i: the node's tributary area), and a regularised Coulomb friction force:
// either an elastic tangential spring of the same stiffness, capped at
// mu * f_n (stick below the cap, slip at it), or, with slip_velocity v0 > 0,
// mu * f_n * min(1, |v_t| / v0) against the slip velocity v_t (no stick
// state, so a zone held by friction on both faces has a unique answer).
// The opposite force goes to the tool, or
// to the three nodes of the other ply's element through its shape functions,
// so momentum is conserved.
//
// Ply/ply side: which faces meet comes from the target element normal n_e,
// the node's normal n_c and the approach velocity (physics.md section 4); it
// is kept while the node stays near the target.
//
// Thermal: the faces found touching (gap between the facing shell surfaces
// at most gap_tolerance) get the contact conductance: a Robin condition with
// the tool temperature, or a conservative link between the two plies. The
// conductance is a constant, or a table of the contact pressure
// p = penalty * penetration (the pressure of the node's springs at that
// moment), linear between its points and held beyond its ends.
//
// The friction coefficient is a constant, or a table of the interface
// temperature, linear between its points and held beyond its ends: the
// temperature of the ply's face that touches (against a tool), or the mean
// of the two facing faces (ply/ply), as of the last thermal step.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/parallel.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace ts::contact {
namespace {

using sdk::Vec3;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Nodes per share of the per-node loops (dealt to the threads round robin).
constexpr int kChunk = 128;

// Unit normals of the nodes (area-weighted over their elements).
void node_normals(const sdk::PartView& p, std::vector<double>& nn) {
  nn.assign(3 * static_cast<std::size_t>(p.num_nodes), 0.0);
  for (int e = 0; e < p.num_elements; ++e) {
    const int* t = &p.triangles[3 * e];
    const Vec3 a = sdk::load3(p.x.data(), t[0]), b = sdk::load3(p.x.data(), t[1]), c = sdk::load3(p.x.data(), t[2]);
    const Vec3 n = sdk::cross(sdk::sub(b, a), sdk::sub(c, a));
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) nn[3 * t[k] + d] += n[d];
  }
  for (int i = 0; i < p.num_nodes; ++i) {
    const Vec3 u = sdk::normalized(sdk::load3(nn.data(), i));
    for (int d = 0; d < 3; ++d) nn[3 * i + d] = u[d];
  }
}

// What the ply/ply search needs of each triangle of the target surface,
// kGeo values per element: its unit normal n and the in-plane gradients g1,
// g2 of its barycentric coordinates w1, w2 (w_k = (x - p0) . g_k for the
// projection of a point x on the triangle's plane, w0 = 1 - w1 - w2; the
// gradient of w0 is g0 = -(g1 + g2)). A degenerate (zero-area) triangle gets
// n = 0 and NaN gradients: its weights compare false, so it is never taken
// for a face and always gets the full closest-point search. One vector pass
// over n triangles, written out component by component.
constexpr int kGeo = 9;

// With a list, the triangles list[0..n) of the part, written in that order
// (the k-th at geo + kGeo k).
template <bool kList>
[[gnu::always_inline]] inline void geometry_body(int n, const int* __restrict list, const int* __restrict tri,
                                                 const double* __restrict x, double* __restrict geo) {
#pragma omp simd
  for (int k = 0; k < n; ++k) {
    const int e = kList ? list[k] : k;
    const int i0 = 3 * tri[3 * e], i1 = 3 * tri[3 * e + 1], i2 = 3 * tri[3 * e + 2];
    const double a0 = x[i0], a1 = x[i0 + 1], a2 = x[i0 + 2];
    const double e10 = x[i1] - a0, e11 = x[i1 + 1] - a1, e12 = x[i1 + 2] - a2;  // p1 - p0
    const double e20 = x[i2] - a0, e21 = x[i2 + 1] - a1, e22 = x[i2 + 2] - a2;  // p2 - p0
    const double n0 = e11 * e22 - e12 * e21, n1 = e12 * e20 - e10 * e22, n2 = e10 * e21 - e11 * e20;
    const double area2 = std::sqrt(n0 * n0 + n1 * n1 + n2 * n2);  // twice the area
    const bool ok = area2 > 0;
    const double inv = 1.0 / area2;
    const double ginv = ok ? inv : std::numeric_limits<double>::quiet_NaN();
    const double u0 = ok ? n0 * inv : 0.0, u1 = ok ? n1 * inv : 0.0, u2 = ok ? n2 * inv : 0.0;
    double* g = geo + kGeo * k;
    g[0] = u0;
    g[1] = u1;
    g[2] = u2;
    g[3] = (e21 * u2 - e22 * u1) * ginv;  // g1 = (p2 - p0) x n / 2A
    g[4] = (e22 * u0 - e20 * u2) * ginv;
    g[5] = (e20 * u1 - e21 * u0) * ginv;
    g[6] = (u1 * e12 - u2 * e11) * ginv;  // g2 = n x (p1 - p0) / 2A
    g[7] = (u2 * e10 - u0 * e12) * ginv;
    g[8] = (u0 * e11 - u1 * e10) * ginv;
  }
}
TS_VECTOR_CLONES
void geometry_block(int n, const int* __restrict tri, const double* __restrict x, double* __restrict geo) {
  geometry_body<false>(n, nullptr, tri, x, geo);
}
TS_VECTOR_CLONES
void geometry_list(int n, const int* __restrict list, const int* __restrict tri, const double* __restrict x,
                   double* __restrict geo) {
  geometry_body<true>(n, list, tri, x, geo);
}

// The geometry of all of p's triangles, in chunks shared out over the
// threads where the part is large.
void surface_geometry(const sdk::PartView& p, std::vector<double>& geo) {
  geo.resize(kGeo * static_cast<std::size_t>(p.num_elements));
  constexpr int kChunk = 512;
  const int chunks = (p.num_elements + kChunk - 1) / kChunk;
  sdk::for_each_index(chunks, chunks > 4, 0, [&](int c) {
    geometry_block(std::min(kChunk, p.num_elements - c * kChunk), &p.triangles[3 * c * kChunk], p.x.data(),
                   &geo[kGeo * static_cast<std::size_t>(c) * kChunk]);
  });
}

// The normal force with its damper and the rate-regularised friction force
// of one node with friction > 0 and slip_velocity > 0, for vector loops
// (force_body(), tool_force_body()): n the unit normal
// pushing the node out, v its velocity relative to the target, k its
// penalty stiffness, m its effective mass; damping2 = 2 damping,
// half_share = share / 2 (share: this pair's share of the node's
// friction). Returns the force and the penalty energy.
//
// Rate-regularised Coulomb: mu N min(1, |v_t| / v0) against the slip, and
// never more than half the force that stops the slip within the step
// (share m |v_t| / 2 dt): on the steep branch the slip then decays without
// changing sign, also where several contacts (a tool and the other ply,
// both ply/ply passes) hold the same node. At the full stopping force, two
// such contacts reverse the slip every step: a vibration at the step's
// frequency limit. Taken as a force per unit slip speed (mag / |v_t|), so
// that one division follows the square root; its limit follows the penalty
// (elastic) pressure only, as force_body() explains.
struct RateConstants {
  double damping2, friction, slip, half_share, dt;
};
struct RateForce {
  double f0, f1, f2, energy;
};
[[gnu::always_inline]] inline RateForce rate_force(double pen, double k, double m, double n0, double n1, double n2,
                                                double v0, double v1, double v2, double damping2,
                                                double friction, double slip, double half_share, double dt) {
  const double vn = v0 * n0 + v1 * n1 + v2 * n2;
  const double fd = k * pen - damping2 * std::sqrt(k * m) * vn;
  const double fn = 0.0 < fd ? fd : 0.0;  // std::max(0.0, fd)
  const double t0 = v0 - n0 * vn, t1 = v1 - n1 * vn, t2 = v2 - n2 * vn;
  const double lim = friction * k * pen;
  const double vm = std::sqrt(t0 * t0 + t1 * t1 + t2 * t2);
  // std::min({lim / vm, lim / slip, share m / 2 dt}): the first of equals
  double ps = lim / vm;
  const double p1 = lim / slip, p2 = half_share * m / dt;
  ps = p1 < ps ? p1 : ps;
  ps = p2 < ps ? p2 : ps;
  const bool slips = vm > 0;
  return {fn * n0 + (slips ? t0 * -ps : 0.0), fn * n1 + (slips ? t1 * -ps : 0.0), fn * n2 + (slips ? t2 * -ps : 0.0),
          0.5 * k * pen * pen};
}

// n nodes against a tool, one vector lane per node: the penetration from
// the distance, then rate_force(). A node apart, or through the tool (no
// force from the far side), gets energy 0 and a force that is not read.
// The tangential springs are cleared (there are none with a slip
// velocity). Every node is computed, in contact or not: a vector pass over
// all of them costs less than a scalar loop over those in contact.
// With kTable, node i's friction coefficient is mu[i] (else c.friction).
template <bool kTable>
[[gnu::always_inline]] inline void tool_force_body(int n, const double* __restrict dist, const double* __restrict tn,
                                                   const double* __restrict v, const double* __restrict area,
                                                   const double* __restrict mass, const double* __restrict mu,
                                                   const double* vtool, double h2, double penalty, RateConstants c,
                                                   double* __restrict f, double* __restrict energy,
                                                   double* __restrict ft) {
  const double w0 = vtool[0], w1 = vtool[1], w2 = vtool[2];
  const double c0 = c.damping2, c1 = c.friction, c2 = c.slip, c3 = c.half_share, c4 = c.dt;
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double pen = h2 - dist[i];
    const bool on = (pen > 0) & !(pen > 2 * h2);
    const RateForce r = rate_force(pen, penalty * area[i], mass[i], tn[3 * i], tn[3 * i + 1], tn[3 * i + 2],
                                   v[3 * i] - w0, v[3 * i + 1] - w1, v[3 * i + 2] - w2, c0, kTable ? mu[i] : c1, c2,
                                   c3, c4);
    energy[i] = on ? r.energy : 0.0;
    f[3 * i] = r.f0;
    f[3 * i + 1] = r.f1;
    f[3 * i + 2] = r.f2;
    ft[3 * i] = 0.0;
    ft[3 * i + 1] = 0.0;
    ft[3 * i + 2] = 0.0;
  }
}
TS_VECTOR_CLONES
void tool_force_block(int n, const double* __restrict dist, const double* __restrict tn, const double* __restrict v,
                      const double* __restrict area, const double* __restrict mass, const double* vtool, double h2,
                      double penalty, RateConstants c, double* __restrict f, double* __restrict energy,
                      double* __restrict ft) {
  tool_force_body<false>(n, dist, tn, v, area, mass, nullptr, vtool, h2, penalty, c, f, energy, ft);
}
TS_VECTOR_CLONES
void tool_force_block_mu(int n, const double* __restrict dist, const double* __restrict tn,
                         const double* __restrict v, const double* __restrict area, const double* __restrict mass,
                         const double* __restrict mu, const double* vtool, double h2, double penalty, RateConstants c,
                         double* __restrict f, double* __restrict energy, double* __restrict ft) {
  tool_force_body<true>(n, dist, tn, v, area, mass, mu, vtool, h2, penalty, c, f, energy, ft);
}

// The friction models, as template arguments of the vector force passes.
enum class Friction { kNone, kElastic, kRate };

// The contact forces of n nodes, one vector lane per node: the normal
// penalty force with its damper and the Coulomb friction force, from each
// node's penetration pen (0 where it gets no force), penalty stiffness k,
// effective mass m (the node's, against a tool), unit normal nrm pushing
// it out, velocity relative to the target v and friction coefficient mu;
// c from rate_constants(). Writes the force f and the stored spring energy
// (0 where pen is 0).
//
// The normal force is k pen less a viscous damper, a fraction of the
// critical value of the node on its spring; it never pulls. Friction:
// - kRate: rate_force();
// - kElastic: a tangential spring of the penalty stiffness, held at the
//   Coulomb limit mu k pen while sliding; last step's spring ft, turned
//   into the current tangent plane, is loaded by the tangential velocity
//   over the step. The new springs go to ft_new (those of the nodes
//   without force as they were in ft: the caller clears those it has to).
//   The limit follows the penalty (elastic) pressure only: a limit that
//   followed the damper would tie the tangential force to the normal
//   velocity, a non-symmetric coupling that can feed vibrations;
// - kNone: no tangential force.
// Without springs (kNone, kRate) ft stays 0 and ft_new is not written.
template <Friction kModel>
[[gnu::always_inline]] inline void force_body(int n, const double* __restrict pen, const double* __restrict k,
                                                  const double* __restrict m, const double* __restrict nrm,
                                                  const double* __restrict v, const double* __restrict mu,
                                                  RateConstants c, const double* __restrict ft,
                                                  double* __restrict f, double* __restrict energy,
                                                  double* __restrict ft_new) {
  const double damping2 = c.damping2, slip = c.slip, half_share = c.half_share, dt = c.dt;
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double p = pen[i], kk = k[i], mm = m[i];
    const double n0 = nrm[3 * i], n1 = nrm[3 * i + 1], n2 = nrm[3 * i + 2];
    const double v0 = v[3 * i], v1 = v[3 * i + 1], v2 = v[3 * i + 2];
    if constexpr (kModel == Friction::kRate) {
      const RateForce r = rate_force(p, kk, mm, n0, n1, n2, v0, v1, v2, damping2, mu[i], slip, half_share, dt);
      f[3 * i] = r.f0;
      f[3 * i + 1] = r.f1;
      f[3 * i + 2] = r.f2;
      energy[i] = p > 0 ? r.energy : 0.0;
    } else {
      const double vn = v0 * n0 + v1 * n1 + v2 * n2;
      const double fd = kk * p - damping2 * std::sqrt(kk * mm) * vn;
      const double fn = 0.0 < fd ? fd : 0.0;  // std::max(0.0, fd)
      double e = 0.5 * kk * p * p;
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      if constexpr (kModel == Friction::kElastic) {
        const double o0 = ft[3 * i], o1 = ft[3 * i + 1], o2 = ft[3 * i + 2];
        const double t0 = v0 - n0 * vn, t1 = v1 - n1 * vn, t2 = v2 - n2 * vn;
        const double lim = mu[i] * kk * p;
        // last step's spring turned into the current tangent plane
        const double mag = std::sqrt(o0 * o0 + o1 * o1 + o2 * o2);
        const double on_n = o0 * n0 + o1 * n1 + o2 * n2;
        double q0 = o0 - n0 * on_n, q1 = o1 - n1 * on_n, q2 = o2 - n2 * on_n;
        const double m2 = std::sqrt(q0 * q0 + q1 * q1 + q2 * q2);
        const double turn = m2 > 0 ? mag / m2 : 1.0;  // x * 1.0 is x
        q0 = q0 * turn;
        q1 = q1 * turn;
        q2 = q2 * turn;
        const double kdt = kk * dt;
        s0 = q0 - t0 * kdt;
        s1 = q1 - t1 * kdt;
        s2 = q2 - t2 * kdt;
        const double len = std::sqrt(s0 * s0 + s1 * s1 + s2 * s2);
        const double cap = len > lim ? lim / len : 1.0;
        s0 = s0 * cap;
        s1 = s1 * cap;
        s2 = s2 * cap;
        e = e + 0.5 * (s0 * s0 + s1 * s1 + s2 * s2) / kk;
        ft_new[3 * i] = p > 0 ? s0 : o0;
        ft_new[3 * i + 1] = p > 0 ? s1 : o1;
        ft_new[3 * i + 2] = p > 0 ? s2 : o2;
      }
      f[3 * i] = fn * n0 + s0;
      f[3 * i + 1] = fn * n1 + s1;
      f[3 * i + 2] = fn * n2 + s2;
      energy[i] = p > 0 ? e : 0.0;
    }
  }
}
#define TS_FORCE_BLOCK(name, model)                                                                              \
  TS_VECTOR_CLONES                                                                                                   \
  void name(int n, const double* __restrict pen, const double* __restrict k, const double* __restrict m,             \
            const double* __restrict nrm, const double* __restrict v, const double* __restrict mu,                   \
            RateConstants c, const double* __restrict ft, double* __restrict f, double* __restrict energy,           \
            double* __restrict ft_new) {                                                                             \
    force_body<model>(n, pen, k, m, nrm, v, mu, c, ft, f, energy, ft_new);                                       \
  }
TS_FORCE_BLOCK(force_block_none, Friction::kNone)
TS_FORCE_BLOCK(force_block_elastic, Friction::kElastic)
TS_FORCE_BLOCK(force_block_rate, Friction::kRate)
#undef TS_FORCE_BLOCK

// What a force pass reads of a chunk of nodes besides the nodes' own
// arrays (force_body()'s pen, k, m, nrm, v, mu): a buffer per thread, so
// that it stays in the cache from the chunk's projections to its forces.
struct ChunkScratch {
  alignas(64) double pen[kChunk], k[kChunk], m[kChunk], mu[kChunk], nrm[3 * kChunk], v[3 * kChunk];
};
ChunkScratch& chunk_scratch() {
  thread_local ChunkScratch s;
  return s;
}

// Candidate target elements of every node of body A: a uniform bucket grid
// over B's triangles (inflated by the reach), flat arrays, rebuilt only when
// a node of A or B has moved more than half the margin since the last build.
class Candidates {
 public:
  bool needs_rebuild(const sdk::PartView& a, const sdk::PartView& b) const {
    if (xa_.size() != a.x.size() || xb_.size() != b.x.size()) return true;
    const double lim = 0.25 * margin_ * margin_;
    for (std::size_t k = 0; k < xa_.size(); k += 3)
      if (dist2(&xa_[k], &a.x[k]) > lim) return true;
    for (std::size_t k = 0; k < xb_.size(); k += 3)
      if (dist2(&xb_[k], &b.x[k]) > lim) return true;
    return false;
  }
  void build(const sdk::PartView& a, const sdk::PartView& b, double reach, double margin) {
    margin_ = margin;
    ++builds_;
    xa_.assign(a.x.begin(), a.x.end());
    xb_.assign(b.x.begin(), b.x.end());
    const double inflate = reach + margin;
    Vec3 lo = {kInf, kInf, kInf}, hi = {-kInf, -kInf, -kInf};
    double h = 0;
    for (int e = 0; e < b.num_elements; ++e)
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = sdk::load3(b.x.data(), b.triangles[3 * e + k]);
        const Vec3 q = sdk::load3(b.x.data(), b.triangles[3 * e + (k + 1) % 3]);
        h = std::max(h, sdk::norm(sdk::sub(p, q)));
        for (int d = 0; d < 3; ++d) {
          lo[d] = std::min(lo[d], p[d] - inflate);
          hi[d] = std::max(hi[d], p[d] + inflate);
        }
      }
    int n[3];
    const double cell = sdk::bucket_grid(lo, hi, std::max(h + 2 * inflate, 1e-12), n);
    auto cell_of = [&](double v, int d) { return sdk::bucket_index(v, lo[d], cell, n[d]); };
    const std::size_t ncell = static_cast<std::size_t>(n[0]) * n[1] * n[2];
    start_.assign(ncell + 1, 0);
    std::vector<int> range(6 * static_cast<std::size_t>(b.num_elements));
    for (int e = 0; e < b.num_elements; ++e) {
      for (int d = 0; d < 3; ++d) {
        double mn = kInf, mx = -kInf;
        for (int k = 0; k < 3; ++k) {
          const double v = b.x[3 * b.triangles[3 * e + k] + d];
          mn = std::min(mn, v);
          mx = std::max(mx, v);
        }
        range[6 * e + d] = cell_of(mn - inflate, d);
        range[6 * e + 3 + d] = cell_of(mx + inflate, d);
      }
      const int* r = &range[6 * e];
      for (int k = r[2]; k <= r[5]; ++k)
        for (int j = r[1]; j <= r[4]; ++j)
          for (int i = r[0]; i <= r[3]; ++i) ++start_[(static_cast<std::size_t>(k) * n[1] + j) * n[0] + i + 1];
    }
    for (std::size_t c = 0; c < ncell; ++c) start_[c + 1] += start_[c];
    elems_.assign(start_[ncell], 0);
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int e = 0; e < b.num_elements; ++e) {
      const int* r = &range[6 * e];
      for (int k = r[2]; k <= r[5]; ++k)
        for (int j = r[1]; j <= r[4]; ++j)
          for (int i = r[0]; i <= r[3]; ++i) elems_[fill[(static_cast<std::size_t>(k) * n[1] + j) * n[0] + i]++] = e;
    }
    // Per node: the elements whose box, grown by reach + margin, holds it.
    node_start_.assign(a.num_nodes + 1, 0);
    node_elems_.clear();
    for (int i = 0; i < a.num_nodes; ++i) {
      const Vec3 x = sdk::load3(a.x.data(), i);
      bool outside = false;
      for (int d = 0; d < 3; ++d) outside = outside || x[d] < lo[d] || x[d] > hi[d];
      if (!outside) {
        const std::size_t c = (static_cast<std::size_t>(cell_of(x[2], 2)) * n[1] + cell_of(x[1], 1)) * n[0] + cell_of(x[0], 0);
        for (int q = start_[c]; q < start_[c + 1]; ++q) {
          const int e = elems_[q];
          bool near = true;
          for (int d = 0; d < 3 && near; ++d) {
            double mn = kInf, mx = -kInf;
            for (int k = 0; k < 3; ++k) {
              const double v = b.x[3 * b.triangles[3 * e + k] + d];
              mn = std::min(mn, v);
              mx = std::max(mx, v);
            }
            near = x[d] >= mn - inflate && x[d] <= mx + inflate;
          }
          if (near) node_elems_.push_back(e);
        }
      }
      node_start_[i + 1] = static_cast<int>(node_elems_.size());
    }
  }
  // Candidate elements of node i: [begin, end).
  std::pair<const int*, const int*> of(int i) const {
    if (node_start_[i] == node_start_[i + 1]) return {nullptr, nullptr};
    return {node_elems_.data() + node_start_[i], node_elems_.data() + node_start_[i + 1]};
  }
  long long builds() const { return builds_; }
  // The entries of node i's candidates in the list of all nodes' (begin;
  // [entry(i), entry(i + 1))), and the number of entries.
  int entry(int i) const { return node_start_[i]; }
  std::size_t entries() const { return node_elems_.size(); }
  // Checkpoints: the positions of the last build and its lists (written
  // or read back by the same list, sdk/state.hpp).
  template <class A>
  bool state_io(A& a) {
    return a.io_vector(xa_) && a.io_vector(xb_) && a.io_vector(start_) && a.io_vector(elems_) &&
           a.io_vector(node_start_) && a.io_vector(node_elems_) && a.io(margin_) && a.io(builds_);
  }

 private:
  static double dist2(const double* p, const double* q) {
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
  }
  std::vector<double> xa_, xb_;
  std::vector<int> start_, elems_, node_start_, node_elems_;
  double margin_ = 0;
  long long builds_ = 0;
};

struct Projection {
  int element = -1;
  double d = 0;            // signed distance of the node from the target's mid-surface (+ on the side of n_e)
  Vec3 n = {0, 0, 1};      // unit direction of d, on the side of n_e
  double w[3] = {0, 0, 0};  // weights of the target point on the element's nodes
  bool border = false;      // off the face at the target's free border (an edge without a neighbour or a vertex of one)
};

// The nodes of b on its free border (1), from its neighbours; once per
// pass (a mesh keeps its topology).
inline void border_nodes(const sdk::PartView& b, std::vector<char>& border) {
  if (border.size() == static_cast<std::size_t>(b.num_nodes)) return;
  border.assign(b.num_nodes, 0);
  for (int e = 0; e < b.num_elements; ++e)
    for (int k = 0; k < 3; ++k)
      if (b.neighbours[3 * static_cast<std::size_t>(e) + k] < 0) {
        border[b.triangles[3 * e + (k + 1) % 3]] = 1;
        border[b.triangles[3 * e + (k + 2) % 3]] = 1;
      }
}

// Whether the closest point of weights w on triangle e of b (off its face:
// a weight 0 or 1) lies on b's free border: at a vertex on it (border, per
// node) or on an edge without a neighbour.
inline bool on_border(const sdk::PartView& b, const std::vector<char>& border, int e, const double* w) {
  const int* t = &b.triangles[3 * static_cast<std::size_t>(e)];
  for (int k = 0; k < 3; ++k)
    if (w[k] == 1.0) return border[t[k]] != 0;
  for (int k = 0; k < 3; ++k)
    if (w[k] == 0.0) return b.neighbours[3 * static_cast<std::size_t>(e) + k] < 0;
  return false;
}

// Plane distance of x from the triangle with per-element geometry g (kGeo
// values) and first node p0, and the weights of x's projection on its
// plane; whether the projection lies in the (closed) triangle (false for a
// degenerate triangle: NaN weights).
inline bool locate(const Vec3& x, const double* g, const double* p0, double* w, double& plane) {
  const double rx = x[0] - p0[0], ry = x[1] - p0[1], rz = x[2] - p0[2];
  plane = rx * g[0] + ry * g[1] + rz * g[2];
  w[1] = rx * g[3] + ry * g[4] + rz * g[5];
  w[2] = rx * g[6] + ry * g[7] + rz * g[8];
  w[0] = 1.0 - w[1] - w[2];
  return w[0] >= 0 && w[1] >= 0 && w[2] >= 0;
}

// A target over an edge or a vertex: r = x - closest point (r . r = d2),
// dn = r . n_e. Its distance is signed by the side of n_e, and its normal
// is the direction from the closest point (the same whichever of the
// triangles sharing that point was found).
inline void off_face(Projection& p, const Vec3& r, double d2, double dn) {
  const double dist = std::sqrt(d2);
  p.d = dn >= 0 ? dist : -dist;
  if (dist > 0) p.n = sdk::scale(r, (dn >= 0 ? 1.0 : -1.0) / dist);
}

// Which nodes a tool query may skip (1) or must ask (0): a node last asked
// at x_q, when the tool had travelled sq, at a distance dist beyond the
// cutoff, cannot have come within the cutoff while it has moved less than
// the slack that the tool's travel since (path - sq) leaves; a relative
// margin covers the round-off of the sums. Nodes at a distance that is not
// finite are always asked. One vector pass.
TS_VECTOR_CLONES
void skip_flags(std::size_t n, const double* __restrict dist, const double* __restrict sq, const double* __restrict x,
                const double* __restrict xq, double cutoff, double path, double* __restrict skip) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const double slack = dist[i] - cutoff - (path - sq[i]) * (1 + 1e-9) - 1e-9 * cutoff;
    const double dx = x[3 * i] - xq[3 * i], dy = x[3 * i + 1] - xq[3 * i + 1], dz = x[3 * i + 2] - xq[3 * i + 2];
    skip[i] = (static_cast<int>(slack > 0) & static_cast<int>(std::abs(dist[i]) < kInf) &
               static_cast<int>(dx * dx + dy * dy + dz * dz < slack * slack))
                  ? 1.0
                  : 0.0;
  }
}

// Lower bounds of the distances from the nodes of A to their candidate
// triangles of B at reference positions, which a search prunes by: a
// candidate whose bound, less what the node and the triangle's corners
// have moved since, exceeds the node's distance to its reference target
// plus that motion is farther than the target now, so the closest point
// is not on it. The search then finds, bit for bit, the target the full
// search finds. Formed again where the candidate lists change and where
// the motion since the reference grows past a fraction of the reach.
struct PruneBounds {
  long long builds = -1;    // the candidate lists' build they were formed for (-1: none)
  double reach = 0;         // of the searches they serve
  std::vector<double> lb;   // per candidate entry (Candidates::entry)
  std::vector<double> xa, xb;  // the reference positions
  std::vector<double> dref;    // per node of a: its target's distance at the reference (reach: none)
  std::vector<int> tref;       // per node of a: its target at the reference (-1: none)
  std::vector<double> da, db, dt;  // this search: motion of each node of a, of b, and per triangle of b its corners' largest
  double moved = 0;                // this search: the largest motion of a plus that of b
  bool active = false;             // prune in this search (the bounds are valid)
};

// One direction of ply/ply search: nodes of `a` against the surface of `b`.
struct Pass {
  PruneBounds prune;
  int a = 0, b = 0;
  std::vector<signed char> side;  // per node of a: +1 above the target, -1 below, 0 not tracked
  std::vector<double> ft;         // per node of a: tangential spring force (N)
  std::vector<double> geo_b;  // surface_geometry of b, kGeo per element
  std::vector<char> border_b;  // per node of b: 1 on its free border (an edge without a neighbour)
  Candidates cand;
  // Per node of a, written by the node's loop, read by the fixed-order sums:
  // its force (3), its spring energy, its target (element, 3 weights), its
  // penetration (where it has a target).
  std::vector<double> scratch, energy, target, pen;
  // With search_interval > 1: the triangle of b that the last full search
  // found for each node of a (-1: none within reach), the passes since
  // that search (counting it), and the passes it covers (search_limit()).
  std::vector<int> kept;
  long long calls = 0, limit = 1;
  // The distinct triangles in kept, their geometry (kGeo each, evaluated at
  // the passes between full searches), each node's place in that list
  // (-1: none), and per triangle of b its place (building the list).
  std::vector<int> kept_list, slot, used;
  std::vector<double> geo_kept;
  // With a friction table: each node's coefficient at its bottom and top
  // face (2 per node of a) for the face temperatures of `version`
  // (ContactForceInput::temperature_version), whether a node of a has
  // faces at different temperatures, the node normals of this call where
  // thermal_contacts has given none, and (against a tool) each node's
  // coefficient.
  std::uint64_t version = 0;
  bool faces_differ = false;
  std::vector<double> mu2, nn_now, mu;
  // The tangential springs of the vector force pass (ft's next values).
  std::vector<double> ft_new;
};

class PenaltyNodeSurface final : public sdk::ContactHandler {
 public:
  sdk::Status configure(const sdk::Params& params, const sdk::ContactPair& pair, std::span<const sdk::PartView> parts,
                        std::span<const sdk::ToolView>) override {
    return sdk::guarded([&] {
      pair_ = pair;
      penalty_ = params.real("penalty");
      friction_ = params.real("friction");
      slip_velocity_ = params.real("slip_velocity");
      damping_ = params.real("damping");
      conductance_ = params.real("conductance");
      h_p_ = params.list("conductance_pressures");
      h_v_ = params.list("conductance_values");
      if (auto st = check_table("conductance_pressures", "Pa", h_p_, "conductance_values", h_v_); !st) return st;
      h_max_ = h_v_.empty() ? conductance_ : *std::max_element(h_v_.begin(), h_v_.end());
      mu_t_ = params.list("friction_temperatures");
      mu_v_ = params.list("friction_values");
      if (auto st = check_table("friction_temperatures", "degC", mu_t_, "friction_values", mu_v_); !st) return st;
      has_friction_ = mu_v_.empty() ? friction_ > 0 : *std::max_element(mu_v_.begin(), mu_v_.end()) > 0;
      gap_tol_ = params.real("gap_tolerance");
      search_interval_ = params.integer("search_interval");
      prune_search_ = params.boolean("prune_search");
      if (search_interval_ != 1 && pair.second.type != sdk::BodyRef::Type::Part)
        return sdk::Status::failure(
            "search_interval applies to ply/ply pairs only (a tool's distances are exact at every step)");
      const sdk::PartView& a = parts[pair.first.index];
      double h = a.thickness;
      if (pair.second.type == sdk::BodyRef::Type::Part) h = std::min(h, parts[pair.second.index].thickness);
      if (gap_tol_ < 0) gap_tol_ = 0.01 * h;  // default: 1 % of the thinner ply
      pass_[0].a = a.index;
      pass_[0].side.assign(a.num_nodes, 0);
      pass_[0].ft.assign(3 * static_cast<std::size_t>(a.num_nodes), 0.0);
      if (pair.second.type == sdk::BodyRef::Type::Part) {
        const sdk::PartView& b = parts[pair.second.index];
        pass_[0].b = b.index;
        pass_[1].a = b.index;
        pass_[1].b = a.index;
        pass_[1].side.assign(b.num_nodes, 0);
        pass_[1].ft.assign(3 * static_cast<std::size_t>(b.num_nodes), 0.0);
      }
      return sdk::Status::success();
    });
  }

  sdk::Status node_stiffness(std::span<const std::span<const double>> node_area,
                             std::span<const std::span<double>> k) override {
    // Node against a rigid tool: k = penalty * A. Ply against ply: the
    // relative motion of the two bodies sees the spring from both sides, so
    // each side is bounded with twice the node's own spring.
    const int a = pair_.first.index;
    const bool tool = pair_.second.type == sdk::BodyRef::Type::Tool;
    for (std::size_t i = 0; i < node_area[a].size(); ++i) k[a][i] += (tool ? 1.0 : 2.0) * penalty_ * node_area[a][i];
    if (!tool) {
      const int b = pair_.second.index;
      for (std::size_t i = 0; i < node_area[b].size(); ++i) k[b][i] += 2.0 * penalty_ * node_area[b][i];
    }
    return sdk::Status::success();
  }

  double largest_conductance() const override { return h_max_; }

  sdk::Status thermal_contacts(std::span<const sdk::PartView> parts, std::span<const sdk::ToolView> tools,
                               std::span<const std::span<const double>> node_area,
                               sdk::ThermalContactMap& out) override {
    return sdk::guarded([&] {
      const sdk::PartView& a = parts[pair_.first.index];
      // The node normals also choose the face whose temperature sets a
      // friction table's coefficient (contact_forces).
      const bool table = !mu_t_.empty();
      if (!(h_max_ > 0) && !table) return sdk::Status::success();  // no heat exchange
      node_normals(a, nn_a_);
      if (table && pair_.second.type == sdk::BodyRef::Type::Part) node_normals(parts[pair_.second.index], nn_b_);
      if (!(h_max_ > 0)) return sdk::Status::success();
      if (pair_.second.type == sdk::BodyRef::Type::Tool) {
        const sdk::ToolView& tool = tools[pair_.second.index];
        query_tool(a, tool);
        for (int i = 0; i < a.num_nodes; ++i) {
          const double c = sdk::dot(sdk::load3(tn_.data(), i), sdk::load3(nn_a_.data(), i));
          // A tool whose outward normal opposes the ply normal lies above it.
          const int face = c < 0 ? sdk::kTop : sdk::kBottom;
          const double gap = dist_[i] - 0.5 * a.thickness;
          if (gap <= gap_tol_)
            out.tool_contacts.push_back({a.index, i, face, tool.index, conductance_at(-penalty_ * gap)});
        }
        return sdk::Status::success();
      }
      const sdk::PartView& b = parts[pair_.second.index];
      Pass& ps = pass_[0];
      surface_geometry(b, ps.geo_b);
      border_nodes(b, ps.border_b);
      const double hsum2 = 0.5 * (a.thickness + b.thickness);
      refresh_candidates(ps, a, b, 2 * hsum2 + gap_tol_);
      for (int i = 0; i < a.num_nodes; ++i) {
        const Projection pr = project(ps, a, b, i, hsum2 + gap_tol_);
        if (pr.element < 0) continue;
        const int s = ps.side[i] != 0 && !pr.border ? ps.side[i] : (pr.d >= 0 ? 1 : -1);
        const double gap = s * pr.d - hsum2;
        if (gap > gap_tol_) continue;
        sdk::HeatLink l;
        l.part_a = a.index;
        l.node_a = i;
        l.part_b = b.index;
        for (int j = 0; j < 3; ++j) {
          l.nodes_b[j] = b.triangles[3 * pr.element + j];
          l.w_b[j] = pr.w[j];
        }
        const double c = sdk::dot(sdk::load3(nn_a_.data(), i), sdk::load3(&ps.geo_b[kGeo * pr.element], 0));
        if (s > 0) {  // node above the target: target's top face, the node's face looking down
          l.face_b = sdk::kTop;
          l.face_a = c > 0 ? sdk::kBottom : sdk::kTop;
        } else {
          l.face_b = sdk::kBottom;
          l.face_a = c > 0 ? sdk::kTop : sdk::kBottom;
        }
        l.conductance = conductance_at(-penalty_ * gap) * node_area[a.index][i];
        out.links.push_back(l);
      }
      return sdk::Status::success();
    });
  }

  sdk::Status contact_forces(const sdk::ContactForceInput& in, sdk::ContactForceOutput& out) override {
    return sdk::guarded([&] {
      if (pair_.second.type == sdk::BodyRef::Type::Tool) return tool_forces(in, out);
      return ply_forces(in, out);
    });
  }

  // Ply/ply: the two passes (nodes of each ply against the other's surface)
  // share nothing they write, so the kernel may run them at the same time.
  int sides() const override { return pair_.second.type == sdk::BodyRef::Type::Part ? 2 : 1; }

  // Checkpoints: per search direction the tracked sides, the tangential
  // springs, the candidate lists and the kept targets between full
  // searches; the tool queries' distances and where they were asked.
  sdk::Status save_state(sdk::StateWriter& out) const override {
    const_cast<PenaltyNodeSurface*>(this)->state_io(out);  // writing changes nothing
    return sdk::Status::success();
  }
  sdk::Status load_state(sdk::StateReader& in) override {
    if (!state_io(in)) return sdk::Status::failure("penalty_node_surface: the checkpoint does not fit this pair");
    return sdk::Status::success();
  }

 private:
  // A table of y at points x: as many entries of each, x increasing.
  static sdk::Status check_table(const char* x_name, const char* x_unit, const std::vector<double>& x,
                                 const char* y_name, const std::vector<double>& y) {
    if (x.size() != y.size())
      return sdk::Status::failure(std::string(x_name) + " has " + std::to_string(x.size()) + " entries, " + y_name +
                                  " has " + std::to_string(y.size()));
    for (std::size_t k = 1; k < x.size(); ++k)
      if (!(x[k] > x[k - 1])) {
        char msg[160];
        std::snprintf(msg, sizeof msg, "%s must increase: entry %zu (%g %s) follows %g %s", x_name, k, x[k], x_unit,
                      x[k - 1], x_unit);
        return sdk::Status::failure(msg);
      }
    return sdk::Status::success();
  }

  // The conductance (W/(m^2 K)) at contact pressure p (Pa; a face within the
  // gap tolerance but not pressed has p <= 0, taken as 0).
  double conductance_at(double p) const {
    if (h_p_.empty()) return conductance_;
    return table_at(h_p_, h_v_, p);
  }
  // The friction coefficient at interface temperature T (degC).
  double friction_at(double T) const {
    if (mu_t_.empty()) return friction_;
    return table_at(mu_t_, mu_v_, T);
  }
  // y(x) of the table (xs increasing, ys as many), linear between its points
  // and held beyond its ends.
  static double table_at(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
    if (!(x > xs.front())) return ys.front();
    if (x >= xs.back()) return ys.back();
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin());
    const double s = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
    return ys[k - 1] + s * (ys[k] - ys[k - 1]);
  }
  // The temperature of face f of node i of part p as of the last thermal
  // step (the part's initial temperature from a host that gives none).
  static double face_temperature(const sdk::ContactForceInput& in, int p, int i, int f) {
    if (static_cast<std::size_t>(p) >= in.face_temperature.size() || in.face_temperature[p].empty())
      return in.parts[p].initial_temperature;
    return in.face_temperature[p][2 * static_cast<std::size_t>(i) + f];
  }
  // With a friction table: ps's coefficients at the faces of its nodes
  // (renewed when the face temperatures change), and the node normals that
  // choose the face where the two differ: those of the last
  // thermal_contacts (every contact sample), else (no thermal solver) this
  // call's. Returns the normals to use (empty where no node's faces differ).
  const std::vector<double>& friction_faces(Pass& ps, const sdk::ContactForceInput& in, const sdk::PartView& a,
                                            const std::vector<double>& thermal_normals) {
    const std::size_t n = static_cast<std::size_t>(a.num_nodes);
    if (in.temperature_version == 0 || ps.version != in.temperature_version || ps.mu2.size() != 2 * n) {
      ps.version = in.temperature_version;
      ps.mu2.resize(2 * n);
      ps.faces_differ = false;
      for (std::size_t i = 0; i < n; ++i) {
        const double tb = face_temperature(in, a.index, static_cast<int>(i), sdk::kBottom);
        const double tt = face_temperature(in, a.index, static_cast<int>(i), sdk::kTop);
        ps.faces_differ = ps.faces_differ || tb != tt;
        ps.mu2[2 * i] = friction_at(tb);
        ps.mu2[2 * i + 1] = friction_at(tt);
      }
    }
    if (!ps.faces_differ) {
      ps.nn_now.clear();
      return ps.nn_now;
    }
    if (thermal_normals.size() == 3 * n) return thermal_normals;
    node_normals(a, ps.nn_now);
    return ps.nn_now;
  }

  // Distances and normals of a's nodes to the tool, for the nodes that can
  // be within `cutoff` (ply thickness + gap tolerance: every force and heat
  // decision looks closer than that). A node last found at distance d > 0
  // from the tool, at position x_q and with the tool since moved along a
  // path of length s - s_q, is now at least d - |x - x_q| - (s - s_q) away:
  // while that exceeds the cutoff it is not asked again and keeps its old
  // distance (beyond the cutoff, so every decision is the one an exact
  // answer gives; its normal is not used). Nodes inside or behind the tool
  // are asked every time, and so are nodes beyond twice the cutoff of a
  // tool that answers them with +infinity (a mesh tool): their distance
  // bounds nothing. Without the tool's displacement (a host that does not
  // give it) every node is asked.
  void query_tool(const sdk::PartView& a, const sdk::ToolView& tool) {
    const std::size_t n = static_cast<std::size_t>(a.num_nodes);
    const double cutoff = a.thickness + gap_tol_;
    const Vec3 u = tool.displacement ? Vec3{tool.displacement[0], tool.displacement[1], tool.displacement[2]}
                                     : Vec3{0, 0, 0};
    if (dist_.size() != n) {  // a distance of 0 is never skipped: every node is asked first
      dist_.assign(n, 0.0);
      tn_.assign(3 * n, 0.0);
      xq_.assign(3 * n, 0.0);
      sq_.assign(n, 0.0);
      tool_path_ = 0;
      tool_u_ = u;
    }
    // Path length of the tool (an upper bound of its displacement between
    // any two queries); a relative margin covers the round-off of the sums.
    tool_path_ += sdk::norm(sdk::sub(u, tool_u_));
    tool_u_ = u;
    // Runs of consecutive nodes to ask are queried in place (one call per
    // run, no copies); where and when a node was asked is kept only for
    // nodes beyond the cutoff, the only ones that can be skipped next time.
    skip_.resize(n);
    // The tool's records of the nodes (query_kept): a cache of the same
    // answers, formed again after a restart rather than saved.
    if (tool.query_kept && kept_.size() != n * tool.kept_bytes) kept_.assign(n * tool.kept_bytes, std::byte{0});
    if (tool.displacement)
      skip_flags(n, dist_.data(), sq_.data(), a.x.data(), xq_.data(), cutoff, tool_path_, skip_.data());
    else
      std::fill(skip_.begin(), skip_.end(), 0.0);
    auto skip = [&](std::size_t i) { return skip_[i] != 0.0; };
    for (std::size_t i = 0; i < n;) {
      if (skip(i)) {
        ++i;
        continue;
      }
      std::size_t j = i + 1;
      while (j < n && !skip(j)) ++j;
      if (tool.query_kept)
        tool.query_kept(tool.context, j - i, &a.x[3 * i], 2 * cutoff, &dist_[i], &tn_[3 * i],
                        kept_.data() + i * tool.kept_bytes);
      else
        tool.query(tool.context, j - i, &a.x[3 * i], 2 * cutoff, &dist_[i], &tn_[3 * i]);
      for (std::size_t k = i; k < j; ++k) {
        if (dist_[k] > cutoff) {
          sq_[k] = tool_path_;
          for (int d = 0; d < 3; ++d) xq_[3 * k + d] = a.x[3 * k + d];
        }
      }
      i = j + 1;  // node j (if any) is skipped
    }
  }

  template <class A>
  bool state_io(A& a) {
    bool ok = true;
    for (Pass& ps : pass_)
      ok = ok && a.io_array(ps.side) && a.io_array(ps.ft) && ps.cand.state_io(a) && a.io_vector(ps.kept) &&
           a.io(ps.calls) && a.io(ps.limit) && a.io_vector(ps.kept_list) && a.io_vector(ps.slot) &&
           a.io_vector(ps.used) && a.io_vector(ps.geo_kept) && a.io_vector(ps.geo_b);
    return ok && a.io_vector(nn_a_) && a.io_vector(nn_b_) && a.io_vector(dist_) && a.io_vector(tn_) && a.io_vector(xq_) &&
           a.io_vector(sq_) && a.io(tool_path_) && a.io(tool_u_);
  }

  // Rebuilds ps's candidate lists if a node has moved too far since the
  // last build.
  void refresh_candidates(Pass& ps, const sdk::PartView& a, const sdk::PartView& b, double reach) {
    if (!ps.cand.needs_rebuild(a, b)) return;
    double h = 0;
    for (int e = 0; e < b.num_elements; ++e)
      for (int k = 0; k < 3; ++k)
        h = std::max(h, sdk::norm(sdk::sub(sdk::load3(b.x.data(), b.triangles[3 * e + k]),
                                           sdk::load3(b.x.data(), b.triangles[3 * e + (k + 1) % 3]))));
    ps.cand.build(a, b, reach, std::max(0.1 * h, 0.5 * reach));
  }

  // The target of node i within `reach` of B's mid-surface: the closest
  // point on B's candidate triangles. Inside a triangle the distance is
  // measured along its normal; on an edge or a vertex (a node over a convex
  // fold finds no triangle under it) along the direction from that point,
  // so the surface acts as if its folds were rounded.
  //
  // Two sweeps: first the triangles the node projects into (closed; the
  // projection is then the closest point, at the plane distance), then the
  // others, skipped where a lower bound of their distance is already
  // farther than the best: the projection is beyond the line of edge k
  // (w_k < 0) by -w_k / |g_k| in the plane, so the distance is at least
  // sqrt(plane^2 + w_k^2 / |g_k|^2). Only the rest get the full
  // closest-point search. Of equally close triangles the first found is kept.
  //
  // With `pruned` (ps.prune active), candidates that PruneBounds shows to be
  // farther than the node's reference target are skipped: the same target.
  Projection project(const Pass& ps, const sdk::PartView& a, const sdk::PartView& b, int i, double reach,
                     bool pruned = false) const {
    Projection best;
    double best_d2 = reach * reach;  // squared: no square root per candidate
    const Vec3 x = sdk::load3(a.x.data(), i);
    const auto [begin, end] = ps.cand.of(i);
    if (!begin) return best;
    const bool self = a.index == b.index;
    // The bound a candidate must pass: the reference target's distance now
    // is at most its distance then plus the motions since (a relative
    // margin covers the round-off of the bounds).
    const PruneBounds& pb = ps.prune;
    const double* lb = pruned ? pb.lb.data() + ps.cand.entry(i) : nullptr;
    double bound = 0;
    if (pruned) {
      const int tr = pb.tref[i];
      bound = tr >= 0 ? pb.dref[i] + pb.da[i] + pb.dt[tr] : reach;
      bound = bound * (1 + 1e-9) + 1e-12 * reach + pb.da[i];
    }
    // Skip candidate *it (triangle e): farther than the bound.
    const int* const first = begin;  // (a structured binding is not captured by Clang 14)
    auto far = [&](const int* it, int e) { return lb && lb[it - first] - pb.dt[e] > bound; };
    // Plane distance and projection weights of x on candidate e.
    auto locate_on = [&](int e, const int* t, double* w, double& plane) {
      return locate(x, &ps.geo_b[kGeo * static_cast<std::size_t>(e)], &b.x[3 * static_cast<std::size_t>(t[0])], w,
                    plane);
    };
    bool face = false;
    Vec3 best_r{0, 0, 0};
    double best_dn = 0;
    auto take = [&](int e, const double* w, double d2) {
      best.element = e;
      best_d2 = d2;
      for (int j = 0; j < 3; ++j) best.w[j] = w[j];
    };
    auto closer = [&](double d2) { return !(d2 > best_d2 || (d2 == best_d2 && best.element >= 0)); };
    // A candidate the node does not project into: bound, then full search.
    auto edge_or_vertex = [&](int e, const int* t, double* w, double plane) {
      const double room = best_d2 - plane * plane;  // what the in-plane distance may add, squared
      if (room < 0) return;
      const double* g = &ps.geo_b[kGeo * static_cast<std::size_t>(e)];
      const double gk[3][3] = {{-g[3] - g[6], -g[4] - g[7], -g[5] - g[8]}, {g[3], g[4], g[5]}, {g[6], g[7], g[8]}};
      for (int k = 0; k < 3; ++k)
        if (w[k] < 0 && w[k] * w[k] > room * (gk[k][0] * gk[k][0] + gk[k][1] * gk[k][1] + gk[k][2] * gk[k][2]))
          return;
      const Vec3 cp = sdk::closest_point_on_triangle(x, sdk::load3(b.x.data(), t[0]), sdk::load3(b.x.data(), t[1]),
                                                     sdk::load3(b.x.data(), t[2]), w);
      const Vec3 r = sdk::sub(x, cp);
      const double d2 = sdk::dot(r, r);
      if (!closer(d2)) return;
      take(e, w, d2);
      best_r = r;
      best_dn = sdk::dot(r, sdk::load3(g, 0));
      face = false;
    };
    // The first sweep keeps what it found of the other candidates (up to
    // kKeep of them; beyond that the second sweep computes it again).
    constexpr int kKeep = 32;
    struct Kept {
      int e;
      double plane, w[3];
    } kept[kKeep];
    int nkept = 0;
    const bool keep = end - begin <= kKeep;
    for (const int* it = begin; it != end; ++it) {
      const int e = *it;
      const int* t = &b.triangles[3 * e];
      if (self && (t[0] == i || t[1] == i || t[2] == i)) continue;  // self contact
      if (far(it, e)) continue;
      double w[3], plane;
      if (!locate_on(e, t, w, plane)) {
        if (keep) kept[nkept++] = {e, plane, {w[0], w[1], w[2]}};
        continue;
      }
      if (!closer(plane * plane)) continue;
      take(e, w, plane * plane);
      best.d = plane;
      face = true;
    }
    if (keep) {
      for (int k = 0; k < nkept; ++k) edge_or_vertex(kept[k].e, &b.triangles[3 * kept[k].e], kept[k].w, kept[k].plane);
    } else {
      for (const int* it = begin; it != end; ++it) {
        const int e = *it;
        const int* t = &b.triangles[3 * e];
        if (self && (t[0] == i || t[1] == i || t[2] == i)) continue;
        if (far(it, e)) continue;
        double w[3], plane;
        if (!locate_on(e, t, w, plane)) edge_or_vertex(e, t, w, plane);
      }
    }
    if (best.element < 0) return best;
    best.n = sdk::load3(&ps.geo_b[kGeo * static_cast<std::size_t>(best.element)], 0);
    if (face) return best;  // d: the plane distance, n: the triangle's normal
    off_face(best, best_r, best_d2, best_dn);
    best.border = on_border(b, ps.border_b, best.element, best.w);
    return best;
  }

  // Before a full search of pass ps (the candidate lists and ps.geo_b
  // current): the motions since the reference of ps.prune, which it prunes
  // by if the lists are those of the reference and the motions stay under
  // kPruneMotion of the reach; otherwise a new reference (the bounds at the
  // current positions; this search records the targets).
  static constexpr double kPruneMotion = 0.05;
  void prepare_prune(Pass& ps, const sdk::PartView& a, const sdk::PartView& b, double reach) const {
    PruneBounds& pb = ps.prune;
    // Every candidate, as at a new reference, without pruning or between
    // searches spaced by search_interval: the plies move farther between
    // them than the bounds serve (on the hemisphere jobs, every search would
    // form them again and prune nothing).
    if (!prune_search_ || search_interval_ > 1) {
      pb.active = false;
      pb.tref.resize(static_cast<std::size_t>(a.num_nodes));
      pb.dref.resize(static_cast<std::size_t>(a.num_nodes));
      return;
    }
    const std::size_t na = static_cast<std::size_t>(a.num_nodes), nb = static_cast<std::size_t>(b.num_nodes);
    pb.da.resize(na);
    pb.db.resize(nb);
    pb.dt.resize(static_cast<std::size_t>(b.num_elements));
    if (pb.builds == ps.cand.builds() && pb.reach == reach && pb.xa.size() == a.x.size() && pb.xb.size() == b.x.size()) {
      double ma = motions(na, a.x.data(), pb.xa.data(), pb.da.data());
      double mb = motions(nb, b.x.data(), pb.xb.data(), pb.db.data());
      pb.moved = ma + mb;
      if (pb.moved <= kPruneMotion * reach) {
        for (int e = 0; e < b.num_elements; ++e) {
          const int* t = &b.triangles[3 * static_cast<std::size_t>(e)];
          pb.dt[e] = std::max(pb.db[t[0]], std::max(pb.db[t[1]], pb.db[t[2]]));
        }
        pb.active = true;
        return;
      }
    }
    pb.active = false;
    pb.builds = ps.cand.builds();
    pb.reach = reach;
    pb.xa.assign(a.x.begin(), a.x.end());
    pb.xb.assign(b.x.begin(), b.x.end());
    pb.dref.assign(na, reach);
    pb.tref.assign(na, -1);
    pb.lb.resize(ps.cand.entries());
    std::fill(pb.da.begin(), pb.da.end(), 0.0);
    std::fill(pb.dt.begin(), pb.dt.end(), 0.0);
    // Each candidate's distance is at least sqrt(plane^2 + (w_k / |g_k|)^2)
    // for any weight w_k < 0 (see project()).
    const int chunks = (a.num_nodes + kChunk - 1) / kChunk;
    sdk::for_each_index(chunks, a.num_nodes > 256, 1, [&](int ch) {
      const int i1 = std::min(a.num_nodes, (ch + 1) * kChunk);
      for (int i = ch * kChunk; i < i1; ++i) {
        const Vec3 x = sdk::load3(a.x.data(), i);
        const auto [begin, end] = ps.cand.of(i);
        double* lb = pb.lb.data() + ps.cand.entry(i);
        for (const int* it = begin; it != end; ++it) {
          const int e = *it;
          const double* g = &ps.geo_b[kGeo * static_cast<std::size_t>(e)];
          double w[3], plane;
          locate(x, g, &b.x[3 * static_cast<std::size_t>(b.triangles[3 * static_cast<std::size_t>(e)])], w, plane);
          const double gk[3][3] = {{-g[3] - g[6], -g[4] - g[7], -g[5] - g[8]}, {g[3], g[4], g[5]}, {g[6], g[7], g[8]}};
          double off = 0;
          for (int k = 0; k < 3; ++k)
            if (w[k] < 0) off = std::max(off, w[k] * w[k] / (gk[k][0] * gk[k][0] + gk[k][1] * gk[k][1] + gk[k][2] * gk[k][2]));
          lb[it - begin] = std::sqrt(plane * plane + off);
        }
      }
    });
  }
  // |x_i - x0_i| of n nodes into d; returns the largest.
  static double motions(std::size_t n, const double* x, const double* x0, double* d) {
    double m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double* p = x + 3 * i;
      const double* q = x0 + 3 * i;
      d[i] = std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
      m = std::max(m, d[i]);
    }
    return m;
  }

  // The closest point of node i on triangle e of B alone, as project()
  // computes it for that one candidate (no target if farther than reach).
  Projection project_on(const Pass& ps, const sdk::PartView& a, const sdk::PartView& b, int i, int e, const double* g,
                        double reach) const {
    Projection best;
    const Vec3 x = sdk::load3(a.x.data(), i);
    const int* t = &b.triangles[3 * static_cast<std::size_t>(e)];
    double w[3], plane;
    const bool inside = locate(x, g, &b.x[3 * static_cast<std::size_t>(t[0])], w, plane);
    const double reach2 = reach * reach;
    best.n = sdk::load3(g, 0);
    if (inside) {
      if (plane * plane > reach2) return best;
      best.element = e;
      best.d = plane;
    } else {
      const Vec3 cp = sdk::closest_point_on_triangle(x, sdk::load3(b.x.data(), t[0]), sdk::load3(b.x.data(), t[1]),
                                                     sdk::load3(b.x.data(), t[2]), w);
      const Vec3 r = sdk::sub(x, cp);
      const double d2 = sdk::dot(r, r);
      if (d2 > reach2) return best;
      best.element = e;
      off_face(best, r, d2, sdk::dot(r, sdk::load3(g, 0)));
      best.border = on_border(b, ps.border_b, e, w);
    }
    for (int k = 0; k < 3; ++k) best.w[k] = w[k];
    return best;
  }

  // The constants of rate_force() and the vector force passes; share: this
  // pair's share of the node's friction (0.5 for each ply/ply pass).
  RateConstants rate_constants(double share, double dt) const {
    return {damping_ * 2.0, friction_, slip_velocity_, 0.5 * share, dt};
  }

  sdk::Status tool_forces(const sdk::ContactForceInput& in, sdk::ContactForceOutput& out) {
    const sdk::PartView& a = in.parts[pair_.first.index];
    const sdk::ToolView& tool = in.tools[pair_.second.index];
    query_tool(a, tool);
    std::vector<double>& scratch = pass_[0].scratch;
    std::vector<double>& energy = pass_[0].energy;
    const auto v = in.velocity[a.index];
    const auto area = in.node_area[a.index];
    const Vec3 vtool = tool.velocity ? Vec3{tool.velocity[0], tool.velocity[1], tool.velocity[2]} : Vec3{0, 0, 0};
    const double h2 = 0.5 * a.thickness;
    // Written below for every node (energy) or every node in contact (forces).
    scratch.resize(3 * static_cast<std::size_t>(a.num_nodes));
    energy.resize(a.num_nodes);
    const bool table = !mu_t_.empty();
    if (table) {  // each node's coefficient at the temperature of its face that looks at the tool
      Pass& ps = pass_[0];
      const std::vector<double>& nn = friction_faces(ps, in, a, nn_a_);
      ps.mu.resize(a.num_nodes);
      for (int i = 0; i < a.num_nodes; ++i) {
        const double c = nn.empty() ? 1.0 : sdk::dot(sdk::load3(tn_.data(), i), sdk::load3(nn.data(), i));
        ps.mu[i] = ps.mu2[2 * static_cast<std::size_t>(i) + (c < 0 ? sdk::kTop : sdk::kBottom)];  // as thermal_contacts
      }
    }
    if (has_friction_ && slip_velocity_ > 0) {  // vector lanes, chunks of kChunk nodes
      const int chunks = (a.num_nodes + kChunk - 1) / kChunk;
      const RateConstants c = rate_constants(1.0, in.dt);
      sdk::for_each_index(chunks, a.num_nodes > 256, 1, [&](int ch) {
        const std::size_t i0 = static_cast<std::size_t>(ch) * kChunk;
        const int m = std::min(kChunk, a.num_nodes - ch * kChunk);
        if (table)
          tool_force_block_mu(m, &dist_[i0], &tn_[3 * i0], &v[3 * i0], &area[i0], &in.mass[a.index][i0],
                              &pass_[0].mu[i0], vtool.data(), h2, penalty_, c, &scratch[3 * i0], &energy[i0],
                              &pass_[0].ft[3 * i0]);
        else
          tool_force_block(m, &dist_[i0], &tn_[3 * i0], &v[3 * i0], &area[i0], &in.mass[a.index][i0], vtool.data(),
                           h2, penalty_, c, &scratch[3 * i0], &energy[i0], &pass_[0].ft[3 * i0]);
      });
    } else {  // elastic slip or no friction: each chunk's penetrations, then its forces in vector lanes
      Pass& ps = pass_[0];
      ps.ft_new.resize(ps.ft.size());
      auto* block = has_friction_ ? force_block_elastic : force_block_none;
      const RateConstants c = rate_constants(1.0, in.dt);
      const int chunks = (a.num_nodes + kChunk - 1) / kChunk;
      sdk::for_each_index(chunks, a.num_nodes > 256, 1, [&](int ch) {
        const int i0 = ch * kChunk, m = std::min(kChunk, a.num_nodes - i0);
        ChunkScratch& s = chunk_scratch();
        for (int l = 0; l < m; ++l) {
          const int i = i0 + l;
          double pen = h2 - dist_[i];
          if (!(pen > 0) || pen > 2 * h2) {  // apart, or through the tool (no force from the far side)
            pen = 0.0;
            for (int d = 0; d < 3; ++d) ps.ft[3 * static_cast<std::size_t>(i) + d] = 0.0;
          }
          s.pen[l] = pen;
          s.k[l] = penalty_ * area[i];
          s.mu[l] = table ? ps.mu[i] : friction_;
          for (int d = 0; d < 3; ++d) s.v[3 * l + d] = v[3 * i + d] - vtool[d];
        }
        const std::size_t j = static_cast<std::size_t>(i0);
        block(m, s.pen, s.k, &in.mass[a.index][j], &tn_[3 * j], s.v, s.mu, c, &ps.ft[3 * j], &scratch[3 * j],
              &energy[j], &ps.ft_new[3 * j]);
      });
      if (has_friction_) std::swap(ps.ft, ps.ft_new);
    }
    // Fixed-order sums: the same results for any thread count.
    auto f = out.force[a.index];
    const std::span<double> pressure = out.pressure.empty() ? std::span<double>() : out.pressure[a.index];
    for (int i = 0; i < a.num_nodes; ++i) {
      if (!(energy[i] > 0)) continue;
      ++out.active;
      out.energy += energy[i];
      if (!out.status.empty()) out.status[a.index][i] = std::max(out.status[a.index][i], 1.0);
      if (!pressure.empty()) pressure[i] += penalty_ * (h2 - dist_[i]);
      for (int d = 0; d < 3; ++d) {
        f[3 * i + d] += scratch[3 * i + d];
        out.tool_force[3 * tool.index + d] -= scratch[3 * i + d];
      }
    }
    return sdk::Status::success();
  }

  // Ply/ply: both directions (nodes of each ply against the other's
  // surface), each with half the penalty, so that two faceted plies wrapped
  // on a curved tool hold each other wherever they touch.
  sdk::Status ply_forces(const sdk::ContactForceInput& in, sdk::ContactForceOutput& out) {
    if (in.side == 0 || in.side == 1) {
      ply_pass(pass_[in.side], 0.5, in, out);
    } else {
      for (Pass& ps : pass_) ply_pass(ps, 0.5, in, out);
    }
    return sdk::Status::success();
  }

  void ply_pass(Pass& ps, double scale, const sdk::ContactForceInput& in, sdk::ContactForceOutput& out) {
    const sdk::PartView& a = in.parts[ps.a];
    const sdk::PartView& b = in.parts[ps.b];
    const double hsum2 = 0.5 * (a.thickness + b.thickness);
    const double track = hsum2 + gap_tol_ + hsum2;  // keep the side while the node stays this close
    // A full search every search_interval passes; in between, each node's
    // triangle of the last one. The candidate lists serve the full searches
    // only, so they are checked (and rebuilt where nodes moved too far)
    // just before each.
    border_nodes(b, ps.border_b);
    if (ps.kept.size() != static_cast<std::size_t>(a.num_nodes)) {
      ps.kept.assign(a.num_nodes, -1);
      ps.calls = 0;
    }
    const bool full = search_interval_ <= 1 || ps.calls == 0 || ps.calls >= ps.limit;
    ps.calls = full ? 1 : ps.calls + 1;
    if (full) {
      refresh_candidates(ps, a, b, track);
      if (search_interval_ > 1)
        ps.limit = search_limit(in.velocity[a.index], in.velocity[b.index], in.dt, track - hsum2);
    }
    const auto va = in.velocity[a.index];
    const auto vb = in.velocity[b.index];
    const auto area = in.node_area[a.index];
    // Read below only for the nodes whose target is set (tg[0] >= 0).
    std::vector<double>& scratch = ps.scratch;
    std::vector<double>& energy = ps.energy;
    std::vector<double>& target = ps.target;
    std::vector<double>& pen_of = ps.pen;
    scratch.resize(3 * static_cast<std::size_t>(a.num_nodes));
    energy.resize(a.num_nodes);
    target.resize(4 * static_cast<std::size_t>(a.num_nodes));
    pen_of.resize(a.num_nodes);
    // Between full searches only the kept triangles are read.
    if (full) {
      surface_geometry(b, ps.geo_b);
      prepare_prune(ps, a, b, track);
    } else {
      ps.geo_kept.resize(kGeo * ps.kept_list.size());
      geometry_list(static_cast<int>(ps.kept_list.size()), ps.kept_list.data(), b.triangles.data(), b.x.data(),
                    ps.geo_kept.data());
    }
    const bool table = !mu_t_.empty();
    // The node's face temperatures through its pass's cache (the target's
    // faces are read directly).
    const std::vector<double>* nn = nullptr;
    if (table) nn = &friction_faces(ps, in, a, &ps == &pass_[0] ? nn_a_ : nn_b_);
    ps.ft_new.resize(ps.ft.size());
    // The projection of node i, its target, and what its force needs, at
    // place l of the chunk's scratch s; pen 0 where it gets none.
    auto node = [&](int i, ChunkScratch& s, int l) {
      double* tg = &target[4 * static_cast<std::size_t>(i)];
      tg[0] = -1;
      pen_of[i] = 0.0;
      s.pen[l] = 0.0;
      Projection pr;
      if (full) {
        pr = project(ps, a, b, i, track, ps.prune.active);
        ps.kept[i] = pr.element;
        if (!ps.prune.active) {  // a new reference: its target
          ps.prune.tref[i] = pr.element;
          ps.prune.dref[i] = pr.element >= 0 ? std::abs(pr.d) : track;
        }
      } else if (ps.kept[i] >= 0) {
        pr = project_on(ps, a, b, i, ps.kept[i], &ps.geo_kept[kGeo * static_cast<std::size_t>(ps.slot[i])], track);
      }
      if (pr.element < 0) {
        ps.side[i] = 0;
        for (int d = 0; d < 3; ++d) ps.ft[3 * static_cast<std::size_t>(i) + d] = 0.0;
        return;
      }
      const int* t = &b.triangles[3 * pr.element];
      const Vec3 ne = pr.n;
      Vec3 vt = {0, 0, 0};
      for (int j = 0; j < 3; ++j) vt = sdk::add(vt, sdk::scale(sdk::load3(vb.data(), t[j]), pr.w[j]));
      const Vec3 vrel = sdk::sub(sdk::load3(va.data(), i), vt);
      if (pr.border) {
        // Round a free border (the rounded edge of the other ply) a node may
        // pass from one side to the other: its side is where it is, so the
        // penetration (half-thicknesses less the distance) and the force
        // (away from the border) do not jump where it crosses the plane.
        ps.side[i] = pr.d >= 0 ? 1 : -1;
      } else if (ps.side[i] == 0) {
        const double g = sdk::dot(ne, vrel);
        if (std::abs(pr.d) >= hsum2 || std::abs(g) * in.dt < std::abs(pr.d)) {
          // Not touching, or it cannot have crossed the target's mid-surface
          // within the step: the side it is on.
          ps.side[i] = pr.d >= 0 ? 1 : -1;
        } else {  // may have crossed within one step: the approach velocity decides
          ps.side[i] = g < 0 ? 1 : g > 0 ? -1 : (pr.d >= 0 ? 1 : -1);
        }
      }
      const double pen = hsum2 - ps.side[i] * pr.d;
      if (!(pen > 0)) {
        for (int d = 0; d < 3; ++d) ps.ft[3 * static_cast<std::size_t>(i) + d] = 0.0;
        return;
      }
      if (pen > 2 * hsum2) {  // went through the other ply: release
        ps.side[i] = 0;
        return;
      }
      double mb = 0;
      for (int j = 0; j < 3; ++j) mb += pr.w[j] * in.mass[b.index][t[j]];
      const double ma = in.mass[a.index][i];
      double mu = friction_;
      if (table) {  // at the mean of the two facing faces' temperatures (the faces of thermal_contacts)
        const double c = nn->empty() ? 1.0 : sdk::dot(sdk::load3(nn->data(), i), ne);
        const bool above = ps.side[i] > 0;
        const int face_a = (above == (c > 0)) ? sdk::kBottom : sdk::kTop;
        const int face_b = above ? sdk::kTop : sdk::kBottom;
        double tb = 0;
        for (int j = 0; j < 3; ++j) tb += pr.w[j] * face_temperature(in, b.index, t[j], face_b);
        mu = friction_at(0.5 * (face_temperature(in, a.index, i, face_a) + tb));
      }
      pen_of[i] = pen;
      s.pen[l] = pen;
      s.k[l] = scale * penalty_ * area[i];
      s.m[l] = ma * mb / (ma + mb);
      s.mu[l] = mu;
      const Vec3 n = sdk::scale(ne, ps.side[i]);
      for (int d = 0; d < 3; ++d) {
        s.nrm[3 * l + d] = n[d];
        s.v[3 * l + d] = vrel[d];
      }
      tg[0] = pr.element;
      tg[1] = pr.w[0];
      tg[2] = pr.w[1];
      tg[3] = pr.w[2];
    };
    auto* block = !has_friction_ ? force_block_none
                  : slip_velocity_ > 0 ? force_block_rate
                                       : force_block_elastic;
    const RateConstants rc = rate_constants(scale, in.dt);
    // The nodes of a, dealt to the threads in interleaved chunks: the cost
    // of a node differs with where it lies (corner or centre of a cell, in
    // contact or not), and a mesh numbers such nodes in runs. Each chunk's
    // projections, then its forces in one vector pass.
    const int chunks = (a.num_nodes + kChunk - 1) / kChunk;
    sdk::for_each_index(chunks, a.num_nodes > 256, 1, [&](int ch) {
      const int i0 = ch * kChunk, m = std::min(kChunk, a.num_nodes - i0);
      ChunkScratch& s = chunk_scratch();
      for (int l = 0; l < m; ++l) node(i0 + l, s, l);
      const std::size_t j = static_cast<std::size_t>(i0);
      block(m, s.pen, s.k, s.m, s.nrm, s.v, s.mu, rc, &ps.ft[3 * j], &scratch[3 * j], &energy[j], &ps.ft_new[3 * j]);
    });
    if (has_friction_ && !(slip_velocity_ > 0)) std::swap(ps.ft, ps.ft_new);
    if (full && search_interval_ > 1) {
      // The triangles kept, each once, in increasing order, and each node's
      // place in that list.
      ps.used.assign(b.num_elements, -1);
      for (int i = 0; i < a.num_nodes; ++i)
        if (ps.kept[i] >= 0) ps.used[ps.kept[i]] = 0;
      ps.kept_list.clear();
      for (int e = 0; e < b.num_elements; ++e) {
        if (ps.used[e] < 0) continue;
        ps.used[e] = static_cast<int>(ps.kept_list.size());
        ps.kept_list.push_back(e);
      }
      ps.slot.resize(a.num_nodes);
      for (int i = 0; i < a.num_nodes; ++i) ps.slot[i] = ps.kept[i] >= 0 ? ps.used[ps.kept[i]] : -1;
    }
    auto fa = out.force[a.index];
    auto fb = out.force[b.index];
    // The pressure of the elastic normal force on the node and, through the
    // weights, on the target's nodes (each pass carries half the penalty).
    const std::span<double> pa = out.pressure.empty() ? std::span<double>() : out.pressure[a.index];
    const std::span<double> pb = out.pressure.empty() ? std::span<double>() : out.pressure[b.index];
    const auto area_b = in.node_area[b.index];
    for (int i = 0; i < a.num_nodes; ++i) {
      const double* tg = &target[4 * static_cast<std::size_t>(i)];
      if (tg[0] < 0) continue;
      ++out.active;
      out.energy += energy[i];
      const int* t = &b.triangles[3 * static_cast<int>(tg[0])];
      const double fn = scale * penalty_ * area[i] * pen_of[i];
      if (!pa.empty()) pa[i] += scale * penalty_ * pen_of[i];
      if (!pb.empty())
        for (int j = 0; j < 3; ++j)
          if (area_b[t[j]] > 0) pb[t[j]] += tg[1 + j] * fn / area_b[t[j]];
      if (!out.status.empty()) {
        out.status[a.index][i] = 2.0;
        for (int j = 0; j < 3; ++j)
          if (tg[1 + j] > 0) out.status[b.index][t[j]] = 2.0;
      }
      for (int d = 0; d < 3; ++d) {
        const double f = scratch[3 * i + d];
        fa[3 * i + d] += f;
        for (int j = 0; j < 3; ++j) fb[3 * t[j] + d] -= tg[1 + j] * f;
      }
    }
  }

  // The passes a full search covers: search_interval, fewer where the
  // plies' speeds could close `gap` in fewer steps. A node without a target
  // at the search is farther than `track` from the other ply's mid-surface,
  // so it is at least gap = track - hsum2 from touching, and the two plies'
  // points approach each other at most at the sum of their largest node
  // speeds. Half of that many steps at the present step, for steps that grow
  // and speeds that change until the next search.
  long long search_limit(std::span<const double> va, std::span<const double> vb, double dt, double gap) const {
    auto fastest = [](std::span<const double> v) {
      double m = 0;
      for (std::size_t k = 0; k + 2 < v.size(); k += 3)
        m = std::max(m, v[k] * v[k] + v[k + 1] * v[k + 1] + v[k + 2] * v[k + 2]);
      return std::sqrt(m);
    };
    const double travel = (fastest(va) + fastest(vb)) * dt;  // per step, at most
    const double n = 0.5 * gap / travel;
    if (!(n < static_cast<double>(search_interval_))) return search_interval_;  // also travel 0
    return std::max<long long>(1, static_cast<long long>(n));
  }

  sdk::ContactPair pair_;
  double penalty_ = 0, friction_ = 0, slip_velocity_ = 0, damping_ = 0, conductance_ = 0, gap_tol_ = 0;
  std::vector<double> mu_t_, mu_v_;  // friction table: temperatures (degC) and coefficients
  bool has_friction_ = false;        // some friction coefficient above 0
  std::vector<double> h_p_, h_v_;  // conductance table: pressures (Pa), conductances (W/(m^2 K))
  double h_max_ = 0;  // the largest conductance the pair can give (W/(m^2 K))
  long long search_interval_ = 1;
  bool prune_search_ = true;  // prepare_prune
  Pass pass_[2];  // tool pairs use pass_[0].ft only
  // Node normals of the first body at the last thermal_contacts, and of the
  // second (a ply) where a friction table needs them.
  std::vector<double> nn_a_, nn_b_, dist_, tn_;
  // Tool queries: where each node beyond the cutoff was last asked (xq_,
  // and the tool's path length then, sq_).
  std::vector<double> xq_, sq_;
  std::vector<double> skip_;  // per node: 1 if not asked at this query
  std::vector<std::byte> kept_;  // per node: the tool's record (ToolView::query_kept)
  double tool_path_ = 0;
  Vec3 tool_u_ = {0, 0, 0};
};

sdk::ContactHandler* create() { return new PenaltyNodeSurface(); }

void register_all(sdk::Registrar& r) {
  sdk::Descriptor d;
  d.kind = sdk::PluginKind::Contact;
  d.name = "penalty_node_surface";
  d.version = "0.13.0";
  d.summary = "Node-to-surface penalty contact with shell thickness and Coulomb friction; carries heat between "
              "touching faces; gives the contact pressure as penalty x penetration";
  d.params = {
      sdk::real_param("penalty", "1.0e11", "Pa/m",
                      "contact pressure per unit penetration; the default keeps the penetration under 1 % of a "
                      "0.5 mm ply up to 0.5 MPa contact pressure",
                      0.0),
      sdk::real_param("friction", "0.0", "-",
                      "Coulomb friction coefficient, regularised as set by slip_velocity. Not used where "
                      "friction_temperatures is given",
                      0.0),
      sdk::list_param("friction_temperatures", "[]", "degC",
                      "interface temperatures T_k, increasing, of a friction coefficient that follows the "
                      "temperature: mu(T) is linear between the points (T_k, friction_values[k]) and held beyond "
                      "the first and last; T is the temperature of the ply's face that touches (against a tool) or "
                      "the mean of the two facing faces (ply/ply), as of the last thermal step (without the "
                      "thermal solver, the initial temperatures). Empty: the constant friction",
                      -1, -273.15),
      sdk::list_param("friction_values", "[]", "-",
                      "the friction coefficients at friction_temperatures (as many entries)", -1, 0.0),
      sdk::real_param("slip_velocity", "0.0", "m/s",
                      "friction regularisation. 0: elastic slip (a tangential spring of the penalty stiffness, "
                      "capped at friction times the normal force; parts can stick). > 0: rate-regularised Coulomb, "
                      "friction times the normal force times min(1, slip speed / slip_velocity) (no sticking; the "
                      "answer does not depend on the load history of a stuck zone)",
                      0.0),
      sdk::real_param("damping", "0.1", "-",
                      "normal contact damping as a fraction of the critical damping of a node on its penalty spring "
                      "(removes the energy a stiff penalty can gain when contact starts or ends within a step)",
                      0.0, 1.0),
      sdk::real_param("conductance", "1000.0", "W/(m^2 K)",
                      "thermal contact conductance h_c (1 / contact resistance); 0 switches the heat exchange off. "
                      "Not used where conductance_pressures is given",
                      0.0),
      sdk::list_param("conductance_pressures", "[]", "Pa",
                      "contact pressures p_k, increasing, of a conductance that follows the pressure: h_c(p) is "
                      "linear between the points (p_k, conductance_values[k]) and held beyond the first and last; "
                      "p = penalty x penetration at the node's face at that moment (a face within gap_tolerance "
                      "but not pressed: p = 0). Needs the mechanics solver (without it the faces carry no "
                      "pressure). Empty: the constant conductance",
                      -1, 0.0),
      sdk::list_param("conductance_values", "[]", "W/(m^2 K)",
                      "the conductances h_c at conductance_pressures (as many entries)", -1, 0.0),
      sdk::real_param("gap_tolerance", "-1", "m",
                      "largest gap between facing shell surfaces still counted as touching for heat exchange; "
                      "negative = 1 % of the thinner ply"),
      sdk::bool_param("self", false, "allow a body in contact with itself"),
      sdk::int_param("search_interval", "1",
                     "ply/ply: steps from one full closest-point search to the next. 1: every step (exact). k > 1: "
                     "in the steps between, each node keeps the triangle the last search found and takes the "
                     "closest point on it; a node that slides onto a neighbouring triangle meets it at most k - 1 "
                     "steps late (a cheaper search at a small error, see the user guide). The next search comes "
                     "sooner where the plies' fastest nodes could close half the gap that a node without a target "
                     "had at the last one",
                     1, 64),
      sdk::bool_param("prune_search", true,
                      "ply/ply with search_interval 1: the search skips the candidate triangles that distance "
                      "bounds show to be farther than the node's target of a recent search (bounds at reference "
                      "positions, less the motions since): the same targets bit for bit, at a fraction of the "
                      "cost. false: every candidate at every search (for checking)"),
  };
  d.example = R"({ "type": "contact", "handler": "penalty_node_surface", "between": ["die", "ply_bottom"], "friction": 0.2, "conductance": 1000.0 })";
  r.add_contact(d, &create);
}

}  // namespace
}  // namespace ts::contact

THERMOSTAMP_PLUGIN("contact_penalty_node_surface", "0.13.0", ts::contact::register_all)
