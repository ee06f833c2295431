#pragma once
// Material laws: membrane (hyperelastic / viscoelastic, by invariants) and
// bending. Called once per block of integration points.
#include <cstddef>
#include <limits>
#include <span>
#include <utility>

#include "parameters.hpp"
#include "status.hpp"

namespace ts::sdk {

enum class LawRole { Membrane, Bending };

// A block of integration points. All tensors are 2x2 symmetric in Voigt
// order [11, 22, 12] (math.hpp), expressed in the material frame of the
// initial configuration: axis 1 along L1 (fibre / warp), axis 2 = n x L1.
// For a woven ply, dir2 gives L2 (weft) in that frame as (cos, sin).
struct MaterialBlock {
  std::size_t n = 0;
  std::span<const double> strain;       // 3n: C (membrane) or curvature chi (bending, 1/m)
  std::span<const double> strain_old;   // 3n: value at the previous step (empty when uses_strain_old() is false)
  std::span<const double> dir2;         // 2n, may be empty for UD laws
  std::span<const double> temperature;  // n, degC
  double dt = 0.0;                      // s
  std::span<double> state;              // n * state_size(), updated in place (see state_size())
  std::span<double> cache;              // n * cache_size() or empty (MaterialLaw::cache_size())
  std::span<double> stress;             // 3n out: S (N/m) or moments M (N m/m)
  std::span<double> energy;             // n out: w (J/m^2), may be empty
  std::span<double> dissipation;        // n out: energy dissipated this step (J/m^2), may be empty
};

class MaterialLaw {
 public:
  virtual ~MaterialLaw() = default;
  virtual Status configure(const Params& params) = 0;
  virtual LawRole role() const = 0;
  // History values per point: the element keeps n * state_size() doubles
  // per block, zero at the start, and hands them as MaterialBlock::state,
  // the same span for the same points at every call, so the law lays out a
  // block's values as it likes (point after point, or value after value).
  virtual int state_size() const { return 0; }
  // Values a law derives from inputs that change seldom (parameters at the
  // point's temperature, which changes only at thermal steps) and keeps to
  // save evaluating them again: cache_size() doubles per point, which the
  // element keeps (NaN at the start) and hands as MaterialBlock::cache,
  // the same span for the same points at every call. They are not history:
  // an element may hand an empty span instead (where the caches of a part
  // would not fit in the processor's cache and reading them costs more
  // than computing), and the law then computes what it needs. The law lays
  // out a block's values as it likes, and must check that they are still
  // valid (for instance, keep the temperature they are for).
  virtual int cache_size() const { return 0; }
  virtual Status evaluate(const MaterialBlock& block) const = 0;
  // Largest tangent stiffness (N/m for membrane, N m for bending) at a
  // temperature, for the stable step estimate.
  virtual double max_stiffness(double temperature) const = 0;
  // Temperatures (degC) the law's temperature-dependent parameters are given
  // for. Outside it the law holds them at the range end; the kernel warns
  // once when a ply's temperature leaves the range.
  virtual std::pair<double, double> temperature_range() const {
    return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  }
  // Whether evaluate() reads MaterialBlock::strain_old. A law that keeps
  // what it needs of the past in its state returns false: the element then
  // neither keeps the previous strains nor passes them (strain_old empty).
  virtual bool uses_strain_old() const { return true; }
};

}  // namespace ts::sdk
