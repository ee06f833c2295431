// layered3d: the full 3D reference. Every ply is a stack of prisms (its
// triangles x thickness_layers) with in-plane and through-thickness
// conduction coupled at every layer, solved as one system (backward Euler,
// conjugate gradients preconditioned by exact through-thickness line solves,
// to a relative residual of 1e-13) or explicitly (forward Euler). The in-thickness quadrature
// is lumped exactly as in the adi rods, so that adi - layered3d measures
// the splitting error alone.
#include <Eigen/Sparse>
#include <algorithm>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <cmath>
#include <limits>
#include <vector>

#include <thermostamp/sdk/plugin.hpp>

#include "thermal_common.hpp"

namespace ts::thermal {
namespace {

class Layered3d final : public sdk::ThermalSplitter {
 public:
  sdk::Status configure(const sdk::Params& params, std::span<const sdk::PartView> parts) override {
    return sdk::guarded([&] {
      implicit_ = params.text("through_thickness") == "implicit";
      dt_safety_ = params.real("dt_safety");
      plies_.resize(parts.size());
      offset_.assign(parts.size() + 1, 0);
      for (std::size_t p = 0; p < parts.size(); ++p) {
        setup_ply(plies_[p], parts[p], parts[p].thickness_layers + 1);
        offset_[p + 1] = offset_[p] + parts[p].num_nodes * plies_[p].nz;
      }
      n_ = offset_.back();
      cap_.assign(n_, 0.0);
      update_capacities();
      for (auto* v : {&t_, &t_new_, &b_, &kt_, &r_, &z_, &p_, &ap_, &d_, &cprime_, &tri_sub_, &tri_diag_, &tri_sup_})
        v->assign(n_, 0.0);
      partial_.assign(64, 0.0);
      rod_start_.clear();
      for (std::size_t p = 0; p < parts.size(); ++p)
        for (int i = 0; i < parts[p].num_nodes; ++i) rod_start_.push_back(offset_[p] + plies_[p].nz * i);
      rod_start_.push_back(n_);
      return sdk::Status::success();
    });
  }
  int values_per_node(int part) const override { return plies_[part].nz; }
  bool takes_conductivity_field() const override { return true; }
  sdk::Status capacities(int part, std::span<double> cap) const override {
    std::copy(cap_.begin() + offset_[part], cap_.begin() + offset_[part + 1], cap.begin());
    return sdk::Status::success();
  }

  sdk::Status step_limits(const sdk::ThermalStepInput& in, double* stable, double* accurate) override {
    return sdk::guarded([&] {
      assemble_if_needed(in);
      *accurate = accurate_dt(plies_, in.faces);
      if (implicit_) {
        *stable = std::numeric_limits<double>::infinity();
      } else {
        // Forward Euler keeps the maximum principle for dt <= C_i / K_ii.
        double rate = 0;
        for (int c = 0; c < n_; ++c) rate = std::max(rate, tri_diag_[c] / cap_[c]);
        *stable = rate > 0 ? dt_safety_ / rate : std::numeric_limits<double>::infinity();
        *accurate = std::min(*accurate, *stable);
      }
      return sdk::Status::success();
    });
  }

