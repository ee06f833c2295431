#pragma once
// Views over kernel-owned data. The kernel owns every array; a plugin reads
// (and, where the interface says so, writes) through these spans and never
// keeps them beyond the call unless the interface says they are stable.
// Storage order: see math.hpp.
#include <span>
#include <string_view>

namespace ts::sdk {

// Effective thermal properties of a ply (in its material frame).
struct ThermalProps {
  double density = 0.0;        // kg/m^3
  double specific_heat = 0.0;  // J/(kg K); for a table c(T), its smallest value (the kernel then
                               // moves each value along the table's enthalpy after every step)
  double k11 = 0.0;            // W/(m K), along the fibres (warp)
  double k22 = 0.0;            // W/(m K), across the fibres, in the plane
  double k33 = 0.0;            // W/(m K), through the thickness
  // For a conductivity table k(T): k11, k22, k33 above are the table's
  // largest values (step limits taken with them hold for any temperature),
  // and every thermal step passes the values at the step's temperatures
  // (ThermalStepInput::conductivity).
  bool conductivity_varies = false;
};

// One ply (a shell part). Arrays are stable for the life of the run: the
// kernel updates x and fibre in place when the ply deforms.
struct PartView {
  int index = 0;
  std::string_view name;
  int num_nodes = 0;
  int num_elements = 0;
  std::span<const double> x0;          // 3 * num_nodes, initial mid-surface coordinates (m)
  std::span<const double> x;           // 3 * num_nodes, current mid-surface coordinates (m)
  std::span<const int> triangles;      // 3 * num_elements
  std::span<const int> neighbours;     // 3 * num_elements, element across edge k, -1 if none
  std::span<const double> fibre;       // 3 * num_elements, unit fibre (warp) direction, current
  double thickness = 0.0;              // m
  int thickness_layers = 1;            // through-thickness thermal elements
  double initial_temperature = 0.0;    // degC
  ThermalProps thermal;
};

// A rigid tool as contact handlers see it. `query` gives, for a batch of
// points, the signed distance to the tool surface (positive on the side the
// outward normal points to, i.e. outside the tool) and that outward unit
// normal at the closest surface point, in the tool's current position. One
// call per batch, not per node. Points farther than `cutoff` from the
// surface may be answered with distance +infinity (mesh tools do so). Each
// point's answer depends on that point only (not on the batch), and `query`
// may be called from several threads at once.
// `velocity` is the tool's current rigid velocity (m/s, 3 values);
// `displacement` its rigid translation from the initial position (m, 3
// values): a handler can bound how far the surface has moved since it last
// asked, and skip points that cannot have come within reach.
// `query_kept` (nullptr for tools without one) answers as `query`, to the
// bit, for points the caller asks about again and again (a part's nodes,
// step after step): the caller keeps `kept_bytes` of memory per point
// (8-byte aligned, zero before the first call, not shared between
// threads), passes the batch's records with it, and the tool keeps there
// what makes the next answers cheaper (a mesh tool: the triangles near the
// point). Records need not be saved at a checkpoint: zeroed again, they
// give the same answers.
struct ToolView {
  int index = 0;
  std::string_view name;
  double temperature = 0.0;  // degC
  const void* context = nullptr;
  void (*query)(const void* context, std::size_t n, const double* points, double cutoff, double* distance,
                double* normal) = nullptr;
  const double* velocity = nullptr;      // 3 values, kernel-owned, updated every step
  const double* displacement = nullptr;  // 3 values, kernel-owned, updated every step
  void (*query_kept)(const void* context, std::size_t n, const double* points, double cutoff, double* distance,
                     double* normal, void* kept) = nullptr;
  std::size_t kept_bytes = 0;  // per point; a multiple of 8
};

}  // namespace ts::sdk
