#include "io/compare.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "io/results_reader.hpp"
#include "io/results_writer.hpp"

namespace ts {

using json = nlohmann::json;

namespace {

// The units of a probe quantity: those of the field it samples.
std::string probe_units(const std::string& quantity) {
  return field_units(quantity.rfind("displacement_", 0) == 0 ? "displacement" : quantity);
}

// One probe's samples of one quantity: time -> (z, value) rows.
struct Series {
  std::vector<double> times;
  std::vector<std::vector<double>> z, values;
};
using ProbeTable = std::map<std::pair<std::string, std::string>, Series>;  // (probe, quantity)

// probes.csv (probe,quantity,time,z,value); an empty table where the file
// is missing. Rows of one sample are consecutive.
ProbeTable read_probes(const std::filesystem::path& file, bool& found) {
  ProbeTable t;
  std::ifstream in(file);
  found = static_cast<bool>(in);
  std::string line;
  if (!found || !std::getline(in, line)) return t;  // the header
  for (int row = 2; std::getline(in, line); ++row) {
    std::string cell[5];
    std::stringstream ss(line);
    for (auto& c : cell) std::getline(ss, c, ',');
    if (cell[0].empty() || cell[2].empty() || cell[4].empty()) continue;
    auto number = [&](const std::string& v) {
      try {
        return std::stod(v);
      } catch (const std::exception&) {
        throw std::runtime_error(file.string() + " line " + std::to_string(row) + ": '" + v + "' is not a number");
      }
    };
    Series& s = t[{cell[0], cell[1]}];
    const double time = number(cell[2]);
    if (s.times.empty() || s.times.back() != time) {
      s.times.push_back(time);
      s.z.emplace_back();
      s.values.emplace_back();
    }
    if (!cell[3].empty()) s.z.back().push_back(number(cell[3]));
    s.values.back().push_back(number(cell[4]));
  }
  return t;
}

// Value of a profile (z, v) at z0: linear between its points, constant
// beyond them; its value where it has one.
double profile_at(const std::vector<double>& z, const std::vector<double>& v, double z0) {
  if (v.size() == 1 || z.size() != v.size()) return v[0];
  if (z0 <= z.front()) return v.front();
  if (z0 >= z.back()) return v.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(z.begin(), z.end(), z0) - z.begin());
  const double a = (z0 - z[k - 1]) / (z[k] - z[k - 1]);
  return (1 - a) * v[k - 1] + a * v[k];
}

// Drops the entries before `from` (s) of a time list and of the lists
// beside it (one entry per time).
template <class... Beside>
void keep_from(double from, std::vector<double>& times, Beside&... beside) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (times[k] < from) continue;
    if (kept != k) {  // (a vector moved onto itself would be left empty)
      times[kept] = times[k];
      ((beside[kept] = std::move(beside[k])), ...);
    }
    ++kept;
  }
  times.resize(kept);
  (beside.resize(kept), ...);
}

// Records |a - b| of one value in d (a NaN difference, once seen, stays;
// two NaN are the same value: a time that neither run reached).
void take(Difference& d, double a, double b, double time, double time_b) {
  const double diff = std::isnan(a) && std::isnan(b) ? 0.0 : std::abs(a - b);
  if (d.values == 0 || diff > d.max_abs || (std::isnan(diff) && !std::isnan(d.max_abs))) {
    d.max_abs = diff;
    d.at_time = time;
    d.at_time_b = time_b;
  }
  d.scale = std::max(d.scale, std::abs(a));
  ++d.values;
}

// A time series table (energy.csv: time and numbers; tools.csv and
// plies.csv: time, the tool's or ply's name, numbers): by key (the tool or
// ply; "" for energy.csv) its times and rows.
struct Table {
  std::vector<std::string> columns;  // the numeric ones after the time
  std::map<std::string, std::pair<std::vector<double>, std::vector<std::vector<double>>>> by_key;
};
Table read_table(const std::filesystem::path& file, bool keyed, bool& found) {
  Table t;
  std::ifstream in(file);
  found = static_cast<bool>(in);
  std::string line;
  if (!found || !std::getline(in, line)) return t;
  std::vector<std::string> head;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) head.push_back(c);
  t.columns.assign(head.begin() + std::min<std::size_t>(head.size(), keyed ? 2 : 1), head.end());
  for (int row = 2; std::getline(in, line); ++row) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    const std::size_t first = keyed ? 2 : 1;
    if (cells.size() != first + t.columns.size()) continue;  // a row cut short
    std::vector<double> v;
    double time = 0;
    try {
      time = std::stod(cells[0]);
      for (std::size_t k = first; k < cells.size(); ++k) v.push_back(std::stod(cells[k]));
    } catch (const std::exception&) {
      throw std::runtime_error(file.string() + " line " + std::to_string(row) + " holds something other than numbers");
    }
    auto& [times, rows] = t.by_key[keyed ? cells[1] : ""];
    times.push_back(time);
    rows.push_back(std::move(v));
  }
  return t;
}

