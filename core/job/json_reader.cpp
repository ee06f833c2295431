#include "job/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ts {

namespace {
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (std::tolower(a[i - 1]) == std::tolower(b[j - 1]) ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::string fmt_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  if (best.empty() || best_d > limit) return "";
  return "did you mean '" + best + "'?";
}

std::string join(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i) out += sep;
    out += items[i];
  }
  return out;
}

std::string json_type_name(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    case json::value_t::string: return "a string (" + j.dump() + ")";
    case json::value_t::boolean: return std::string("a boolean (") + (j.get<bool>() ? "true" : "false") + ")";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: return "a number (" + j.dump() + ")";
    default: return "something else";
  }
}

static std::string escape_token(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

std::string pointer_append(const std::string& ptr, const std::string& key) { return ptr + "/" + escape_token(key); }
std::string pointer_append(const std::string& ptr, std::size_t index) { return ptr + "/" + std::to_string(index); }

ObjectReader::ObjectReader(const json& j, std::string pointer) : j_(j), ptr_(std::move(pointer)) {
  if (!j_.is_object()) throw JobError(ptr_.empty() ? "/" : ptr_, "expected an object, found " + json_type_name(j_));
}

bool ObjectReader::has(const std::string& key) {
  known_.insert(key);
  return j_.contains(key) && !j_.at(key).is_null();
}

const json& ObjectReader::raw(const std::string& key) {
  known_.insert(key);
  if (!j_.contains(key)) throw JobError(at(key), "required, missing");
  return j_.at(key);
}

const json* ObjectReader::optional_raw(const std::string& key) {
  known_.insert(key);
  if (!j_.contains(key) || j_.at(key).is_null()) return nullptr;
  return &j_.at(key);
}

double as_real(const json& v, const std::string& ptr) {
  if (!v.is_number()) throw JobError(ptr, "expected a number, found " + json_type_name(v));
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw JobError(ptr, "expected a finite number");
  return x;
}

std::vector<double> as_reals(const json& v, const std::string& ptr, int size) {
  if (!v.is_array()) throw JobError(ptr, "expected an array of numbers, found " + json_type_name(v));
  if (size >= 0 && static_cast<int>(v.size()) != size)
    throw JobError(ptr, "expected " + std::to_string(size) + " numbers, found " + std::to_string(v.size()));
  std::vector<double> out;
  for (std::size_t i = 0; i < v.size(); ++i) out.push_back(as_real(v[i], pointer_append(ptr, i)));
  return out;
}

double ObjectReader::real(const std::string& key, std::optional<double> def, double min, bool min_exclusive,
                          double max) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required number, missing");
    return *def;
  }
  const double x = as_real(*v, at(key));
  if (min_exclusive ? !(x > min) : !(x >= min))
    throw JobError(at(key), std::string("must be ") + (min_exclusive ? "> " : ">= ") + fmt_number(min) +
                                ", found " + fmt_number(x));
  if (x > max) throw JobError(at(key), "must be <= " + fmt_number(max) + ", found " + fmt_number(x));
  return x;
}

long long ObjectReader::integer(const std::string& key, std::optional<long long> def, long long min,
                                long long max) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required integer, missing");
    return *def;
  }
  if (!v->is_number_integer() && !v->is_number_unsigned()) {
    if (v->is_number_float() && std::floor(v->get<double>()) == v->get<double>()) {
      // 8.0 is accepted as 8
    } else {
      throw JobError(at(key), "expected an integer, found " + json_type_name(*v));
    }
  }
  // The range is checked on the value as written (1e30 does not fit a long
  // long: converting it first would report garbage).
  const double d = v->get<double>();
  if (d < static_cast<double>(min)) throw JobError(at(key), "must be >= " + std::to_string(min) + ", found " + v->dump());
  if (d > static_cast<double>(max)) throw JobError(at(key), "must be <= " + std::to_string(max) + ", found " + v->dump());
  if (!(std::abs(d) < 9.2e18))  // beyond what a long long holds (a max of LLONG_MAX rounds up as a double)
    throw JobError(at(key), "must be <= " + std::to_string(max) + ", found " + v->dump());
  return v->is_number_float() ? static_cast<long long>(d) : v->get<long long>();
}

bool ObjectReader::boolean(const std::string& key, std::optional<bool> def) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required boolean, missing");
    return *def;
  }
  if (!v->is_boolean()) throw JobError(at(key), "expected true or false, found " + json_type_name(*v));
  return v->get<bool>();
}

std::string ObjectReader::text(const std::string& key, std::optional<std::string> def) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required string, missing");
    return *def;
  }
  if (!v->is_string()) throw JobError(at(key), "expected a string, found " + json_type_name(*v));
  return v->get<std::string>();
}

std::string ObjectReader::choice(const std::string& key, const std::vector<std::string>& choices,
                                 std::optional<std::string> def) {
  std::string s = text(key, std::move(def));
  if (std::find(choices.begin(), choices.end(), s) == choices.end()) {
    std::string msg = "unknown value '" + s + "'";
    const std::string dym = did_you_mean(s, choices);
    if (!dym.empty()) msg += "; " + dym;
    msg += "; valid values are: " + join(choices);
    throw JobError(at(key), msg);
  }
  return s;
}

std::vector<double> ObjectReader::reals(const std::string& key, int size, std::optional<std::vector<double>> def) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required array of numbers, missing");
    return *def;
  }
  return as_reals(*v, at(key), size);
}

std::vector<std::string> ObjectReader::texts(const std::string& key, std::optional<std::vector<std::string>> def) {
  const json* v = optional_raw(key);
  if (!v) {
    if (!def) throw JobError(at(key), "required array of strings, missing");
    return *def;
  }
  if (!v->is_array()) throw JobError(at(key), "expected an array of strings, found " + json_type_name(*v));
  std::vector<std::string> out;
  for (std::size_t i = 0; i < v->size(); ++i) {
    if (!(*v)[i].is_string())
      throw JobError(pointer_append(at(key), i), "expected a string, found " + json_type_name((*v)[i]));
    out.push_back((*v)[i].get<std::string>());
  }
  return out;
}

void ObjectReader::finish() const {
  std::vector<std::string> known(known_.begin(), known_.end());
  for (auto it = j_.begin(); it != j_.end(); ++it) {
    if (known_.count(it.key())) continue;
    std::string msg = "unknown key '" + it.key() + "'";
    const std::string dym = did_you_mean(it.key(), known);
    msg += dym.empty() ? "; allowed keys: " + join(known) : "; " + dym;
    throw JobError(at(it.key()), msg);
  }
}

}  // namespace ts
