#include "split_thermal.hpp"

#include <algorithm>
#include <map>
#include <cmath>
#include <limits>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "linked_solver.hpp"

namespace ts::thermal {

namespace {
int thread_id() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}
int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
// One implicit step of R rods at once: forward and back substitution with
// the shared factors of each rod's face pair. The R recurrences are
// independent, so their latencies overlap; each rod's arithmetic is the same
// as when it is solved alone.
struct RodGroupData {
  int nz;
  const double* gk;  // nz per factor id: conductance of the layer below value k (W/(m^2 K)), gk[0] = 0
  const double* cap;
  const double* inv_den;
  const double* g_inv_den;
  const int* id;
  const double *hb, *ht, *tb, *tt;
  double* t;
};

constexpr int kRodGroup = 4;

template <int R>
void solve_rods(const RodGroupData& d, int i0) {
  const int nz = d.nz;
  double* ti[R];
  const double* inv[R];
  const double* gi[R];
  const double* gk[R];
  double prev[R];
  for (int r = 0; r < R; ++r) {
    const int i = i0 + r;
    ti[r] = d.t + static_cast<std::size_t>(nz) * i;
    inv[r] = d.inv_den + static_cast<std::size_t>(nz) * d.id[i];
    gi[r] = d.g_inv_den + static_cast<std::size_t>(nz) * d.id[i];
    gk[r] = d.gk + static_cast<std::size_t>(nz) * d.id[i];
    // Forward substitution (a_k = -g), in place.
    prev[r] = (d.cap[0] * ti[r][0] + d.hb[i] * d.tb[i] + (nz == 1 ? d.ht[i] * d.tt[i] : 0.0)) * inv[r][0];
    ti[r][0] = prev[r];
  }
  for (int k = 1; k < nz; ++k)
    for (int r = 0; r < R; ++r) {
      double rr = d.cap[k] * ti[r][k];
      if (k == nz - 1) rr += d.ht[i0 + r] * d.tt[i0 + r];
      prev[r] = (rr + gk[r][k] * prev[r]) * inv[r][k];
      ti[r][k] = prev[r];
    }
  // Back substitution: T_k = d_k - c'_k T_{k+1}, c'_k = -g_{k+1} / den_k.
  for (int k = nz - 2; k >= 0; --k)
    for (int r = 0; r < R; ++r) {
      prev[r] = ti[r][k] + gi[r][k] * prev[r];
      ti[r][k] = prev[r];
    }
}

}  // namespace

SplitThermal::SplitThermal(bool layered) : layered_(layered), linked_solver_(std::make_unique<LinkedSolver>()) {}
SplitThermal::~SplitThermal() = default;

sdk::Status SplitThermal::configure(const sdk::Params& params, std::span<const sdk::PartView> parts) {
  return sdk::guarded([&] {
    implicit_ = params.text("through_thickness") == "implicit";
    dt_safety_ = params.real("dt_safety");
    inplane_layers_ = layered_ && params.text("in_plane") == "layers";
    plies_.resize(parts.size());
    int nz_max = 1;
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const int nz = layered_ ? parts[p].thickness_layers + 1 : 1;
      setup_ply(plies_[p], parts[p], nz);
      nz_max = std::max(nz_max, nz);
    }
    node_heat_.resize(parts.size());
    scratch_.resize(parts.size());
    mean_.resize(parts.size());
    k_mean_.resize(parts.size());
    rod_lo_.resize(parts.size());
    mean_old_.resize(parts.size());
    factors_.assign(parts.size(), RodFactors{});
    rod_hi_.resize(parts.size());
    t_old_.resize(parts.size());
    linked_.resize(parts.size());
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const int n = parts[p].num_nodes;
      node_heat_[p].assign(n, 0.0);
      scratch_[p].assign(4 * static_cast<std::size_t>(n) * (inplane_layers_ ? plies_[p].nz : 1), 0.0);
      mean_[p].assign(n, 0.0);
      k_mean_[p].assign(parts[p].thermal.conductivity_varies ? 2 * static_cast<std::size_t>(n) : 0, 0.0);
      rod_lo_[p].assign(n, 0.0);
      mean_old_[p].assign(n, 0.0);
      rod_hi_[p].assign(n, 0.0);
      t_old_[p].assign(static_cast<std::size_t>(n) * plies_[p].nz, 0.0);
      linked_[p].assign(n, 0);
    }
    nz_max_ = nz_max;
    thread_work_.assign(max_threads(), std::vector<double>(5 * nz_max, 0.0));
    return sdk::Status::success();
  });
}

