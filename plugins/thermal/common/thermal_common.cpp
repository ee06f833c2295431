#include "thermal_common.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <thermostamp/sdk/math.hpp>

namespace ts::thermal {

using sdk::Vec3;

void setup_ply(PlyThermal& ply, const sdk::PartView& part, int nz) {
  ply.view = &part;
  ply.nz = nz;
  ply.h = part.thickness;
  ply.e = nz > 1 ? part.thickness / (nz - 1) : part.thickness;
  ply.rho_c = part.thermal.density * part.thermal.specific_heat;
  ply.k33 = part.thermal.k33;
  ply.w.assign(nz, ply.e);
  if (nz > 1) {
    ply.w.front() = 0.5 * ply.e;
    ply.w.back() = 0.5 * ply.e;
  }
  // Node-node pattern from the triangles.
  const int n = part.num_nodes;
  std::vector<std::vector<int>> adj(n);
  for (int el = 0; el < part.num_elements; ++el)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) adj[part.triangles[3 * el + a]].push_back(part.triangles[3 * el + b]);
  Csr& m = ply.k2d;
  m.n = n;
  m.row_start.assign(n + 1, 0);
  m.col.clear();
  for (int i = 0; i < n; ++i) {
    auto& r = adj[i];
    r.push_back(i);
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    m.col.insert(m.col.end(), r.begin(), r.end());
    m.row_start[i + 1] = static_cast<int>(m.col.size());
  }
  m.val.assign(m.col.size(), 0.0);
  m.elem_slot.assign(9 * part.num_elements, 0);
  for (int el = 0; el < part.num_elements; ++el)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int i = part.triangles[3 * el + a], j = part.triangles[3 * el + b];
        const auto first = m.col.begin() + m.row_start[i], last = m.col.begin() + m.row_start[i + 1];
        m.elem_slot[9 * el + 3 * a + b] = static_cast<int>(std::lower_bound(first, last, j) - m.col.begin());
      }
  ply.area.assign(n, 0.0);
  update_geometry(ply);
}

void update_geometry(PlyThermal& ply) {
  const sdk::PartView& part = *ply.view;
  const double* x = part.x.data();
  // Lumped areas of the initial configuration: capacities and face
  // exchanges follow the material (mass is conserved when the ply
  // stretches); conduction follows the current geometry.
  const bool first = !ply.area_set;
  if (first) std::fill(ply.area.begin(), ply.area.end(), 0.0);
  std::fill(ply.k2d.val.begin(), ply.k2d.val.end(), 0.0);
  const double k11 = part.thermal.k11, k22 = part.thermal.k22;
  const bool varies = part.thermal.conductivity_varies;
  if (varies) {
    ply.g11.resize(6 * static_cast<std::size_t>(part.num_elements));
    ply.g22.resize(6 * static_cast<std::size_t>(part.num_elements));
  }
  for (int el = 0; el < part.num_elements; ++el) {
    const int* t = &part.triangles[3 * el];
    const Vec3 x0 = sdk::load3(x, t[0]), x1 = sdk::load3(x, t[1]), x2 = sdk::load3(x, t[2]);
    const Vec3 nn = sdk::cross(sdk::sub(x1, x0), sdk::sub(x2, x0));
    const double two_a = sdk::norm(nn);
    const double A = 0.5 * two_a;
    const Vec3 n = sdk::scale(nn, 1.0 / two_a);
    // Fibre direction projected on the element plane; t = n x f.
    Vec3 f = sdk::load3(part.fibre.data(), el);
    f = sdk::normalized(sdk::sub(f, sdk::scale(n, sdk::dot(f, n))));
    const Vec3 tdir = sdk::cross(n, f);
    // grad N_a = n x (x_c - x_b) / (2A), (a, b, c) cyclic.
    const Vec3 xs[3] = {x0, x1, x2};
    double gf[3], gt[3];
    for (int a = 0; a < 3; ++a) {
      const Vec3 g = sdk::scale(sdk::cross(n, sdk::sub(xs[(a + 2) % 3], xs[(a + 1) % 3])), 1.0 / two_a);
      gf[a] = sdk::dot(g, f);
      gt[a] = sdk::dot(g, tdir);
    }
    if (first) {
      const Vec3 y0 = sdk::load3(part.x0.data(), t[0]), y1 = sdk::load3(part.x0.data(), t[1]),
                 y2 = sdk::load3(part.x0.data(), t[2]);
      const double A0 = 0.5 * sdk::norm(sdk::cross(sdk::sub(y1, y0), sdk::sub(y2, y0)));
      for (int a = 0; a < 3; ++a) ply.area[t[a]] += A0 / 3.0;
    }
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b)
        ply.k2d.val[ply.k2d.elem_slot[9 * el + 3 * a + b]] += A * (k11 * gf[a] * gf[b] + k22 * gt[a] * gt[b]);
    }
    if (varies) {
      double* u = &ply.g11[6 * static_cast<std::size_t>(el)];
      double* v = &ply.g22[6 * static_cast<std::size_t>(el)];
      int q = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b, ++q) {
          u[q] = A * gf[a] * gf[b];
          v[q] = A * gt[a] * gt[b];
        }
    }
  }
  ply.area_set = true;
  update_inplane_bounds(ply);
}

