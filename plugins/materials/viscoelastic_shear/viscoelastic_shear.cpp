// viscoelastic_shear: in-plane shear with a temperature-dependent scale and
// a generalised Maxwell (Prony) relaxation (physics.md section 2):
//   S0_sh = 2 d/dC [ omega(T) sum_i k_sh_i I_sh^(2i) ],
//   S_sh(t) = int G(t - s) d/ds[S0_sh] ds, G = g_inf + sum_i g_i exp(-t/tau_i).
// omega, g_i and tau_i are piecewise linear in T with a break at t_break
// (270 degC in the reference data). Out of range values are clamped:
// omega >= 0, g_i >= 0, sum g_i <= 1, tau_i >= 1e-9 s. Listed next to
// ud_hyperelastic or woven_hyperelastic, its stress adds to theirs.
#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include <thermostamp/sdk/invariants.hpp>
#include <thermostamp/sdk/plugin.hpp>
#include <thermostamp/sdk/prony.hpp>

namespace {

using namespace ts::sdk;

class ViscoelasticShear final : public MaterialLaw {
 public:
  Status configure(const Params& p) override {
    return guarded([&]() -> Status {
      const auto& ks = p.list("k_sh");
      for (int i = 0; i < 3; ++i) k_sh_[i] = ks[i];
      const double tb = p.real("t_break");
      t_min_ = p.real("t_min");
      t_max_ = p.real("t_max");
      if (!(t_max_ > t_min_)) return Status::failure("t_max must be above t_min");
      omega_ = {tb, p.real("omega_at_break"), p.real("omega_slope_below"), p.real("omega_slope_above")};
      const auto& g = p.list("g");
      const auto& tau = p.list("tau");
      const auto& gb = p.list("g_slope_below");
      const auto& ga = p.list("g_slope_above");
      const auto& tb_ = p.list("tau_slope_below");
      const auto& ta = p.list("tau_slope_above");
      n_ = static_cast<int>(g.size());
      if (n_ > 16) return Status::failure("at most 16 Maxwell branches, found " + std::to_string(n_));
      if (tau.size() != g.size())
        return Status::failure("tau has " + std::to_string(tau.size()) + " entries, g has " + std::to_string(g.size()));
      auto slopes = [&](const std::vector<double>& v, const char* name) -> std::vector<double> {
        if (v.empty()) return std::vector<double>(n_, 0.0);
        if (static_cast<int>(v.size()) != n_)
          throw std::invalid_argument(std::string(name) + " needs one entry per branch (" + std::to_string(n_) + ")");
        return v;
      };
      const auto gb2 = slopes(gb, "g_slope_below"), ga2 = slopes(ga, "g_slope_above");
      const auto tb2 = slopes(tb_, "tau_slope_below"), ta2 = slopes(ta, "tau_slope_above");
      double sum = 0;
      for (int i = 0; i < n_; ++i) {
        if (!(tau[i] > 0))
          return Status::failure("tau[" + std::to_string(i) + "] must be > 0 s, found " + std::to_string(tau[i]));
        sum += g[i];
        g_.push_back({tb, g[i], gb2[i], ga2[i]});
        tau_.push_back({tb, tau[i], tb2[i], ta2[i]});
      }
      if (sum > 1.0)
        return Status::failure("the Maxwell weights g sum to " + std::to_string(sum) + " at t_break; it must be <= 1");
      return Status::success();
    });
  }
  LawRole role() const override { return LawRole::Membrane; }
  // Per point: S0 at the previous step (3), the branch states H_i (3 per
  // branch), then the parameters at the point's last temperature (a flag,
  // T, omega, g_i, 1 / tau_i): the temperature changes only when the
  // thermal solver advances, so they are evaluated once per thermal step.
  int state_size() const override { return 3 + 3 * n_ + 3 + 2 * n_; }
  std::pair<double, double> temperature_range() const override { return {t_min_, t_max_}; }

  // Clamped parameters at temperature T.
  void at(double T, double* omega, double* g, double* tau) const {
    T = std::clamp(T, t_min_, t_max_);
    *omega = std::max(0.0, omega_(T));
    double sum = 0;
    for (int i = 0; i < n_; ++i) {
      g[i] = std::max(0.0, g_[i](T));
      tau[i] = std::max(1e-9, tau_[i](T));
      sum += g[i];
    }
    if (sum > 1.0)
      for (int i = 0; i < n_; ++i) g[i] /= sum;
  }

