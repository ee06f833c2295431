#pragma once
// Declared parameters: a plugin lists what it accepts (name, type, default,
// unit, bounds, doc). The kernel validates the job against this list before
// anything runs (unknown keys with "did you mean", wrong types, bounds),
// fills the defaults, and hands the plugin a Params object. The same list
// generates `thermostamp plugins`, the job reference and the job schema.
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ts::sdk {

enum class ParamType { Real, Integer, Boolean, String, Choice, RealList };

inline const char* to_string(ParamType t) {
  switch (t) {
    case ParamType::Real: return "real";
    case ParamType::Integer: return "integer";
    case ParamType::Boolean: return "boolean";
    case ParamType::String: return "string";
    case ParamType::Choice: return "choice";
    case ParamType::RealList: return "real list";
  }
  return "?";
}

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::Real;
  std::string default_json;  // JSON text of the default; empty = required
  std::string unit;          // SI unit, "-" when dimensionless
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;  // value must be > min instead of >= min
  std::vector<std::string> choices;  // for Choice
  int list_size = -1;                // for RealList: required length, -1 any
  std::string doc;
};

// Small builders so that descriptors read like a table.
inline ParamSpec real_param(std::string name, std::string def, std::string unit, std::string doc,
                            double min = -std::numeric_limits<double>::infinity(),
                            double max = std::numeric_limits<double>::infinity(),
                            bool min_exclusive = false) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = ParamType::Real;
  p.default_json = std::move(def);
  p.unit = std::move(unit);
  p.doc = std::move(doc);
  p.min = min;
  p.max = max;
  p.min_exclusive = min_exclusive;
  return p;
}
inline ParamSpec int_param(std::string name, std::string def, std::string doc, double min, double max) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = ParamType::Integer;
  p.default_json = std::move(def);
  p.unit = "-";
  p.doc = std::move(doc);
  p.min = min;
  p.max = max;
  return p;
}
inline ParamSpec choice_param(std::string name, std::string def, std::vector<std::string> choices,
                              std::string doc) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = ParamType::Choice;
  p.default_json = "\"" + def + "\"";
  p.unit = "-";
  p.choices = std::move(choices);
  p.doc = std::move(doc);
  return p;
}
inline ParamSpec list_param(std::string name, std::string def, std::string unit, std::string doc, int size = -1,
                            double min = -std::numeric_limits<double>::infinity()) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = ParamType::RealList;
  p.default_json = std::move(def);
  p.unit = std::move(unit);
  p.list_size = size;
  p.min = min;
  p.doc = std::move(doc);
  return p;
}
inline ParamSpec bool_param(std::string name, bool def, std::string doc) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = ParamType::Boolean;
  p.default_json = def ? "true" : "false";
  p.unit = "-";
  p.doc = std::move(doc);
  return p;
}

// The validated parameter values a plugin receives (defaults filled in).
class Params {
 public:
  struct Value {
    ParamType type = ParamType::Real;
    double real = 0.0;
    long long integer = 0;
    bool boolean = false;
    std::string text;
    std::vector<double> list;
  };

  void set(const std::string& name, Value v) { values_[name] = std::move(v); }
  bool has(const std::string& name) const { return values_.count(name) != 0; }

  double real(const std::string& name) const { return get(name).real; }
  long long integer(const std::string& name) const { return get(name).integer; }
  bool boolean(const std::string& name) const { return get(name).boolean; }
  const std::string& text(const std::string& name) const { return get(name).text; }
  const std::vector<double>& list(const std::string& name) const { return get(name).list; }
  const std::map<std::string, Value>& all() const { return values_; }

 private:
  const Value& get(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw std::out_of_range("parameter '" + name + "' is not declared");
    return it->second;
  }
  std::map<std::string, Value> values_;
};

}  // namespace ts::sdk
