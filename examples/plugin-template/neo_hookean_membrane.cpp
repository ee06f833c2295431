// An isotropic compressible neo-Hookean membrane, as an example of a
// material law plugin written outside ThermoStamp.
//
//   w = mu/2 (tr C - 2 - ln J2) + lambda/4 (ln J2)^2,   J2 = det C   (J/m^2)
//   S = 2 dw/dC = mu (I - C^-1) + lambda ln(J2) C^-1                (N/m)
//
// C and S are 2x2 symmetric tensors in Voigt order [11, 22, 12] with the
// tensor shear component (thermostamp/sdk/math.hpp); mu and lambda are
// membrane moduli in N/m.
#include <cmath>

#include <thermostamp/sdk/plugin.hpp>

namespace neo_hookean {

using namespace ts::sdk;

class NeoHookeanMembrane final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&] {
      mu_ = p.real("mu");
      lambda_ = p.real("lambda");
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  Status evaluate(const MaterialBlock& b) const override {
    for (std::size_t q = 0; q < b.n; ++q) {
      const double c11 = b.strain[3 * q], c22 = b.strain[3 * q + 1], c12 = b.strain[3 * q + 2];
      const double j2 = c11 * c22 - c12 * c12;
      if (!(j2 > 0)) return Status::failure("det C <= 0 at point " + std::to_string(q));
      const double inv[3] = {c22 / j2, c11 / j2, -c12 / j2};  // C^-1
      const double lj = std::log(j2);
      const double identity[3] = {1.0, 1.0, 0.0};
      for (int k = 0; k < 3; ++k) b.stress[3 * q + k] = mu_ * (identity[k] - inv[k]) + lambda_ * lj * inv[k];
      if (!b.energy.empty()) b.energy[q] = 0.5 * mu_ * (c11 + c22 - 2.0 - lj) + 0.25 * lambda_ * lj * lj;
    }
    return Status::success();
  }
  double max_stiffness(double) const override { return 2 * mu_ + lambda_; }

 private:
  double mu_ = 0, lambda_ = 0;
};

MaterialLaw* create() { return new NeoHookeanMembrane(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "neo_hookean_membrane";
  d.version = "1.0.0";
  d.summary = "Isotropic compressible neo-Hookean membrane (example plugin)";
  d.params = {real_param("mu", "", "N/m", "shear modulus of the membrane", 0.0, 1e15, true),
              real_param("lambda", "0.0", "N/m", "first Lame modulus of the membrane", 0.0)};
  d.example = R"({ "law": "neo_hookean_membrane", "mu": 1.0e4, "lambda": 2.0e4 })";
  r.add_material(d, &create);
}

}  // namespace neo_hookean

#ifndef NEO_HOOKEAN_NO_ENTRY_POINT
THERMOSTAMP_PLUGIN("material_neo_hookean_membrane", "1.0.0", neo_hookean::register_all)
#endif
