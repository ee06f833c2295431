// A thermal plugin that goes wrong on purpose: after `fail_time` it writes a
// NaN into one node, so that the kernel's failure path can be tested.
#include <limits>
#include <thermostamp/sdk/plugin.hpp>

namespace {

class NanAfter final : public ts::sdk::ThermalSplitter {
 public:
  ts::sdk::Status configure(const ts::sdk::Params& p, std::span<const ts::sdk::PartView> parts) override {
    fail_time_ = p.real("fail_time");
    nodes_ = parts.empty() ? 0 : parts[0].num_nodes;
    return ts::sdk::Status::success();
  }
  int values_per_node(int) const override { return 1; }
  ts::sdk::Status capacities(int, std::span<double> c) const override {
    for (double& v : c) v = 1.0;
    return ts::sdk::Status::success();
  }
  ts::sdk::Status step_limits(const ts::sdk::ThermalStepInput&, double* stable, double* accurate) override {
    *stable = std::numeric_limits<double>::infinity();
    *accurate = 0.1;
    return ts::sdk::Status::success();
  }
  ts::sdk::Status advance(const ts::sdk::ThermalStepInput& in, std::span<const std::span<double>> T,
                          ts::sdk::ThermalStepReport* report) override {
    t_ += in.dt;
    if (report) report->heat_in = 0;
    if (t_ > fail_time_ && nodes_ > 1) T[0][1] = std::numeric_limits<double>::quiet_NaN();
    return ts::sdk::Status::success();
  }

 private:
  double fail_time_ = 0, t_ = 0;
  int nodes_ = 0;
};

ts::sdk::ThermalSplitter* create() { return new NanAfter(); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Thermal;
  d.name = "nan_after";
  d.version = "0.0.1";
  d.summary = "test plugin: produces a NaN after fail_time";
  d.params = {ts::sdk::real_param("fail_time", "0.5", "s", "time after which a NaN appears", 0.0),
              ts::sdk::choice_param("through_thickness", "implicit", {"implicit", "explicit"}, "ignored"),
              ts::sdk::real_param("dt_safety", "0.9", "-", "ignored", 0.0, 1.0, true)};
  r.add_thermal(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("thermal_nan_after", "0.0.1", register_all)