void assemble_inplane(PlyThermal& ply, const double* k11, const double* k22, std::size_t stride) {
  const sdk::PartView& part = *ply.view;
  double* val = ply.k2d.val.data();
  std::fill(ply.k2d.val.begin(), ply.k2d.val.end(), 0.0);
  constexpr int kPair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (int el = 0; el < part.num_elements; ++el) {
    const int* t = &part.triangles[3 * el];
    const double c11 = (k11[stride * t[0]] + k11[stride * t[1]] + k11[stride * t[2]]) / 3.0;
    const double c22 = (k22[stride * t[0]] + k22[stride * t[1]] + k22[stride * t[2]]) / 3.0;
    const double* u = &ply.g11[6 * static_cast<std::size_t>(el)];
    const double* v = &ply.g22[6 * static_cast<std::size_t>(el)];
    const int* slot = &ply.k2d.elem_slot[9 * static_cast<std::size_t>(el)];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) val[slot[3 * a + b]] += c11 * u[kPair[a][b]] + c22 * v[kPair[a][b]];
  }
}

void assemble_inplane_layers(PlyThermal& ply, const double* kf) {
  const sdk::PartView& part = *ply.view;
  const std::size_t nz = static_cast<std::size_t>(ply.nz);
  ply.k2d_layers.resize(ply.k2d.val.size() * nz);
  std::fill(ply.k2d_layers.begin(), ply.k2d_layers.end(), 0.0);
  double* val = ply.k2d_layers.data();
  constexpr int kPair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  const bool parallel = static_cast<long long>(ply.k2d.n) * static_cast<long long>(nz) > kParallelValues;
#ifdef _OPENMP
  const std::size_t most_threads = static_cast<std::size_t>(omp_get_max_threads());
#else
  const std::size_t most_threads = 1;
#endif
  const std::size_t per_thread = 2 * nz + 1;
  if (ply.layer_work.size() < most_threads * per_thread) ply.layer_work.resize(most_threads * per_thread);
  double* work = ply.layer_work.data();
  // Each thread assembles a range of the layer values (every value is summed
  // over the elements in the same order whatever the thread count).
#pragma omp parallel if (parallel)
  {
#ifdef _OPENMP
    const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t me = static_cast<std::size_t>(omp_get_thread_num());
#else
    const std::size_t threads = 1, me = 0;
#endif
    const std::size_t k0 = nz * me / threads, k1 = nz * (me + 1) / threads, w = k1 - k0;
    double* c11 = work + per_thread * me;  // per layer value of the range: the element's k11, k22
    double* c22 = c11 + w;
    for (int el = 0; el < part.num_elements && w > 0; ++el) {
      const int* t = &part.triangles[3 * el];
      const double* n0 = kf + 3 * nz * t[0];
      const double* n1 = kf + 3 * nz * t[1];
      const double* n2 = kf + 3 * nz * t[2];
      const double* u = &ply.g11[6 * static_cast<std::size_t>(el)];
      const double* v = &ply.g22[6 * static_cast<std::size_t>(el)];
      const int* slot = &ply.k2d.elem_slot[9 * static_cast<std::size_t>(el)];
      for (std::size_t q = 0; q < w; ++q) {
        const std::size_t k = 3 * (k0 + q);
        c11[q] = (n0[k] + n1[k] + n2[k]) / 3.0;
        c22[q] = (n0[k + 1] + n1[k + 1] + n2[k + 1]) / 3.0;
      }
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          double* dst = val + nz * slot[3 * a + b] + k0;
          const double ua = u[kPair[a][b]], va = v[kPair[a][b]];
          for (std::size_t q = 0; q < w; ++q) dst[q] += c11[q] * ua + c22[q] * va;
        }
    }
  }
  double rate = 0;
  bool positive = false;
  const int n = ply.k2d.n;
  const int* rs = ply.k2d.row_start.data();
  const int* col = ply.k2d.col.data();
  const double* area = ply.area.data();
  const double rho_c = ply.rho_c;