sdk::Status SplitThermal::capacities(int part, std::span<double> cap) const {
  const PlyThermal& ply = plies_[part];
  for (int i = 0; i < ply.view->num_nodes; ++i)
    for (int k = 0; k < ply.nz; ++k) cap[ply.nz * i + k] = ply.rho_c * ply.w[k] * ply.area[i];
  return sdk::Status::success();
}

sdk::Status SplitThermal::step_limits(const sdk::ThermalStepInput& in, double* stable, double* accurate) {
  return sdk::guarded([&] {
    if (in.geometry_changed)
      for (auto& p : plies_) update_geometry(p);
    *stable = implicit_ ? std::numeric_limits<double>::infinity() : dt_safety_ * rods_stable_dt(plies_, in.faces, in.links);
    *accurate = accurate_dt(plies_, in.faces);
    if (!implicit_) *accurate = std::min(*accurate, *stable);
    return sdk::Status::success();
  });
}

// Thomas forward elimination of (C/dt + K_rod + Robin) for one rod (faces
// hb, ht; layer conductances gk, gk[0] = gk[nz] = 0) into slot `id` of rf
// (its arrays hold at least nz (id + 1) values), and the rod's responses.
void SplitThermal::factor_rod(RodFactors& rf, int id, int nz, double hb, double ht, const double* gk) {
  const std::size_t o = static_cast<std::size_t>(nz) * id;
  double* inv = rf.inv_den.data() + o;
  double* gi = rf.g_inv_den.data() + o;
  double cp_prev = 0;
  for (int k = 0; k < nz; ++k) {
    double b = rf.cap[k] + gk[k] + gk[k + 1];
    if (k == 0) b += hb;
    if (k == nz - 1) b += ht;
    const double den = b - (k > 0 ? -gk[k] : 0.0) * cp_prev;
    inv[k] = 1.0 / den;
    gi[k] = gk[k + 1] / den;  // -c_k / den
    rf.gk[o + k] = gk[k];
    cp_prev = (k + 1 < nz ? -gk[k + 1] : 0.0) / den;
  }
  rod_responses(rf, id, nz);
}

// The responses of the rod in slot `id` to a unit flux on each face:
// M^-1 e_bottom, M^-1 e_top (for the rods joined by links).
void SplitThermal::rod_responses(RodFactors& rf, int id, int nz) {
  const std::size_t o = static_cast<std::size_t>(nz) * id;
  const double* inv = rf.inv_den.data() + o;
  const double* gi = rf.g_inv_den.data() + o;
  const double* gk = rf.gk.data() + o;
  for (int face = 0; face < 2; ++face) {
    double* v = (face == 0 ? rf.v_bottom : rf.v_top).data() + o;
    std::fill(v, v + nz, 0.0);
    v[face == 0 ? 0 : nz - 1] = 1.0;
    double prev = 0;
    for (int k = 0; k < nz; ++k) {
      prev = (v[k] + gk[k] * prev) * inv[k];
      v[k] = prev;
    }
    for (int k = nz - 2; k >= 0; --k) v[k] += gi[k] * v[k + 1];
  }
}

