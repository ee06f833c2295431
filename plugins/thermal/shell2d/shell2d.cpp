// shell2d: the plain thermal shell, one temperature per node; the face
// fluxes are sources of the in-plane problem and the face temperature is the
// node temperature (no through-thickness gradient).
#include <thermostamp/sdk/plugin.hpp>

#include "split_thermal.hpp"
#include "thermal_common.hpp"

namespace {

ts::sdk::ThermalSplitter* create() { return new ts::thermal::SplitThermal(false); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Thermal;
  d.name = "shell2d";
  d.version = "1.1.0";
  d.summary = "Plain thermal shell: one temperature per node, face fluxes as sources";
  d.params = ts::thermal::splitter_params(
      "treatment of the face fluxes: implicit (backward Euler, unconditionally stable) or "
                            "explicit (forward Euler)");
  d.example = R"({ "splitter": "shell2d" })";
  r.add_thermal(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("thermal_shell2d", "1.1.0", register_all)
