// adi: the paper's alternating-direction split (physics.md section 3): a
// 1D rod of thickness_layers linear elements at every node, then in-plane
// conduction on the ply's triangles of the through-thickness mean (the
// reference method) or, with in_plane = "layers", of every layer value.
#include <thermostamp/sdk/plugin.hpp>

#include "split_thermal.hpp"
#include "thermal_common.hpp"

namespace {

ts::sdk::ThermalSplitter* create() { return new ts::thermal::SplitThermal(true); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Thermal;
  d.name = "adi";
  d.version = "1.2.0";
  d.summary = "ADI split: through-thickness rods at every node + in-plane conduction of the mean";
  d.params = ts::thermal::splitter_params(
      "1D rod scheme: implicit = backward Euler with a tridiagonal solve (unconditionally "
                            "stable); explicit = forward Euler as in the reference method (dt <= rho c e^2 / 2 k33)");
  d.params.push_back(ts::sdk::choice_param(
      "in_plane", "mean", {"mean", "layers"},
      "in-plane conduction step: mean = of the through-thickness mean only, the deviation profile carried "
      "along (the reference method, Eqs. 20-31); layers = of every layer value (the lateral flow of the "
      "deviation is kept: more accurate where the face conditions change over a distance comparable to the "
      "thickness, e.g. at the edge of a contact patch; the in-plane step costs thickness_layers + 1 times more)"));
  d.example = R"({ "splitter": "adi", "through_thickness": "implicit" })";
  r.add_thermal(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("thermal_adi", "1.2.0", register_all)
