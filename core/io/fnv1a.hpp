#pragma once
// FNV-1a, 64 bits: a hash of values fed byte by byte (low byte first).
#include <cstdint>

namespace ts {

inline constexpr std::uint64_t kFnv1aOffset = 1469598103934665603ULL;

// Mixes the 8 bytes of v into h.
inline void fnv1a_mix(std::uint64_t& h, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) {
    h ^= static_cast<unsigned char>(v >> (8 * b));
    h *= 1099511628211ULL;
  }
}

}  // namespace ts
