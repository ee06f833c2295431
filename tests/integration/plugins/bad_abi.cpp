// A plugin that claims another SDK ABI version: the host must refuse it.
#include <thermostamp/sdk/plugin.hpp>

namespace {
void register_all(ts::sdk::Registrar&) {}
}  // namespace

extern "C" BOOST_SYMBOL_EXPORT const ts::sdk::PluginEntry* thermostamp_plugin_entry() {
  static const ts::sdk::PluginEntry entry{999, "thermal_badabi", "0.0.1", "9.9.9", &register_all};
  return &entry;
}