// The numbers of a summary, by path (array entries named by their "name",
// else their "constraint", where they have one), without what depends on the
// machine rather than on the run's results.
void flatten(const json& j, const std::string& path, std::map<std::string, double>& out) {
  static const char* skip[] = {"wall_time_s", "wall_time_total_s", "peak_memory_MB", "timing_s", "threads",
                               "contact_beside_elements", "contact_schedule_share", "restarted_from_s",
                               "checkpoint_s"};
  if (j.is_number()) {
    out[path] = j.get<double>();
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (path.empty() && std::find(std::begin(skip), std::end(skip), it.key()) != std::end(skip)) continue;
      flatten(it.value(), path.empty() ? it.key() : path + "/" + it.key(), out);
    }
  } else if (j.is_array()) {
    for (std::size_t k = 0; k < j.size(); ++k) {
      std::string key = std::to_string(k);
      if (j[k].is_object() && j[k].contains("constraint") && j[k]["constraint"].is_string()) key = j[k]["constraint"];
      if (j[k].is_object() && j[k].contains("name") && j[k]["name"].is_string()) key = j[k]["name"];
      flatten(j[k], path + (key.rfind('/', 0) == 0 ? "" : "/") + key, out);
    }
  }
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

std::vector<int> match_times(const std::vector<double>& a, const std::vector<double>& b, double& offset) {
  std::vector<int> m(a.size(), -1);
  std::vector<double> gaps;
  for (std::size_t k = 1; k < a.size(); ++k) gaps.push_back(a[k] - a[k - 1]);
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  const double tol = gaps.empty() ? 1e-9 * std::max(1.0, std::abs(a.empty() ? 0 : a[0]))
                                  : 0.25 * gaps[gaps.size() / 2];
  for (std::size_t k = 0; k < a.size(); ++k) {
    const auto it = std::lower_bound(b.begin(), b.end(), a[k]);
    int best = -1;
    double d = std::numeric_limits<double>::infinity();
    for (auto j : {it - b.begin() - 1, it - b.begin()})
      if (j >= 0 && j < static_cast<std::ptrdiff_t>(b.size()) && std::abs(b[j] - a[k]) < d) {
        d = std::abs(b[j] - a[k]);
        best = static_cast<int>(j);
      }
    if (best >= 0 && d <= tol) {
      m[k] = best;
      offset = std::max(offset, d);
    }
  }
  return m;
}

