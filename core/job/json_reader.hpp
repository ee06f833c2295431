#pragma once
// Reads one JSON object of a job file against what is allowed there: every
// access declares its key, and finish() rejects any key nobody asked for,
// with a "did you mean" suggestion. Every error carries the JSON pointer.
#include <array>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "job/errors.hpp"

namespace ts {

using json = nlohmann::json;

std::string json_type_name(const json& j);
std::string pointer_append(const std::string& ptr, const std::string& key);
std::string pointer_append(const std::string& ptr, std::size_t index);

class ObjectReader {
 public:
  ObjectReader(const json& j, std::string pointer);

  const std::string& pointer() const { return ptr_; }
  std::string at(const std::string& key) const { return pointer_append(ptr_, key); }
  bool has(const std::string& key);  // declares the key
  const json& raw(const std::string& key);  // required, any type
  const json* optional_raw(const std::string& key);

  double real(const std::string& key, std::optional<double> def = std::nullopt,
              double min = -std::numeric_limits<double>::infinity(), bool min_exclusive = false,
              double max = std::numeric_limits<double>::infinity());
  long long integer(const std::string& key, std::optional<long long> def, long long min, long long max);
  bool boolean(const std::string& key, std::optional<bool> def);
  std::string text(const std::string& key, std::optional<std::string> def = std::nullopt);
  std::string choice(const std::string& key, const std::vector<std::string>& choices,
                     std::optional<std::string> def = std::nullopt);
  std::vector<double> reals(const std::string& key, int size,
                            std::optional<std::vector<double>> def = std::nullopt);
  std::vector<std::string> texts(const std::string& key,
                                 std::optional<std::vector<std::string>> def = std::nullopt);
  void declare(const std::string& key) { known_.insert(key); }
  // Rejects keys that were never declared.
  void finish() const;

 private:
  const json& j_;
  std::string ptr_;
  std::set<std::string> known_;
};

double as_real(const json& v, const std::string& ptr);
// A number as the job reader's messages print it (the stream's default form).
std::string fmt_number(double v);
std::vector<double> as_reals(const json& v, const std::string& ptr, int size);

}  // namespace ts