#pragma omp parallel if (parallel)
  {
#ifdef _OPENMP
    double* sum = work + per_thread * static_cast<std::size_t>(omp_get_thread_num());  // row sums of |K| per layer value
#else
    double* sum = work;
#endif
    double my_rate = 0;
    bool my_positive = false;
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      std::fill(sum, sum + nz, 0.0);
      for (int p = rs[i]; p < rs[i + 1]; ++p) {
        const double* x = val + nz * p;
        const bool off = col[p] != i;
        for (std::size_t k = 0; k < nz; ++k) {
          sum[k] += std::abs(x[k]);
          my_positive = my_positive || (off && x[k] > 0);
        }
      }
      for (std::size_t k = 0; k < nz; ++k) my_rate = std::max(my_rate, sum[k] / (rho_c * area[i]));
    }
#pragma omp critical
    {
      rate = std::max(rate, my_rate);
      positive = positive || my_positive;
    }
  }
  ply.inplane_rate = rate;
  ply.inplane_positive_offdiag = positive;
}

void update_inplane_bounds(PlyThermal& ply) {
  // Gershgorin bound of C^-1 K for the in-plane problem (h cancels).
  double rate = 0;
  for (int i = 0; i < ply.k2d.n; ++i) {
    double s = 0;
    for (int p = ply.k2d.row_start[i]; p < ply.k2d.row_start[i + 1]; ++p) s += std::abs(ply.k2d.val[p]);
    rate = std::max(rate, s / (ply.rho_c * ply.area[i]));
  }
  ply.inplane_rate = rate;
  ply.inplane_positive_offdiag = false;
  for (int i = 0; i < ply.k2d.n; ++i)
    for (int p = ply.k2d.row_start[i]; p < ply.k2d.row_start[i + 1]; ++p)
      if (ply.k2d.col[p] != i && ply.k2d.val[p] > 0) ply.inplane_positive_offdiag = true;
}

