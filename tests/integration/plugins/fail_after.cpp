// A contact handler that goes wrong on purpose: from `fail_time` on its
// contact_forces reports a failure, so that the kernel's failure path can be
// tested (also when the contact runs as a task beside the element blocks);
// with `thermal_fail_call` n > 0, its n-th thermal_contacts call fails.
#include <thermostamp/sdk/plugin.hpp>

namespace {

class FailAfter final : public ts::sdk::ContactHandler {
 public:
  ts::sdk::Status configure(const ts::sdk::Params& p, const ts::sdk::ContactPair&,
                            std::span<const ts::sdk::PartView>, std::span<const ts::sdk::ToolView>) override {
    fail_time_ = p.real("fail_time");
    thermal_fail_call_ = p.integer("thermal_fail_call");
    return ts::sdk::Status::success();
  }
  ts::sdk::Status thermal_contacts(std::span<const ts::sdk::PartView>, std::span<const ts::sdk::ToolView>,
                                   std::span<const std::span<const double>>, ts::sdk::ThermalContactMap&) override {
    if (++thermal_calls_ == thermal_fail_call_) return ts::sdk::Status::failure("thermal contacts failed on purpose");
    return ts::sdk::Status::success();
  }
  ts::sdk::Status contact_forces(const ts::sdk::ContactForceInput& in, ts::sdk::ContactForceOutput&) override {
    if (in.time >= fail_time_) return ts::sdk::Status::failure("failed on purpose");
    return ts::sdk::Status::success();
  }

 private:
  double fail_time_ = 0;
  long long thermal_fail_call_ = 0, thermal_calls_ = 0;
};

ts::sdk::ContactHandler* create() { return new FailAfter(); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Contact;
  d.name = "fail_after";
  d.version = "0.0.1";
  d.summary = "test plugin: contact forces fail from fail_time on";
  d.params = {ts::sdk::real_param("fail_time", "0.5", "s", "time from which contact_forces fails", 0.0),
              ts::sdk::int_param("thermal_fail_call", "0", "the thermal_contacts call that fails (0: none)", 0, 1e9)};
  r.add_contact(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("contact_fail_after", "0.0.1", register_all)
