// thermo_linear_bending: moments linear in the curvature in the fibre frame,
// with rigidities linear in temperature (physics.md section 2):
//   R_1(T) = beta1_T T + beta1_B, R_2(T) = beta2_T T + beta2_B,
//   M11 = R_1 chi11, M22 = R_2 chi22, M12 = R_12 chi12, R_12 = twist_ratio (R_1 + R_2) / 2,
//   w = 1/2 (R_1 chi11^2 + R_2 chi22^2 + 2 R_12 chi12^2)   (J/m^2).
// Rigidities in N m (moment per unit width per unit curvature), clamped at 0.
#include <algorithm>

#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/simd.hpp>

namespace {

using namespace ts::sdk;

struct Rigidity {
  double b1t, b1b, b2t, b2b, twist, t_min, t_max;
};

// The law over n points in one vector pass (ThermoLinearBending::rigidities
// written out, same operations, same bits); W may be null.
TS_VECTOR_CLONES
void bending_block(std::size_t n, Rigidity r, const double* __restrict T, const double* __restrict chi,
                   double* __restrict M, double* __restrict W) {
#pragma omp simd
  for (std::size_t q = 0; q < n; ++q) {
    double t = T[q];
    t = t < r.t_min ? r.t_min : t;
    t = r.t_max < t ? r.t_max : t;
    double r1 = r.b1t * t + r.b1b, r2 = r.b2t * t + r.b2b;
    r1 = 0.0 < r1 ? r1 : 0.0;
    r2 = 0.0 < r2 ? r2 : 0.0;
    const double r12 = r.twist * 0.5 * (r1 + r2);
    const double c0 = chi[3 * q], c1 = chi[3 * q + 1], c2 = chi[3 * q + 2];
    M[3 * q] = r1 * c0;
    M[3 * q + 1] = r2 * c1;
    M[3 * q + 2] = r12 * c2;
    if (W) W[q] = 0.5 * (r1 * c0 * c0 + r2 * c1 * c1 + 2 * r12 * c2 * c2);
  }
}

class ThermoLinearBending final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&] {
      b1t_ = p.real("beta1_T");
      b1b_ = p.real("beta1_B");
      b2t_ = p.real("beta2_T");
      b2b_ = p.real("beta2_B");
      twist_ = p.real("twist_ratio");
      t_min_ = p.real("t_min");
      t_max_ = p.real("t_max");
      if (!(t_max_ > t_min_)) return Status::failure("t_max must be above t_min");
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Bending; }
  bool uses_strain_old() const override { return false; }
  std::pair<double, double> temperature_range() const override { return {t_min_, t_max_}; }
  void rigidities(double T, double* r1, double* r2, double* r12) const {
    T = std::clamp(T, t_min_, t_max_);
    *r1 = std::max(0.0, b1t_ * T + b1b_);
    *r2 = std::max(0.0, b2t_ * T + b2b_);
    *r12 = twist_ * 0.5 * (*r1 + *r2);
  }
  Status evaluate(const MaterialBlock& b) const override {
    bending_block(b.n, {b1t_, b1b_, b2t_, b2b_, twist_, t_min_, t_max_}, b.temperature.data(), b.strain.data(),
                  b.stress.data(), b.energy.empty() ? nullptr : b.energy.data());
    return Status::success();
  }
  double max_stiffness(double T) const override {
    double r1, r2, r12;
    rigidities(T, &r1, &r2, &r12);
    return std::max({r1, r2, r12});
  }

 private:
  double b1t_ = 0, b1b_ = 0, b2t_ = 0, b2b_ = 0, twist_ = 0, t_min_ = -273.15, t_max_ = 1e4;
};

MaterialLaw* create() { return new ThermoLinearBending(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "thermo_linear_bending";
  d.version = "1.0.2";
  d.summary = "Bending: moments linear in curvature, rigidities linear in temperature, fibre frame";
  d.params = {real_param("beta1_T", "0.0", "N m/degC", "slope of the rigidity along the fibres R_1(T)"),
              real_param("beta1_B", "", "N m", "R_1 at 0 degC"),
              real_param("beta2_T", "0.0", "N m/degC", "slope of the rigidity across the fibres R_2(T)"),
              real_param("beta2_B", "", "N m", "R_2 at 0 degC"),
              real_param("twist_ratio", "0.0", "-",
                         "twist rigidity R_12 as a fraction of (R_1 + R_2)/2; 0 gives the ply no twist rigidity (what "
                         "resists twist is then the element's discretisation: see docs/verification.md, bending in two "
                         "dimensions)",
                         0.0, 1.0),
              real_param("t_min", "200.0", "degC", "lowest temperature the rigidities hold for; below it they are held at t_min (with a warning)"),
              real_param("t_max", "350.0", "degC", "highest temperature the rigidities hold for; above it they are held at t_max (with a warning)")};
  d.example = R"({ "law": "thermo_linear_bending", "beta1_T": -2.0e-5, "beta1_B": 6.4e-3, "beta2_T": -2.0e-6, "beta2_B": 6.4e-4 })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_thermo_linear_bending", "1.0.2", register_all)
