#include "plugins/describe.hpp"

#include <sstream>

namespace ts {

namespace {
std::string bound_text(const sdk::ParamSpec& p) {
  std::ostringstream s;
  const bool lo = std::isfinite(p.min), hi = std::isfinite(p.max);
  if (p.type == sdk::ParamType::Choice) {
    s << "one of: " << join(p.choices);
  } else if (lo && hi) {
    s << (p.min_exclusive ? "(" : "[") << p.min << ", " << p.max << "]";
  } else if (lo) {
    s << (p.min_exclusive ? "> " : ">= ") << p.min;
  } else if (hi) {
    s << "<= " << p.max;
  }
  return s.str();
}
}  // namespace

json descriptor_json(const PluginRecord& r) {
  const auto& d = r.descriptor;
  json params = json::array();
  for (const auto& p : d.params) {
    json j = {{"name", p.name}, {"type", sdk::to_string(p.type)}, {"unit", p.unit}, {"doc", p.doc}};
    j["default"] = p.default_json.empty() ? json(nullptr) : json::parse(p.default_json);
    j["required"] = p.default_json.empty();
    if (std::isfinite(p.min)) j["min"] = p.min;
    if (std::isfinite(p.max)) j["max"] = p.max;
    if (p.min_exclusive) j["min_exclusive"] = true;
    if (!p.choices.empty()) j["choices"] = p.choices;
    params.push_back(j);
  }
  return {{"kind", sdk::to_string(d.kind)}, {"name", d.name},     {"version", d.version},
          {"summary", d.summary},           {"params", params},   {"example", d.example},
          {"library", r.library}};
}

std::string descriptor_text(const PluginRecord& r) {
  const auto& d = r.descriptor;
  std::ostringstream s;
  s << sdk::to_string(d.kind) << "/" << d.name << " " << d.version << " - " << d.summary << "\n";
  for (const auto& p : d.params) {
    s << "    " << p.name << " (" << sdk::to_string(p.type);
    if (!p.unit.empty() && p.unit != "-") s << ", " << p.unit;
    s << (p.default_json.empty() ? ", required" : ", default " + p.default_json);
    const std::string b = bound_text(p);
    if (!b.empty()) s << ", " << b;
    s << "): " << p.doc << "\n";
  }
  return s.str();
}

std::string reference_markdown(const std::vector<const PluginRecord*>& records) {
  std::ostringstream s;
  s << "# Plugin reference\n\nGenerated from the plugin descriptors by `thermostamp plugins --markdown`; "
       "do not edit by hand.\n\n";
  for (const char* kind : {"thermal", "contact", "material", "element"}) {
    bool any = false;
    for (const auto* r : records) {
      if (std::string(sdk::to_string(r->descriptor.kind)) != kind) continue;
      if (!any) s << "## " << kind << " plugins\n\n";
      any = true;
      const auto& d = r->descriptor;
      s << "### `" << d.name << "` (" << kind << ", version " << d.version << ")\n\n" << d.summary << "\n\n";
      if (!d.params.empty()) {
        s << "| parameter | type | default | unit | allowed | meaning |\n|---|---|---|---|---|---|\n";
        for (const auto& p : d.params)
          s << "| `" << p.name << "` | " << sdk::to_string(p.type) << " | "
            << (p.default_json.empty() ? "required" : "`" + p.default_json + "`") << " | " << p.unit << " | "
            << bound_text(p) << " | " << p.doc << " |\n";
        s << "\n";
      }
      if (!d.example.empty()) s << "Example:\n\n```json\n" << d.example << "\n```\n\n";
    }
  }
  return s.str();
}

}  // namespace ts