  Status evaluate(const MaterialBlock& b) const override {
    const FibreFrame f;
    double g[16], inv_tau[16], decay[16], ramp[16], omega = 0, T_last = 0;
    const int ns = state_size(), cache = 3 + 3 * n_;
    for (std::size_t q = 0; q < b.n; ++q) {
      const Sym2 C = {b.strain[3 * q], b.strain[3 * q + 1], b.strain[3 * q + 2]};
      FibreFrame fr = f;
      if (!b.dir2.empty()) {
        fr.c = b.dir2[2 * q];
        fr.s = b.dir2[2 * q + 1];
      }
      const Invariants v = invariants(C, fr, kSh);
      double* st = b.state.data() + static_cast<std::size_t>(ns) * q;
      const double T = b.temperature[q];
      if (q == 0 || T != T_last) {  // parameters change with temperature only
        double* c = st + cache;
        if (c[0] == 1.0 && c[1] == T) {  // as at this point's previous step
          omega = c[2];
          for (int i = 0; i < n_; ++i) {
            g[i] = c[3 + i];
            inv_tau[i] = c[3 + n_ + i];
          }
        } else {
          double tau[16];
          at(T, &omega, g, tau);
          for (int i = 0; i < n_; ++i) inv_tau[i] = 1.0 / tau[i];
          c[0] = 1.0;
          c[1] = T;
          c[2] = omega;
          for (int i = 0; i < n_; ++i) {
            c[3 + i] = g[i];
            c[3 + n_ + i] = inv_tau[i];
          }
        }
        prony_factors_inv(n_, inv_tau, b.dt, decay, ramp);
        T_last = T;
      }
      double wsh, dwsh;
      even_polynomial(k_sh_, 3, v.sh, &wsh, &dwsh);
      Sym2 s0{0, 0, 0};
      add_stress(s0, omega * dwsh, v.dsh);
      double s[3];
      prony_step(n_, g, decay, ramp, st, s0.data(), st + 3, s);
      for (int k = 0; k < 3; ++k) {
        st[k] = s0[k];
        b.stress[3 * q + k] = s[k];
      }
      if (!b.energy.empty()) b.energy[q] = omega * wsh;  // elastic (unrelaxed) energy
    }
    return Status::success();
  }
  double max_stiffness(double T) const override {
    double omega, g[16], tau[16];
    at(T, &omega, g, tau);
    return 2 * omega * (2 * std::abs(k_sh_[0]) + 12 * std::abs(k_sh_[1]) + 30 * std::abs(k_sh_[2]));
  }

 private:
  double t_min_ = 200, t_max_ = 350;
  double k_sh_[3] = {0, 0, 0};
  BrokenLine omega_;
  std::vector<BrokenLine> g_, tau_;
  int n_ = 0;
};

MaterialLaw* create() { return new ViscoelasticShear(); }

void register_all(Registrar& r) {
  Descriptor d;
  d.kind = PluginKind::Material;
  d.name = "viscoelastic_shear";
  d.version = "1.0.1";
  d.summary = "In-plane shear, temperature-dependent scale and Prony-series relaxation (adds to a membrane law)";
  d.params = {
      list_param("k_sh", "", "N/m", "shear coefficients of w_sh = omega(T) sum k_sh^i I_sh^(2i)", 3),
      real_param("t_break", "270.0", "degC", "temperature of the break of the piecewise-linear laws"),
      real_param("t_min", "200.0", "degC", "lowest temperature the parameters hold for; below it they are held at t_min (with a warning)"),
      real_param("t_max", "350.0", "degC", "highest temperature the parameters hold for; above it they are held at t_max (with a warning)"),
      real_param("omega_at_break", "1.0", "-", "shear scale omega at t_break"),
      real_param("omega_slope_below", "0.0", "1/degC", "d omega / dT below t_break"),
      real_param("omega_slope_above", "0.0", "1/degC", "d omega / dT above t_break"),
      list_param("g", "[]", "-", "Maxwell weights g_i at t_break (sum <= 1; g_inf = 1 - sum)", -1, 0.0),
      list_param("tau", "[]", "s", "relaxation times tau_i at t_break (> 0)", -1, 0.0),
      list_param("g_slope_below", "[]", "1/degC", "d g_i / dT below t_break (empty: 0)"),
      list_param("g_slope_above", "[]", "1/degC", "d g_i / dT above t_break (empty: 0)"),
      list_param("tau_slope_below", "[]", "s/degC", "d tau_i / dT below t_break (empty: 0)"),
      list_param("tau_slope_above", "[]", "s/degC", "d tau_i / dT above t_break (empty: 0)"),
  };
  d.example = R"({ "law": "viscoelastic_shear", "k_sh": [18.5, 46.4, -21.3], "omega_slope_below": -0.02, "omega_slope_above": -0.01, "g": [0.5, 0.3], "tau": [0.2, 2.0] })";
  r.add_material(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("material_viscoelastic_shear", "1.0.0", register_all)