  sdk::Status advance(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T,
                      sdk::ThermalStepReport* report) override {
    return sdk::guarded([&] {
      assemble_if_needed(in);
      const double dt = in.dt;
      std::vector<double>& t = t_;
      std::vector<double>& t_new = t_new_;
      for (std::size_t p = 0; p < plies_.size(); ++p)
        std::copy(T[p].begin(), T[p].end(), t.begin() + offset_[p]);
      // Robin right-hand side b: sum H A T_ext at the face values.
      std::vector<double>& b = b_;
      std::fill(b.begin(), b.end(), 0.0);
      for (std::size_t p = 0; p < plies_.size(); ++p) {
        const PlyThermal& ply = plies_[p];
        const auto& f = in.faces[p];
        for (int i = 0; i < ply.view->num_nodes; ++i) {
          const int o = offset_[p] + ply.nz * i;
          b[o] += f.h_bottom[i] * ply.area[i] * f.t_bottom[i];
          b[o + ply.nz - 1] += f.h_top[i] * ply.area[i] * f.t_top[i];
        }
      }
      multiply(t, kt_);  // K T^n
      if (implicit_) {
        // (C/dt + K) d = b - K T^n, T^{n+1} = T^n + d.
        for (int i = 0; i < n_; ++i) r_[i] = b[i] - kt_[i];
        const int iterations = solve_pcg(dt, t);
        if (iterations < 0)
          throw std::runtime_error("layered3d: conjugate gradients did not converge in 2000 iterations");
        for (int i = 0; i < n_; ++i) t_new[i] = t[i] + d_[i];
        last_iterations_ = iterations;
      } else {
        for (int i = 0; i < n_; ++i) t_new[i] = t[i] + dt * (b[i] - kt_[i]) / cap_[i];
      }
      const std::vector<double>& tf = implicit_ ? t_new : t;  // face temperature of the Robin terms
      double heat = 0;
      for (std::size_t p = 0; p < plies_.size(); ++p) {
        const PlyThermal& ply = plies_[p];
        const auto& f = in.faces[p];
        for (int i = 0; i < ply.view->num_nodes; ++i) {
          const int o = offset_[p] + ply.nz * i;
          heat += dt * ply.area[i] *
                  (f.h_bottom[i] * (f.t_bottom[i] - tf[o]) + f.h_top[i] * (f.t_top[i] - tf[o + ply.nz - 1]));
        }
        std::copy(t_new.begin() + offset_[p], t_new.begin() + offset_[p + 1], T[p].begin());
      }
      if (report && report->face_values.size() == plies_.size()) {
        bool sized = true;
        for (std::size_t p = 0; p < plies_.size(); ++p)
          sized = sized && report->face_values[p].size() == 2 * static_cast<std::size_t>(plies_[p].view->num_nodes);
        for (std::size_t p = 0; sized && p < plies_.size(); ++p) {
          const PlyThermal& ply = plies_[p];
          double* out = report->face_values[p].data();
          for (int i = 0; i < ply.view->num_nodes; ++i) {
            const int o = offset_[p] + ply.nz * i;
            out[2 * i] = tf[o];
            out[2 * i + 1] = tf[o + ply.nz - 1];
          }
        }
        report->face_values_filled = sized;
      }
      if (report) {
        report->heat_in = heat;
        report->substeps = implicit_ ? last_iterations_ : 1;
      }
      return sdk::Status::success();
    });
  }

 private:
  // y = K x, rows in parallel (each row summed in a fixed order).
  void multiply(const std::vector<double>& x, std::vector<double>& y) const {
    const int* rs = k_.outerIndexPtr();
    const int* col = k_.innerIndexPtr();
    const double* val = k_.valuePtr();
#pragma omp parallel for schedule(static) if (n_ > 4096)
    for (int r = 0; r < n_; ++r) {
      double s = 0;
      for (int q = rs[r]; q < rs[r + 1]; ++q) s += val[q] * x[col[q]];
      y[r] = s;
    }
  }

  // Dot product summed in fixed blocks: the same bits for any thread count.
  double dot(const std::vector<double>& a, const std::vector<double>& b) {
    const int nb = static_cast<int>(partial_.size());
#pragma omp parallel for schedule(static) if (n_ > 4096)
    for (int k = 0; k < nb; ++k) {
      const int lo = static_cast<int>(static_cast<long long>(n_) * k / nb);
      const int hi = static_cast<int>(static_cast<long long>(n_) * (k + 1) / nb);
      double s = 0;
      for (int i = lo; i < hi; ++i) s += a[i] * b[i];
      partial_[k] = s;
    }
    double s = 0;
    for (double v : partial_) s += v;
    return s;
  }

