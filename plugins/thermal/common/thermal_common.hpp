#pragma once
// Building blocks shared by the thermal splitters (adi, shell2d, layered3d):
// lumped through-thickness discretisation of a ply, the in-plane conduction
// matrix of its triangles, a tridiagonal solver. Only SDK headers are used.
#include <span>
#include <vector>

#include <string>

#include <thermostamp/sdk/parameters.hpp>
#include <thermostamp/sdk/thermal.hpp>
#include <thermostamp/sdk/views.hpp>

namespace ts::thermal {

// Loops over the layer values of a ply run on several threads above this
// many values (below it, starting the threads costs more than they save).
inline constexpr long long kParallelValues = 8192;

// Compressed sparse rows, node-node, symmetric pattern with the diagonal.
struct Csr {
  std::vector<int> row_start;  // n + 1
  std::vector<int> col;
  std::vector<double> val;
  std::vector<int> elem_slot;  // per element, 9 positions into val (a-major)
  int n = 0;
};

// One ply as the thermal splitters see it.
struct PlyThermal {
  const sdk::PartView* view = nullptr;
  int nz = 1;              // values per node (thickness_layers + 1, or 1 for a plain shell)
  double h = 0;            // thickness, m
  double e = 0;            // layer thickness, m (h when nz == 1)
  double rho_c = 0;        // J/(m^3 K)
  double k33 = 0;          // W/(m K)
  std::vector<double> w;   // nz through-thickness lumping weights, m; sum = h
  std::vector<double> area;  // lumped node area of the initial configuration, m^2
  bool area_set = false;
  Csr k2d;                 // in-plane conduction of one unit thickness: K_ab = A grad Na . Ks grad Nb (W/(m K))
  // Per element, 6 values each (ab = 00, 01, 02, 11, 12, 22): A (grad Na . f)
  // (grad Nb . f) and the same across the fibres, for a conductivity that
  // varies from element to element (assemble_inplane).
  std::vector<double> g11, g22;
  // The in-plane operator of every layer value (assemble_inplane_layers):
  // K's values in k2d's pattern, nz per entry (entry-major).
  std::vector<double> k2d_layers;
  std::vector<double> layer_work;  // per thread, 2 nz + 1 values (assemble_inplane_layers)
  double inplane_rate = 0; // Gershgorin bound of max eigenvalue of C^-1 K in plane, 1/s
  bool inplane_positive_offdiag = false;  // K has K_ij > 0 (i != j): not an M-matrix, flux limiting needed
};

// Sets nz, weights, pattern and values for the current geometry of `part`.
void setup_ply(PlyThermal& ply, const sdk::PartView& part, int nz);
void update_geometry(PlyThermal& ply);

// Assembles k2d for a conductivity that varies over the ply: element e
// takes the mean of its three nodes' values k11[stride * node],
// k22[stride * node] (W/(m K)). The explicit in-plane step then needs
// update_inplane_bounds.
void assemble_inplane(PlyThermal& ply, const double* k11, const double* k22, std::size_t stride);
// The in-plane rate bound and the sign flag of the current k2d.
void update_inplane_bounds(PlyThermal& ply);
// Assembles k2d_layers for a conductivity that varies through the ply: layer
// value k of element e takes the mean of its three nodes' k11, k22 of that
// value (kf: 3 per value, node-major as the temperatures), and sets the
// rate bound and sign flag over every layer (advance_inplane with
// per_layer = true then takes these operators).
void assemble_inplane_layers(PlyThermal& ply, const double* kf);

// Largest forward-Euler step of the rods, Robin faces and (explicit) links
// that keeps the discrete maximum principle: min_i C_i / K_ii, s.
double rods_stable_dt(std::span<const PlyThermal> plies, std::span<const sdk::FaceConditions> faces,
                      std::span<const sdk::HeatLink> links);

// Step recommended for the accuracy of backward Euler: 1 % of the shortest
// through-thickness diffusion time rho c h^2 / k33 and Robin time rho c h / H.
double accurate_dt(std::span<const PlyThermal> plies, std::span<const sdk::FaceConditions> faces);

// Solves a tridiagonal system in place (Thomas algorithm); d is overwritten
// with the solution; c' is kept in `work` (size n).
void solve_tridiagonal(int n, const double* a, const double* b, const double* c, double* d, double* work);

// Advances values of every node of `ply` over dt by the in-plane problem
// rho c dT/dt = div(Ks grad T) (the mean's rho c h d<T>/dt = div(h Ks
// grad <T>) divided by h) with forward Euler sub-steps (at most 0.9 of the
// stable step). `values` holds `stride` values per node (node-major; stride
// 1: the mean, stride nz: every layer of the rods), each advanced by the
// same operator, in place; `scratch` has as many entries. Returns the number
// of sub-steps; throws std::runtime_error where more than 1e6 would be
// needed. Where K is not an M-matrix (anisotropic conductivity, obtuse
// or distorted triangles give K_ij > 0), the pairs with K_ij > 0 carry
// anti-diffusive fluxes; they are limited (Zalesak, algebraic flux
// correction) so that no value leaves the range its stencil held before the
// sub-step. The fluxes are pairwise, so heat is conserved exactly. `scratch`
// then needs 4 x values.size() entries.
// With per_layer, value k of every node (stride = nz) takes its own
// operator, k2d_layers.
int advance_inplane(const PlyThermal& ply, double dt, std::span<double> values, std::span<double> scratch,
                    int stride = 1, bool per_layer = false);

// The parameters every thermal splitter declares (the job contract writes
// them for any splitter): through_thickness and dt_safety.
std::vector<sdk::ParamSpec> splitter_params(const std::string& through_thickness_doc);

// True when two link lists are identical.
bool same_links(std::span<const sdk::HeatLink> a, std::span<const sdk::HeatLink> b);

// Mean through the thickness of node i (consistent with linear elements).
inline double rod_mean(const PlyThermal& ply, const double* t) {
  double s = 0;
  for (int k = 0; k < ply.nz; ++k) s += ply.w[k] * t[k];
  return s / ply.h;
}

}  // namespace ts::thermal
