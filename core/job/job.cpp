#include "job/job.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include <thermostamp/sdk/math.hpp>

namespace ts {
namespace {
// Thermal runs whose steps would land on more frames or probe samples than
// any run can take: refused at input (see the output section).
constexpr double kMaxFrames = 1e6;
constexpr double kMaxProbeSamples = 1e7;
constexpr double kMaxSeriesRows = 1e6;  // energy.csv rows, kept in memory until the end
// A temperature (degC) given as a number, or as rows [t (s), T (degC)]
// with increasing times (into `rows`; the first value is returned).
double temperature_or_rows(ObjectReader& r, const std::string& key, std::optional<double> def,
                           std::vector<std::array<double, 2>>& rows) {
  const json* v = r.optional_raw(key);
  if (!v || !v->is_array()) return r.real(key, def, -273.15);
  const std::string tp = r.at(key);
  if (v->empty()) throw JobError(tp, "expected a number or rows [t, T]");
  for (std::size_t k = 0; k < v->size(); ++k) {
    const std::string rp = pointer_append(tp, k);
    const auto row = as_reals((*v)[k], rp, 2);
    if (k > 0 && !(row[0] > rows.back()[0])) throw JobError(rp, "times must increase from row to row");
    if (!(row[1] >= -273.15)) throw JobError(pointer_append(rp, 1), "must be >= -273.15 degC");
    rows.push_back({row[0], row[1]});
  }
  return rows.front()[1];
}
double finish_specific_heat_rows(std::vector<std::array<double, 2>>& rows, double& largest);
std::array<double, 3> finish_conductivity_rows(std::vector<std::array<double, 4>>& rows);

// A specific heat (J/(kg K)) given as a number, or as rows [T (degC), c]
// with increasing temperatures (into `rows`, left empty where every value
// is the same). Returns the number, or the rows' smallest value; `largest`
// is the number, or the rows' largest value.
double specific_heat_or_rows(ObjectReader& r, std::vector<std::array<double, 2>>& rows, double& largest) {
  const json* v = r.optional_raw("specific_heat");
  if (!v || !v->is_array()) return largest = r.real("specific_heat", std::nullopt, 0.0, true);
  const std::string tp = r.at("specific_heat");
  if (v->empty()) throw JobError(tp, "expected a number (J/kg/K) or rows [T (degC), c (J/kg/K)]");
  for (std::size_t k = 0; k < v->size(); ++k) {
    const std::string rp = pointer_append(tp, k);
    const auto row = as_reals((*v)[k], rp, 2);
    if (!(row[0] >= -273.15)) throw JobError(pointer_append(rp, 0), "must be >= -273.15 degC");
    if (k > 0 && !(row[0] > rows.back()[0])) throw JobError(pointer_append(rp, 0), "temperatures must increase from row to row");
    if (!(row[1] > 0)) {
      std::ostringstream os;
      os << "must be > 0 J/kg/K, found " << row[1];
      throw JobError(pointer_append(rp, 1), os.str());
    }
    rows.push_back({row[0], row[1]});
  }
  return finish_specific_heat_rows(rows, largest);
}

// The rows of a specific heat read or formed: returns their smallest value
// and sets `largest`; rows of one value are cleared (a constant).
double finish_specific_heat_rows(std::vector<std::array<double, 2>>& rows, double& largest) {
  double c_min = rows.front()[1], c_max = c_min;
  for (const auto& row : rows) {
    c_min = std::min(c_min, row[1]);
    c_max = std::max(c_max, row[1]);
  }
  if (c_min == c_max) rows.clear();
  largest = c_max;
  return c_min;
}

// materials.<m>.conductivity: [k11, k22, k33] (W/(m K)), or rows
// [T (degC), k11, k22, k33]; returns the values, or the table's largest.
std::array<double, 3> conductivity_or_rows(ObjectReader& r, std::vector<std::array<double, 4>>& rows) {
  const json& v = r.raw("conductivity");
  const std::string tp = r.at("conductivity");
  auto check = [](const std::string& rp, const std::vector<double>& row, int first) {
    for (int d = 0; d < 3; ++d)
      if (!(row[first + d] > 0)) {
        std::ostringstream os;
        os << "conductivity must be > 0 W/m/K, found " << row[first + d];
        throw JobError(pointer_append(rp, first + d), os.str());
      }
  };
  if (!v.is_array() || v.empty() || !v[0].is_array()) {
    const auto k = r.reals("conductivity", 3);
    check(tp, k, 0);
    return {k[0], k[1], k[2]};
  }
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string rp = pointer_append(tp, k);
    if (!v[k].is_array())
      throw JobError(rp, "expected a row [T (degC), k11, k22, k33 (W/m/K)], found " + json_type_name(v[k]));
    const auto row = as_reals(v[k], rp, 4);
    if (!(row[0] >= -273.15)) throw JobError(pointer_append(rp, 0), "must be >= -273.15 degC");
    if (k > 0 && !(row[0] > rows.back()[0])) throw JobError(pointer_append(rp, 0), "temperatures must increase from row to row");
    check(rp, row, 1);
    rows.push_back({row[0], row[1], row[2], row[3]});
  }
  return finish_conductivity_rows(rows);
}

// The rows of a conductivity read or formed: returns each column's largest
// value; rows that are all the same are cleared (a constant).
std::array<double, 3> finish_conductivity_rows(std::vector<std::array<double, 4>>& rows) {
  std::array<double, 3> largest{0, 0, 0};
  bool varies = false;
  for (const auto& row : rows)
    for (int d = 0; d < 3; ++d) {
      largest[d] = std::max(largest[d], row[d + 1]);
      varies = varies || row[d + 1] != rows.front()[d + 1];
    }
  if (!varies) rows.clear();
  return largest;
}

// A constituent's property of `n` values (1 or 2) for the mixture: a number
// (n = 1) or n numbers, or rows [T (degC), v1 .. vn] with increasing
// temperatures. Returns rows {T, v1, v2}; a constant is one row whose T is
// NaN. Every value must be > 0 (`unit` for the messages).
std::vector<std::array<double, 3>> constituent_rows(ObjectReader& r, const std::string& key, int n,
                                                    const std::string& unit) {
  const json& v = r.raw(key);
  const std::string tp = r.at(key);
  auto positive = [&](double x, const std::string& ptr) {
    if (!(x > 0)) throw JobError(ptr, "must be > 0 " + unit + ", found " + fmt_number(x));
  };
  const std::string row_form = n == 1 ? "[T (degC), value]" : "[T (degC), axial, transverse]";
  const std::string form = n == 1 ? "a number (" + unit + ") or rows " + row_form
                                  : "[axial, transverse] (" + unit + ") or rows " + row_form;
  if (v.is_number() && n == 1) {
    const double x = as_real(v, tp);
    positive(x, tp);
    return {{std::numeric_limits<double>::quiet_NaN(), x, 0.0}};
  }
  if (!v.is_array() || v.empty()) throw JobError(tp, "expected " + form + ", found " + json_type_name(v));
  if (!v[0].is_array()) {
    if (n == 1) throw JobError(tp, "expected " + form + ", found an array of numbers");
    const auto x = as_reals(v, tp, n);
    for (int d = 0; d < n; ++d) positive(x[d], pointer_append(tp, d));
    return {{std::numeric_limits<double>::quiet_NaN(), x[0], x[1]}};
  }
  std::vector<std::array<double, 3>> rows;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string rp = pointer_append(tp, k);
    if (!v[k].is_array()) throw JobError(rp, "expected a row " + row_form + ", found " + json_type_name(v[k]));
    const auto row = as_reals(v[k], rp, n + 1);
    if (!(row[0] >= -273.15)) throw JobError(pointer_append(rp, 0), "must be >= -273.15 degC");
    if (k > 0 && !(row[0] > rows.back()[0]))
      throw JobError(pointer_append(rp, 0), "temperatures must increase from row to row");
    for (int d = 1; d <= n; ++d) positive(row[d], pointer_append(rp, d));
    rows.push_back({row[0], row[1], n == 2 ? row[2] : 0.0});
  }
  return rows;
}