Comparison compare_outputs(const std::filesystem::path& a, const std::filesystem::path& b, double from) {
  for (const auto& d : {a, b}) {
    if (!std::filesystem::is_directory(d)) throw std::runtime_error("'" + d.string() + "' is not a folder");
    if (!std::filesystem::exists(d / "summary.json") && !std::filesystem::exists(d / "probes.csv") &&
        !std::filesystem::exists(d / "results.h5"))
      throw std::runtime_error("'" + d.string() + "' holds no output of a run (summary.json, probes.csv, results.h5)");
  }
  Comparison c;
  // Something one folder has and the other has not (or cannot be read).
  auto unmatched = [&] { c.identical = c.matched = false; };
  auto note = [&](const std::string& n) {
    c.notes.push_back(n);
    unmatched();
  };

  // Probes.
  bool found_a = false, found_b = false;
  ProbeTable pa = read_probes(a / "probes.csv", found_a), pb = read_probes(b / "probes.csv", found_b);
  for (ProbeTable* t : {&pa, &pb})
    for (auto& [key, series] : *t) keep_from(from, series.times, series.z, series.values);
  if (found_a != found_b) note("probes.csv only in " + (found_a ? a : b).string());
  for (const auto& [key, sa] : pa) {
    const auto it = pb.find(key);
    Difference d;
    d.what = key.first + " " + key.second;
    d.units = probe_units(key.second);
    if (it == pb.end()) {
      d.note = "only in A";
      unmatched();
      c.probes.push_back(d);
      continue;
    }
    const Series& sb = it->second;
    const std::vector<int> m = match_times(sa.times, sb.times, c.largest_time_offset);
    int alone = 0;  // A's samples without one of B's
    for (std::size_t k = 0; k < m.size(); ++k) {
      if (m[k] < 0) {
        ++alone;
        continue;
      }
      const auto& za = sa.z[k];
      const auto& va = sa.values[k];
      const auto& zb = sb.z[m[k]];
      const auto& vb = sb.values[m[k]];
      // B's profile at A's points where the two differ (other layer counts)
      const bool same_points = za == zb && va.size() == vb.size();
      for (std::size_t i = 0; i < va.size(); ++i)
        take(d, va[i], same_points ? vb[i] : profile_at(zb, vb, za.empty() ? 0.0 : za[i]), sa.times[k],
             sb.times[m[k]]);
      if (!same_points) d.note = "B's profile interpolated at A's points";
    }
    if (alone > 0 || sa.times.size() != sb.times.size()) {
      d.note += std::string(d.note.empty() ? "" : "; ") + std::to_string(alone) + " of A's " +
                std::to_string(sa.times.size()) + " samples without one of B's at their time (B has " +
                std::to_string(sb.times.size()) + ")";
      unmatched();
    }
    if (d.max_abs != 0 || std::isnan(d.max_abs) || !d.note.empty()) c.identical = false;
    c.probes.push_back(d);
  }
  for (const auto& [key, sb] : pb)
    if (!pa.count(key)) {
      Difference d;
      d.what = key.first + " " + key.second;
      d.units = probe_units(key.second);
      d.note = "only in B";
      unmatched();
      c.probes.push_back(d);
    }

  // Fields of the frames at the same times.
  {
    QuietHdf5 quiet;
    const bool ha = std::filesystem::exists(a / "results.h5"), hb = std::filesystem::exists(b / "results.h5");
    if (ha != hb) note("results.h5 only in " + (ha ? a : b).string());
    const hid_t fa = ha ? H5Fopen((a / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
    const hid_t fb = hb ? H5Fopen((b / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
    if (ha && fa < 0) note((a / "results.h5").string() + " cannot be read");
    if (hb && fb < 0) note((b / "results.h5").string() + " cannot be read");
    if (fa >= 0 && fb >= 0) {
      Frames ra = read_frames(fa), rb = read_frames(fb);
      keep_from(from, ra.times, ra.names);
      keep_from(from, rb.times, rb.names);
      const std::vector<int> m = match_times(ra.times, rb.times, c.largest_time_offset);
      const long long matched = std::count_if(m.begin(), m.end(), [](int k) { return k >= 0; });
      if (matched < static_cast<long long>(ra.times.size()) || ra.times.size() != rb.times.size())
        note(std::to_string(matched) + " of A's " + std::to_string(ra.times.size()) +
             " frames matched by time with B's " + std::to_string(rb.times.size()));
      std::map<std::string, Difference> by_name;  // "part/field"
      std::vector<std::string> order;
      auto entry = [&](const std::string& part, const std::string& field) -> Difference& {
        const std::string key = part + "/" + field;
        if (!by_name.count(key)) {
          order.push_back(key);
          by_name[key].what = key;
          by_name[key].units = field_units(field);
        }
        return by_name[key];
      };
      for (std::size_t k = 0; k < m.size(); ++k) {
        if (m[k] < 0) continue;
        const std::string ga = "frames/" + ra.names[k], gb = "frames/" + rb.names[m[k]];
        const auto parts_b = members(fb, gb);
        for (const auto& part : members(fa, ga)) {
          if (!std::binary_search(parts_b.begin(), parts_b.end(), part)) continue;
          const auto fields_b = members(fb, gb + "/" + part);
          const auto fields_a = members(fa, ga + "/" + part);
          for (const auto& field : fields_a) {
            const std::string key = part + "/" + field;
            Difference& d = entry(part, field);
            if (!std::binary_search(fields_b.begin(), fields_b.end(), field)) {
              d.note = "only in A";
              unmatched();
              continue;
            }
            std::vector<hsize_t> sha, shb;
            const auto va = read_values(fa, ga + "/" + key, sha), vb = read_values(fb, gb + "/" + key, shb);
            if (sha != shb || va.empty()) {
              d.note = "other shapes (other meshes or layers): not compared";
              unmatched();
              continue;
            }
            for (std::size_t i = 0; i < va.size(); ++i) take(d, va[i], vb[i], ra.times[k], rb.times[m[k]]);
          }
          for (const auto& field : fields_b) {  // and those B has, A not
            if (std::binary_search(fields_a.begin(), fields_a.end(), field)) continue;
            entry(part, field).note = "only in B";
            unmatched();
          }
        }
      }
      for (const auto& key : order) {
        const Difference& d = by_name[key];
        if (d.max_abs != 0 || std::isnan(d.max_abs) || !d.note.empty()) c.identical = false;
        c.fields.push_back(d);
      }
    }
    if (fa >= 0) H5Fclose(fa);
    if (fb >= 0) H5Fclose(fb);
  }

  // The energy, tool and ply histories.
  for (const auto& [file, keyed] :
       {std::pair<const char*, bool>{"energy.csv", false}, {"tools.csv", true}, {"plies.csv", true}}) {
    bool in_a = false, in_b = false;
    Table ta = read_table(a / file, keyed, in_a), tb = read_table(b / file, keyed, in_b);
    for (Table* t : {&ta, &tb})
      for (auto& [key, rows] : t->by_key) keep_from(from, rows.first, rows.second);
    if (in_a != in_b) note(std::string(file) + " only in " + (in_a ? a : b).string());
    if (!in_a || !in_b) continue;
    // Columns one run has and the other has not (another version's, another output setting's).
    for (const auto& [t, other, who] : {std::tuple<const Table*, const Table*, const char*>{&ta, &tb, "A"},
                                        {&tb, &ta, "B"}})
      for (const std::string& col : t->columns)
        if (std::find(other->columns.begin(), other->columns.end(), col) == other->columns.end())
          note(std::string(file) + ": column '" + col + "' only in " + who);
    for (const auto& [key, sa_rows] : ta.by_key) {
      const auto it = tb.by_key.find(key);
      if (it == tb.by_key.end()) {
        note(std::string(file) + ": '" + key + "' only in A");
        continue;
      }
      const auto& [times_a, rows_a] = sa_rows;
      const auto& [times_b, rows_b] = it->second;
      const std::vector<int> m = match_times(times_a, times_b, c.largest_time_offset);
      const long long matched = std::count_if(m.begin(), m.end(), [](int k) { return k >= 0; });
      if (matched < static_cast<long long>(times_a.size()) || times_a.size() != times_b.size())
        note(std::string(file) + (key.empty() ? "" : " " + key) + ": " + std::to_string(matched) + " of A's " +
             std::to_string(times_a.size()) + " rows matched by time with B's " + std::to_string(times_b.size()));
      for (std::size_t col = 0; col < ta.columns.size(); ++col) {
        const auto jb = std::find(tb.columns.begin(), tb.columns.end(), ta.columns[col]);
        if (jb == tb.columns.end()) continue;
        const std::size_t colb = static_cast<std::size_t>(jb - tb.columns.begin());
        Difference d;
        d.what = std::string(file) + " " + (key.empty() ? "" : key + " ") + ta.columns[col];
        d.units = series_column_units((keyed ? "key_" : "") + ta.columns[col]);
        for (std::size_t k = 0; k < m.size(); ++k)
          if (m[k] >= 0) take(d, rows_a[k][col], rows_b[m[k]][colb], times_a[k], times_b[m[k]]);
        if (d.max_abs != 0 || std::isnan(d.max_abs)) c.identical = false;
        c.series.push_back(d);
      }
    }
  }

  // The summaries' figures.
  const bool sa = std::filesystem::exists(a / "summary.json"), sb = std::filesystem::exists(b / "summary.json");
  if (sa != sb) note("summary.json only in " + (sa ? a : b).string());
  if (sa && sb) {
    std::map<std::string, double> na, nb;
    try {
      json ja = json::parse(std::ifstream(a / "summary.json")), jb = json::parse(std::ifstream(b / "summary.json"));
      // Summaries before 0.23.0 have no `materials`: a run is compared
      // with an older one on its results alone.
      if (ja.is_object() && jb.is_object() && ja.contains("materials") != jb.contains("materials")) {
        ja.erase("materials");
        jb.erase("materials");
      }
      flatten(ja, "", na);
      flatten(jb, "", nb);
    } catch (const std::exception& e) {
      note(std::string("a summary.json cannot be read: ") + e.what());
    }
    for (const auto& [path, va] : na) {
      const auto it = nb.find(path);
      if (it == nb.end()) {
        note("summary " + path + " only in A");
        continue;
      }
      if (va == it->second) continue;
      // The first row at which something happened (a ply's first unstable
      // or over-limit row), before `from` in both: the rows before it are
      // not compared (a run extended from a checkpoint kept its first
      // spacing there).
      const bool row_time = path.size() > 7 && path.compare(path.size() - 7, 7, "_from_s") == 0 &&
                            path.find("threshold") == std::string::npos;
      if (row_time && va < from && it->second < from) continue;
      Difference d;
      d.what = path;
      d.a = va;
      d.b = it->second;
      d.max_abs = std::abs(va - it->second);
      d.scale = std::abs(va);
      d.values = 1;
      c.summary.push_back(d);
      c.identical = false;
    }
    for (const auto& [path, vb] : nb)
      if (!na.count(path)) note("summary " + path + " only in B");
  }
  return c;
}

double Comparison::largest_relative(std::string* where) const {
  double worst = 0;
  for (const auto* v : {&probes, &fields, &series, &summary})
    for (const Difference& d : *v) {
      if (d.values == 0) continue;
      const double r = std::isnan(d.max_abs) ? std::numeric_limits<double>::infinity()
                       : d.max_abs == 0     ? 0.0
                       : d.scale > 0        ? d.max_abs / d.scale
                                            : std::numeric_limits<double>::infinity();
      if (r > worst) {
        worst = r;
        if (where) *where = d.what;
      }
    }
  return worst;
}

bool Comparison::within(double rtol) const { return matched && largest_relative() <= rtol; }

json Comparison::to_json() const {
  auto list = [](const std::vector<Difference>& v, bool figures) {
    json out = json::array();
    for (const auto& d : v) {
      json e = {{"what", d.what}, {"max_abs", std::isnan(d.max_abs) ? json(nullptr) : json(d.max_abs)}};
      if (figures) {
        e["a"] = d.a;
        e["b"] = d.b;
      } else {
        e["units"] = d.units;
        e["scale"] = d.scale;
        e["at_time_s"] = d.at_time;
        e["at_time_b_s"] = d.at_time_b;
        e["values"] = d.values;
      }
      if (!d.note.empty()) e["note"] = d.note;
      out.push_back(e);
    }
    return out;
  };
  std::string where;
  const double rel = largest_relative(&where);
  return {{"identical", identical},
          {"matched", matched},
          {"largest_relative", std::isfinite(rel) ? json(rel) : json(nullptr)},
          {"largest_relative_in", where},
          {"probes", list(probes, false)},
          {"fields", list(fields, false)},
          {"series", list(series, false)},
          {"summary", list(summary, true)},
          {"largest_time_offset_s", largest_time_offset},
          {"notes", notes}};
}

std::string Comparison::to_text(const std::filesystem::path& a, const std::filesystem::path& b) const {
  std::ostringstream o;
  o << "A: " << a.string() << "\nB: " << b.string() << "\n";
  auto section = [&](const char* title, const std::vector<Difference>& v) {
    if (v.empty()) return;
    o << "\n" << title << "\n";
    for (const auto& d : v) {
      o << "  " << d.what << ": ";
      if (d.values == 0 && !d.note.empty()) {
        o << d.note << "\n";
        continue;
      }
      const std::string units = d.units.empty() || d.units == "1" ? "" : " " + d.units;
      if (d.max_abs == 0)
        o << "equal (" << d.values << " values, largest |A| " << fmt(d.scale) << units << ")";
      else
        o << "largest |A - B| " << fmt(d.max_abs) << units << " at t = " << fmt(d.at_time) << " s"
          << (fmt(d.at_time_b) != fmt(d.at_time) ? " against B's at " + fmt(d.at_time_b) + " s" : "")
          << " (largest |A| " << fmt(d.scale) << units << ", " << d.values << " values)";
      if (!d.note.empty()) o << "; " << d.note;
      o << "\n";
    }
  };
  section("probes (samples at the same times):", probes);
  section("fields (frames at the same times):", fields);
  section("histories (rows at the same times):", series);
  if (!summary.empty()) {
    o << "\nsummary (the figures that differ: A, B, |A - B|):\n";
    for (const auto& d : summary) o << "  " << d.what << ": " << fmt(d.a) << ", " << fmt(d.b) << ", " << fmt(d.max_abs) << "\n";
  }
  if (largest_time_offset > 0)
    o << "\nsamples and frames matched by time up to " << fmt(largest_time_offset) << " s apart\n";
  for (const auto& n : notes) o << "note: " << n << "\n";
  std::string where;
  const double rel = largest_relative(&where);
  if (!identical && rel > 0)
    o << "\nlargest relative difference (|A - B| over the largest |A| of its quantity): " << fmt(rel) << ", " << where
      << "\n";
  o << "\n" << (identical ? "identical: every value compared is equal" : "not identical") << "\n";
  return o.str();
}

}  // namespace ts
