#include "io/files.hpp"

#include <cstdio>
#include <cstring>
#include <system_error>

namespace ts {

std::string write_failure_reason(const std::filesystem::path& dir, int err, const std::string& otherwise) {
  std::string why = err != 0 ? std::string(std::strerror(err)) : otherwise;
  std::error_code ec;
  if (const auto space = std::filesystem::space(dir, ec); !ec && space.capacity > 0) {
    const double b = static_cast<double>(space.available);
    char free[64];
    std::snprintf(free, sizeof free, " (%.3g %s free on its device)", b >= 1e9 ? b / 1e9 : b / 1e6,
                  b >= 1e9 ? "GB" : "MB");
    why += free;
  }
  return why;
}

}  // namespace ts
