#pragma once
// Finite-difference check of a membrane or bending law: the stress it
// returns against the derivative of the energy it returns,
//   membrane: S = kStressFactor dw/dC,  bending: M = dw/dchi,
// by central differences on each Voigt component (the 12 component is
// perturbed symmetrically, C12 and C21 together). Returns the largest
// difference relative to the largest stress component.
#include <algorithm>
#include <cmath>
#include <vector>

#include "invariants.hpp"
#include "material.hpp"

namespace ts::sdk {

struct FdCheck {
  double max_relative_error = 0;
  Sym2 stress{}, stress_fd{};
};

inline FdCheck fd_check(const MaterialLaw& law, const Sym2& strain, double temperature, double step = 1e-6,
                        Sym2 dir2 = {0.0, 1.0, 0.0}) {
  const int ns = law.state_size();
  auto eval = [&](const Sym2& e, Sym2* s) {
    std::vector<double> state(ns, 0.0), stress(3), energy(1);
    const double d2[2] = {dir2[0], dir2[1]};
    const double t[1] = {temperature};
    MaterialBlock b;
    b.n = 1;
    b.strain = std::span<const double>(e.data(), 3);
    b.strain_old = std::span<const double>(e.data(), 3);
    b.dir2 = std::span<const double>(d2, 2);
    b.temperature = std::span<const double>(t, 1);
    b.dt = 0.0;
    b.state = state;
    b.stress = stress;
    b.energy = energy;
    law.evaluate(b);
    if (s) *s = {stress[0], stress[1], stress[2]};
    return energy[0];
  };
  FdCheck r;
  eval(strain, &r.stress);
  const double factor = law.role() == LawRole::Membrane ? kStressFactor : 1.0;
  for (int k = 0; k < 3; ++k) {
    Sym2 p = strain, m = strain;
    p[k] += step;
    m[k] -= step;
    const double d = (eval(p, nullptr) - eval(m, nullptr)) / (2 * step);
    // d/dC11 of w is (dw/dC)_11; a symmetric perturbation of C12 gives 2 (dw/dC)_12.
    r.stress_fd[k] = k < 2 ? factor * d : 0.5 * factor * d;
  }
  double scale = 0, err = 0;
  for (int k = 0; k < 3; ++k) {
    scale = std::max(scale, std::abs(r.stress[k]));
    err = std::max(err, std::abs(r.stress[k] - r.stress_fd[k]));
  }
  r.max_relative_error = scale > 0 ? err / scale : err;
  return r;
}

}  // namespace ts::sdk
