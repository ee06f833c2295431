// layered3d: the full 3D reference. Every ply is a stack of prisms (its
// triangles x thickness_layers) with in-plane and through-thickness
// conduction coupled at every layer, solved as one system (backward Euler,
// sparse LDL^T) or explicitly (forward Euler). The in-thickness quadrature
// is lumped exactly as in the adi rods, so that adi - layered3d measures
// the splitting error alone.
#include <Eigen/Sparse>
#include <algorithm>
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
      rhs_.resize(n_);
      return sdk::Status::success();
    });
  }
  int values_per_node(int part) const override { return plies_[part].nz; }
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
        for (int c = 0; c < k_.outerSize(); ++c) rate = std::max(rate, k_.coeff(c, c) / cap_[c]);
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
      Eigen::VectorXd t(n_);
      for (std::size_t p = 0; p < plies_.size(); ++p)
        std::copy(T[p].begin(), T[p].end(), t.data() + offset_[p]);
      // Robin right-hand side b: sum H A T_ext at the face values.
      Eigen::VectorXd b = Eigen::VectorXd::Zero(n_);
      for (std::size_t p = 0; p < plies_.size(); ++p) {
        const PlyThermal& ply = plies_[p];
        const auto& f = in.faces[p];
        for (int i = 0; i < ply.view->num_nodes; ++i) {
          const int o = offset_[p] + ply.nz * i;
          b[o] += f.h_bottom[i] * ply.area[i] * f.t_bottom[i];
          b[o + ply.nz - 1] += f.h_top[i] * ply.area[i] * f.t_top[i];
        }
      }
      Eigen::VectorXd t_new(n_);
      if (implicit_) {
        if (!factored_ || dt != factored_dt_) {
          Eigen::SparseMatrix<double> a = k_;
          for (int i = 0; i < n_; ++i) a.coeffRef(i, i) += cap_[i] / dt;
          if (!pattern_analyzed_) {
            ldlt_.analyzePattern(a);
            pattern_analyzed_ = true;
          }
          ldlt_.factorize(a);
          if (ldlt_.info() != Eigen::Success) throw std::runtime_error("layered3d: factorisation failed");
          factored_ = true;
          factored_dt_ = dt;
        }
        for (int i = 0; i < n_; ++i) rhs_[i] = cap_[i] / dt * t[i] + b[i];
        t_new = ldlt_.solve(rhs_);
      } else {
        const Eigen::VectorXd kt = k_ * t;
        for (int i = 0; i < n_; ++i) t_new[i] = t[i] + dt * (b[i] - kt[i]) / cap_[i];
      }
      const Eigen::VectorXd& tf = implicit_ ? t_new : t;  // face temperature of the Robin terms
      double heat = 0;
      for (std::size_t p = 0; p < plies_.size(); ++p) {
        const PlyThermal& ply = plies_[p];
        const auto& f = in.faces[p];
        for (int i = 0; i < ply.view->num_nodes; ++i) {
          const int o = offset_[p] + ply.nz * i;
          heat += dt * ply.area[i] *
                  (f.h_bottom[i] * (f.t_bottom[i] - tf[o]) + f.h_top[i] * (f.t_top[i] - tf[o + ply.nz - 1]));
        }
        std::copy(t_new.data() + offset_[p], t_new.data() + offset_[p + 1], T[p].begin());
      }
      if (report) {
        report->heat_in = heat;
        report->substeps = 1;
      }
      return sdk::Status::success();
    });
  }

 private:
  void update_capacities() {
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const PlyThermal& ply = plies_[p];
      for (int i = 0; i < ply.view->num_nodes; ++i)
        for (int k = 0; k < ply.nz; ++k) cap_[offset_[p] + ply.nz * i + k] = ply.rho_c * ply.w[k] * ply.area[i];
    }
  }

  void assemble_if_needed(const sdk::ThermalStepInput& in) {
    bool changed = !assembled_ || in.geometry_changed || in.links_changed;
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
    std::vector<Eigen::Triplet<double>> trip;
    for (std::size_t p = 0; p < plies_.size(); ++p) {
      const PlyThermal& ply = plies_[p];
      const int nz = ply.nz;
      const double g = ply.k33 / ply.e;
      const auto& f = in.faces[p];
      const auto& m = ply.k2d;
      for (int i = 0; i < ply.view->num_nodes; ++i) {
        const int o = offset_[p] + nz * i;
        const double A = ply.area[i];
        for (int k = 0; k < nz; ++k) {
          // In-plane conduction in the slice of value k (lumped weight w_k).
          for (int q = m.row_start[i]; q < m.row_start[i + 1]; ++q)
            trip.emplace_back(o + k, offset_[p] + nz * m.col[q] + k, m.val[q] * ply.w[k]);
          if (k + 1 < nz) {
            trip.emplace_back(o + k, o + k, g * A);
            trip.emplace_back(o + k + 1, o + k + 1, g * A);
            trip.emplace_back(o + k, o + k + 1, -g * A);
            trip.emplace_back(o + k + 1, o + k, -g * A);
          }
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
        trip.emplace_back(ia, ia, g);
        trip.emplace_back(ib, ib, g);
        trip.emplace_back(ia, ib, -g);
        trip.emplace_back(ib, ia, -g);
      }
    }
    const bool pattern_may_change = in.links_changed || !assembled_;
    k_.resize(n_, n_);
    k_.setFromTriplets(trip.begin(), trip.end());
    k_.makeCompressed();
    assembled_ = true;
    factored_ = false;
    if (pattern_may_change) pattern_analyzed_ = false;
  }

  bool implicit_ = true;
  double dt_safety_ = 0.9;
  std::vector<PlyThermal> plies_;
  std::vector<int> offset_;
  int n_ = 0;
  std::vector<double> cap_, last_h_;
  Eigen::SparseMatrix<double> k_;
  Eigen::VectorXd rhs_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool assembled_ = false, factored_ = false, pattern_analyzed_ = false;
  double factored_dt_ = 0;
};

sdk::ThermalSplitter* create() { return new Layered3d(); }

void register_all(sdk::Registrar& r) {
  sdk::Descriptor d;
  d.kind = sdk::PluginKind::Thermal;
  d.name = "layered3d";
  d.version = "1.0.0";
  d.summary = "Full 3D reference: every ply as a stack of prisms, in-plane and through-thickness conduction coupled";
  d.params = {
      sdk::choice_param("through_thickness", "implicit", {"implicit", "explicit"},
                        "implicit: backward Euler on the whole 3D system (sparse LDL^T); explicit: forward Euler "
                        "within the stable step"),
      sdk::real_param("dt_safety", "0.9", "-", "fraction of the critical step used by the explicit scheme", 0.0, 1.0,
                      true),
  };
  d.example = R"({ "splitter": "layered3d", "through_thickness": "implicit" })";
  r.add_thermal(d, &create);
}

}  // namespace
}  // namespace ts::thermal

THERMOSTAMP_PLUGIN("thermal_layered3d", "1.0.0", ts::thermal::register_all)
