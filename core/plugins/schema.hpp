#pragma once
// JSON Schema (draft 2020-12) of job files, generated from the plugin
// descriptors, so that editors validate and complete job files.
#include <vector>

#include "plugins/registry.hpp"

namespace ts {

json job_schema(const std::vector<const PluginRecord*>& records);

}  // namespace ts
