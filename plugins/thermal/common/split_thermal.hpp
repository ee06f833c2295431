#pragma once
// The operator-split thermal shell used by the `adi` and `shell2d` plugins
// (physics.md section 3):
//   1. through the thickness, at every node, over dt with the face
//      conditions (explicit, or implicit backward Euler with a tridiagonal
//      solve; rods joined by ply/ply contact conductances are coupled
//      through a small interface system of their face values, so that the
//      exchange is implicit and conserves heat exactly);
//   2. mean <T> = (1/h) int T dz and deviation T~ = T - <T>;
//   3. the mean alone by the in-plane problem rho c h d<T>/dt = div(h Ks grad <T>);
//   4. T = <T>new + T~ (the paper's Eq. 31 prints -T~; +T~ is right, Eq. 20).
//      Where this uniform shift would carry a value outside the range its
//      in-plane stencil held before the step (a steep through-thickness
//      profile next to strong in-plane conduction), the same heat is given
//      to the values in proportion to their room below that range instead:
//      heat is conserved and no value leaves the range. The step report
//      counts these nodes; with ordinary profiles there are none.
// With in_plane = "layers" (adi) steps 2-4 are replaced by the in-plane
// problem for every layer value (rho c dT/dt = div(Ks grad T) per layer):
// the lateral flow of the deviation is kept, only the time split remains.
// With one value per node (shell2d) step 1 reduces to the face fluxes as
// sources of a plain thermal shell and steps 2-4 to its in-plane conduction.
#include <memory>
#include <vector>

#include <thermostamp/sdk/thermal.hpp>

#include "thermal_common.hpp"

namespace ts::thermal {

class LinkedSolver;  // sparse solve of rods joined by links

class SplitThermal : public sdk::ThermalSplitter {
 public:
  explicit SplitThermal(bool layered);
  ~SplitThermal() override;
  sdk::Status configure(const sdk::Params& params, std::span<const sdk::PartView> parts) override;
  int values_per_node(int part) const override { return plies_[part].nz; }
  sdk::Status capacities(int part, std::span<double> capacity) const override;
  sdk::Status step_limits(const sdk::ThermalStepInput& in, double* stable_dt, double* accurate) override;
  sdk::Status advance(const sdk::ThermalStepInput& in, std::span<const std::span<double>> temperature,
                      sdk::ThermalStepReport* report) override;
  bool takes_conductivity_field() const override { return true; }

 private:
  double rods_explicit(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T);
  bool update_rod_factors(const sdk::ThermalStepInput& in);
  struct RodFactors;
  static void factor_rod(RodFactors& rf, int id, int nz, double hb, double ht, const double* gk);
  static void rod_responses(RodFactors& rf, int id, int nz);
  // The part's conductivity values of this step (3 per value), or null.
  static const double* conductivity(const sdk::ThermalStepInput& in, std::size_t part) {
    return part < in.conductivity.size() && !in.conductivity[part].empty() ? in.conductivity[part].data() : nullptr;
  }
  double rods_implicit(const sdk::ThermalStepInput& in, std::span<const std::span<double>> T);

  bool layered_;          // true: one rod of thickness_layers elements per node (adi)
  bool implicit_ = true;  // through-thickness scheme
  bool inplane_layers_ = false;  // in-plane conduction of every layer instead of the mean (adi only)
  double dt_safety_ = 0.9;
  int nz_max_ = 1;
  std::vector<PlyThermal> plies_;
  // Per part, where the report gives room for the face values (2 per node),
  // else null; take_face_values sets them and says whether all are given.
  bool take_face_values(sdk::ThermalStepReport* report);
  std::vector<double*> face_out_;
  std::vector<std::vector<double>> node_heat_;   // per part, per node: J in this step
  std::vector<std::vector<double>> scratch_;     // per part
  std::vector<std::vector<double>> mean_;        // per part
  std::vector<std::vector<double>> k_mean_;      // per part, 2 per node: k11, k22 through-thickness means
  std::vector<std::vector<double>> rod_lo_, rod_hi_, mean_old_;
  struct RodFactors {  // shared tridiagonal factorisations, one per (h_bottom, h_top) pair
    double dt = -1;
    std::vector<double> hb, ht, cap, inv_den, g_inv_den, v_bottom, v_top, gk;
    std::vector<int> id;  // per node
  };
  std::vector<RodFactors> factors_;  // per part  // per part: range of each rod before the in-plane step
  std::vector<std::vector<double>> t_old_;       // per part (explicit links)
  std::vector<std::vector<double>> thread_work_; // per thread, 4 * nz
  std::vector<std::vector<char>> linked_;        // per part, per node: bit 1 << face for each linked face
  std::unique_ptr<LinkedSolver> linked_solver_;
  std::vector<sdk::HeatLink> last_links_;
  std::vector<std::vector<int>> linked_offset_;  // per part, 2 per node (bottom, top): unknown or -1
  std::vector<double> linked_rhs_, linked_flux_;
  std::vector<double> linked_sinv_;  // 4 per linked unknown, at the first linked face of each rod: A S^-1
  int linked_count_ = 0;
  bool linked_valid_ = false;
};

}  // namespace ts::thermal