// The value `d` (1 or 2) of constituent rows at T: linear between the rows,
// held beyond them.
double constituent_at(const std::vector<std::array<double, 3>>& rows, double t, int d) {
  if (rows.size() == 1 || t <= rows.front()[0]) return rows.front()[d];
  if (t >= rows.back()[0]) return rows.back()[d];
  std::size_t k = 1;
  while (rows[k][0] < t) ++k;
  const auto &a = rows[k - 1], &b = rows[k];
  return a[d] + (b[d] - a[d]) * ((t - a[0]) / (b[0] - a[0]));
}

// The temperatures of the rows among `tables` (sorted, each once); empty
// when every one is a constant.
std::vector<double> row_temperatures(std::initializer_list<const std::vector<std::array<double, 3>>*> tables) {
  std::vector<double> ts;
  for (const auto* t : tables)
    if (!std::isnan(t->front()[0]))
      for (const auto& row : *t) ts.push_back(row[0]);
  std::sort(ts.begin(), ts.end());
  ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
  return ts;
}

// materials.<m>.mixture: the ply's thermal data from its matrix and fibres
// at a fibre volume fraction Vf: density and heat capacity per volume by
// the parallel rule, k11 (along the fibres) parallel, k22 and k33 (across
// them, where matrix and fibres lie in series) by the series rule. With
// rows, the ply's rows are the mixture at every temperature of the
// constituents' rows.
void parse_mixture(const json& v, const std::string& ptr, MaterialDef& m) {
  ObjectReader r(v, ptr);
  const double vf = r.real("fibre_volume_fraction", std::nullopt, 0.0, false, 1.0);
  ObjectReader mr(r.raw("matrix"), r.at("matrix"));
  ObjectReader fr(r.raw("fibre"), r.at("fibre"));
  r.finish();
  const double rho_m = mr.real("density", std::nullopt, 0.0, true);
  const auto c_m = constituent_rows(mr, "specific_heat", 1, "J/kg/K");
  const auto k_m = constituent_rows(mr, "conductivity", 1, "W/m/K");
  mr.finish();
  const double rho_f = fr.real("density", std::nullopt, 0.0, true);
  const auto c_f = constituent_rows(fr, "specific_heat", 1, "J/kg/K");
  const auto k_f = constituent_rows(fr, "conductivity", 2, "W/m/K");
  fr.finish();

  const double vm = 1.0 - vf;
  m.mixture_fibre_fraction = vf;
  m.density = vf * rho_f + vm * rho_m;
  m.mixture_matrix_mass_fraction = vm * rho_m / m.density;
  auto c_at = [&](double t) {
    return (vf * rho_f * constituent_at(c_f, t, 1) + vm * rho_m * constituent_at(c_m, t, 1)) / m.density;
  };
  auto k_at = [&](double t) -> std::array<double, 3> {
    const double km = constituent_at(k_m, t, 1);
    const double across = 1.0 / (vf / constituent_at(k_f, t, 2) + vm / km);
    return {vf * constituent_at(k_f, t, 1) + vm * km, across, across};
  };
  const auto tc = row_temperatures({&c_m, &c_f});
  if (tc.empty()) {
    m.specific_heat = m.specific_heat_max = c_at(0.0);
  } else {
    for (double t : tc) m.specific_heat_table.push_back({t, c_at(t)});
    m.specific_heat = finish_specific_heat_rows(m.specific_heat_table, m.specific_heat_max);
  }
  const auto tk = row_temperatures({&k_m, &k_f});
  if (tk.empty()) {
    m.conductivity = k_at(0.0);
  } else {
    for (double t : tk) {
      const auto k = k_at(t);
      m.conductivity_table.push_back({t, k[0], k[1], k[2]});
    }
    m.conductivity = finish_conductivity_rows(m.conductivity_table);
  }
}

// materials.<m>.crystallisation: the Nakamura kinetics of the matrix.
// matrix_mass_fraction: the matrix's share of the ply's mass where the
// material has a mixture, else negative.
MaterialDef::Crystallisation parse_crystallisation(const json& v, const std::string& ptr, double matrix_mass_fraction) {
  MaterialDef::Crystallisation c;
  c.present = true;
  c.pointer = ptr;
  ObjectReader r(v, ptr);
  if (r.has("matrix_latent_heat")) {
    if (r.has("latent_heat"))
      throw JobError(r.at("matrix_latent_heat"),
                     "give either latent_heat (J/kg of ply) or matrix_latent_heat (J/kg of matrix), not both");
    if (matrix_mass_fraction < 0)
      throw JobError(r.at("matrix_latent_heat"), "needs the material's 'mixture' (the matrix's share of the ply's "
                                                 "mass); without one, give latent_heat in J/kg of ply");
    c.matrix_latent_heat = r.real("matrix_latent_heat", std::nullopt, 0.0);
    c.latent_heat = c.matrix_latent_heat * matrix_mass_fraction;
  } else {
    c.latent_heat = r.real("latent_heat", std::nullopt, 0.0);
  }
  c.avrami_exponent = r.real("avrami_exponent", std::nullopt, 0.0, true, 10.0);
  c.initial = r.real("initial", 0.0, 0.0);
  if (!(c.initial <= 1.0)) throw JobError(r.at("initial"), "must be at most 1 (a relative crystallinity)");
  const json& rate = r.raw("rate");
  const std::string rp = r.at("rate");
  if (rate.is_array()) {
    if (rate.empty()) throw JobError(rp, "expected rows [T (degC), K (1/s)] or an object {k_max, t_max, half_width}");
    double k_max = 0;
    for (std::size_t k = 0; k < rate.size(); ++k) {
      const std::string kp = pointer_append(rp, k);
      const auto row = as_reals(rate[k], kp, 2);
      if (!(row[0] >= -273.15)) throw JobError(pointer_append(kp, 0), "must be >= -273.15 degC");
      if (k > 0 && !(row[0] > c.rate_rows.back()[0]))
        throw JobError(pointer_append(kp, 0), "temperatures must increase from row to row");
      if (!(row[1] >= 0)) throw JobError(pointer_append(kp, 1), "must be >= 0 1/s, found " + fmt_number(row[1]));
      c.rate_rows.push_back({row[0], row[1]});
      k_max = std::max(k_max, row[1]);
    }
    if (!(k_max > 0)) throw JobError(rp, "every rate is zero: the matrix would never crystallise");
  } else if (rate.is_object()) {
    ObjectReader g(rate, rp);
    c.k_max = g.real("k_max", std::nullopt, 0.0, true);
    c.t_max = g.real("t_max", std::nullopt, -273.15);
    c.half_width = g.real("half_width", std::nullopt, 0.0, true);
    g.finish();
  } else {
    throw JobError(rp, "expected rows [T (degC), K (1/s)] or an object {k_max, t_max, half_width}, found " +
                           json_type_name(rate));
  }
  if (const json* melting = r.optional_raw("melting")) {
    const std::string mp = r.at("melting");
    if (!melting->is_array() || melting->size() < 2)
      throw JobError(mp, "expected at least two rows [T (degC), share of the crystals still solid], from 1 to 0");
    for (std::size_t k = 0; k < melting->size(); ++k) {
      const std::string kp = pointer_append(mp, k);
      const auto row = as_reals((*melting)[k], kp, 2);
      if (!(row[0] >= -273.15)) throw JobError(pointer_append(kp, 0), "must be >= -273.15 degC");
      if (k > 0 && !(row[0] > c.melting_rows.back()[0]))
        throw JobError(pointer_append(kp, 0), "temperatures must increase from row to row");
      if (!(row[1] >= 0 && row[1] <= 1))
        throw JobError(pointer_append(kp, 1), "must be between 0 and 1 (a share of the crystals), found " +
                                                  fmt_number(row[1]));
      if (k > 0 && !(row[1] <= c.melting_rows.back()[1]))
        throw JobError(pointer_append(kp, 1), "the share still solid must not rise with the temperature");
      c.melting_rows.push_back({row[0], row[1]});
    }
    if (c.melting_rows.front()[1] != 1.0)
      throw JobError(pointer_append(pointer_append(mp, 0), 1), "must be 1: every crystal is solid below the melting");
    if (c.melting_rows.back()[1] != 0.0)
      throw JobError(pointer_append(pointer_append(mp, melting->size() - 1), 1),
                     "must be 0: every crystal has melted above the melting");
  }
  r.finish();
  return c;
}
}  // namespace

