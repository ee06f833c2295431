// A membrane law for the tests: an isotropic stress that follows the
// temperature, S11 = S22 = k (T - t_ref), S12 = 0, whatever the strain, so
// that the stresses of an output frame show the element temperatures the
// kernel gave the law.
#include <thermostamp/sdk/plugin.hpp>

namespace {

class TemperatureStress final : public ts::sdk::MaterialLaw {
 public:
  ts::sdk::Status configure(const ts::sdk::Params& p) override {
    k_ = p.real("k");
    t_ref_ = p.real("t_ref");
    return ts::sdk::Status::success();
  }
  ts::sdk::LawRole role() const override { return ts::sdk::LawRole::Membrane; }
  ts::sdk::Status evaluate(const ts::sdk::MaterialBlock& b) const override {
    for (std::size_t q = 0; q < b.n; ++q) {
      const double s = k_ * (b.temperature[q] - t_ref_);
      b.stress[3 * q] = s;
      b.stress[3 * q + 1] = s;
      b.stress[3 * q + 2] = 0.0;
      if (!b.energy.empty()) b.energy[q] = 0.0;
    }
    return ts::sdk::Status::success();
  }
  double max_stiffness(double) const override { return k_; }
  bool uses_strain_old() const override { return false; }

 private:
  double k_ = 0, t_ref_ = 0;
};

ts::sdk::MaterialLaw* create() { return new TemperatureStress(); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Material;
  d.name = "temperature_stress";
  d.version = "0.0.1";
  d.summary = "test plugin: membrane stress k (T - t_ref) in both directions";
  d.params = {ts::sdk::real_param("k", "1.0", "N/m/degC", "stress per degree", 0.0),
              ts::sdk::real_param("t_ref", "0.0", "degC", "temperature of zero stress")};
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_temperature_stress", "0.0.1", register_all)