  // z = M^-1 r with M the through-thickness (tridiagonal) blocks of C/dt + K.
  void precondition(const std::vector<double>& r, std::vector<double>& z, double dt) {
    const int rods = static_cast<int>(rod_start_.size()) - 1;
#pragma omp parallel for schedule(static) if (rods > 512)
    for (int q = 0; q < rods; ++q) {
      const int o = rod_start_[q], m = rod_start_[q + 1] - o;
      // Thomas algorithm on the block, in place in z.
      double c_prev = 0, d_prev = 0;
      for (int k = 0; k < m; ++k) {
        const double a = k > 0 ? tri_sub_[o + k] : 0.0;
        const double den = tri_diag_[o + k] + cap_[o + k] / dt - a * c_prev;
        c_prev = (k + 1 < m ? tri_sup_[o + k] : 0.0) / den;
        d_prev = (r[o + k] - a * d_prev) / den;
        z[o + k] = d_prev;
        cprime_[o + k] = c_prev;
      }
      for (int k = m - 2; k >= 0; --k) z[o + k] -= cprime_[o + k] * z[o + k + 1];
    }
  }

  // Preconditioned conjugate gradients on (C/dt + K) d = r_, d_ out.
  int solve_pcg(double dt, const std::vector<double>& t) {
    std::fill(d_.begin(), d_.end(), 0.0);
    const double r0 = std::sqrt(dot(r_, r_));
    if (r0 == 0) return 0;
    // Stop at 1e-13 of the initial residual, or at the round-off floor of
    // the terms that cancel in it (1e-14 of |C T / dt|).
    for (int i = 0; i < n_; ++i) z_[i] = cap_[i] / dt * t[i];
    const double tol = std::max(1e-13 * r0, 1e-14 * std::sqrt(dot(z_, z_)));
    precondition(r_, z_, dt);
    p_ = z_;
    double rz = dot(r_, z_);
    for (int it = 1; it <= 2000; ++it) {
      multiply(p_, ap_);
      for (int i = 0; i < n_; ++i) ap_[i] += cap_[i] / dt * p_[i];
      const double alpha = rz / dot(p_, ap_);
      for (int i = 0; i < n_; ++i) {
        d_[i] += alpha * p_[i];
        r_[i] -= alpha * ap_[i];
      }
      if (std::sqrt(dot(r_, r_)) <= tol) return it;
      precondition(r_, z_, dt);
      const double rz_new = dot(r_, z_);
      const double beta = rz_new / rz;
      rz = rz_new;
      for (int i = 0; i < n_; ++i) p_[i] = z_[i] + beta * p_[i];
    }
    return -1;
  }

  void update_capacities() {
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const PlyThermal& ply = plies_[p];
      for (int i = 0; i < ply.view->num_nodes; ++i)
        for (int k = 0; k < ply.nz; ++k) cap_[offset_[p] + ply.nz * i + k] = ply.rho_c * ply.w[k] * ply.area[i];
    }
  }

