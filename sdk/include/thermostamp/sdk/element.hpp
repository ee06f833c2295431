#pragma once
// Shell elements: internal forces and stable step over a range of elements.
#include <span>

#include "material.hpp"
#include "parameters.hpp"
#include "status.hpp"
#include "views.hpp"

namespace ts::sdk {

struct ElementRange {
  int begin = 0;  // first element
  int end = 0;    // one past the last
};

struct ElementForceInput {
  const PartView* part = nullptr;
  ElementRange range;
  double dt = 0.0;
  std::span<const double> temperature;  // per node (mean through the thickness), degC
  const MaterialLaw* membrane = nullptr;
  const MaterialLaw* bending = nullptr;
};

struct ElementForceOutput {
  std::span<double> element_force;  // 9 per element of the range (3 nodes x xyz), overwritten
  double internal_energy = 0.0;     // J, accumulated over the range
  double dissipated = 0.0;          // J, accumulated over the range
  double stable_dt = 0.0;           // s, minimum over the range
};

class ElementKernel {
 public:
  virtual ~ElementKernel() = default;
  virtual Status configure(const Params& params, const PartView& part) = 0;
  virtual Status internal_forces(const ElementForceInput& in, ElementForceOutput& out) = 0;
};

}  // namespace ts::sdk