namespace {
// The elimination of rod i of a ply whose conductivity varies into slot
// `slot` of the factor arrays; one division per value. gk[k]: k33 at the
// mean of values k - 1 and k over the layer thickness. The same arithmetic
// as solve_rods_varying.
void eliminate_rod(int i, int slot, int nz, double e, const double* cap, const double* hb, const double* ht,
                   const double* kf, double* inv_den, double* g_inv_den, double* gk_out) {
  double cp_prev = 0, g_lo = 0;
  for (int k = 0; k < nz; ++k) {
    const std::size_t v = static_cast<std::size_t>(nz) * i + k;
    const std::size_t o = static_cast<std::size_t>(nz) * slot + k;
    const double g_hi = k + 1 < nz ? 0.5 * (kf[3 * v + 2] + kf[3 * v + 5]) / e : 0.0;
    double b = cap[k] + g_lo + g_hi;
    if (k == 0) b += hb[i];
    if (k == nz - 1) b += ht[i];
    const double inv = 1.0 / (b + g_lo * cp_prev);
    inv_den[o] = inv;
    g_inv_den[o] = g_hi * inv;
    gk_out[o] = g_lo;
    cp_prev = -g_hi * inv;
    g_lo = g_hi;
  }
}

// One implicit step of R rods of a ply whose conductivity varies, not
// joined by links: elimination and substitution in one pass, nothing kept
// (c' of the R rods in `work`, R nz values). The same arithmetic as
// eliminate_rod followed by solve_rods.
template <int R>
void solve_rods_varying(int i0, int nz, double e, const double* cap, const double* hb, const double* ht,
                        const double* tb, const double* tt, const double* kf, double* t, double* work) {
  double cp_prev[R], g_lo[R], prev[R];
  for (int r = 0; r < R; ++r) cp_prev[r] = g_lo[r] = prev[r] = 0.0;
  for (int k = 0; k < nz; ++k)
    for (int r = 0; r < R; ++r) {
      const int i = i0 + r;
      const std::size_t v = static_cast<std::size_t>(nz) * i + k;
      const double g_hi = k + 1 < nz ? 0.5 * (kf[3 * v + 2] + kf[3 * v + 5]) / e : 0.0;
      double b = cap[k] + g_lo[r] + g_hi;
      double rr = cap[k] * t[v];
      if (k == 0) {
        b += hb[i];
        rr += hb[i] * tb[i];
      }
      if (k == nz - 1) {
        b += ht[i];
        rr += ht[i] * tt[i];
      }
      const double inv = 1.0 / (b + g_lo[r] * cp_prev[r]);
      prev[r] = (rr + g_lo[r] * prev[r]) * inv;
      t[v] = prev[r];
      work[static_cast<std::size_t>(nz) * r + k] = g_hi * inv;
      cp_prev[r] = -g_hi * inv;
      g_lo[r] = g_hi;
    }
  for (int k = nz - 2; k >= 0; --k)
    for (int r = 0; r < R; ++r) {
      const std::size_t v = static_cast<std::size_t>(nz) * (i0 + r) + k;
      prev[r] = t[v] + work[static_cast<std::size_t>(nz) * r + k] * prev[r];
      t[v] = prev[r];
    }
}
}  // namespace

bool SplitThermal::update_rod_factors(const sdk::ThermalStepInput& in) {
  bool any = false;
  // The rods of a ply differ only by their two face conductances; their
  // tridiagonal factorisations are shared by every node with the same pair.
  const double dt = in.dt;
  for (std::size_t p = 0; p < plies_.size(); ++p) {
    const PlyThermal& ply = plies_[p];
    const int n = ply.view->num_nodes, nz = ply.nz;
    const auto& f = in.faces[p];
    RodFactors& rf = factors_[p];
    const double* kf = conductivity(in, p);
    bool same = !kf && rf.dt == dt && !in.geometry_changed && static_cast<int>(rf.hb.size()) == n;
    for (int i = 0; same && i < n; ++i) same = rf.hb[i] == f.h_bottom[i] && rf.ht[i] == f.h_top[i];
    if (same) continue;
    any = true;
    rf.dt = dt;
    rf.hb.assign(f.h_bottom.begin(), f.h_bottom.end());
    rf.ht.assign(f.h_top.begin(), f.h_top.end());
    rf.cap.resize(nz);
    for (int k = 0; k < nz; ++k) rf.cap[k] = ply.rho_c * ply.w[k] / dt;
    rf.id.resize(n);
    auto size_for = [&](std::size_t ids) {
      for (auto* v : {&rf.inv_den, &rf.g_inv_den, &rf.v_bottom, &rf.v_top, &rf.gk}) v->resize(nz * ids);
    };
    if (kf) {
      // A conductivity that depends on the temperature: every rod has its
      // own layer conductances, k33 at the mean of the layer's two values.
      // Only the rods joined by links keep factors (and face responses);
      // rods_implicit solves the others in one pass.
      const char* linked = linked_[p].data();
      int slots = 0;
      for (int i = 0; i < n; ++i) slots += linked[i] != 0;
      size_for(slots);
      slots = 0;
      for (int i = 0; i < n; ++i) {
        rf.id[i] = linked[i] ? slots : -1;
        if (!linked[i]) continue;
        eliminate_rod(i, slots, nz, ply.e, rf.cap.data(), f.h_bottom.data(), f.h_top.data(), kf, rf.inv_den.data(),
                      rf.g_inv_den.data(), rf.gk.data());
        rod_responses(rf, slots++, nz);
      }
      continue;
    }
    const double g = nz > 1 ? ply.k33 / ply.e : 0.0;
    std::vector<double> gk(nz + 1, 0.0);  // gk[k]: layer between values k - 1 and k; gk[0] = gk[nz] = 0
    for (int k = 1; k < nz; ++k) gk[k] = g;
    std::map<std::pair<double, double>, int> ids;
    for (int i = 0; i < n; ++i) {
      const auto key = std::make_pair(f.h_bottom[i], f.h_top[i]);
      auto it = ids.find(key);
      if (it == ids.end()) {
        it = ids.emplace(key, static_cast<int>(ids.size())).first;
        size_for(ids.size());
        factor_rod(rf, it->second, nz, key.first, key.second, gk.data());
      }
      rf.id[i] = it->second;
    }
  }
  return any;
}