  void assemble_if_needed(const sdk::ThermalStepInput& in) {
    const bool links_changed = in.links_changed && !same_links(in.links, last_links_);
    // A conductivity that depends on the temperature changes K at every step.
    bool field = false;
    for (const auto& k : in.conductivity) field = field || !k.empty();
    bool changed = !assembled_ || in.geometry_changed || links_changed || field || assembled_with_field_;
    assembled_with_field_ = field;
    // With a varying conductivity K keeps its pattern from step to step: the
    // values go straight into the places found at the last full assembly.
    const bool refill = field && slots_valid_ && !links_changed;
    if (links_changed) last_links_.assign(in.links.begin(), in.links.end());
    if (!changed) {
      std::size_t q = 0;
      for (const auto& f : in.faces)
        for (std::size_t i = 0; i < f.h_bottom.size(); ++i, q += 2)
          if (f.h_bottom[i] != last_h_[q] || f.h_top[i] != last_h_[q + 1]) changed = true;
    }
    if (!changed) return;
    if (in.geometry_changed) {
      for (auto& p : plies_) update_geometry(p);
      update_capacities();
    }
    last_h_.clear();
    for (const auto& f : in.faces)
      for (std::size_t i = 0; i < f.h_bottom.size(); ++i) {
        last_h_.push_back(f.h_bottom[i]);
        last_h_.push_back(f.h_top[i]);
      }
    std::vector<Eigen::Triplet<double>>& trip = trip_;
    trip.clear();
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const PlyThermal& ply = plies_[p];
      const int nz = ply.nz;
      const double g = ply.k33 / ply.e;
      const auto& f = in.faces[p];
      const auto& m = ply.k2d;
      if (p < in.conductivity.size() && !in.conductivity[p].empty()) {
        add_varying(in.conductivity[p].data(), p, f, trip);
        continue;
      }
      for (int i = 0; i < ply.view->num_nodes; ++i) {
        const int o = offset_[p] + nz * i;
        const double A = ply.area[i];
        for (int k = 0; k < nz; ++k) {
          // In-plane conduction in the slice of value k (lumped weight w_k).
          for (int q = m.row_start[i]; q < m.row_start[i + 1]; ++q)
            trip.emplace_back(o + k, offset_[p] + nz * m.col[q] + k, m.val[q] * ply.w[k]);
          if (k + 1 < nz) add_pair(trip, o + k, o + k + 1, g * A);
        }
        trip.emplace_back(o, o, f.h_bottom[i] * A);
        trip.emplace_back(o + nz - 1, o + nz - 1, f.h_top[i] * A);
      }
    }
    for (const auto& l : in.links) {
      // Three node-to-node conductances G w_j (sdk/thermal.hpp).
      const PlyThermal& pa = plies_[l.part_a];
      const PlyThermal& pb = plies_[l.part_b];
      const int ia = offset_[l.part_a] + pa.nz * l.node_a + (l.face_a == sdk::kTop ? pa.nz - 1 : 0);
      for (int j = 0; j < 3; ++j) {
        const double g = l.conductance * l.w_b[j];
        if (g == 0) continue;
        const int ib = offset_[l.part_b] + pb.nz * l.nodes_b[j] + (l.face_b == sdk::kTop ? pb.nz - 1 : 0);
        add_pair(trip, ia, ib, g);
      }
    }
    if (!refill) assemble_pattern(field);
    if (field) {
      // Every step sums the triplets the same way, whether the pattern was
      // found again or not (a restarted run gives the same bits).
      double* val = k_.valuePtr();
      std::fill(val, val + k_.nonZeros(), 0.0);
      for (std::size_t t = 0; t < trip.size(); ++t) val[slot_[t]] += trip[t].value();
      for (int r = 0; r < n_; ++r) {
        tri_sub_[r] = tri_slot_[3 * r] >= 0 ? val[tri_slot_[3 * r]] : 0.0;
        tri_diag_[r] = val[tri_slot_[3 * r + 1]];
        tri_sup_[r] = tri_slot_[3 * r + 2] >= 0 ? val[tri_slot_[3 * r + 2]] : 0.0;
      }
    }
  }

  // K from the triplets in trip_ (and, with a varying conductivity, the
  // places of the triplets and of the through-thickness blocks in K's values).
  void assemble_pattern(bool field) {
    const std::vector<Eigen::Triplet<double>>& trip = trip_;
    k_.resize(n_, n_);
    k_.setFromTriplets(trip.begin(), trip.end());
    k_.makeCompressed();
    assembled_ = true;
    // Through-thickness blocks for the preconditioner.
    for (int q = 0; q + 1 < static_cast<int>(rod_start_.size()); ++q)
      for (int r = rod_start_[q]; r < rod_start_[q + 1]; ++r) {
        tri_sub_[r] = r > rod_start_[q] ? k_.coeff(r, r - 1) : 0.0;
        tri_diag_[r] = k_.coeff(r, r);
        tri_sup_[r] = r + 1 < rod_start_[q + 1] ? k_.coeff(r, r + 1) : 0.0;
      }
    slots_valid_ = field;
    if (field) {
      // The place of every triplet (and of the through-thickness blocks) in K's values.
      const int* outer = k_.outerIndexPtr();
      const int* inner = k_.innerIndexPtr();
      auto place = [&](int r, int c) {
        const int* it = std::lower_bound(inner + outer[r], inner + outer[r + 1], c);
        return it != inner + outer[r + 1] && *it == c ? static_cast<int>(it - inner) : -1;
      };
      slot_.resize(trip.size());
      for (std::size_t t = 0; t < trip.size(); ++t) slot_[t] = place(trip[t].row(), trip[t].col());
      tri_slot_.assign(3 * static_cast<std::size_t>(n_), -1);
      for (int q = 0; q + 1 < static_cast<int>(rod_start_.size()); ++q)
        for (int r = rod_start_[q]; r < rod_start_[q + 1]; ++r) {
          if (r > rod_start_[q]) tri_slot_[3 * r] = place(r, r - 1);
          tri_slot_[3 * r + 1] = place(r, r);
          if (r + 1 < rod_start_[q + 1]) tri_slot_[3 * r + 2] = place(r, r + 1);
        }
    }
  }

