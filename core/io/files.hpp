#pragma once
// What the output files share: why writing one failed.
#include <filesystem>
#include <string>

namespace ts {

// Why writing a file in `dir` failed: the system's reason (errno `err`,
// where a write set one; `otherwise` if it is 0) and " (X MB free on its
// device)", the space left where the file is (a full disk, or a quota).
std::string write_failure_reason(const std::filesystem::path& dir, int err, const std::string& otherwise);

}  // namespace ts
