#pragma once
// Thermal splitters: plugins that advance the temperature of every ply over
// one thermal step. The kernel owns the temperature arrays (one per part,
// values_per_node(part) values per node, bottom to top, see math.hpp) and
// the face conditions; the splitter owns its work arrays.
#include <span>

#include "parameters.hpp"
#include "state.hpp"
#include "status.hpp"
#include "views.hpp"

namespace ts::sdk {

enum Face : int { kBottom = 0, kTop = 1 };

// Robin condition on each face of each node: q = h (T_face - T_ext), leaving
// the ply. h = 0 means adiabatic. Filled by the kernel every thermal step
// from heat_exchange interactions and tool contact.
struct FaceConditions {
  std::span<const double> h_bottom;  // W/(m^2 K), per node
  std::span<const double> t_bottom;  // degC, per node
  std::span<const double> h_top;
  std::span<const double> t_top;
};

// Conductance between face `face_a` of node `node_a` (part `part_a`) and the
// point of face `face_b` of part `part_b` at weights w_b (sum 1) of nodes
// nodes_b. It acts as three node-to-node conductances conductance * w_b[j]:
// heat W_j = conductance * w_b[j] * (T_a - T_b[j]) leaves a and enters b_j.
// Node a thus loses conductance * (T_a - sum_j w_b[j] T_b[j]), the Robin
// flux towards the facing surface temperature interpolated at its
// projection; the exchange conserves heat exactly and keeps the discrete
// maximum principle (every coupling is a positive conductance).
struct HeatLink {
  int part_a = 0;
  int node_a = 0;
  int face_a = kBottom;
  int part_b = 0;
  int nodes_b[3] = {0, 0, 0};
  double w_b[3] = {0, 0, 0};
  int face_b = kTop;
  double conductance = 0.0;  // W/K (h_c times the area of node a)
};

struct ThermalStepInput {
  double dt = 0.0;                                // s
  std::span<const FaceConditions> faces;          // one per part
  std::span<const HeatLink> links;                // ply-to-ply conductances
  bool geometry_changed = false;                  // parts' x or fibre moved since last step
  bool links_changed = false;                     // links differ from the last step
  // Temperature-dependent conductivity (advance only; step_limits takes
  // ThermalProps, the table's largest values). One span per part: empty
  // where the ply's conductivity is constant, else k11, k22, k33 (W/(m K))
  // of every temperature value at the start of the step, 3 per value in the
  // order of the temperatures (node-major, bottom to top).
  std::span<const std::span<const double>> conductivity;
};

struct ThermalStepReport {
  double heat_in = 0.0;     // J that entered the plies through Robin faces during the step
  int substeps = 1;         // internal sub-steps taken (in-plane explicit sub-cycling, ...)
  long long limited = 0;    // nodes where a bound-preserving correction acted
  // Room the kernel gives for the face values the step's face conditions and
  // links were taken at: one span per part, 2 values per node (bottom, top;
  // degC), or empty. A splitter that fills it sets face_values_filled; the
  // kernel then splits the heat through each face exactly among the tools,
  // the heat exchanges and the links: a face of area A with conductance h
  // and far temperature t_ext received dt A h (t_ext - value), a link
  // conductance (sum_j w_b[j] value_b[j] - value_a) dt. An implicit scheme
  // gives the values its Robin terms were solved at (after the
  // through-thickness solve, before an in-plane step that moves them), an
  // explicit one those at the start of the step. A splitter that does not
  // fill it leaves the kernel to use the values at the end of the step.
  std::span<const std::span<double>> face_values;
  bool face_values_filled = false;
};

class ThermalSplitter {
 public:
  virtual ~ThermalSplitter() = default;
  // Called once with the validated parameters and every part.
  virtual Status configure(const Params& params, std::span<const PartView> parts) = 0;
  // Through-thickness values per node of a part (1 for a plain shell).
  virtual int values_per_node(int part) const = 0;
  // Lumped heat capacity (J/K) of each value of a part, node-major like T;
  // sum(capacity * T) is the stored heat the kernel audits.
  virtual Status capacities(int part, std::span<double> capacity) const = 0;
  // Largest step the scheme accepts for these conditions (infinity when
  // unconditionally stable), and the step it recommends for accuracy.
  virtual Status step_limits(const ThermalStepInput& in, double* stable_dt, double* accurate_dt) = 0;
  // Advances every part's temperature from t to t + in.dt, in place.
  virtual Status advance(const ThermalStepInput& in, std::span<const std::span<double>> temperature,
                         ThermalStepReport* report) = 0;
  // True when advance() uses ThermalStepInput::conductivity. A job whose
  // ply has a conductivity table is refused with a splitter that says false
  // (the default), rather than run with constant values.
  virtual bool takes_conductivity_field() const { return false; }
  // Checkpoints (state.hpp): whatever the splitter carries from one step to
  // the next beyond the kernel's temperatures and its results depend on.
  // Work arrays and factorisations it forms again from its inputs need not
  // be carried. The defaults: nothing to carry.
  virtual Status save_state(StateWriter& /*out*/) const { return Status::success(); }
  virtual Status load_state(StateReader& /*in*/) { return Status::success(); }
};

}  // namespace ts::sdk