double SplitThermal::rods_implicit(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T) {
  const double dt = in.dt;
  const bool factors_changed = update_rod_factors(in);
  for (std::size_t p = 0; p < plies_.size(); ++p) {
    const PlyThermal& ply = plies_[p];
    const int nz = ply.nz;
    const int n = ply.view->num_nodes;
    const auto& f = in.faces[p];
    const RodFactors& rf = factors_[p];
    const double* cap = rf.cap.data();
    double* t = T[p].data();
    double* heat = node_heat_[p].data();
    double* face_out = face_out_[p];  // report->face_values, where given
    const char* linked = linked_[p].data();
    const RodGroupData d{nz, rf.gk.data(), cap, rf.inv_den.data(), rf.g_inv_den.data(), rf.id.data(), f.h_bottom.data(),
                         f.h_top.data(), f.t_bottom.data(), f.t_top.data(), t};
    const double* kf = conductivity(in, p);
    const int groups = (n + kRodGroup - 1) / kRodGroup;
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * nz > kParallelValues)
    for (int gidx = 0; gidx < groups; ++gidx) {
      const int i0 = gidx * kRodGroup;
      if (kf) {
        double* work = thread_work_[thread_id()].data();
        bool any_linked = i0 + kRodGroup > n;
        for (int i = i0; i < std::min(n, i0 + kRodGroup); ++i) any_linked = any_linked || linked[i];
        if (!any_linked) {
          solve_rods_varying<kRodGroup>(i0, nz, ply.e, cap, f.h_bottom.data(), f.h_top.data(), f.t_bottom.data(),
                                        f.t_top.data(), kf, t, work);
        } else {
          for (int i = i0; i < std::min(n, i0 + kRodGroup); ++i) {
            if (linked[i]) {
              solve_rods<1>(d, i);
            } else {
              solve_rods_varying<1>(i, nz, ply.e, cap, f.h_bottom.data(), f.h_top.data(), f.t_bottom.data(),
                                    f.t_top.data(), kf, t, work);
            }
          }
        }
      } else if (i0 + kRodGroup <= n) {
        solve_rods<kRodGroup>(d, i0);
      } else {
        for (int i = i0; i < n; ++i) solve_rods<1>(d, i);
      }
      for (int i = i0; i < std::min(n, i0 + kRodGroup); ++i) {
        if (linked[i]) continue;  // corrected below for the link fluxes
        const double* ti = t + static_cast<std::size_t>(nz) * i;
        heat[i] = dt * ply.area[i] *
                  (f.h_bottom[i] * (f.t_bottom[i] - ti[0]) + f.h_top[i] * (f.t_top[i] - ti[nz - 1]));
        if (face_out) {
          face_out[2 * static_cast<std::size_t>(i)] = ti[0];
          face_out[2 * static_cast<std::size_t>(i) + 1] = ti[nz - 1];
        }
      }
    }
  }
  if (in.links.empty()) return 0.0;

  // Rods joined by links. Each rod was solved above without its link
  // fluxes (u = M^-1 b); its linked face values respond to their face
  // fluxes f through S = E M^-1 E^T (E picks the linked faces: one or two
  // per rod). The linked face values y solve the small interface system
  // (S^-1 + L) y = S^-1 E u, L the link conductances, and the rods are
  // corrected by x = u - M^-1 E^T (L y). Exact and conservative; only the
  // linked faces are unknowns of the sparse factorisation, which is redone
  // only when the step, links, geometry or faces change.
  const bool links_changed = in.links_changed && !same_links(in.links, last_links_);
  if (links_changed) last_links_.assign(in.links.begin(), in.links.end());
  const bool rebuild = !linked_valid_ || links_changed || factors_changed;
  if (links_changed || !linked_valid_) {
    linked_offset_.resize(plies_.size());
    linked_count_ = 0;
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const int n = plies_[p].view->num_nodes;
      linked_offset_[p].assign(2 * static_cast<std::size_t>(n), -1);
      for (int i = 0; i < n; ++i) {
        const int mask = linked_[p][i];
        if (!mask) continue;
        if (plies_[p].nz == 1) {  // one value: both faces are the same unknown
          linked_offset_[p][2 * i] = linked_offset_[p][2 * i + 1] = linked_count_++;
          continue;
        }
        for (int face = 0; face < 2; ++face)
          if (mask & (1 << face)) linked_offset_[p][2 * i + face] = linked_count_++;
      }
    }
    linked_rhs_.assign(linked_count_, 0.0);
    linked_flux_.assign(linked_count_, 0.0);
  }
  const auto& offset = linked_offset_;
  auto end_index = [&](int part, int node, int face) { return offset[part][2 * node + face]; };
  LinkedSolver& s = *linked_solver_;
  if (rebuild) {
    s.begin(linked_count_);
    // A S^-1 per linked node as a 2x2 block (bottom, top) in four slots at
    // the unknown of its first linked face; the rows and columns of a face
    // that is not linked stay zero. With one value per node both faces are
    // the same unknown (1x1).
    linked_sinv_.assign(4 * static_cast<std::size_t>(linked_count_), 0.0);
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const RodFactors& rf = factors_[p];
      const int nz = plies_[p].nz;
      for (int i = 0; i < plies_[p].view->num_nodes; ++i) {
        const int ob = offset[p][2 * i], ot = offset[p][2 * i + 1];
        if (ob < 0 && ot < 0) continue;
        const double A = plies_[p].area[i];
        const std::size_t o = static_cast<std::size_t>(nz) * rf.id[i];
        double* si = &linked_sinv_[4 * static_cast<std::size_t>(ob >= 0 ? ob : ot)];
        const bool two = ob >= 0 && ot >= 0 && ot != ob;
        if (two) {
          const double s00 = rf.v_bottom[o], s01 = rf.v_top[o], s10 = rf.v_bottom[o + nz - 1],
                       s11 = rf.v_top[o + nz - 1];
          const double det = s00 * s11 - s01 * s10;
          si[0] = A * s11 / det;
          si[1] = -A * s01 / det;
          si[2] = -A * s10 / det;
          si[3] = A * s00 / det;
          s.add(ob, ot, si[1]);
          s.add(ot, ob, si[2]);
        } else if (ob >= 0) {
          si[0] = A / rf.v_bottom[o];
        } else {
          si[3] = A / rf.v_top[o + nz - 1];
        }
        if (ob >= 0) s.add(ob, ob, si[0]);
        if (ot >= 0 && ot != ob) s.add(ot, ot, si[3]);
      }
    }
    for (const auto& l : in.links) {
      const int ia = end_index(l.part_a, l.node_a, l.face_a);
      for (int j = 0; j < 3; ++j) {
        const double gl = l.conductance * l.w_b[j];
        if (gl == 0) continue;
        const int ib = end_index(l.part_b, l.nodes_b[j], l.face_b);
        s.add(ia, ia, gl);
        s.add(ib, ib, gl);
        s.add(ia, ib, -gl);
        s.add(ib, ia, -gl);
      }
    }
    if (!s.finish()) throw std::runtime_error("the ply/ply interface system could not be factorised");
    linked_valid_ = true;
  }
  std::vector<double>& y = linked_rhs_;
  for (std::size_t p = 0; p < plies_.size(); ++p) {
    const int nz = plies_[p].nz;
    const int* off = offset[p].data();
    const double* t = T[p].data();
    for (int i = 0; i < plies_[p].view->num_nodes; ++i) {
      const int ob = off[2 * i], ot = off[2 * i + 1];
      if (ob < 0 && ot < 0) continue;
      const double* ti = t + static_cast<std::size_t>(nz) * i;
      const double* si = &linked_sinv_[4 * static_cast<std::size_t>(ob >= 0 ? ob : ot)];  // A S^-1
      if (ob >= 0) y[ob] = si[0] * ti[0] + si[1] * ti[nz - 1];
      if (ot >= 0 && ot != ob) y[ot] = si[2] * ti[0] + si[3] * ti[nz - 1];
    }
  }
  s.solve(y);
  // Link fluxes into each face value (W), then the rod corrections.
  std::vector<double>& fl = linked_flux_;
  std::fill(fl.begin(), fl.end(), 0.0);
  for (const auto& l : in.links) {
    const int ia = end_index(l.part_a, l.node_a, l.face_a);
    for (int j = 0; j < 3; ++j) {
      const double gl = l.conductance * l.w_b[j];
      if (gl == 0) continue;
      const int ib = end_index(l.part_b, l.nodes_b[j], l.face_b);
      const double q = gl * (y[ia] - y[ib]);
      fl[ia] += q;
      fl[ib] -= q;
    }
  }
  for (std::size_t p = 0; p < plies_.size(); ++p) {
    const PlyThermal& ply = plies_[p];
    const int nz = ply.nz;
    const int n = ply.view->num_nodes;
    const RodFactors& rf = factors_[p];
    const auto& f = in.faces[p];
    const int* off = offset[p].data();
    const int* id = rf.id.data();
    const double* area = ply.area.data();
    const double* vb = rf.v_bottom.data();
    const double* vt = rf.v_top.data();
    const double *hb = f.h_bottom.data(), *ht = f.h_top.data(), *tb = f.t_bottom.data(), *tt = f.t_top.data();
    const double* flux = fl.data();
    double* t = T[p].data();
    double* heat = node_heat_[p].data();
    double* face_out = face_out_[p];  // report->face_values, where given
    for (int i = 0; i < n; ++i) {
      const int ob = off[2 * i], ot = off[2 * i + 1];
      if (ob < 0 && ot < 0) continue;
      double* ti = t + static_cast<std::size_t>(nz) * i;
      const double* vbi = vb + static_cast<std::size_t>(nz) * id[i];
      const double* vti = vt + static_cast<std::size_t>(nz) * id[i];
      // Flux through each linked face (one unknown for both with one value).
      const double fb = ob >= 0 ? flux[ob] / area[i] : 0.0;
      const double ft = ot >= 0 && ot != ob ? flux[ot] / area[i] : 0.0;
      for (int k = 0; k < nz; ++k) ti[k] -= fb * vbi[k] + ft * vti[k];
      heat[i] = dt * area[i] * (hb[i] * (tb[i] - ti[0]) + ht[i] * (tt[i] - ti[nz - 1]));
      if (face_out) {
        face_out[2 * static_cast<std::size_t>(i)] = ti[0];
        face_out[2 * static_cast<std::size_t>(i) + 1] = ti[nz - 1];
      }
    }
  }
  return 0.0;
}

