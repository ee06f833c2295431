#pragma once
// Finds, loads and keeps plugin libraries; validates parameters against
// their descriptors. Libraries are found next to the executable
// (../plugins, ../lib/thermostamp/plugins), in THERMOSTAMP_PLUGIN_PATH and in
// a job's plugin_paths. A library named thermostamp_<kind>_<name>.so is
// loaded when a job names <name> of that kind; the others only when asked
// for everything (`thermostamp plugins`) or when a name is not found.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <thermostamp/sdk/plugin.hpp>

#include "job/json_reader.hpp"

namespace ts {

struct PluginRecord {
  sdk::Descriptor descriptor;
  void* create = nullptr;  // factory, cast by kind
  std::string library;     // file it came from
  std::string library_version;  // the version the library declares (THERMOSTAMP_PLUGIN)
};

class PluginRegistry final : public sdk::Registrar {
 public:
  PluginRegistry();
  void add_search_dir(const std::filesystem::path& dir);
  const std::vector<std::filesystem::path>& search_dirs() const { return dirs_; }

  // Loads every library found (for listing). Errors of individual libraries
  // are collected in load_errors() instead of stopping.
  void load_all();
  const std::vector<std::string>& load_errors() const { return errors_; }

  // Finds the plugin, loading its library if needed; throws JobError naming
  // `pointer` with the list of valid names when it does not exist.
  const PluginRecord& require(sdk::PluginKind kind, const std::string& name, const std::string& pointer);
  std::vector<const PluginRecord*> all() const;
  std::vector<std::string> loaded_names() const;  // "thermal/adi", ... in order of loading

  // Loads one library file; throws JobError on ABI mismatch or a file that
  // is not a plugin.
  void load_library(const std::filesystem::path& file);

  void add_thermal(const sdk::Descriptor& d, sdk::ThermalSplitter* (*create)()) override;
  void add_contact(const sdk::Descriptor& d, sdk::ContactHandler* (*create)()) override;
  void add_material(const sdk::Descriptor& d, sdk::MaterialLaw* (*create)()) override;
  void add_element(const sdk::Descriptor& d, sdk::ElementKernel* (*create)()) override;

 private:
  void add(const sdk::Descriptor& d, void* create);
  std::vector<std::filesystem::path> candidate_files() const;
  std::vector<std::filesystem::path> dirs_;
  std::vector<std::string> loaded_files_;
  std::map<std::string, PluginRecord> records_;  // key "kind/name"
  std::vector<std::string> order_;
  std::vector<std::string> used_;
  std::vector<std::string> errors_;
  std::string current_library_;
  std::string current_library_version_;
};

// Validates a JSON object against a descriptor: unknown keys (with "did you
// mean"), types, bounds; fills defaults. `extra_keys` are keys owned by the
// kernel in the same object (ignored here).
sdk::Params validate_params(const json& obj, const std::string& pointer, const sdk::Descriptor& d,
                            const std::vector<std::string>& extra_keys = {});

std::string kind_dir_name(sdk::PluginKind k);

}  // namespace ts