  // A conductance G (W/K) between values a and b: K_aa, K_bb += G; K_ab, K_ba -= G.
  static void add_pair(std::vector<Eigen::Triplet<double>>& trip, int a, int b, double G) {
    trip.emplace_back(a, a, G);
    trip.emplace_back(b, b, G);
    trip.emplace_back(a, b, -G);
    trip.emplace_back(b, a, -G);
  }

  // K's triplets of a ply whose conductivity varies: every slice with the
  // conductivity of its values (the element's mean of its three nodes), every
  // layer with k33 at the mean of its two values.
  void add_varying(const double* kf, std::size_t p, const sdk::FaceConditions& f,
                   std::vector<Eigen::Triplet<double>>& trip) {
    PlyThermal& ply = plies_[p];
    const int nz = ply.nz;
    const auto& m = ply.k2d;
    const std::size_t stride = 3 * static_cast<std::size_t>(nz);
    for (int k = 0; k < nz; ++k) {
      assemble_inplane(ply, kf + 3 * k, kf + 3 * k + 1, stride);
      for (int i = 0; i < ply.view->num_nodes; ++i)
        for (int q = m.row_start[i]; q < m.row_start[i + 1]; ++q)
          trip.emplace_back(offset_[p] + nz * i + k, offset_[p] + nz * m.col[q] + k, m.val[q] * ply.w[k]);
    }
    for (int i = 0; i < ply.view->num_nodes; ++i) {
      const int o = offset_[p] + nz * i;
      const double A = ply.area[i];
      const double* ki = kf + stride * i;
      for (int k = 0; k + 1 < nz; ++k) {
        add_pair(trip, o + k, o + k + 1, 0.5 * (ki[3 * k + 2] + ki[3 * k + 5]) / ply.e * A);
      }
      trip.emplace_back(o, o, f.h_bottom[i] * A);
      trip.emplace_back(o + nz - 1, o + nz - 1, f.h_top[i] * A);
    }
  }

  bool implicit_ = true;
  bool assembled_with_field_ = false;
  bool slots_valid_ = false;
  std::vector<Eigen::Triplet<double>> trip_;
  std::vector<int> slot_, tri_slot_;  // places in K's values: of each triplet; 3 per value (sub, diag, sup)
  double dt_safety_ = 0.9;
  std::vector<PlyThermal> plies_;
  std::vector<int> offset_;
  int n_ = 0;
  std::vector<double> cap_, last_h_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> k_;
  std::vector<double> tri_sub_, tri_diag_, tri_sup_;  // through-thickness blocks of K
  std::vector<int> rod_start_;
  std::vector<double> t_, t_new_, b_, kt_, r_, z_, p_, ap_, d_, cprime_, partial_;
  std::vector<sdk::HeatLink> last_links_;
  bool assembled_ = false;
  int last_iterations_ = 0;
};

sdk::ThermalSplitter* create() { return new Layered3d(); }

void register_all(sdk::Registrar& r) {
  sdk::Descriptor d;
  d.kind = sdk::PluginKind::Thermal;
  d.name = "layered3d";
  d.version = "1.1.0";
  d.summary = "Full 3D reference: every ply as a stack of prisms, in-plane and through-thickness conduction coupled";
  d.params = splitter_params(
      "implicit: backward Euler on the whole 3D system (conjugate gradients with exact "
                        "through-thickness line solves as preconditioner); explicit: forward Euler "
                        "within the stable step");
  d.example = R"({ "splitter": "layered3d", "through_thickness": "implicit" })";
  r.add_thermal(d, &create);
}

}  // namespace
}  // namespace ts::thermal

THERMOSTAMP_PLUGIN("thermal_layered3d", "1.1.0", ts::thermal::register_all)
