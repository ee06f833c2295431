#pragma once
// checkpoint.bin: the state of a run between two steps, from which
// `thermostamp run --restart` continues it. A file of named sections (the
// kernel's state, then each plugin's, sdk/state.hpp), written to a
// temporary file and renamed, so that a run stopped while writing one
// keeps the one before.
//
// Layout: the magic "THERMOSTAMP-CHECKPOINT\n", a format number (uint32),
// the plugin ABI it was written with (int32), the section count (uint64),
// then per section its name (uint64 length + bytes) and its bytes (uint64
// length + bytes); native byte order (a checkpoint is read back on the
// machine type that wrote it).
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace ts {

struct Checkpoint {
  std::vector<std::pair<std::string, std::vector<unsigned char>>> sections;
  void add(std::string name, std::vector<unsigned char> bytes) { sections.emplace_back(std::move(name), std::move(bytes)); }
  // The section of that name, null when absent.
  const std::vector<unsigned char>* find(const std::string& name) const;
  // The section of that name; throws std::runtime_error naming it when absent.
  const std::vector<unsigned char>& section(const std::string& name) const;
};

inline constexpr const char* kCheckpointFile = "checkpoint.bin";

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& c);
// Throws std::runtime_error with a one-line reason (missing, not a
// checkpoint, truncated, another plugin ABI).
Checkpoint read_checkpoint(const std::filesystem::path& file);

}  // namespace ts
