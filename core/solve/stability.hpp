#pragma once
// Material stability of a ply's membrane laws (docs/mechanics-method.md,
// "Material stability"): the smallest stiffness of the laws' long-term
// response against an in-plane increment dF = a (x) n,
//   q = min over unit a, n of (a (x) n) : A : (a (x) n),
//   A_iJkL = delta_ik S_JL + F_iM F_kN CC_MJNL,
// the smallest eigenvalue of the acoustic tensor Q(n)_ik = A_iJkL n_J n_L
// (N/m). S is the laws' stress summed, CC = dS/dE their tangent, both at the
// point's C and temperature and for the long-term response: each law is
// asked as after an endless hold at that strain (a zeroed history and a step
// of 1e30 s, so that a Prony series leaves its g_inf part). q < 0: the laws
// have lost strong ellipticity there (an in-plane pattern of any wavelength,
// down to the mesh's, lowers the energy).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <thermostamp/sdk/material.hpp>

namespace ts {

// The step of the long-term evaluation (s).
inline constexpr double kLongTermDt = 1e30;
// The strain increment of the finite differences that form CC from S.
inline constexpr double kStabilityStrainStep = 1e-6;

// The acoustic tensor's smallest eigenvalue over the directions n, from F
// (any F with F^T F = C: the result does not depend on the rotation), the
// stress S (Voigt [11, 22, 12], material frame, N/m) and the tangent D
// (D[3 v + k] = dS_v / dE_k, E_k the Voigt strain [E11, E22, E12] with E12
// the tensor component, moved together with E21). theta_min, where not
// null, receives the angle of the worst n from the material axis 1 (rad, in
// [0, pi)).
double acoustic_minimum(const double F[4], const double S[3], const double D[9], double* theta_min = nullptr);
// Q(n) for n = (cos theta, sin theta): Q[0] = Q_11, Q[1] = Q_22, Q[2] = Q_12.
void acoustic_tensor(const double F[4], const double S[3], const double D[9], double theta, double Q[3]);
// U = sqrt(C) (row-major 2 x 2) of a symmetric positive definite C (Voigt).
void stretch_of(const double C[3], double U[4]);

struct StabilityScratch {
  std::vector<double> strain, temperature, stress, sum, state;
};

// q (N/m) of n points with C (3 per point, Voigt, material frame) at the
// temperatures T (degC) for the membrane laws `laws` (their stresses add);
// q is NaN where C is not positive definite or a law gives no finite
// stress. Returns an empty string, or the message of a law that failed.
// theta, where not null, receives the angle of each point's worst n from the
// material axis 1 (rad, [0, pi)); response, where not null, the long-term S
// and D of each point (12 values: S, then D as acoustic_minimum takes it).
std::string long_term_stability(std::span<const sdk::MaterialLaw* const> laws, std::size_t n, const double* C,
                                const double* T, double* q, StabilityScratch& s, double* theta = nullptr,
                                double* response = nullptr);

// The threshold below which q counts as a loss of stability: round-off of
// the finite differences aside, 1e-9 of the laws' largest stiffness at T.
double stability_tolerance(std::span<const sdk::MaterialLaw* const> laws, double T);

// q of each element of a ply from its Green-Lagrange membrane strains E
// (3 per element, as ElementFields::strain gives them: C = I + 2 E) at the
// mean of its nodes' temperatures, and the tolerance at that temperature;
// over blocks of elements on the threads (the same values on any number);
// theta, where not null, the angle of each element's worst n (as
// long_term_stability). Returns an empty string, or the message of a law
// that failed.
std::string ply_stability(std::span<const sdk::MaterialLaw* const> laws, std::span<const int> triangles,
                          std::span<const double> node_temperature, std::span<const double> strain,
                          std::vector<double>& q, std::vector<double>& tolerance,
                          std::vector<double>* theta = nullptr);

}  // namespace ts
