#include "io/checkpoint.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <thermostamp/sdk/plugin.hpp>

#include "io/files.hpp"

namespace ts {

namespace {
constexpr char kMagic[] = "THERMOSTAMP-CHECKPOINT\n";
constexpr std::uint32_t kFormat = 9;

template <class T>
void put(std::ofstream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
void put_bytes(std::ofstream& out, const void* data, std::size_t n) {
  put(out, static_cast<std::uint64_t>(n));
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
}
}  // namespace

const std::vector<unsigned char>* Checkpoint::find(const std::string& name) const {
  for (const auto& s : sections)
    if (s.first == name) return &s.second;
  return nullptr;
}

const std::vector<unsigned char>& Checkpoint::section(const std::string& name) const {
  if (const auto* s = find(name)) return *s;
  throw std::runtime_error("the checkpoint has no section '" + name + "'");
}

std::string kept_checkpoint_name(double t) {
  char name[64];
  std::snprintf(name, sizeof name, "checkpoint_%.9g.bin", t);
  return name;
}

std::vector<KeptCheckpoint> kept_checkpoints(const std::filesystem::path& dir) {
  std::vector<KeptCheckpoint> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir / kKeptCheckpointFolder, ec)) {
    const std::string name = e.path().filename().string();
    const std::string head = "checkpoint_", tail = ".bin";
    if (name.size() <= head.size() + tail.size() || name.rfind(head, 0) != 0 || !name.ends_with(tail)) continue;
    const std::string number = name.substr(head.size(), name.size() - head.size() - tail.size());
    char* end = nullptr;
    const double t = std::strtod(number.c_str(), &end);
    if (end != number.c_str() + number.size() || !std::isfinite(t)) continue;
    out.push_back({t, e.path()});
  }
  std::sort(out.begin(), out.end(), [](const KeptCheckpoint& a, const KeptCheckpoint& b) { return a.t < b.t; });
  return out;
}

void link_or_copy(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::error_code ec;
  std::filesystem::remove(to, ec);  // perhaps a name of another file: that file stays
  std::filesystem::create_hard_link(from, to, ec);
  if (!ec) return;
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
  if (ec) {
    const std::string why = write_failure_reason(to.parent_path(), ec.value(), ec.message());
    std::filesystem::remove(to, ec);
    throw std::runtime_error("cannot write " + to.string() + ": " + why);
  }
}

void keep_checkpoint(const std::filesystem::path& written, const std::filesystem::path& dir, double t) {
  const auto folder = dir / kKeptCheckpointFolder;
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw std::runtime_error("cannot create " + folder.string() + ": " + ec.message());
  link_or_copy(written, folder / kept_checkpoint_name(t));
}

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& c) {
  auto tmp = file;
  tmp += ".tmp";
  errno = 0;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + tmp.string() + ": " + std::strerror(errno));
    out.write(kMagic, sizeof kMagic - 1);
    put(out, kFormat);
    put(out, static_cast<std::int32_t>(sdk::kAbiVersion));
    put(out, static_cast<std::uint64_t>(c.sections.size()));
    for (const auto& [name, bytes] : c.sections) {
      put_bytes(out, name.data(), name.size());
      put_bytes(out, bytes.data(), bytes.size());
    }
    out.flush();
    if (!out) {  // the checkpoint before it, if any, stays
      const std::string why = write_failure_reason(file.parent_path(), errno, "the stream failed");
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error("cannot write " + tmp.string() + ": " + why);
    }
  }
  std::filesystem::rename(tmp, file);
}

Checkpoint read_checkpoint(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("no checkpoint " + file.string() + " (a run writes one when it is interrupted, "
                                    "at output.checkpoint_interval, at --checkpoint-minutes and at its end)");
  const std::string what = file.string() + " is not a ThermoStamp checkpoint";
  char magic[sizeof kMagic - 1];
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0) throw std::runtime_error(what);
  std::uint32_t format = 0;
  std::int32_t abi = 0;
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(&format), sizeof format);
  in.read(reinterpret_cast<char*>(&abi), sizeof abi);
  in.read(reinterpret_cast<char*>(&count), sizeof count);
  if (!in || format != kFormat) throw std::runtime_error(what + " of this version (format " + std::to_string(format) + ")");
  if (abi != sdk::kAbiVersion)
    throw std::runtime_error(file.string() + " was written with plugin ABI " + std::to_string(abi) + ", this build has " +
                             std::to_string(sdk::kAbiVersion) + ": restart it with the version that wrote it");
  const auto size = std::filesystem::file_size(file);
  auto get_bytes = [&](auto& v) {
    std::uint64_t n = 0;
    if (!in.read(reinterpret_cast<char*>(&n), sizeof n) || n > size) throw std::runtime_error(file.string() + " is truncated");
    v.resize(n);
    if (n > 0 && !in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n)))
      throw std::runtime_error(file.string() + " is truncated");
  };
  Checkpoint c;
  for (std::uint64_t k = 0; k < count; ++k) {
    std::string name;
    std::vector<unsigned char> bytes;
    get_bytes(name);
    get_bytes(bytes);
    c.add(std::move(name), std::move(bytes));
  }
  return c;
}

}  // namespace ts
