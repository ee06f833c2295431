#pragma once
// Descriptors rendered for people and tools: `thermostamp plugins`, the
// generated job reference (Markdown) and the JSON listing.
#include <string>
#include <vector>

#include "plugins/registry.hpp"

namespace ts {

json descriptor_json(const PluginRecord& r);
std::string descriptor_text(const PluginRecord& r);
std::string reference_markdown(const std::vector<const PluginRecord*>& records);

}  // namespace ts