double rows_mean(const std::vector<std::array<double, 2>>& tab, double t0, double t1) {
  auto at = [&](double t) {  // linear between rows, held beyond the ends
    if (t <= tab.front()[0]) return tab.front()[1];
    if (t >= tab.back()[0]) return tab.back()[1];
    std::size_t k = 1;
    while (tab[k][0] < t) ++k;
    const double s = (t - tab[k - 1][0]) / (tab[k][0] - tab[k - 1][0]);
    return tab[k - 1][1] + s * (tab[k][1] - tab[k - 1][1]);
  };
  if (!(t1 > t0)) return at(t0);
  // Trapezoids between t0, the rows inside (t0, t1) and t1.
  double sum = 0, ta = t0, va = at(t0);
  for (const auto& row : tab) {
    if (row[0] <= t0) continue;
    if (row[0] >= t1) break;
    sum += 0.5 * (va + row[1]) * (row[0] - ta);
    ta = row[0];
    va = row[1];
  }
  sum += 0.5 * (va + at(t1)) * (t1 - ta);
  return sum / (t1 - t0);
}

std::array<double, 3> rows_at(const std::vector<std::array<double, 4>>& tab, double t) {
  if (t <= tab.front()[0]) return {tab.front()[1], tab.front()[2], tab.front()[3]};
  if (t >= tab.back()[0]) return {tab.back()[1], tab.back()[2], tab.back()[3]};
  const auto it = std::upper_bound(tab.begin(), tab.end(), t, [](double v, const auto& row) { return v < row[0]; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double s = (t - a[0]) / (b[0] - a[0]);
  return {a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]), a[3] + s * (b[3] - a[3])};
}

std::array<double, 3> MotionDef::force_at(double t) const {
  return force_table.empty() ? force : rows_at(force_table, t);
}

std::array<double, 3> MotionDef::prescribed(double t) const {
  if (kind == Kind::Velocity) return {velocity[0] * t, velocity[1] * t, velocity[2] * t};
  if (kind == Kind::Displacement) return rows_at(table, t);
  return {0, 0, 0};
}

double ToolDef::temperature_over(double t0, double t1) const {
  return temperature_table.empty() ? temperature : rows_mean(temperature_table, t0, t1);
}

bool RegionDef::contains(double x, double y) const {
  switch (kind) {
    case Kind::All: return true;
    case Kind::Circle: return (x - centre[0]) * (x - centre[0]) + (y - centre[1]) * (y - centre[1]) <= radius * radius;
    case Kind::Box: return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1];
  }
  return false;
}

namespace {
// materials.<m>.card: a material card (a file holding a material object,
// share/materials) whose keys the material takes where it does not give
// them itself. The "card" key stays, naming the file as given.
void resolve_material_cards(json& doc, const std::filesystem::path& base_dir) {
  if (!doc.is_object() || !doc.contains("materials") || !doc["materials"].is_object()) return;
  for (auto it = doc["materials"].begin(); it != doc["materials"].end(); ++it) {
    json& m = it.value();
    if (!m.is_object() || !m.contains("card")) continue;
    const std::string ptr = pointer_append(pointer_append("/materials", it.key()), "card");
    if (!m["card"].is_string()) throw JobError(ptr, "expected the path of a material card, found " + json_type_name(m["card"]));
    const std::filesystem::path given = m["card"].get<std::string>();
    const std::filesystem::path file = given.is_absolute() ? given : base_dir / given;
    if (!std::filesystem::is_regular_file(file)) throw JobError(ptr, "material card '" + file.string() + "' not found");
    json card;
    try {
      card = read_job_document(file);
    } catch (const JobError& e) {
      throw JobError(ptr, std::string("material card: ") + e.what());
    }
    if (!card.is_object()) throw JobError(ptr, "the material card '" + file.string() + "' holds " + json_type_name(card) + ", not a material object");
    if (card.contains("card")) throw JobError(ptr, "the material card '" + file.string() + "' names another card; a card holds the material itself");
    for (auto c = card.begin(); c != card.end(); ++c)
      if (!m.contains(c.key())) m[c.key()] = c.value();
  }
}
}  // namespace

std::filesystem::path material_card_file(const Job& job, const MaterialDef& m) {
  const json* mats = job.document.contains("materials") ? &job.document["materials"] : nullptr;
  if (!mats || !mats->contains(m.name) || !(*mats)[m.name].contains("card")) return {};
  const std::filesystem::path given = (*mats)[m.name]["card"].get<std::string>();
  return std::filesystem::absolute(given.is_absolute() ? given : job.base_dir / given).lexically_normal();
}

json read_job_document(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw JobError("", "cannot open job file '" + file.string() + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    // Translate the byte offset into line:column for the user.
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < std::min<std::size_t>(e.byte, text.size()); ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    std::string what = e.what();
    const auto pos = what.find("syntax error");
    if (pos != std::string::npos) what = what.substr(pos);
    throw JobError("", file.string() + ":" + std::to_string(line) + ":" + std::to_string(col) +
                           ": not valid JSON (" + what + ")");
  }
  resolve_material_cards(doc, file.has_parent_path() ? file.parent_path() : std::filesystem::path("."));
  return doc;
}

