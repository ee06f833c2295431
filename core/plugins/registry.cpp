#include "plugins/registry.hpp"

#include <algorithm>
#include <cmath>
#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <cstdlib>
#include <sstream>

#include "job/errors.hpp"

namespace ts {

namespace {
// Loaded libraries live until the process ends (never unloaded: objects and
// vtables they created may still be referenced during shutdown).
std::vector<boost::dll::shared_library>& keep_alive() {
  static auto* libs = new std::vector<boost::dll::shared_library>();
  return *libs;
}

std::string key_of(sdk::PluginKind k, const std::string& name) { return std::string(sdk::to_string(k)) + "/" + name; }
}  // namespace

std::string kind_dir_name(sdk::PluginKind k) { return sdk::to_string(k); }

PluginRegistry::PluginRegistry() {
  std::filesystem::path exe_dir;
  try {
    exe_dir = std::filesystem::path(boost::dll::program_location().parent_path().string());
  } catch (...) {
  }
  if (!exe_dir.empty()) {
    add_search_dir(exe_dir / ".." / "plugins");
    add_search_dir(exe_dir / ".." / "lib" / "thermostamp" / "plugins");
  }
  if (const char* env = std::getenv("THERMOSTAMP_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':'))
      if (!item.empty()) add_search_dir(item);
  }
}

void PluginRegistry::add_search_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  auto canon = std::filesystem::weakly_canonical(dir, ec);
  const auto d = ec ? dir : canon;
  if (std::find(dirs_.begin(), dirs_.end(), d) == dirs_.end()) dirs_.push_back(d);
}

std::vector<std::filesystem::path> PluginRegistry::candidate_files() const {
  std::vector<std::filesystem::path> out;
  for (const auto& d : dirs_) {
    std::error_code ec;
    if (!std::filesystem::is_directory(d, ec)) continue;
    std::vector<std::filesystem::path> here;
    for (const auto& e : std::filesystem::directory_iterator(d, ec)) {
      const std::string f = e.path().filename().string();
      if (f.rfind("thermostamp_", 0) == 0 && e.path().extension() == ".so") here.push_back(e.path());
    }
    std::sort(here.begin(), here.end());
    out.insert(out.end(), here.begin(), here.end());
  }
  return out;
}

void PluginRegistry::load_library(const std::filesystem::path& file) {
  const std::string path = std::filesystem::weakly_canonical(file).string();
  if (std::find(loaded_files_.begin(), loaded_files_.end(), path) != loaded_files_.end()) return;
  loaded_files_.push_back(path);
  boost::dll::shared_library lib;
  try {
    lib.load(path, boost::dll::load_mode::rtld_lazy | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw JobError("", "cannot load plugin library '" + path + "': " + e.what());
  }
  if (!lib.has("thermostamp_plugin_entry"))
    throw JobError("", "'" + path + "' is not a ThermoStamp plugin (no thermostamp_plugin_entry symbol)");
  auto entry_fn = lib.get<const sdk::PluginEntry*()>("thermostamp_plugin_entry");
  const sdk::PluginEntry* entry = entry_fn();
  if (!entry) throw JobError("", "plugin library '" + path + "' returned no entry");
  if (entry->abi_version != sdk::kAbiVersion) {
    // Only the first field may be read when the versions differ.
    throw JobError("", "plugin library '" + path + "' was built against SDK ABI version " +
                           std::to_string(entry->abi_version) + "; this ThermoStamp has SDK ABI version " +
                           std::to_string(sdk::kAbiVersion) + " (SDK " + sdk::kSdkVersion +
                           "): rebuild the plugin against this SDK");
  }
  current_library_ = path;
  current_library_version_ = entry->library_version ? entry->library_version : "";
  entry->register_all(*this);
  current_library_.clear();
  current_library_version_.clear();
  keep_alive().push_back(std::move(lib));
}

void PluginRegistry::load_all() {
  for (const auto& f : candidate_files()) {
    try {
      load_library(f);
    } catch (const JobError& e) {
      errors_.push_back(e.what());
    }
  }
}

void PluginRegistry::add(const sdk::Descriptor& d, void* create) {
  const std::string key = key_of(d.kind, d.name);
  if (records_.count(key)) {
    errors_.push_back("plugin " + key + " from '" + current_library_ + "' ignored: already provided by '" +
                      records_[key].library + "'");
    return;
  }
  records_[key] = PluginRecord{d, create, current_library_, current_library_version_};
  order_.push_back(key);
}

void PluginRegistry::add_thermal(const sdk::Descriptor& d, sdk::ThermalSplitter* (*c)()) {
  add(d, reinterpret_cast<void*>(c));
}
void PluginRegistry::add_contact(const sdk::Descriptor& d, sdk::ContactHandler* (*c)()) {
  add(d, reinterpret_cast<void*>(c));
}
void PluginRegistry::add_material(const sdk::Descriptor& d, sdk::MaterialLaw* (*c)()) {
  add(d, reinterpret_cast<void*>(c));
}
void PluginRegistry::add_element(const sdk::Descriptor& d, sdk::ElementKernel* (*c)()) {
  add(d, reinterpret_cast<void*>(c));
}

const PluginRecord& PluginRegistry::require(sdk::PluginKind kind, const std::string& name, const std::string& pointer) {
  const std::string key = key_of(kind, name);
  auto mark_used = [&](const PluginRecord& r) -> const PluginRecord& {
    if (std::find(used_.begin(), used_.end(), key) == used_.end()) used_.push_back(key);
    return r;
  };
  if (auto it = records_.find(key); it != records_.end()) return mark_used(it->second);
  const std::string file = "thermostamp_" + kind_dir_name(kind) + "_" + name + ".so";
  for (const auto& d : dirs_) {
    std::error_code ec;
    if (std::filesystem::exists(d / file, ec)) {
      try {
        load_library(d / file);
      } catch (const JobError& e) {
        throw JobError(pointer, e.what());
      }
      break;
    }
  }
  if (auto it = records_.find(key); it != records_.end()) return mark_used(it->second);
  load_all();  // maybe a library providing several plugins
  if (auto it = records_.find(key); it != records_.end()) return mark_used(it->second);
  std::vector<std::string> valid;
  for (const auto& [k, r] : records_)
    if (r.descriptor.kind == kind) valid.push_back(r.descriptor.name);
  std::string msg = std::string("unknown ") + sdk::to_string(kind) + " plugin '" + name + "'";
  const std::string dym = did_you_mean(name, valid);
  if (!dym.empty()) msg += "; " + dym;
  msg += valid.empty() ? "; no " + std::string(sdk::to_string(kind)) + " plugin was found in: " + [&] {
    std::vector<std::string> ds;
    for (const auto& d : dirs_) ds.push_back(d.string());
    return join(ds);
  }() : "; valid types are: " + join(valid);
  throw JobError(pointer, msg);
}

std::vector<const PluginRecord*> PluginRegistry::all() const {
  std::vector<const PluginRecord*> out;
  for (const auto& k : order_) out.push_back(&records_.at(k));
  return out;
}

std::vector<std::string> PluginRegistry::loaded_names() const { return used_; }

namespace {
std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

sdk::Params::Value convert(const json& v, const std::string& ptr, const sdk::ParamSpec& spec) {
  sdk::Params::Value out;
  out.type = spec.type;
  switch (spec.type) {
    case sdk::ParamType::Real: {
      out.real = as_real(v, ptr);
      const double x = out.real;
      if (spec.min_exclusive ? !(x > spec.min) : !(x >= spec.min))
        throw JobError(ptr, std::string("must be ") + (spec.min_exclusive ? "> " : ">= ") + fmt(spec.min) +
                                (spec.unit.empty() || spec.unit == "-" ? "" : " " + spec.unit) + ", found " + fmt(x));
      if (x > spec.max) throw JobError(ptr, "must be <= " + fmt(spec.max) + ", found " + fmt(x));
      break;
    }
    case sdk::ParamType::Integer: {
      if (!v.is_number_integer() && !v.is_number_unsigned())
        throw JobError(ptr, "expected an integer, found " + json_type_name(v));
      out.integer = v.get<long long>();
      if (out.integer < spec.min || out.integer > spec.max)
        throw JobError(ptr, "must be between " + fmt(spec.min) + " and " + fmt(spec.max) + ", found " +
                                std::to_string(out.integer));
      out.real = static_cast<double>(out.integer);
      break;
    }
    case sdk::ParamType::Boolean:
      if (!v.is_boolean()) throw JobError(ptr, "expected true or false, found " + json_type_name(v));
      out.boolean = v.get<bool>();
      break;
    case sdk::ParamType::String:
      if (!v.is_string()) throw JobError(ptr, "expected a string, found " + json_type_name(v));
      out.text = v.get<std::string>();
      break;
    case sdk::ParamType::Choice: {
      if (!v.is_string()) throw JobError(ptr, "expected a string, found " + json_type_name(v));
      out.text = v.get<std::string>();
      if (std::find(spec.choices.begin(), spec.choices.end(), out.text) == spec.choices.end()) {
        std::string msg = "unknown value '" + out.text + "'";
        const std::string dym = did_you_mean(out.text, spec.choices);
        if (!dym.empty()) msg += "; " + dym;
        throw JobError(ptr, msg + "; valid values are: " + join(spec.choices));
      }
      break;
    }
    case sdk::ParamType::RealList: {
      out.list = as_reals(v, ptr, spec.list_size);
      for (std::size_t i = 0; i < out.list.size(); ++i)
        if (!(out.list[i] >= spec.min && out.list[i] <= spec.max)) {
          const std::string unit = spec.unit.empty() || spec.unit == "-" ? "" : " " + spec.unit;
          const std::string bound = std::isinf(spec.max)   ? ">= " + fmt(spec.min) + unit
                                    : std::isinf(spec.min) ? "<= " + fmt(spec.max) + unit
                                                           : "between " + fmt(spec.min) + " and " + fmt(spec.max) + unit;
          throw JobError(pointer_append(ptr, i), "must be " + bound + ", found " + fmt(out.list[i]));
        }
      break;
    }
  }
  return out;
}
}  // namespace

sdk::Params validate_params(const json& obj, const std::string& pointer, const sdk::Descriptor& d,
                            const std::vector<std::string>& extra_keys) {
  if (!obj.is_object()) throw JobError(pointer, "expected an object, found " + json_type_name(obj));
  sdk::Params params;
  std::vector<std::string> names;
  for (const auto& s : d.params) names.push_back(s.name);
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (std::find(extra_keys.begin(), extra_keys.end(), it.key()) != extra_keys.end()) continue;
    if (std::find(names.begin(), names.end(), it.key()) == names.end()) {
      std::vector<std::string> allowed = names;
      allowed.insert(allowed.end(), extra_keys.begin(), extra_keys.end());
      std::string msg = "unknown parameter '" + it.key() + "' for " + sdk::to_string(d.kind) + " plugin '" + d.name + "'";
      const std::string dym = did_you_mean(it.key(), allowed);
      msg += dym.empty() ? "; allowed: " + join(allowed) : "; " + dym;
      throw JobError(pointer_append(pointer, it.key()), msg);
    }
  }
  for (const auto& s : d.params) {
    const std::string ptr = pointer_append(pointer, s.name);
    if (obj.contains(s.name) && !obj.at(s.name).is_null()) {
      params.set(s.name, convert(obj.at(s.name), ptr, s));
    } else if (!s.default_json.empty()) {
      params.set(s.name, convert(json::parse(s.default_json), ptr, s));
    } else {
      throw JobError(ptr, "required parameter of " + std::string(sdk::to_string(d.kind)) + " plugin '" + d.name +
                              "' (" + s.doc + "), missing");
    }
  }
  return params;
}

}  // namespace ts
