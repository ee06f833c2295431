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
// Where a run with output.keep_checkpoints keeps each checkpoint it writes:
// DIR/checkpoints/checkpoint_<t>.bin, t in s to 9 significant digits.
inline constexpr const char* kKeptCheckpointFolder = "checkpoints";
std::string kept_checkpoint_name(double t);

struct KeptCheckpoint {
  double t = 0;  // s, as its name gives it
  std::filesystem::path file;
};
// The kept checkpoints of output folder `dir`, by time (none without the
// folder; files of other names are left out).
std::vector<KeptCheckpoint> kept_checkpoints(const std::filesystem::path& dir);
// `to` as a second name of the file `from` where the file system allows it,
// else as a copy (an existing `to` is replaced). Throws std::runtime_error
// with the reason.
void link_or_copy(const std::filesystem::path& from, const std::filesystem::path& to);
// Keeps the checkpoint just written to `written` as the kept checkpoint of
// time t in `dir` (a second name of the same file where the file system
// allows it, else a copy). Throws std::runtime_error with the reason.
void keep_checkpoint(const std::filesystem::path& written, const std::filesystem::path& dir, double t);

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& c);
// Throws std::runtime_error with a one-line reason (missing, not a
// checkpoint, truncated, another plugin ABI).
Checkpoint read_checkpoint(const std::filesystem::path& file);

}  // namespace ts