namespace {
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

bool is_index(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

void set_path(json& node, const std::vector<std::string>& keys, std::size_t k, const json& value,
              const std::string& shown) {
  const std::string& key = keys[k];
  const bool last = k + 1 == keys.size();
  if (key == "*") {
    if (!node.is_array() && !node.is_object())
      throw JobError("", "--set " + shown + ": '*' needs an array or object");
    for (auto& child : node) {
      if (last) child = value;
      else set_path(child, keys, k + 1, value, shown);
    }
    return;
  }
  if (node.is_array()) {
    if (!is_index(key)) throw JobError("", "--set " + shown + ": '" + key + "' is not an array index");
    const std::size_t i = std::stoul(key);
    if (i >= node.size())
      throw JobError("", "--set " + shown + ": index " + key + " out of range (size " + std::to_string(node.size()) + ")");
    if (last) node[i] = value;
    else set_path(node[i], keys, k + 1, value, shown);
    return;
  }
  if (node.is_null()) node = json::object();
  if (!node.is_object()) throw JobError("", "--set " + shown + ": '" + key + "' is inside a non-object value");
  if (last) node[key] = value;
  else set_path(node[key], keys, k + 1, value, shown);
}
}  // namespace

void apply_set(json& doc, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw JobError("", "--set expects PATH=VALUE, found '" + assignment + "'");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  json value;
  try {
    value = json::parse(text);
  } catch (...) {
    value = text;  // a bare word is a string
  }
  set_path(doc, split(path, '.'), 0, value, assignment);
}

void apply_set_value(json& doc, const std::string& path, const json& value) {
  set_path(doc, split(path, '.'), 0, value, path + "=" + value.dump());
}

namespace {

MeshDef parse_mesh(const json& j, const std::string& ptr, const std::filesystem::path& base) {
  ObjectReader r(j, ptr);
  MeshDef m;
  if (r.has("file")) {
    m.kind = MeshDef::Kind::File;
    const std::string f = r.text("file");
    m.file = std::filesystem::path(f).is_absolute() ? std::filesystem::path(f) : base / f;
    if (!std::filesystem::exists(m.file)) throw JobError(r.at("file"), "mesh file '" + m.file.string() + "' not found");
    m.reorder = r.boolean("reorder", true);
    m.scale = r.real("scale", 1.0, 0.0, true);
  } else {
    const std::string gen = r.choice("generator", {"rectangle"});
    (void)gen;
    if (r.has("reorder"))
      throw JobError(r.at("reorder"),
                     "only for a mesh read from a file: the rectangle generator numbers its triangles row by row");
    if (r.has("scale"))
      throw JobError(r.at("scale"), "only for a mesh read from a file: the rectangle generator's sizes are in metres");
    const auto o = r.reals("origin", 3, std::vector<double>{0, 0, 0});
    const auto s = r.reals("size", 2);
    for (int d = 0; d < 2; ++d)
      if (!(s[d] > 0)) throw JobError(pointer_append(r.at("size"), d), "must be > 0, found " + std::to_string(s[d]));
    const auto dv = r.raw("divisions");
    if (!dv.is_array() || dv.size() != 2) throw JobError(r.at("divisions"), "expected two integers [nx, ny]");
    for (int d = 0; d < 2; ++d) {
      if (!dv[d].is_number_integer() || dv[d].get<long long>() < 1 || dv[d].get<long long>() > 100000)
        throw JobError(pointer_append(r.at("divisions"), d), "expected an integer >= 1, found " + json_type_name(dv[d]));
      m.divisions[d] = dv[d].get<int>();
    }
    m.crossed = r.choice("pattern", {"alternating", "crossed"}, std::string("alternating")) == "crossed";
    m.origin = {o[0], o[1], o[2]};
    m.size = {s[0], s[1]};
  }
  r.finish();
  return m;
}

int find_index(const std::vector<std::string>& names, const std::string& name) {
  auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

std::string unknown_name(const std::string& what, const std::string& name, const std::vector<std::string>& known) {
  std::string msg = "unknown " + what + " '" + name + "'";
  const std::string dym = did_you_mean(name, known);
  if (!dym.empty()) msg += "; " + dym;
  msg += known.empty() ? "; none is defined" : "; known: " + join(known);
  return msg;
}

}  // namespace

std::string describe_mixture(const MaterialDef& m) {
  if (m.mixture_fibre_fraction < 0) return "";
  char line[512];
  std::string s;
  std::snprintf(line, sizeof line,
                "thermal data from its mixture at a fibre volume fraction of %g (matrix mass fraction %.4g): density "
                "%.6g kg/m3, ",
                m.mixture_fibre_fraction, m.mixture_matrix_mass_fraction, m.density);
  s = line;
  if (m.specific_heat_table.empty())
    std::snprintf(line, sizeof line, "specific heat %.6g J/(kg K), ", m.specific_heat);
  else
    std::snprintf(line, sizeof line, "specific heat %.6g to %.6g J/(kg K) over %zu rows, ", m.specific_heat,
                  m.specific_heat_max, m.specific_heat_table.size());
  s += line;
  if (m.conductivity_table.empty()) {
    std::snprintf(line, sizeof line, "conductivity %.6g, %.6g, %.6g W/(m K)", m.conductivity[0], m.conductivity[1],
                  m.conductivity[2]);
  } else {
    double k11[2] = {m.conductivity[0], m.conductivity[0]};
    for (const auto& row : m.conductivity_table) k11[0] = std::min(k11[0], row[1]);
    std::snprintf(line, sizeof line, "conductivity k11 %.6g to %.6g, k22 = k33 %.6g to %.6g W/(m K) over %zu rows",
                  k11[0], k11[1], m.k33_range()[0], m.k33_range()[1], m.conductivity_table.size());
  }
  return s + line;
}

namespace {
void parse_job_into(Job& job);
}  // namespace

Job parse_job(const json& given, const std::filesystem::path& file) {
  Job job;
  job.file = file;
  job.base_dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  job.document = given;
  resolve_material_cards(job.document, job.base_dir);  // a document built in memory
  try {
    parse_job_into(job);
  } catch (const JobError& e) {
    throw with_material_card(job, e);
  }
  return job;
}

JobError with_material_card(const Job& job, const JobError& e) {
  // An error in a value the material took from its card: say which card.
  static const std::string prefix = "/materials/";
  const std::string& ptr = e.pointer();
  if (ptr.rfind(prefix, 0) != 0 || !job.document.contains("materials")) return e;
  const auto slash = ptr.find('/', prefix.size());
  if (slash == std::string::npos) return e;
  const auto end = ptr.find('/', slash + 1);
  const std::string name = ptr.substr(prefix.size(), slash - prefix.size());
  const std::string key = ptr.substr(slash + 1, end == std::string::npos ? std::string::npos : end - slash - 1);
  const json& mats = job.document["materials"];
  if (!mats.is_object() || !mats.contains(name) || !mats[name].is_object() || !mats[name].contains("card") ||
      key == "card" || !mats[name]["card"].is_string())
    return e;
  const std::filesystem::path given = mats[name]["card"].get<std::string>();
  const std::filesystem::path file = given.is_absolute() ? given : job.base_dir / given;
  json card;
  try {
    card = read_job_document(file);
  } catch (const JobError&) {
    return e;
  }
  if (!card.is_object() || !card.contains(key) || card[key] != mats[name][key]) return e;
  std::string what = e.what();
  if (what.rfind(ptr + ": ", 0) == 0) what = what.substr(ptr.size() + 2);
  return JobError(ptr, what + " (from the material card '" + file.lexically_normal().string() + "')");
}

namespace {
// Rows [t, x, y, z] of a non-empty array (at p), times increasing.
std::vector<std::array<double, 4>> rows_of_four(const json& rows, const std::string& p) {
  std::vector<std::array<double, 4>> out;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto row = as_reals(rows[k], pointer_append(p, k), 4);
    if (k > 0 && !(row[0] > out.back()[0])) throw JobError(pointer_append(p, k), "times must increase from row to row");
    out.push_back({row[0], row[1], row[2], row[3]});
  }
  return out;
}

// A motion given by "velocity" (m/s) or by "displacement" rows
// [t, dx, dy, dz] (m): a tool's, or a gripper's anchor's.
void read_moved(ObjectReader& mo, MotionDef& motion) {
  if (mo.optional_raw("velocity")) {
    motion.kind = MotionDef::Kind::Velocity;
    const auto v = mo.reals("velocity", 3);
    motion.velocity = {v[0], v[1], v[2]};
    return;
  }
  motion.kind = MotionDef::Kind::Displacement;
  const json& tab = mo.raw("displacement");
  const std::string tp = mo.at("displacement");
  if (!tab.is_array() || tab.empty()) throw JobError(tp, "expected rows [t, dx, dy, dz]");
  motion.table = rows_of_four(tab, tp);
}

void parse_job_into(Job& job) {
  const json& doc = job.document;
  ObjectReader top(doc, "");
  const std::string format = top.text("format");
  if (format != "thermostamp-job/1")
    throw JobError("/format", "unsupported format '" + format + "'; this version reads 'thermostamp-job/1'");
  job.name = top.text("name");
  top.text("description", std::string());
  if (job.name.empty() || job.name.find_first_of("/\\") != std::string::npos)
    throw JobError("/name", "must be a non-empty name without '/' (it names the output folder)");
  {
    ObjectReader t(top.raw("time"), "/time");
    job.t_end = t.real("end", std::nullopt, 0.0, true);
    t.finish();
  }

  // plugin_paths (optional): extra folders searched for plugin libraries.
  for (const auto& p : top.texts("plugin_paths", std::vector<std::string>{})) {
    std::filesystem::path path(p);
    job.plugin_paths.push_back(path.is_absolute() ? path : job.base_dir / path);
  }

  // materials
  std::vector<std::string> material_names;
  {
    const json& mats = top.raw("materials");
    if (!mats.is_object() || mats.empty())
      throw JobError("/materials", "expected an object with at least one material, found " + json_type_name(mats));
    for (auto it = mats.begin(); it != mats.end(); ++it) {
      MaterialDef m;
      m.name = it.key();
      m.pointer = pointer_append("/materials", it.key());
      ObjectReader r(it.value(), m.pointer);
      if (const json* mix = r.optional_raw("mixture")) {
        for (const char* key : {"density", "specific_heat", "conductivity"})
          if (r.has(key))
            throw JobError(r.at(key), "give either 'mixture' or density, specific_heat and conductivity, not both");
        parse_mixture(*mix, r.at("mixture"), m);
        m.has_thermal = true;
      }
      if (r.has("density") && !m.has_thermal) m.density = r.real("density", std::nullopt, 0.0, true);
      if (!m.has_thermal && (r.has("specific_heat") || r.has("conductivity"))) {
        m.has_thermal = true;
        m.density = r.real("density", std::nullopt, 0.0, true);
        m.specific_heat = specific_heat_or_rows(r, m.specific_heat_table, m.specific_heat_max);
        m.conductivity = conductivity_or_rows(r, m.conductivity_table);
      }
      if (const json* v = r.optional_raw("crystallisation"))
        m.crystallisation = parse_crystallisation(*v, r.at("crystallisation"),
                                                  m.mixture_fibre_fraction >= 0 ? m.mixture_matrix_mass_fraction : -1.0);
      if (const json* v = r.optional_raw("membrane")) m.membrane = *v;
      if (const json* v = r.optional_raw("bending")) m.bending = *v;
      if (const json* v = r.optional_raw("in_plane_bending")) {
        if (!r.has("bending"))
          throw JobError(r.at("in_plane_bending"), "needs a bending law too (materials." + m.name + ".bending)");
        m.in_plane_bending = *v;
      }
      r.declare("source");
      r.declare("description");
      r.declare("card");  // taken in by resolve_material_cards
      r.finish();
      material_names.push_back(m.name);
      job.materials.push_back(std::move(m));
    }
  }

  // parts
  std::vector<std::string> part_names;
  {
    const json& parts = top.raw("parts");
    if (!parts.is_array() || parts.empty())
      throw JobError("/parts", "expected an array with at least one part, found " + json_type_name(parts));
    for (std::size_t i = 0; i < parts.size(); ++i) {
      PartDef p;
      p.pointer = pointer_append("/parts", i);
      ObjectReader r(parts[i], p.pointer);
      p.name = r.text("name");
      if (find_index(part_names, p.name) >= 0) throw JobError(r.at("name"), "duplicate part name '" + p.name + "'");
      p.mesh = parse_mesh(r.raw("mesh"), r.at("mesh"), job.base_dir);
      p.thickness = r.real("thickness", std::nullopt, 0.0, true);
      const std::string mat = r.text("material");
      p.material = find_index(material_names, mat);
      if (p.material < 0) throw JobError(r.at("material"), unknown_name("material", mat, material_names));
      const auto f = r.reals("fibre_direction", 3, std::vector<double>{1, 0, 0});
      p.fibre_direction = {f[0], f[1], f[2]};
      if (f[0] * f[0] + f[1] * f[1] + f[2] * f[2] == 0.0)
        throw JobError(r.at("fibre_direction"), "must not be the zero vector");
      p.element = r.text("element", std::string("shell_rf_t3"));
      if (const json* it = r.optional_raw("initial_temperature"); it && it->is_object()) {
        ObjectReader g(*it, r.at("initial_temperature"));
        p.initial_results = job.base_dir / g.text("results");
        std::error_code ec;
        if (!std::filesystem::is_regular_file(p.initial_results, ec))
          throw JobError(g.at("results"), "cannot read the results file '" + p.initial_results.string() + "'");
        p.initial_results_part = g.text("part", std::string());
        p.initial_results_time = g.real("time", -1.0);
        if (g.has("time") && p.initial_results_time < 0) throw JobError(g.at("time"), "must be >= 0");
        g.finish();
      } else {
        p.initial_temperature = r.real("initial_temperature", 20.0, -273.15);
      }
      p.thickness_layers = static_cast<int>(r.integer("thickness_layers", 8, 1, 10000));
      p.flip = r.boolean("flip", false);
      r.finish();
      part_names.push_back(p.name);
      job.parts.push_back(std::move(p));
    }
  }

  // tools
  std::vector<std::string> tool_names;
  if (const json* tools = top.optional_raw("tools")) {
    if (!tools->is_array()) throw JobError("/tools", "expected an array, found " + json_type_name(*tools));
    for (std::size_t i = 0; i < tools->size(); ++i) {
      ToolDef t;
      t.pointer = pointer_append("/tools", i);
      ObjectReader r((*tools)[i], t.pointer);
      t.name = r.text("name");
      if (find_index(tool_names, t.name) >= 0 || find_index(part_names, t.name) >= 0)
        throw JobError(r.at("name"), "name '" + t.name + "' is already used by another part or tool");
      ObjectReader s(r.raw("surface"), r.at("surface"));
      t.surface.type = s.choice("type", {"plane", "sphere", "revolved", "mesh"});
      if (t.surface.type == "plane") {
        const auto p = s.reals("point", 3);
        const auto n = s.reals("normal", 3);
        t.surface.point = {p[0], p[1], p[2]};
        t.surface.normal = {n[0], n[1], n[2]};
        if (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] == 0.0) throw JobError(s.at("normal"), "must not be the zero vector");
      } else if (t.surface.type == "sphere") {
        const auto c = s.reals("centre", 3);
        t.surface.centre = {c[0], c[1], c[2]};
        t.surface.radius = s.real("radius", std::nullopt, 0.0, true);
      } else if (t.surface.type == "revolved") {
        if (const json* ax = s.optional_raw("axis")) {
          ObjectReader a(*ax, s.at("axis"));
          const auto o = a.reals("origin", 3, std::vector<double>{0, 0, 0});
          const auto d = a.reals("direction", 3, std::vector<double>{0, 0, 1});
          t.surface.axis_origin = {o[0], o[1], o[2]};
          t.surface.axis_direction = {d[0], d[1], d[2]};
          if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] == 0.0)
            throw JobError(a.at("direction"), "must not be the zero vector");
          a.finish();
        }
        const json& prof = s.raw("profile");
        const std::string pp = s.at("profile");
        if (!prof.is_array() || prof.empty())
          throw JobError(pp, "expected a non-empty array of {\"line\": ...} or {\"arc\": ...} pieces");
        for (std::size_t k = 0; k < prof.size(); ++k) {
          const std::string kp = pointer_append(pp, k);
          ObjectReader g(prof[k], kp);
          ProfileSegment seg;
          auto point2 = [&](const json& v, const std::string& ptr) {
            const auto q = as_reals(v, ptr, 2);
            if (q[0] < 0) throw JobError(ptr, "the radius r must be >= 0");
            return std::array<double, 2>{q[0], q[1]};
          };
          if (const json* line = g.optional_raw("line")) {
            if (!line->is_array() || line->size() != 2)
              throw JobError(g.at("line"), "expected two (r, z) points [[r0, z0], [r1, z1]]");
            seg.a = point2((*line)[0], pointer_append(g.at("line"), 0));
            seg.b = point2((*line)[1], pointer_append(g.at("line"), 1));
          } else if (const json* arc = g.optional_raw("arc")) {
            ObjectReader c(*arc, g.at("arc"));
            seg.arc = true;
            seg.a = point2(c.raw("from"), c.at("from"));
            seg.b = point2(c.raw("to"), c.at("to"));
            const auto cc = c.reals("centre", 2);
            seg.centre = {cc[0], cc[1]};
            c.finish();
            const double ra = std::hypot(seg.a[0] - seg.centre[0], seg.a[1] - seg.centre[1]);
            const double rb = std::hypot(seg.b[0] - seg.centre[0], seg.b[1] - seg.centre[1]);
            if (!(ra > 0) || std::abs(ra - rb) > 1e-6 * ra)
              throw JobError(c.at("centre"), "the arc's end points are not at the same distance from its centre (" +
                                                 std::to_string(ra) + " and " + std::to_string(rb) + " m)");
            const double cr = (seg.a[0] - seg.centre[0]) * (seg.b[1] - seg.centre[1]) -
                              (seg.a[1] - seg.centre[1]) * (seg.b[0] - seg.centre[0]);
            const double dt = (seg.a[0] - seg.centre[0]) * (seg.b[0] - seg.centre[0]) +
                              (seg.a[1] - seg.centre[1]) * (seg.b[1] - seg.centre[1]);
            if (std::abs(cr) < 1e-12 * ra * ra && dt < 0)
              throw JobError(g.at("arc"), "a half circle is ambiguous: split it into two arcs");
          } else {
            throw JobError(kp, "expected {\"line\": [[r0, z0], [r1, z1]]} or {\"arc\": {\"from\", \"to\", \"centre\"}}");
          }
          g.finish();
          if (std::hypot(seg.b[0] - seg.a[0], seg.b[1] - seg.a[1]) <= 0)
            throw JobError(kp, "a profile piece of zero length");
          t.surface.profile.push_back(seg);
        }
      } else {  // mesh
        const std::string f = s.text("file");
        t.surface.file = job.base_dir / f;
        t.surface.flip = s.boolean("flip", false);
        t.surface.scale = s.real("scale", 1.0, 0.0, true);
        std::error_code ec;
        if (!std::filesystem::is_regular_file(t.surface.file, ec))
          throw JobError(s.at("file"), "cannot read the tool mesh '" + t.surface.file.string() + "'");
      }
      s.finish();
      if (const json* m = r.optional_raw("motion")) {
        ObjectReader mo(*m, r.at("motion"));
        const bool hv = mo.optional_raw("velocity") != nullptr, hd = mo.optional_raw("displacement") != nullptr,
                   hf = mo.optional_raw("force") != nullptr;
        if (int(hv) + int(hd) + int(hf) != 1)
          throw JobError(mo.pointer(), "give exactly one of \"velocity\", \"displacement\" or \"force\"");
        if (hv || hd) {
          read_moved(mo, t.motion);
        } else {
          t.motion.kind = MotionDef::Kind::Force;
          const json& fj = mo.raw("force");
          const std::string fp = mo.at("force");
          if (fj.is_array() && !fj.empty() && fj.front().is_array()) {  // rows [t, fx, fy, fz]
            auto& tab = t.motion.force_table;
            tab = rows_of_four(fj, fp);
            // The tool moves along one line: every row along the first that
            // is not zero (either way, or zero).
            bool found = false;
            for (std::size_t k = 0; k < tab.size(); ++k) {
              const sdk::Vec3 f{tab[k][1], tab[k][2], tab[k][3]};
              const double f2 = sdk::dot(f, f);
              if (f2 == 0.0) continue;
              if (!found) {
                found = true;
                t.motion.force = f;
              } else if (const sdk::Vec3 c = sdk::cross(t.motion.force, f);
                         sdk::dot(c, c) > 1e-18 * sdk::dot(t.motion.force, t.motion.force) * f2) {
                throw JobError(pointer_append(fp, k), "every row's force must lie along the first row that is not "
                                                      "zero (the tool moves along one line)");
              }
            }
            if (!found) throw JobError(fp, "must not be zero in every row (the tool moves along the force)");
          } else {
            const auto f = mo.reals("force", 3);
            t.motion.force = {f[0], f[1], f[2]};
            if (f[0] * f[0] + f[1] * f[1] + f[2] * f[2] == 0.0)
              throw JobError(fp, "must not be the zero vector (the tool moves along the force)");
          }
          t.motion.mass = mo.real("mass", std::nullopt, 0.0, true);
          t.motion.damping = mo.real("damping", 0.0, 0.0);
        }
        mo.finish();
      }
      t.temperature = temperature_or_rows(r, "temperature", 20.0, t.temperature_table);
      r.finish();
      tool_names.push_back(t.name);
      job.tools.push_back(std::move(t));
    }
  }

  auto find_body = [&](const std::string& name, const std::string& ptr) {
    BodyDef b;
    b.index = find_index(part_names, name);
    if (b.index >= 0) return b;
    b.index = find_index(tool_names, name);
    b.is_tool = true;
    if (b.index >= 0) return b;
    std::vector<std::string> all = part_names;
    all.insert(all.end(), tool_names.begin(), tool_names.end());
    throw JobError(ptr, unknown_name("part or tool", name, all));
  };

  // "part": a name or "*" (every part).
  auto select_parts = [&](ObjectReader& r) {
    std::vector<int> parts;
    const std::string part = r.text("part");
    if (part == "*") {
      for (std::size_t p = 0; p < job.parts.size(); ++p) parts.push_back(static_cast<int>(p));
    } else {
      const int p = find_index(part_names, part);
      if (p < 0) throw JobError(r.at("part"), unknown_name("part", part, part_names));
      parts.push_back(p);
    }
    return parts;
  };
  // "dofs": a list of x, y, z (default all).
  auto read_dofs = [](ObjectReader& r, std::array<bool, 3>& dofs) {
    const auto names = r.texts("dofs", std::vector<std::string>{"x", "y", "z"});
    for (std::size_t k = 0; k < names.size(); ++k) {
      const auto& dof = names[k];
      if (dof != "x" && dof != "y" && dof != "z")
        throw JobError(pointer_append(r.at("dofs"), k), "unknown dof '" + dof + "'; valid: x, y, z");
      dofs[dof[0] - 'x'] = true;
    }
  };

  // interactions
  if (const json* inter = top.optional_raw("interactions")) {
    if (!inter->is_array()) throw JobError("/interactions", "expected an array, found " + json_type_name(*inter));
    for (std::size_t i = 0; i < inter->size(); ++i) {
      const std::string ptr = pointer_append("/interactions", i);
      ObjectReader r((*inter)[i], ptr);
      const std::string type = r.choice("type", {"contact", "heat_exchange"});
      if (type == "contact") {
        ContactDef c;
        c.pointer = ptr;
        c.handler = r.text("handler", std::string("penalty_node_surface"));
        const auto between = r.texts("between");
        if (between.size() != 2) throw JobError(r.at("between"), "expected two body names");
        c.first = find_body(between[0], pointer_append(r.at("between"), 0));
        c.second = find_body(between[1], pointer_append(r.at("between"), 1));
        if (c.first.is_tool && c.second.is_tool)
          throw JobError(r.at("between"), "contact between two rigid tools is not meaningful");
        if (c.first.is_tool) std::swap(c.first, c.second);  // first is always a part
        c.params = json::object();
        for (auto it = (*inter)[i].begin(); it != (*inter)[i].end(); ++it)
          if (it.key() != "type" && it.key() != "handler" && it.key() != "between") c.params[it.key()] = it.value();
        const bool self = c.params.contains("self") && c.params["self"].is_boolean() && c.params["self"].get<bool>();
        if (!c.first.is_tool && !c.second.is_tool && c.first.index == c.second.index && !self)
          throw JobError(r.at("between"), "a body in contact with itself needs \"self\": true");
        job.contacts.push_back(std::move(c));
        continue;  // the handler's descriptor checks the remaining keys
      }
      HeatExchangeDef h;
      h.pointer = ptr;
      h.parts = select_parts(r);
      const std::string face = r.choice("face", {"top", "bottom", "both"});
      h.top = face != "bottom";
      h.bottom = face != "top";
      h.emissivity = r.real("emissivity", 0.0, 0.0, false, 1.0);
      // h may be left out where the face radiates.
      h.h = r.real("h", h.emissivity > 0 ? std::optional<double>(0.0) : std::nullopt, 0.0);
      h.ambient = temperature_or_rows(r, "ambient", std::nullopt, h.ambient_table);
      if (const json* reg = r.optional_raw("region")) {
        ObjectReader g(*reg, r.at("region"));
        if (g.has("circle")) {
          ObjectReader c(g.raw("circle"), g.at("circle"));
          const auto ctr = c.reals("centre", 2);
          h.region.kind = RegionDef::Kind::Circle;
          h.region.centre = {ctr[0], ctr[1]};
          h.region.radius = c.real("radius", std::nullopt, 0.0, true);
          c.finish();
        } else if (g.has("box")) {
          const json& b = g.raw("box");
          if (!b.is_array() || b.size() != 2) throw JobError(g.at("box"), "expected [[xmin, ymin], [xmax, ymax]]");
          const auto lo = as_reals(b[0], pointer_append(g.at("box"), 0), 2);
          const auto hi = as_reals(b[1], pointer_append(g.at("box"), 1), 2);
          if (!(hi[0] > lo[0] && hi[1] > lo[1])) throw JobError(g.at("box"), "max corner must be above the min corner");
          h.region.kind = RegionDef::Kind::Box;
          h.region.lo = {lo[0], lo[1]};
          h.region.hi = {hi[0], hi[1]};
        } else {
          throw JobError(r.at("region"), "expected { \"circle\": {...} } or { \"box\": [[...], [...]] }");
        }
        g.finish();
      }
      r.finish();
      job.heat_exchanges.push_back(std::move(h));
    }
  }

  if (const json* c = top.optional_raw("constraints")) {
    if (!c->is_array()) throw JobError("/constraints", "expected an array, found " + json_type_name(*c));
    int grippers = 0;  // default names gripper1, gripper2, ...
    for (std::size_t i = 0; i < c->size(); ++i) {
      ConstraintDef d;
      d.pointer = pointer_append("/constraints", i);
      ObjectReader r((*c)[i], d.pointer);
      const std::string type = r.choice("type", {"symmetry", "fix", "velocity", "force", "gripper"});
      d.parts = select_parts(r);
      if (type == "symmetry") {
        d.type = ConstraintDef::Type::Symmetry;
        const std::string plane = r.choice("plane", {"x", "y", "z"});
        d.plane = plane[0] - 'x';
      } else {
        const json& box = r.raw("box");
        if (!box.is_array() || box.size() != 2) throw JobError(r.at("box"), "expected [[x0, y0, z0], [x1, y1, z1]]");
        const auto lo = as_reals(box[0], pointer_append(r.at("box"), 0), 3);
        const auto hi = as_reals(box[1], pointer_append(r.at("box"), 1), 3);
        d.lo = {lo[0], lo[1], lo[2]};
        d.hi = {hi[0], hi[1], hi[2]};
        if (type == "fix") {
          d.type = ConstraintDef::Type::Fix;
          read_dofs(r, d.dofs);
        } else if (type == "force") {
          d.type = ConstraintDef::Type::Force;
          const auto f = r.reals("force", 3);
          d.force = {f[0], f[1], f[2]};
          d.ramp = r.real("ramp", 0.0, 0.0);
        } else if (type == "gripper") {
          d.type = ConstraintDef::Type::Gripper;
          d.name = r.text("name", "gripper" + std::to_string(++grippers));
          if (d.name.empty()) throw JobError(r.at("name"), "must not be empty");
          for (const ConstraintDef& o : job.constraints)
            if (o.type == ConstraintDef::Type::Gripper && o.name == d.name)
              throw JobError(r.at("name"), "a gripper named '" + d.name + "' is already defined at " + o.pointer);
          const auto a = r.reals("anchor", 3);
          d.anchor = {a[0], a[1], a[2]};
          d.stiffness = r.real("stiffness", std::nullopt, 0.0, true);
          d.preload = r.real("preload", 0.0, 0.0);
          d.ramp = r.real("ramp", 0.0, 0.0);
          d.tension_only = r.boolean("tension_only", true);
          const std::string jaws = r.choice("jaws", {"flexible", "rigid", "swivelling"}, std::string("flexible"));
          d.rigid = jaws != "flexible";
          d.swivelling = jaws == "swivelling";
          if (r.optional_raw("release")) d.release = r.real("release", std::nullopt, 0.0, true);
          if (const json* m = r.optional_raw("anchor_motion")) {
            ObjectReader mo(*m, r.at("anchor_motion"));
            const bool hv = mo.optional_raw("velocity") != nullptr, hd = mo.optional_raw("displacement") != nullptr;
            if (int(hv) + int(hd) != 1)
              throw JobError(mo.pointer(), "give exactly one of \"velocity\" or \"displacement\"");
            read_moved(mo, d.anchor_motion);
            mo.finish();
          }
        } else {
          d.type = ConstraintDef::Type::Velocity;
          const auto v = r.reals("velocity", 3);
          d.velocity = {v[0], v[1], v[2]};
          read_dofs(r, d.dofs);  // only these components are prescribed
        }
      }
      r.finish();
      job.constraints.push_back(d);
    }
  }

  // solvers
  if (const json* s = top.optional_raw("solvers")) {
    ObjectReader r(*s, "/solvers");
    if (const json* m = r.optional_raw("mechanics")) {
      job.mechanics = true;
      ObjectReader mr(*m, "/solvers/mechanics");
      MechanicsDef& md = job.mechanics_settings;
      md.dt_safety = mr.real("dt_safety", 0.8, 0.0, true, 2.0);
      if (const json* ms = mr.optional_raw("mass_scaling")) {
        ObjectReader sr(*ms, "/solvers/mechanics/mass_scaling");
        md.target_dt = sr.real("target_dt", 0.0, 0.0);
        md.mass_factor = sr.real("factor", 1.0, 1.0);
        sr.finish();
      }
      md.damping = mr.real("damping", 0.0, 0.0);
      md.damping_normal = mr.choice("damping_direction", {"all", "normal"}, std::string("all")) == "normal";
      const auto g = mr.reals("gravity", 3, std::vector<double>{0, 0, 0});
      md.gravity = {g[0], g[1], g[2]};
      md.energy_tolerance = mr.real("energy_tolerance", 0.05, 0.0, true);
      md.contact_schedule =
          mr.choice("contact_schedule", {"auto", "beside", "in_turn", "by_part"}, std::string("auto"));
      md.bending_subcycles = static_cast<int>(mr.integer("bending_subcycles", 1, 1, 64));
      mr.finish();
    }
    if (const json* t = r.optional_raw("thermal")) {
      ThermalSolverDef th;
      ObjectReader tr(*t, "/solvers/thermal");
      th.splitter = tr.text("splitter");
      th.subcycle = static_cast<int>(tr.integer("subcycle", 0, 0, 1000000000));
      th.dt = tr.real("dt", 0.0, 0.0);
      th.contact_samples = static_cast<int>(tr.integer("contact_samples", 8, 1, 1000));
      th.params = json::object();
      for (auto it = t->begin(); it != t->end(); ++it)
        if (it.key() != "splitter" && it.key() != "subcycle" && it.key() != "dt" && it.key() != "contact_samples")
          th.params[it.key()] = it.value();
      job.thermal = th;
    }
    r.finish();
  }
  if (job.mechanics) {
    for (std::size_t i = 0; i < job.parts.size(); ++i) {
      const auto& m = job.materials[job.parts[i].material];
      if (m.membrane.is_null())
        throw JobError(m.pointer, "material '" + m.name + "' has no membrane law but part '" + job.parts[i].name +
                                      "' uses it with the mechanics solver");
      if (!(m.density > 0))
        throw JobError(m.pointer + "/density", "required by the mechanics solver (kg/m3), missing");
    }
  }
  if (job.thermal) {
    for (const auto& p : job.parts) {
      const auto& m = job.materials[p.material];
      if (!m.has_thermal)
        throw JobError(m.pointer, "material '" + m.name + "' has no thermal data (density, specific_heat, conductivity) "
                                  "but part '" + p.name + "' uses it in a thermal job");
    }
  }

  // output
  if (const json* o = top.optional_raw("output")) {
    ObjectReader r(*o, "/output");
    job.output.interval = r.real("interval", job.t_end, 0.0, true);
    // A thermal run lands its steps on the frame times: an interval that
    // would take more frames than any run can write is an input error, not
    // hours of tiny steps. (With mechanics a frame comes at most once per
    // step: an interval below the step writes one after every step.)
    if (const double frames = job.t_end / job.output.interval; !job.mechanics && frames > kMaxFrames)
      throw JobError(r.at("interval"), "an interval of " + fmt_number(job.output.interval) + " s would write " +
                                           fmt_number(frames) + " frames over " + fmt_number(job.t_end) +
                                           " s (at most " + fmt_number(kMaxFrames) + ")");
    job.output.checkpoint_interval = r.real("checkpoint_interval", 0.0, 0.0);
    job.output.checkpoint_at_end = r.boolean("checkpoint_at_end", true);
    job.output.keep_checkpoints = r.boolean("keep_checkpoints", false);
    job.output.series_interval = r.real("series_interval", 0.0, 0.0);
    job.output.compression = static_cast<int>(r.integer("compression", 0, 0, 9));
    // true: the tools cut at the symmetry planes of the plies; "whole": as
    // they are; false: none.
    if (const json* v = r.optional_raw("tool_surfaces"); v && v->is_string()) {
      if (v->get<std::string>() != "whole")
        throw JobError(r.at("tool_surfaces"), "expected true, false or \"whole\", found \"" + v->get<std::string>() + "\"");
      job.output.tool_surfaces_whole = true;
    } else if (v && !v->is_boolean()) {
      throw JobError(r.at("tool_surfaces"), "expected true, false or \"whole\", found " + json_type_name(*v));
    } else {
      job.output.tool_surfaces = r.boolean("tool_surfaces", true);
    }
    // A number for every ply, or an object of numbers by material (every
    // material a part uses, no other), as a value per part; `check` throws
    // for a value out of range (its message, at the value's pointer).
    auto per_material = [&](const std::string& key, const std::function<std::string(double)>& check) {
      std::vector<double> out;
      const json* v = r.optional_raw(key);
      if (!v) return out;
      auto value = [&](const json& x, const std::string& ptr) {
        const double d = as_real(x, ptr);
        if (const std::string why = check(d); !why.empty()) throw JobError(ptr, why);
        return d;
      };
      if (!v->is_object()) {
        if (!v->is_number())
          throw JobError(r.at(key), "expected a number or an object of numbers by material, found " +
                                        json_type_name(*v));
        out.assign(job.parts.size(), value(*v, r.at(key)));
        return out;
      }
      for (const auto& [name, x] : v->items())
        if (find_index(material_names, name) < 0)
          throw JobError(pointer_append(r.at(key), name), unknown_name("material", name, material_names));
      for (const auto& p : job.parts) {
        const std::string& mat = job.materials[p.material].name;
        if (!v->contains(mat))
          throw JobError(r.at(key), "no value for material '" + mat + "' of part '" + p.name + "'");
        out.push_back(value(v->at(mat), pointer_append(r.at(key), mat)));
      }
      return out;
    };
    job.output.temperature_threshold = per_material("temperature_threshold", [](double d) {
      return d > -273.15 ? std::string() : "must be > -273.15, found " + fmt_number(d);
    });
    if (r.has("shear_angle_limit") && !job.mechanics)
      throw JobError(r.at("shear_angle_limit"), "a shear angle limit needs the mechanics solver "
                                                "(solvers.mechanics is absent or null)");
    job.output.shear_angle_limit = per_material("shear_angle_limit", [](double d) {
      return d > 0 && d < 90 ? std::string() : "must be > 0 and < 90 (degrees), found " + fmt_number(d);
    });
    if (const double iv = job.output.series_interval;
        iv > 0 && (job.mechanics || job.thermal) && job.t_end / iv > kMaxSeriesRows)
      throw JobError(r.at("series_interval"), "an interval of " + fmt_number(iv) + " s would write " +
                                                  fmt_number(job.t_end / iv) + " rows over " + fmt_number(job.t_end) +
                                                  " s (at most " + fmt_number(kMaxSeriesRows) + ")");
    job.output.fields = r.texts("fields", OutputDef::default_fields());
    for (std::size_t i = 0; i < job.output.fields.size(); ++i) {
      const auto& f = job.output.fields[i];
      if (std::find(known_fields().begin(), known_fields().end(), f) == known_fields().end()) {
        std::string msg = "unknown field '" + f + "'";
        const std::string dym = did_you_mean(f, known_fields());
        if (!dym.empty()) msg += "; " + dym;
        throw JobError(pointer_append(r.at("fields"), i), msg + "; valid fields: " + join(known_fields()));
      }
      if (f == "crystallinity" &&
          (!job.thermal || std::none_of(job.parts.begin(), job.parts.end(), [&](const PartDef& p) {
             return job.materials[p.material].crystallisation.present;
           })))
        throw JobError(pointer_append(r.at("fields"), i),
                       "the field 'crystallinity' needs the thermal solver and a ply whose material has "
                       "'crystallisation'");
      if (f == "below_threshold_from" && (job.output.temperature_threshold.empty() || !job.thermal))
        throw JobError(pointer_append(r.at("fields"), i),
                       "the field 'below_threshold_from' needs output.temperature_threshold and the thermal solver");
    }
    if (const json* pr = r.optional_raw("probes")) {
      if (!pr->is_array()) throw JobError(r.at("probes"), "expected an array, found " + json_type_name(*pr));
      std::vector<std::string> probe_names;
      for (std::size_t i = 0; i < pr->size(); ++i) {
        ProbeDef p;
        p.pointer = pointer_append("/output/probes", i);
        ObjectReader q((*pr)[i], p.pointer);
        p.name = q.text("name");
        if (find_index(probe_names, p.name) >= 0) throw JobError(q.at("name"), "duplicate probe name '" + p.name + "'");
        if (p.name.find_first_of(",\"\n") != std::string::npos)
          throw JobError(q.at("name"), "a probe name cannot contain commas, quotes or newlines");
        const std::string part = q.text("part");
        p.part = find_index(part_names, part);
        if (p.part < 0) throw JobError(q.at("part"), unknown_name("part", part, part_names));
        const auto at = q.reals("at", 3);
        p.at = {at[0], at[1], at[2]};
        p.quantities = q.texts("quantities", std::vector<std::string>{"temperature_profile", "temperature_mean"});
        for (std::size_t k = 0; k < p.quantities.size(); ++k) {
          const auto& v = p.quantities[k];
          const auto& known = known_probe_quantities();
          if (std::find(known.begin(), known.end(), v) == known.end()) {
            std::string msg = "unknown quantity '" + v + "'";
            const std::string dym = did_you_mean(v, known);
            if (!dym.empty()) msg += "; " + dym;
            throw JobError(pointer_append(q.at("quantities"), k), msg + "; valid quantities: " + join(known));
          }
          if (v == "crystallinity_profile" && (!job.thermal || !job.materials[job.parts[p.part].material].crystallisation.present))
            throw JobError(pointer_append(q.at("quantities"), k),
                           "'crystallinity_profile' needs the thermal solver and a part whose material has "
                           "'crystallisation'; part '" + part + "' has none");
        }
        p.interval = q.real("interval", 0.0, 0.0);
        if (!job.mechanics && p.interval > 0 && job.t_end / p.interval > kMaxProbeSamples)
          throw JobError(q.at("interval"), "an interval of " + fmt_number(p.interval) + " s would take " +
                                               fmt_number(job.t_end / p.interval) + " samples over " +
                                               fmt_number(job.t_end) + " s (at most " + fmt_number(kMaxProbeSamples) +
                                               "; 0 samples every step)");
        q.finish();
        probe_names.push_back(p.name);
        job.output.probes.push_back(std::move(p));
      }
    }
    r.finish();
  } else {
    job.output.interval = job.t_end;
    job.output.fields = OutputDef::default_fields();
  }
  top.finish();
  // The document as run, its file paths made absolute: written to the
  // output folder, it runs the same job from anywhere.
  json& run_doc = job.document_as_run;
  run_doc = doc;
  auto absolute = [](const std::filesystem::path& p) {
    return std::filesystem::absolute(p).lexically_normal().string();
  };
  for (std::size_t i = 0; i < job.parts.size(); ++i) {
    if (job.parts[i].mesh.kind == MeshDef::Kind::File)
      run_doc["parts"][i]["mesh"]["file"] = absolute(job.parts[i].mesh.file);
    if (!job.parts[i].initial_results.empty())
      run_doc["parts"][i]["initial_temperature"]["results"] = absolute(job.parts[i].initial_results);
  }
  for (std::size_t i = 0; i < job.tools.size(); ++i)
    if (!job.tools[i].surface.file.empty())
      run_doc["tools"][i]["surface"]["file"] = absolute(job.tools[i].surface.file);
  for (std::size_t i = 0; i < job.plugin_paths.size(); ++i)
    run_doc["plugin_paths"][i] = absolute(job.plugin_paths[i]);
  // Materials from cards carry the cards' values: the job as run needs
  // no card.
  for (auto& m : run_doc["materials"])
    if (m.is_object()) m.erase("card");
}
}  // namespace

Job load_job(const std::filesystem::path& file, const std::vector<std::string>& sets) {
  json doc = read_job_document(file);
  for (const auto& s : sets) apply_set(doc, s);
  return parse_job(doc, file);
}

}  // namespace ts
