// woven_hyperelastic: w = k_warp I_e1^2 + k_weft I_e2^2 + sum_i k_sh_i I_sh^(2i)
// (physics.md section 2; Guzman-Maldonado et al. 2015). Energy per unit
// initial area (J/m^2), stiffnesses in N/m.
#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/plugin.hpp>

namespace {

using namespace ts::sdk;

class WovenHyperelastic final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&] {
      k_warp_ = p.real("k_warp");
      k_weft_ = p.real("k_weft");
      const auto& ks = p.list("k_sh");
      for (int i = 0; i < 3; ++i) k_sh_[i] = ks[i];
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  bool uses_strain_old() const override { return false; }
  Status evaluate(const MaterialBlock& b) const override {
    for (std::size_t q = 0; q < b.n; ++q) {
      const Sym2 C = {b.strain[3 * q], b.strain[3 * q + 1], b.strain[3 * q + 2]};
      FibreFrame f;
      if (!b.dir2.empty()) {
        f.c = b.dir2[2 * q];
        f.s = b.dir2[2 * q + 1];
      }
      const Invariants v = invariants(C, f);
      double wsh, dwsh;
      even_polynomial(k_sh_, 3, v.sh, &wsh, &dwsh);
      Sym2 S{0, 0, 0};
      add_stress(S, 2 * k_warp_ * v.e1, v.de1);
      add_stress(S, 2 * k_weft_ * v.e2, v.de2);
      add_stress(S, dwsh, v.dsh);
      for (int k = 0; k < 3; ++k) b.stress[3 * q + k] = S[k];
      if (!b.energy.empty()) b.energy[q] = k_warp_ * v.e1 * v.e1 + k_weft_ * v.e2 * v.e2 + wsh;
    }
    return Status::success();
  }
  double max_stiffness(double) const override { return 2 * std::max(k_warp_, k_weft_); }

 private:
  double k_warp_ = 0, k_weft_ = 0, k_sh_[3] = {0, 0, 0};
};

MaterialLaw* create() { return new WovenHyperelastic(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "woven_hyperelastic";
  d.version = "1.1.0";
  d.summary = "Woven membrane: warp and weft elongation (log strain) and in-plane shear, by invariants";
  const ParamSpec ksh = list_param("k_sh", "[0, 0, 0]", "N/m",
                                   "shear coefficients k_sh^1..3 of w_sh = sum k_sh^i I_sh^(2i), I_sh = sin(gamma)", 3);
  d.params = {real_param("k_warp", "", "N/m", "warp stiffness: w_e1 = k_warp I_e1^2, I_e1 = 1/2 ln I41", 0.0, 1e15, true),
              real_param("k_weft", "", "N/m", "weft stiffness: w_e2 = k_weft I_e2^2", 0.0, 1e15, true), ksh};
  d.example = R"({ "law": "woven_hyperelastic", "k_warp": 1.0e5, "k_weft": 1.0e5, "k_sh": [18.5, 46.4, -21.3] })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_woven_hyperelastic", "1.1.0", register_all)
