#pragma once
// Shell elements: internal forces, energy and stable step over a range of
// elements, one call per range (OpenMP blocks), tight loops inside.
#include <cstdint>
#include <limits>
#include <span>

#include "material.hpp"
#include "parameters.hpp"
#include "state.hpp"
#include "status.hpp"
#include "views.hpp"

namespace ts::sdk {

struct ElementSetup {
  const PartView* part = nullptr;
  std::span<const MaterialLaw* const> membrane;  // laws whose stresses add
  const MaterialLaw* bending = nullptr;          // may be null
  // May be null; only with a bending law. A bending law evaluated with the
  // in-plane curvature of the fibres as chi11 (chi22 = chi12 = 0, 1/m),
  // whose M11 (N m/m) and energy w (J/m^2) give the fibres' resistance to
  // bending in the ply's plane (a second-gradient term: it gives fibre
  // waviness an energy that grows with its wavenumber). The element
  // evaluates it at every evaluation, whatever the bending_weight, and
  // counts its step in the stable step.
  const MaterialLaw* in_plane_bending = nullptr;
  double density = 0.0;                          // kg/m^3 (areal mass = density * thickness)
  // Per element, per edge k (opposite node k): kEdgeFree (interior or free
  // boundary), kEdgeClamped (boundary edge whose nodes are held: the slope
  // normal to it is held too), or kEdgeSymmetryX/Y/Z (boundary edge on the
  // symmetry plane x = 0, y = 0 or z = 0: the mirrored ply continues it).
  // Empty: all free.
  std::span<const int> edge_condition;
  double temperature = 20.0;  // degC, the part's initial temperature (laws probed at set-up see it)
};

inline constexpr int kEdgeFree = 0;
inline constexpr int kEdgeClamped = 1;
inline constexpr int kEdgeSymmetryX = 2;  // + 1 for y, + 2 for z

struct ElementRange {
  int begin = 0;  // first element
  int end = 0;    // one past the last
};

struct ElementForceInput {
  // The kernel splits a part into the same ranges at every call (they
  // depend on the part only), with the same patch_slot for a range, so an
  // element may keep data per range (a copy of its slots, say) and hand
  // its laws the same state span for the same points every time.
  ElementRange range;
  double dt = 0.0;                          // s, step of the laws' history (viscoelasticity)
  std::span<const double> node_temperature; // per node (mean through the thickness), degC
  bool commit = true;                       // update the laws' history (false: trial evaluation)
  // Where the forces of each element's 6-node patch go: 6 per element of
  // the range, indexed from the range's first element (entry 6 (e -
  // range.begin) + a): the element's 3 nodes, then for k = 0..2 the node of
  // the neighbour across edge k that is not on that edge (-1 when edge k
  // has no neighbour), each as its index i in ElementForceOutput::node_force
  // (values 3 i .. 3 i + 2).
  std::span<const int> patch_slot;
  // Which pass of the step (0 .. ElementKernel::passes() - 1). A range is
  // called with pass k only after every range it may read (see
  // ElementKernel::pass_reach) has been called with pass k - 1: by default
  // every range with pass 0, then every range with pass 1, and so on. Only
  // the last pass adds forces, energy and stable step (and reports a
  // degenerate element); earlier ones only prepare.
  int pass = 0;
  // Whether the kernel writes the stresses and curvatures of fields() for
  // the state of this evaluation (an output frame follows it). Where false,
  // an element may skip storing values that only fields() reports: its
  // stresses and curvatures then stay those of the last evaluation with
  // fields_due (shear angle and fibre direction come from the positions
  // and are always current). An evaluation with fields_due and a
  // bending_weight of 0 still forms the curvatures of its positions for
  // fields(), without the bending's forces or history.
  bool fields_due = true;
  // Optional, one per element of the part (indexed by element number, not
  // from range.begin): a factor on each element's stable step (the
  // kernel's mass scaling); ElementForceOutput::stable_dt is the smallest
  // scaled step of the range. Empty: factor 1 (the kernel leaves it empty
  // where no element's step is scaled).
  std::span<const double> dt_scale;
  // Optional: a number that changes whenever node_temperature changes and
  // never returns to an earlier value. Evaluations with the same nonzero
  // value see the same node temperatures, so an element may keep what it
  // derives from them alone (its elements' temperatures) from one to the
  // next. 0: unknown, the temperatures may differ at every evaluation.
  std::uint64_t temperature_version = 0;
  // The weight of the bending forces in this evaluation: 1 as a rule. Where
  // the kernel evaluates the bending less often than the membrane
  // (solvers.mechanics.bending_subcycles), 0 in the evaluations that carry
  // no bending (an element may skip its bending passes and then reports
  // the bending energy of its last evaluation with bending) and k in the
  // one that carries the bending of the next k steps: over those steps the
  // element delivers k times its bending forces, as an impulse in this
  // evaluation or in part spread over the k steps (shell_rf_t3 applies a
  // slowly varying part of its bending forces at every step and the rest
  // as the impulse; docs/mechanics-method.md). Elements without bending
  // ignore it.
  double bending_weight = 1.0;
  // Where the kernel runs the part's passes interleaved (see
  // ElementKernel::pass_reach; on one thread it does): the ranges are the
  // part's blocks of block_size elements in order (range b = [b block_size,
  // min(n, (b + 1) block_size)), the last one may be smaller), block is
  // this range's b, and pass_window W > 0 says that whatever a block's
  // passes leave for later passes (its own, and those of the ranges within
  // the reach that read it) has been read for the last time before block
  // b + W starts its pass 0. An element may then keep such values of a step
  // in W block-sized buffers, block b's in buffer b mod W, which stay in
  // cache, instead of arrays over the whole part. 0 (the default): no such
  // bound (each range's pass k - 1 may come before any range's pass k);
  // block and block_size are then 0 too.
  int pass_window = 0;
  int block = 0;
  int block_size = 0;
};

struct ElementForceOutput {
  // Internal nodal forces (N), added to (the caller zeroes them first):
  // xyz of slot i at 3 i .. 3 i + 2, slots as ElementForceInput::patch_slot
  // numbers them. The kernel gives each block its own slots, so that a call
  // adds into a small array that stays in cache.
  std::span<double> node_force;
  double energy = 0.0;              // J, hyperelastic energy of the range (accumulated)
  double stable_dt = 0.0;           // s, minimum over the range of the steps times dt_scale (set by the call)
  std::span<double> element_dt;     // optional: stable step of each element, unscaled (entries of the range)
  int failed_element = -1;          // first degenerate element found, -1 if none
  // s, the smallest stable step of the range's bending alone, times
  // dt_scale, from an evaluation with a bending_weight above 0 (set by the
  // call; infinity where the element has no bending or did not evaluate
  // it). The kernel chooses how many steps one bending evaluation carries
  // from it.
  double bending_dt = std::numeric_limits<double>::infinity();
};

// Per-element results for output.
struct ElementFields {
  std::span<double> shear_angle;  // degrees, one per element
  std::span<double> stress;       // 3 per element, S (N/m) in the material frame
  std::span<double> fibre;        // 3 per element, current fibre direction
  std::span<double> curvature;    // 3 per element, bending curvature (1/m) in the material frame
  // 3 per element, the Green-Lagrange membrane strain E = (C - I) / 2 in the
  // material frame, [E11, E22, E12] (tensor components, dimensionless; E11
  // along the initial fibre direction): the strain conjugate to `stress`.
  std::span<double> strain;
};

class ElementKernel {
 public:
  virtual ~ElementKernel() = default;
  virtual Status configure(const Params& params, const ElementSetup& setup) = 0;
  virtual Status internal_forces(const ElementForceInput& in, ElementForceOutput& out) = 0;
  virtual Status fields(ElementFields& out) const = 0;
  // Passes over all ranges per force evaluation (after configure): more
  // than one where an element's forces need values of elements of other
  // ranges (the bending curvature of shell_rf_t3 reads its neighbours').
  virtual int passes() const { return 1; }
  // How far pass k of a range reads what pass k - 1 wrote: for the elements
  // at most this many steps across edges (1: the range's elements and their
  // neighbours across their edges), or -1 (the default) for any element of
  // the part. With a reach, the kernel may call a range's next pass as soon
  // as the ranges holding those elements have done theirs, before the rest
  // of the part (on one thread it does, so that a range's values are still
  // in cache for its next pass); the results must not depend on that order.
  virtual int pass_reach() const { return -1; }
  // Checkpoints (state.hpp): whatever the element carries from one force
  // evaluation to the next beyond the kernel's arrays, above all its laws'
  // history (MaterialLaw::state_size) and the previous strains. save_state
  // is called between steps; load_state on an element configured by the
  // same job, before its first evaluation, with what save_state wrote. The
  // defaults: nothing to carry.
  virtual Status save_state(StateWriter& /*out*/) const { return Status::success(); }
  virtual Status load_state(StateReader& /*in*/) { return Status::success(); }
};

}  // namespace ts::sdk
