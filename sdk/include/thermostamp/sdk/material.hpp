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
  std::span<double> state;              // n * state_size(), updated in place
  std::span<double> stress;             // 3n out: S (N/m) or moments M (N m/m)
  std::span<double> energy;             // n out: w (J/m^2), may be empty
  std::span<double> dissipation;        // n out: energy dissipated this step (J/m^2), may be empty
};

class MaterialLaw {
 public:
  virtual ~MaterialLaw() = default;
  virtual Status configure(const Params& params) = 0;
  virtual LawRole role() const = 0;
  virtual int state_size() const { return 0; }
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