double rods_stable_dt(std::span<const PlyThermal> plies, std::span<const sdk::FaceConditions> faces,
                      std::span<const sdk::HeatLink> links) {
  // Forward Euler with lumped capacity keeps the discrete maximum principle
  // (and is stable) for dt <= C_i / K_ii at every value i: for an interior
  // rod value this is rho c e^2 / (2 k33), the paper's bound.
  std::vector<std::vector<double>> link_g(plies.size());  // per part, 2 per node: sum of link conductances / area
  for (std::size_t p = 0; p < plies.size(); ++p) link_g[p].assign(2 * plies[p].view->num_nodes, 0.0);
  for (const auto& l : links) {
    link_g[l.part_a][2 * l.node_a + l.face_a] += l.conductance / plies[l.part_a].area[l.node_a];
    for (int j = 0; j < 3; ++j)
      link_g[l.part_b][2 * l.nodes_b[j] + l.face_b] += l.conductance * l.w_b[j] / plies[l.part_b].area[l.nodes_b[j]];
  }
  double rate = 0;
  for (std::size_t p = 0; p < plies.size(); ++p) {
    const PlyThermal& ply = plies[p];
    const double g = ply.nz > 1 ? ply.k33 / ply.e : 0.0;
    for (int i = 0; i < ply.view->num_nodes; ++i) {
      const double hb = faces[p].h_bottom[i] + link_g[p][2 * i];
      const double ht = faces[p].h_top[i] + link_g[p][2 * i + 1];
      if (ply.nz == 1) {
        rate = std::max(rate, (hb + ht) / (ply.rho_c * ply.w[0]));
      } else {
        rate = std::max(rate, (g + hb) / (ply.rho_c * ply.w[0]));
        rate = std::max(rate, (g + ht) / (ply.rho_c * ply.w[ply.nz - 1]));
        if (ply.nz > 2) rate = std::max(rate, 2 * g / (ply.rho_c * ply.e));
      }
    }
  }
  return rate > 0 ? 1.0 / rate : std::numeric_limits<double>::infinity();
}

double accurate_dt(std::span<const PlyThermal> plies, std::span<const sdk::FaceConditions> faces) {
  double tau = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < plies.size(); ++p) {
    const PlyThermal& ply = plies[p];
    tau = std::min(tau, ply.rho_c * ply.h * ply.h / ply.k33);
    double hmax = 0;
    for (int i = 0; i < ply.view->num_nodes; ++i)
      hmax = std::max({hmax, faces[p].h_bottom[i], faces[p].h_top[i]});
    if (hmax > 0) tau = std::min(tau, ply.rho_c * ply.h / hmax);
  }
  return 0.01 * tau;
}

std::vector<sdk::ParamSpec> splitter_params(const std::string& through_thickness_doc) {
  return {sdk::choice_param("through_thickness", "implicit", {"implicit", "explicit"}, through_thickness_doc),
          sdk::real_param("dt_safety", "0.9", "-", "fraction of the critical step used by the explicit scheme", 0.0,
                          1.0, true)};
}

bool same_links(std::span<const sdk::HeatLink> a, std::span<const sdk::HeatLink> b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto &x = a[i], &y = b[i];
    if (x.part_a != y.part_a || x.node_a != y.node_a || x.face_a != y.face_a || x.part_b != y.part_b ||
        x.face_b != y.face_b || x.conductance != y.conductance)
      return false;
    for (int j = 0; j < 3; ++j)
      if (x.nodes_b[j] != y.nodes_b[j] || x.w_b[j] != y.w_b[j]) return false;
  }
  return true;
}

void solve_tridiagonal(int n, const double* a, const double* b, const double* c, double* d, double* cp) {
  // a: sub-diagonal (a[0] unused), b: diagonal, c: super-diagonal (c[n-1] unused).
  double denom = b[0];
  cp[0] = n > 1 ? c[0] / denom : 0.0;
  d[0] = d[0] / denom;
  for (int i = 1; i < n; ++i) {
    denom = b[i] - a[i] * cp[i - 1];
    cp[i] = i + 1 < n ? c[i] / denom : 0.0;
    d[i] = (d[i] - a[i] * d[i - 1]) / denom;
  }
  for (int i = n - 2; i >= 0; --i) d[i] -= cp[i] * d[i + 1];
}

namespace {

// r = K m for W values per node (the layer values of a rod, contiguous): one
// pass over each row with the W sums held in registers.
template <std::size_t W>
void row_kernel(int n, const int* rs, const int* col, const double* val, const double* m, double* r) {
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * W > kParallelValues)
  for (int i = 0; i < n; ++i) {
    double acc[W > 0 ? W : 1] = {};
    for (int p = rs[i]; p < rs[i + 1]; ++p) {
      const double v = val[p];
      const double* mj = m + W * static_cast<std::size_t>(col[p]);
      for (std::size_t k = 0; k < W; ++k) acc[k] += v * mj[k];
    }
    double* ri = r + W * static_cast<std::size_t>(i);
    for (std::size_t k = 0; k < W; ++k) ri[k] = acc[k];
  }
}