double SplitThermal::rods_explicit(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T) {
  const double dt = in.dt;
  if (!in.links.empty())
    for (std::size_t p = 0; p < plies_.size(); ++p) std::copy(T[p].begin(), T[p].end(), t_old_[p].begin());
  for (std::size_t p = 0; p < plies_.size(); ++p) {
    const PlyThermal& ply = plies_[p];
    const int nz = ply.nz;
    const int n = ply.view->num_nodes;
    const double g = nz > 1 ? ply.k33 / ply.e : 0.0;
    const double* kf = conductivity(in, p);
    const auto& f = in.faces[p];
    double* t = T[p].data();
    double* heat = node_heat_[p].data();
    double* face_out = face_out_[p];  // report->face_values, where given
#pragma omp parallel for schedule(static) if (static_cast<long long>(n) * nz > kParallelValues)
    for (int i = 0; i < n; ++i) {
      double* ti = t + static_cast<std::size_t>(nz) * i;
      double* old = thread_work_[thread_id()].data();
      double* gk = old + nz;  // gk[k]: layer between values k - 1 and k
      std::copy(ti, ti + nz, old);
      for (int k = 1; k < nz; ++k) {
        const double* ki = kf ? kf + 3 * (static_cast<std::size_t>(nz) * i + k) : nullptr;
        gk[k] = kf ? 0.5 * (ki[-1] + ki[2]) / ply.e : g;
      }
      const double hb = f.h_bottom[i], ht = f.h_top[i];
      for (int k = 0; k < nz; ++k) {
        double q = 0;  // W/m^2 leaving value k
        if (k > 0) q += gk[k] * (old[k] - old[k - 1]);
        if (k + 1 < nz) q += gk[k + 1] * (old[k] - old[k + 1]);
        if (k == 0) q += hb * (old[0] - f.t_bottom[i]);
        if (k == nz - 1) q += ht * (old[nz - 1] - f.t_top[i]);
        ti[k] = old[k] - dt * q / (ply.rho_c * ply.w[k]);
      }
      heat[i] = dt * ply.area[i] * (hb * (f.t_bottom[i] - old[0]) + ht * (f.t_top[i] - old[nz - 1]));
      if (face_out) {
        face_out[2 * static_cast<std::size_t>(i)] = old[0];
        face_out[2 * static_cast<std::size_t>(i) + 1] = old[nz - 1];
      }
    }
  }
  for (const auto& l : in.links) {  // serial: deterministic order
    const PlyThermal& pa = plies_[l.part_a];
    const int ka = l.face_a == sdk::kTop ? pa.nz - 1 : 0;
    const std::size_t ia = static_cast<std::size_t>(pa.nz) * l.node_a + ka;
    const PlyThermal& pb = plies_[l.part_b];
    const int kb = l.face_b == sdk::kTop ? pb.nz - 1 : 0;
    for (int j = 0; j < 3; ++j) {
      const std::size_t ib = static_cast<std::size_t>(pb.nz) * l.nodes_b[j] + kb;
      const double q = dt * l.conductance * l.w_b[j] * (t_old_[l.part_a][ia] - t_old_[l.part_b][ib]);  // J, a -> b_j
      T[l.part_a][ia] -= q / (pa.rho_c * pa.w[ka] * pa.area[l.node_a]);
      T[l.part_b][ib] += q / (pb.rho_c * pb.w[kb] * pb.area[l.nodes_b[j]]);
    }
  }
  return 0.0;
}

