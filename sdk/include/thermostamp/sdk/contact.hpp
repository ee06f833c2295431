#pragma once
// Contact handlers: detect which faces of plies touch tools or other plies,
// produce the thermal contact map (always) and contact forces (when the
// mechanics solver runs).
#include <cstdint>
#include <span>
#include <vector>

#include "parameters.hpp"
#include "state.hpp"
#include "status.hpp"
#include "thermal.hpp"
#include "views.hpp"

namespace ts::sdk {

// A body taking part in a contact pair: a ply or a rigid tool.
struct BodyRef {
  enum class Type { Part, Tool } type = Type::Part;
  int index = 0;  // into the parts or tools spans
};

struct ContactPair {
  BodyRef first;   // nodes of `first` are searched against `second` (ply/ply)
  BodyRef second;
};

// A face of a ply node touching a tool: Robin condition (h, tool temperature).
struct ToolHeatContact {
  int part = 0;
  int node = 0;
  int face = kTop;
  int tool = 0;
  double conductance = 0.0;  // W/(m^2 K)
};

// What a handler fills every detection pass (kernel-owned; cleared by the kernel).
struct ThermalContactMap {
  std::vector<ToolHeatContact> tool_contacts;
  std::vector<HeatLink> links;  // ply/ply, conductance already times the node's area
};

// Mechanical contact. Forces are computed at the current positions with
// the current (half-step) velocities and accumulated into `force` (3 per
// node per part); the reaction on each tool into `tool_force` (3 per tool,
// the force the plies exert on the tool). `energy` is the elastic energy
// stored in the penalty springs (normal and tangential) of this pair.
struct ContactForceInput {
  std::span<const PartView> parts;
  std::span<const ToolView> tools;
  double time = 0.0;
  double dt = 0.0;                                    // the step just taken
  std::span<const std::span<const double>> velocity;  // per part, 3 * num_nodes (m/s)
  std::span<const std::span<const double>> node_area; // per part, num_nodes (m^2), initial tributary area
  std::span<const std::span<const double>> mass;      // per part, num_nodes (kg), lumped, mass scaling included
  // The side of the pair to compute, for a handler whose sides() is 2:
  // 0 the nodes of the pair's first body against the second body, 1 the
  // nodes of the second against the first, -1 both.
  int side = -1;
  // Per part, 2 * num_nodes: the temperature (degC) of each node's bottom
  // face (entry 2 i, at z = -h/2) and top face (entry 2 i + 1, at +h/2),
  // the end values of the through-thickness field at the last thermal step
  // (with one value per node, both that value; without the thermal solver,
  // the initial temperatures). For interface laws that follow the
  // temperature, such as a friction coefficient.
  std::span<const std::span<const double>> face_temperature;
  // A number that changes whenever face_temperature changes and never
  // returns to an earlier value: calls with the same nonzero value see the
  // same face temperatures, so a handler may keep what it derives from them
  // from one call to the next. 0: unknown, they may differ at every call.
  std::uint64_t temperature_version = 0;
};
// The views in `parts` and `velocity` hold this step's values, but may be
// copies of the kernel's arrays (with contact_schedule by_part, the other
// ply's positions and velocities, written for this step by the thread
// that integrates that ply): read them within the call and keep no
// pointer into them from one call to the next.
// The kernel hands every call arrays of its own for the parts of the pair
// (or arrays that only calls run in turn on the same thread share): add to
// them, never read them for other pairs' forces, and write nothing to the
// spans of parts outside the pair (they may be empty).
struct ContactForceOutput {
  std::span<const std::span<double>> force;  // per part, 3 * num_nodes (accumulate)
  std::span<double> tool_force;              // 3 * num_tools (accumulate)
  std::span<const std::span<double>> status; // per part, num_nodes: set to 1 (tool) or 2 (ply) where in contact
  // Per part, num_nodes, or empty (then not wanted): add, at every node of
  // either body, the normal force this pair puts on the node divided by the
  // node's area (node_area), Pa: the pressure on the node's face that
  // touches the pair's other body. Forces spread over a target's nodes count
  // there too. The kernel sums what the calls of one pair add (both sides)
  // and shows per node the largest over its pairs, so that a node pressed
  // on both faces shows the larger of the two. A penalty handler gives its
  // springs' elastic force (penalty x penetration per unit area), without
  // the damper.
  std::span<const std::span<double>> pressure;
  double energy = 0.0;
  long long active = 0;  // nodes in contact
};

class ContactHandler {
 public:
  virtual ~ContactHandler() = default;
  virtual Status configure(const Params& params, const ContactPair& pair,
                           std::span<const PartView> parts, std::span<const ToolView> tools) = 0;
  // The contacts that carry heat at this moment: called at the start and,
  // with the mechanics, at every contact sample (several a thermal step;
  // the kernel averages their conductances over the step). Node areas
  // (m^2) per part are given so that links carry h_c * area.
  virtual Status thermal_contacts(std::span<const PartView> parts, std::span<const ToolView> tools,
                                  std::span<const std::span<const double>> node_area,
                                  ThermalContactMap& out) = 0;
  virtual Status contact_forces(const ContactForceInput&, ContactForceOutput&) {
    return Status::failure("this contact handler has no mechanical contact");
  }
  // The sides of a pair of two plies that contact_forces can compute one
  // at a time (ContactForceInput::side): 2 lets the kernel run the two
  // sides of one step at the same time on two threads, each beside the
  // elements of the ply whose nodes it moves, so the handler must then keep
  // whatever a side writes (scratch arrays, state) apart from the other
  // side's. 1 (the default): every call computes the whole pair (side -1).
  virtual int sides() const { return 1; }
  // Upper bound of the contact stiffness (N/m) the pair can put on every
  // node, accumulated into `stiffness` (per part, num_nodes) for the nodes of
  // both bodies. The kernel uses it for the stable step and mass scaling, so
  // that a penalty never silently breaks the explicit step.
  virtual Status node_stiffness(std::span<const std::span<const double>> /*node_area*/,
                                std::span<const std::span<double>> /*stiffness*/) {
    return Status::success();
  }
  // Upper bound of the conductance (W/(m^2 K)) the pair can put on a face of
  // its plies' nodes at any time of the run (a conductance that follows the
  // contact pressure reaches it only under load; a face that touches only
  // later has none at the start). The kernel chooses the thermal step from
  // it: an explicit scheme's stable step and the step for accuracy then hold
  // for every conductance the pair can give. 0 (the default): only the
  // conductances of the thermal contact map at the start count.
  virtual double largest_conductance() const { return 0.0; }
  // Checkpoints (state.hpp): whatever the handler carries from one call to
  // the next and its results depend on (tangential springs of stuck nodes,
  // the sides nodes are tracked on, search lists that are kept over several
  // steps). save_state is called between steps; load_state on a handler
  // configured by the same job, before its first call after configure. The
  // defaults: nothing to carry.
  virtual Status save_state(StateWriter& /*out*/) const { return Status::success(); }
  virtual Status load_state(StateReader& /*in*/) { return Status::success(); }
};

}  // namespace ts::sdk