// The same with an operator per layer value (val: W per entry).
template <std::size_t W>
void row_kernel_layers(int n, const int* rs, const int* col, const double* val, const double* m, double* r) {
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * W > kParallelValues)
  for (int i = 0; i < n; ++i) {
    double acc[W > 0 ? W : 1] = {};
    for (int p = rs[i]; p < rs[i + 1]; ++p) {
      const double* v = val + W * static_cast<std::size_t>(p);
      const double* mj = m + W * static_cast<std::size_t>(col[p]);
      for (std::size_t k = 0; k < W; ++k) acc[k] += v[k] * mj[k];
    }
    double* ri = r + W * static_cast<std::size_t>(i);
    for (std::size_t k = 0; k < W; ++k) ri[k] = acc[k];
  }
}

using RowKernel = void (*)(int, const int*, const int*, const double*, const double*, double*);

template <std::size_t... W>
constexpr std::array<RowKernel, sizeof...(W)> make_row_kernels(std::index_sequence<W...>) {
  return {&row_kernel<W>...};
}
template <std::size_t... W>
constexpr std::array<RowKernel, sizeof...(W)> make_row_kernels_layers(std::index_sequence<W...>) {
  return {&row_kernel_layers<W>...};
}

// Widths 0..33 (up to 32 layers); wider rods take the generic loop.
constexpr auto kRowKernels = make_row_kernels(std::make_index_sequence<34>{});
constexpr auto kRowKernelsLayers = make_row_kernels_layers(std::make_index_sequence<34>{});

}  // namespace

