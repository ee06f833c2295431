#pragma once
// The plugin entry point. Every plugin library exports exactly one C symbol,
// `thermostamp_plugin_entry`, returning a PluginEntry. The host reads
// `abi_version` first and refuses the library if it differs from its own
// kAbiVersion; only then does it call `register_all`, through which the
// library registers a descriptor and a factory for each object it provides.
//
// Rules at the boundary: no exception crosses it (use guarded()), objects
// are created by the library's factory and deleted through their virtual
// destructor, and libraries stay loaded for the life of the process.
#include <boost/config.hpp>
#include <string>
#include <vector>

#include "contact.hpp"
#include "element.hpp"
#include "material.hpp"
#include "parameters.hpp"
#include "status.hpp"
#include "thermal.hpp"

namespace ts::sdk {

// Bump when any type of this SDK changes layout or meaning.
inline constexpr int kAbiVersion = 22;
inline constexpr const char* kSdkVersion = "0.22.0";

enum class PluginKind { Element, Material, Thermal, Contact };

inline const char* to_string(PluginKind k) {
  switch (k) {
    case PluginKind::Element: return "element";
    case PluginKind::Material: return "material";
    case PluginKind::Thermal: return "thermal";
    case PluginKind::Contact: return "contact";
  }
  return "?";
}

struct Descriptor {
  PluginKind kind = PluginKind::Thermal;
  std::string name;     // what a job writes ("adi", "penalty_node_surface", ...)
  std::string version;  // of the plugin
  std::string summary;  // one line
  std::vector<ParamSpec> params;
  std::string example;  // a minimal JSON snippet using it
};

class Registrar {
 public:
  virtual ~Registrar() = default;
  virtual void add_thermal(const Descriptor& d, ThermalSplitter* (*create)()) = 0;
  virtual void add_contact(const Descriptor& d, ContactHandler* (*create)()) = 0;
  virtual void add_material(const Descriptor& d, MaterialLaw* (*create)()) = 0;
  virtual void add_element(const Descriptor& d, ElementKernel* (*create)()) = 0;
};

// Layout fixed for every ABI version: abi_version is always the first field.
struct PluginEntry {
  int abi_version;
  const char* library;          // library name, e.g. "thermal_adi"
  const char* library_version;  // version of the library
  const char* sdk_version;      // SDK it was built against
  void (*register_all)(Registrar& registrar);
};

}  // namespace ts::sdk

// Declares the entry point of a plugin library.
//   THERMOSTAMP_PLUGIN("thermal_adi", "1.0.0", register_fn)
#define THERMOSTAMP_PLUGIN(LIBNAME, LIBVERSION, REGISTER_FN)                                   \
  extern "C" BOOST_SYMBOL_EXPORT const ::ts::sdk::PluginEntry* thermostamp_plugin_entry() {   \
    static const ::ts::sdk::PluginEntry entry{::ts::sdk::kAbiVersion, LIBNAME, LIBVERSION,     \
                                              ::ts::sdk::kSdkVersion, &REGISTER_FN};          \
    return &entry;                                                                            \
  }