// Where the report gives room for every part's face values, the rod
// passes write them (face_out_; null where not given).
bool SplitThermal::take_face_values(sdk::ThermalStepReport* report) {
  face_out_.assign(plies_.size(), nullptr);
  if (!report || report->face_values.size() != plies_.size()) return false;
  for (std::size_t p = 0; p < plies_.size(); ++p)
    if (report->face_values[p].size() != 2 * static_cast<std::size_t>(plies_[p].view->num_nodes)) return false;
  for (std::size_t p = 0; p < plies_.size(); ++p) face_out_[p] = report->face_values[p].data();
  return true;
}

sdk::Status SplitThermal::advance(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T,
                                  sdk::ThermalStepReport* report) {
  return sdk::guarded([&] {
    if (in.geometry_changed)
      for (auto& p : plies_) update_geometry(p);
    // The thread count may have changed since configure().
    if (static_cast<int>(thread_work_.size()) < max_threads())
      thread_work_.resize(max_threads(), std::vector<double>(5 * nz_max_, 0.0));
    for (auto& l : linked_) std::fill(l.begin(), l.end(), 0);
    const bool filled = take_face_values(report);
    if (implicit_) {
      for (const auto& l : in.links) {
        linked_[l.part_a][l.node_a] |= static_cast<char>(1 << l.face_a);
        for (int j = 0; j < 3; ++j) linked_[l.part_b][l.nodes_b[j]] |= static_cast<char>(1 << l.face_b);
      }
      rods_implicit(in, T);  // face values: those the Robin terms and links were solved at
    } else {
      rods_explicit(in, T);  // face values: those at the start of the step
    }
    if (filled && report) report->face_values_filled = true;
    int substeps = 1;
    long long limited_nodes = 0;
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const PlyThermal& ply = plies_[p];
      const int nz = ply.nz;
      const int n = ply.view->num_nodes;
      double* t = T[p].data();
      double* m = mean_[p].data();
      double* lo = rod_lo_[p].data();
      double* m_old = mean_old_[p].data();
      double* hi = rod_hi_[p].data();
      const double* kf = conductivity(in, p);
      if (inplane_layers_ && kf) {
        // Each layer value with the conductivity of its own values.
        assemble_inplane_layers(plies_[p], kf);
        substeps = std::max(substeps, advance_inplane(ply, in.dt, T[p], scratch_[p], nz, true));
        continue;
      }
      if (inplane_layers_) {
        // Every layer value by the in-plane operator: the lateral flow of the
        // through-thickness deviation is kept (no recomposition needed).
        substeps = std::max(substeps, advance_inplane(ply, in.dt, T[p], scratch_[p], nz));
        continue;
      }
      if (kf) {
        // The mean's operator with the conductivity's mean through the thickness.
        double* kn = k_mean_[p].data();
        for (int i = 0; i < n; ++i) {
          const double* ki = kf + 3 * static_cast<std::size_t>(nz) * i;
          double s11 = 0, s22 = 0;
          for (int k = 0; k < nz; ++k) {
            s11 += ply.w[k] * ki[3 * k];
            s22 += ply.w[k] * ki[3 * k + 1];
          }
          kn[2 * i] = s11 / ply.h;
          kn[2 * i + 1] = s22 / ply.h;
        }
        assemble_inplane(plies_[p], kn, kn + 1, 2);
        update_inplane_bounds(plies_[p]);
      }
#pragma omp parallel for schedule(static) if (n > 1024)
      for (int i = 0; i < n; ++i) {
        const double* ti = t + static_cast<std::size_t>(nz) * i;
        double s = 0, mn = ti[0], mx = ti[0];
        for (int k = 0; k < nz; ++k) {
          s += ply.w[k] * ti[k];
          mn = std::min(mn, ti[k]);
          mx = std::max(mx, ti[k]);
        }
        m[i] = s / ply.h;
        m_old[i] = m[i];
        lo[i] = mn;
        hi[i] = mx;
      }
      substeps = std::max(substeps, advance_inplane(ply, in.dt, mean_[p], scratch_[p]));
      const Csr& k2d = ply.k2d;
      long long limited = 0;
#pragma omp parallel for schedule(static) reduction(+ : limited) if (n > 1024)
      for (int i = 0; i < n; ++i) {
        double* ti = t + static_cast<std::size_t>(nz) * i;
        const double delta = m[i] - m_old[i];  // <T>new - <T>: T = <T>new + T~ (Eq. 20)
        if (delta == 0.0) continue;
        // Range of the values this node's in-plane stencil held before the step.
        double lower = lo[i], upper = hi[i];
        for (int q = k2d.row_start[i]; q < k2d.row_start[i + 1]; ++q) {
          lower = std::min(lower, lo[k2d.col[q]]);
          upper = std::max(upper, hi[k2d.col[q]]);
        }
        if (hi[i] + delta <= upper && lo[i] + delta >= lower) {
          for (int k = 0; k < nz; ++k) ti[k] += delta;
          continue;
        }
        // The uniform shift would leave the stencil's range (steep profiles
        // next to strong in-plane conduction): give the same heat to the
        // values in proportion to the room they have below the bound, which
        // conserves heat and keeps every value inside the range.
        double room_sum = 0;
        for (int k = 0; k < nz; ++k) room_sum += ply.w[k] * (delta > 0 ? upper - ti[k] : ti[k] - lower);
        if (room_sum <= 0) {
          for (int k = 0; k < nz; ++k) ti[k] += delta;
          continue;
        }
        ++limited;
        const double f = delta * ply.h / room_sum;
        for (int k = 0; k < nz; ++k) ti[k] += f * (delta > 0 ? upper - ti[k] : ti[k] - lower);
      }
      limited_nodes += limited;
    }
    double heat = 0;
    for (const auto& h : node_heat_)
      for (double q : h) heat += q;
    if (report) {
      report->heat_in = heat;
      report->substeps = substeps;
      report->limited = limited_nodes;
    }
    return sdk::Status::success();
  });
}

}  // namespace ts::thermal