int advance_inplane(const PlyThermal& ply, double dt, std::span<double> values, std::span<double> scratch,
                    int stride, bool per_layer) {
  if (ply.inplane_rate <= 0) return 0;
  const double dt_max = 0.9 * 2.0 / ply.inplane_rate;
  const double needed = std::ceil(dt / dt_max - 1e-12);
  // Beyond this the explicit in-plane scheme is the wrong tool (and the
  // count would not fit an int).
  constexpr double kMaxSubsteps = 1e6;
  if (!(needed <= kMaxSubsteps)) {
    char counts[96];
    std::snprintf(counts, sizeof counts, "%.3g explicit sub-steps in a thermal step of %.3g s", needed, dt);
    throw std::runtime_error("in-plane conduction of part '" + std::string(ply.view->name) + "' would need " +
                             counts + " (at most 1e6): its in-plane conductivity is too high for this mesh");
  }
  const int steps = std::max(1, static_cast<int>(needed));
  const double ds = dt / steps;
  const int n = ply.k2d.n;
  const int* rs = ply.k2d.row_start.data();
  const int* col = ply.k2d.col.data();
  const double* val = per_layer ? ply.k2d_layers.data() : ply.k2d.val.data();
  const double* area = ply.area.data();
  const double inv_rc = 1.0 / ply.rho_c;
  double* m = values.data();
  double* r = scratch.data();
  const std::size_t w = static_cast<std::size_t>(stride);
  // K_ij of value k: one operator for every value, or one per layer value.
  const std::size_t vw = per_layer ? w : 0;
  auto kij = [val, vw](int p, std::size_t k) { return vw ? val[vw * p + k] : val[p]; };
  if (ply.inplane_positive_offdiag) {
    // Algebraic flux correction. Low order: the pairs with K_ij < 0 (a
    // convex combination for ds <= 0.9 * 2 / rate, since the Gershgorin rate
    // is 2 max K-_ii / (rho c A_i)). High order adds the limited fluxes of
    // the pairs with K_ij > 0. Flux into i from j: ds/(rho c) (-K_ij) (T_j - T_i).
    const std::size_t nw = static_cast<std::size_t>(n) * w;
    double* low = scratch.data();    // low-order values
    double* rp = low + nw;           // R+ per value
    double* rm = rp + nw;            // R- per value
    double* out = rm + nw;           // new values
    const double c0 = ds * inv_rc;
    for (int s = 0; s < steps; ++s) {
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * w > kParallelValues)
      for (int i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < w; ++k) {
          const double ti = m[w * i + k];
          double dl = 0, pp = 0, pm = 0, tmax = ti, tmin = ti;
          for (int p = rs[i]; p < rs[i + 1]; ++p) {
            const int j = col[p];
            if (j == i) continue;
            const double tj = m[w * j + k];
            tmax = std::max(tmax, tj);
            tmin = std::min(tmin, tj);
            const double v = kij(p, k);
            const double f = c0 * -v * (tj - ti);
            if (v <= 0) {
              dl += f;
            } else if (f > 0) {
              pp += f;
            } else {
              pm += f;
            }
          }
          const double tl = ti + dl / area[i];
          low[w * i + k] = tl;
          const double qp = area[i] * (tmax - tl), qm = area[i] * (tmin - tl);
          rp[w * i + k] = pp > 0 ? std::clamp(qp / pp, 0.0, 1.0) : 1.0;
          rm[w * i + k] = pm < 0 ? std::clamp(qm / pm, 0.0, 1.0) : 1.0;
        }
      }
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * w > kParallelValues)
      for (int i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < w; ++k) {
          const double ti = m[w * i + k];
          double acc = 0;
          for (int p = rs[i]; p < rs[i + 1]; ++p) {
            const int j = col[p];
            const double v = kij(p, k);
            if (j == i || v <= 0) continue;
            const double f = c0 * -v * (m[w * j + k] - ti);
            // Symmetric factor (alpha_ij = alpha_ji): heat is conserved.
            const double a = f > 0 ? std::min(rp[w * i + k], rm[w * j + k]) : std::min(rm[w * i + k], rp[w * j + k]);
            acc += a * f;
          }
          out[w * i + k] = low[w * i + k] + acc / area[i];
        }
      }
      std::copy(out, out + nw, m);
    }
    return steps;
  }
  for (int s = 0; s < steps; ++s) {
    if (per_layer && w < kRowKernelsLayers.size()) {
      kRowKernelsLayers[w](n, rs, col, val, m, r);
    } else if (per_layer) {
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * w > kParallelValues)
      for (int i = 0; i < n; ++i) {
        double* ri = r + w * i;
        for (std::size_t k = 0; k < w; ++k) ri[k] = 0.0;
        for (int p = rs[i]; p < rs[i + 1]; ++p) {
          const double* v = val + w * static_cast<std::size_t>(p);
          const double* mj = m + w * col[p];
          for (std::size_t k = 0; k < w; ++k) ri[k] += v[k] * mj[k];
        }
      }
    } else if (stride == 1) {
#pragma omp parallel for schedule(static) if (n > 1024)
      for (int i = 0; i < n; ++i) {
        double acc = 0;
        for (int p = rs[i]; p < rs[i + 1]; ++p) acc += val[p] * m[col[p]];
        r[i] = acc;
      }
    } else if (w < kRowKernels.size()) {
      kRowKernels[w](n, rs, col, val, m, r);
    } else {
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * w > kParallelValues)
      for (int i = 0; i < n; ++i) {
        double* ri = r + w * i;
        for (std::size_t k = 0; k < w; ++k) ri[k] = 0.0;
        for (int p = rs[i]; p < rs[i + 1]; ++p) {
          const double v = val[p];
          const double* mj = m + w * col[p];
          for (std::size_t k = 0; k < w; ++k) ri[k] += v * mj[k];
        }
      }
    }
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * w > kParallelValues)
    for (int i = 0; i < n; ++i) {
      const double f = ds * inv_rc / area[i];
      for (std::size_t k = 0; k < w; ++k) m[w * i + k] -= f * r[w * i + k];
    }
  }
  return steps;
}

}  // namespace ts::thermal
