// ud_hyperelastic: w = k_fibre I_e1^2 + p_ct I_lt^2 + sum_i k_sh_i I_sh^(2i),
// with the transverse invariant I_lt = 1/2 ln(I3 / I41), independent of the
// in-plane shear (Bigot et al. 2022). L2 = n x L1. Energy per unit initial
// area (J/m^2), stiffnesses in N/m. A temperature-dependent, viscoelastic
// shear is added by listing `viscoelastic_shear` next to this law.
#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/plugin.hpp>

namespace {

using namespace ts::sdk;

class UdHyperelastic final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&] {
      k_fibre_ = p.real("k_fibre");
      p_ct_ = p.real("p_ct");
      const auto& ks = p.list("k_sh");
      for (int i = 0; i < 3; ++i) k_sh_[i] = ks[i];
      has_shear_ = ks[0] != 0 || ks[1] != 0 || ks[2] != 0;
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  Status evaluate(const MaterialBlock& b) const override {
    const FibreFrame f;  // L2 = n x L1 = (0, 1) in the material frame
    for (std::size_t q = 0; q < b.n; ++q) {
      const Sym2 C = {b.strain[3 * q], b.strain[3 * q + 1], b.strain[3 * q + 2]};
      const Invariants v = invariants(C, f, has_shear_ ? kE1 | kLt | kSh : kE1 | kLt);
      double wsh, dwsh;
      even_polynomial(k_sh_, 3, v.sh, &wsh, &dwsh);
      Sym2 S{0, 0, 0};
      add_stress(S, 2 * k_fibre_ * v.e1, v.de1);
      add_stress(S, 2 * p_ct_ * v.lt, v.dlt);
      add_stress(S, dwsh, v.dsh);
      for (int k = 0; k < 3; ++k) b.stress[3 * q + k] = S[k];
      if (!b.energy.empty()) b.energy[q] = k_fibre_ * v.e1 * v.e1 + p_ct_ * v.lt * v.lt + wsh;
    }
    return Status::success();
  }
  double max_stiffness(double) const override { return 2 * std::max(k_fibre_, p_ct_); }

 private:
  double k_fibre_ = 0, p_ct_ = 0, k_sh_[3] = {0, 0, 0};
  bool has_shear_ = false;
};

MaterialLaw* create() { return new UdHyperelastic(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "ud_hyperelastic";
  d.version = "1.0.0";
  d.summary = "UD membrane: fibre elongation, transverse elongation I_lt = 1/2 ln(I3/I41), optional elastic shear";
  const ParamSpec ksh = list_param("k_sh", "[0, 0, 0]", "N/m",
                                   "elastic shear coefficients of w_sh = sum k_sh^i I_sh^(2i) (zero when viscoelastic_shear carries the shear)", 3);
  d.params = {real_param("k_fibre", "", "N/m", "fibre stiffness: w_e1 = k_fibre I_e1^2, I_e1 = 1/2 ln I41", 0.0, 1e15, true),
              real_param("p_ct", "", "N/m", "transverse stiffness: w_lt = p_ct I_lt^2", 0.0, 1e15, true), ksh};
  d.example = R"({ "law": "ud_hyperelastic", "k_fibre": 5.0e6, "p_ct": 50.0 })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_ud_hyperelastic", "1.0.0", register_all)
