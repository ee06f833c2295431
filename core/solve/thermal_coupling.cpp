// The thermal side of the kernel: the splitter's set-up and step size,
// the faces' conditions (tools, convection, radiation, ply/ply links), the
// initial temperatures from an earlier run, the heat capacity and
// crystallisation after each thermal step, the heat stored and the check of
// every value (docs/thermal-method.md).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "io/logging.hpp"
#include "io/results_reader.hpp"
#include "solve/simulation_internal.hpp"
#include "solve/tools.hpp"

namespace ts {

using detail::fmt_g;

void Simulation::build_thermal() {
  // Contact handlers: needed for the thermal contact map.
  for (const auto& c : job_.contacts) {
    const PluginRecord& rec = registry_.require(sdk::PluginKind::Contact, c.handler, c.pointer + "/handler");
    const sdk::Params params = validate_params(c.params, c.pointer, rec.descriptor);
    std::unique_ptr<sdk::ContactHandler> h(reinterpret_cast<sdk::ContactHandler* (*)()>(rec.create)());
    sdk::ContactPair pair;
    pair.first = {sdk::BodyRef::Type::Part, c.first.index};
    pair.second = {c.second.is_tool ? sdk::BodyRef::Type::Tool : sdk::BodyRef::Type::Part, c.second.index};
    if (auto s = h->configure(params, pair, part_views_, tool_views_); !s)
      throw JobError(c.pointer, "contact handler '" + c.handler + "': " + s.message);
    contacts_.push_back(std::move(h));
  }
  if (!job_.thermal) {
    for (const auto& m : job_.materials)
      if (m.crystallisation.present)
        logger("job")->warn("{}: ignored, an isothermal job has no crystallisation", m.crystallisation.pointer);
    return;
  }
  const ThermalSolverDef& th = *job_.thermal;
  const PluginRecord& rec = registry_.require(sdk::PluginKind::Thermal, th.splitter, th.pointer + "/splitter");
  const sdk::Params params =
      validate_params(th.params, th.pointer, rec.descriptor, {"splitter", "subcycle", "dt", "contact_samples"});
  splitter_.reset(reinterpret_cast<sdk::ThermalSplitter* (*)()>(rec.create)());
  for (const auto& st : parts_) {
    const MaterialDef& mat = job_.materials[st->def->material];
    if (!mat.conductivity_table.empty() && !splitter_->takes_conductivity_field()) {
      if (mat.mixture_fibre_fraction >= 0)
        throw JobError(mat.pointer + "/mixture", "the thermal splitter '" + th.splitter +
                                                     "' takes no temperature-dependent conductivity; give the "
                                                     "matrix and fibre constant conductivities or choose another "
                                                     "splitter");
      throw JobError(mat.pointer + "/conductivity", "the thermal splitter '" + th.splitter +
                                                        "' takes no temperature-dependent conductivity; give "
                                                        "constant values [k11, k22, k33] or choose another splitter");
    }
  }
  if (auto s = splitter_->configure(params, part_views_); !s)
    throw JobError(th.pointer, "thermal plugin '" + th.splitter + "': " + s.message);
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    st.nz = splitter_->values_per_node(static_cast<int>(p));
    const std::size_t n = static_cast<std::size_t>(st.mesh.num_nodes()) * st.nz;
    st.T.assign(n, st.def->initial_temperature);
    st.cap.assign(n, 0.0);
    const MaterialDef& mat = job_.materials[st.def->material];
    if (!mat.specific_heat_table.empty()) {
      st.cp = HeatCapacityTable(mat.specific_heat_table);
      st.T_step.assign(n, 0.0);
    }
    if (!mat.conductivity_table.empty()) {
      st.kt = ConductivityTable(mat.conductivity_table);
      st.k_field.assign(3 * n, 0.0);
    }
    if (const auto& c = mat.crystallisation; c.present) {
      st.kin = CrystallisationKinetics(c.latent_heat, c.avrami_exponent, c.rate_rows, c.k_max, c.t_max, c.half_width,
                                       c.melting_rows);
      st.c_latent = mat.specific_heat;
      st.X.assign(n, c.initial);
      st.theta.assign(n, st.kin.integral(c.initial));
      st.X_mean.assign(st.mesh.num_nodes(), c.initial);
      st.T_step.assign(n, 0.0);
    }
    if (auto s = splitter_->capacities(static_cast<int>(p), st.cap); !s)
      throw JobError(th.pointer, "thermal plugin '" + th.splitter + "': " + s.message);
    st.t0 = st.def->initial_temperature;
    if (!st.def->initial_results.empty()) {
      load_initial_temperature(st);
      double q = 0, c = 0;
      for (std::size_t k = 0; k < n; ++k) {
        q += st.cap[k] * st.T[k];
        c += st.cap[k];
      }
      st.t0 = c > 0 ? q / c : st.T[0];
      part_views_[p].initial_temperature = st.t0;
    }
    st.mean.assign(st.mesh.num_nodes(), 0.0);
    st.top.assign(st.mesh.num_nodes(), 0.0);
    st.bottom.assign(st.mesh.num_nodes(), 0.0);
  }
  assemble_faces(0.0);
  contact_last_ = contact_map_;  // the first contact sample's left end
  update_far_temperatures(0.0, 0.0);
  bool any_table = false;
  for (const auto& st : parts_) any_table = any_table || !st->kt.empty();
  if (any_table)
    for (const auto& st : parts_) conductivity_.emplace_back(st->k_field);
  faces_.resize(parts_.size());
  for (std::size_t p = 0; p < parts_.size(); ++p)
    faces_[p] = {parts_[p]->h_bottom, parts_[p]->t_bottom, parts_[p]->h_top, parts_[p]->t_top};
  // The step holds for every conductance the contact pairs can give over
  // the run, not only those of the start: each ply's faces are taken with
  // at least the largest conductance of the pairs it is in.
  std::vector<double> bound(parts_.size(), 0.0);
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    const double h = contacts_[c]->largest_conductance();
    bound[job_.contacts[c].first.index] = std::max(bound[job_.contacts[c].first.index], h);
    if (!job_.contacts[c].second.is_tool)
      bound[job_.contacts[c].second.index] = std::max(bound[job_.contacts[c].second.index], h);
  }
  std::vector<std::vector<double>> h_bound(2 * parts_.size());
  std::vector<sdk::FaceConditions> limit_faces = faces_;
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    if (!(bound[p] > 0)) continue;
    for (int f = 0; f < 2; ++f) {
      const std::vector<double>& h = f == 0 ? parts_[p]->h_bottom : parts_[p]->h_top;
      std::vector<double>& hb = h_bound[2 * p + f];
      hb.resize(h.size());
      for (std::size_t i = 0; i < h.size(); ++i) hb[i] = std::max(h[i], bound[p]);
      (f == 0 ? limit_faces[p].h_bottom : limit_faces[p].h_top) = hb;
    }
  }
  sdk::ThermalStepInput in;
  in.faces = limit_faces;
  in.links = contact_map_.links;
  in.links_changed = true;
  if (auto s = splitter_->step_limits(in, &thermal_stable_dt_, &thermal_accurate_dt_); !s)
    throw JobError(th.pointer, "thermal plugin '" + th.splitter + "': " + s.message);
  double dt = thermal_accurate_dt_;
  if (th.dt > 0) {
    if (th.dt > thermal_stable_dt_ * (1 + 1e-12))
      throw JobError(th.pointer + "/dt", "thermal step " + fmt_g(th.dt) + " s exceeds the stable step " +
                                             fmt_g(thermal_stable_dt_) +
                                             " s of the explicit scheme (dt_safety included); lower it or use "
                                             "\"through_thickness\": \"implicit\"");
    dt = th.dt;
  }
  if (!(dt > 0) || !std::isfinite(dt)) dt = job_.output.interval;
  const double steps = job_.t_end / dt;
  if (steps > 2e8)
    throw JobError(th.pointer, "the thermal step " + fmt_g(dt) + " s would need " + fmt_g(steps, 3) +
                                   " steps to reach " + fmt_g(job_.t_end) +
                                   " s; the explicit scheme is limited by thin layers or high conductances here: "
                                   "use \"through_thickness\": \"implicit\"");
  // Alone, the thermal solver lands its steps on the frames: a whole number
  // of steps per frame interval (or per time.end, if shorter). With the
  // mechanics a thermal step ends at the first mechanical step at or after
  // each multiple of the step chosen here (Run::thermal_due), whatever the
  // frames: another frame interval changes no result.
  thermal_dt_ = dt;
  if (!job_.mechanics) {
    const double interval = std::min(job_.output.interval, job_.t_end);
    thermal_dt_ = interval / std::max(1.0, std::ceil(interval / dt * (1 - 1e-12)));
  }
}

void Simulation::update_far_temperatures(double t0, double t1) {
  // Tools: their views and the faces they touch.
  bool any = false;
  for (std::size_t k = 0; k < tool_views_.size(); ++k) {
    if (job_.tools[k].temperature_table.empty()) continue;
    tool_views_[k].temperature = job_.tools[k].temperature_over(t0, t1);
    any = true;
  }
  if (any)
    for (const auto& tc : contact_map_.tool_contacts) {
      PartState& st = *parts_[tc.part];
      (tc.face == sdk::kTop ? st.t_top : st.t_bottom)[tc.node] = tool_views_[tc.tool].temperature;
    }
  // Heat exchanges: the ambient, and radiation at the face's temperature.
  constexpr double kSigma = 5.670374419e-8, kKelvin = 273.15;  // W/(m^2 K^4), the Stefan-Boltzmann constant
  // The conductance of exchange h at a face (part, node, face) over the step.
  auto exchange_h = [&](const HeatExchangeDef& h, int part, int node, int face, double ambient) {
    if (!(h.emissivity > 0)) return h.h;
    const PartState& st = *parts_[part];
    const std::size_t base = static_cast<std::size_t>(st.nz) * node;
    const double T = st.T[base + (face == sdk::kTop ? st.nz - 1 : 0)] + kKelvin, Ta = ambient + kKelvin;
    return h.h + h.emissivity * kSigma * (T * T + Ta * Ta) * (T + Ta);
  };
  for (const ExchangeFace& f : exchange_faces_) {
    const HeatExchangeDef& h = job_.heat_exchanges[static_cast<std::size_t>(f.exchange)];
    PartState& st = *parts_[f.part];
    const double ambient = h.ambient_over(t0, t1);
    (f.face == sdk::kTop ? st.t_top : st.t_bottom)[f.node] = ambient;
    if (h.emissivity > 0)
      (f.face == sdk::kTop ? st.h_top : st.h_bottom)[f.node] = f.scale * exchange_h(h, f.part, f.node, f.face, ambient);
  }
  for (const MixedFace& m : mixed_faces_) {
    if (m.exchange < 0) {
      mix_face(m, m.h_ex, m.t_ex);
      continue;
    }
    const HeatExchangeDef& h = job_.heat_exchanges[static_cast<std::size_t>(m.exchange)];
    const double ambient = h.ambient_over(t0, t1);
    mix_face(m, m.scale * exchange_h(h, m.part, m.node, m.face, ambient), ambient);
  }
}

void Simulation::mix_face(const MixedFace& m, double h_ex, double t_ex) {
  double h = 0, hT = 0;
  for (int k = m.begin; k < m.end; ++k) {
    const sdk::ToolHeatContact& tc = contact_map_.tool_contacts[static_cast<std::size_t>(mixed_contacts_[k])];
    h += tc.conductance;
    hT += tc.conductance * tool_views_[tc.tool].temperature;
  }
  const double g = m.free * h_ex;
  h += g;
  hT += g * t_ex;
  PartState& st = *parts_[m.part];
  const double first = tool_views_[contact_map_.tool_contacts[mixed_contacts_[m.begin]].tool].temperature;
  (m.face == sdk::kTop ? st.h_top : st.h_bottom)[m.node] = h;
  (m.face == sdk::kTop ? st.t_top : st.t_bottom)[m.node] = h > 0 ? hT / h : first;
}

void Simulation::load_initial_temperature(PartState& st) {
  const PartDef& def = *st.def;
  const std::string ptr = def.pointer + "/initial_temperature", path = def.initial_results.string();
  const std::string part = def.initial_results_part.empty() ? def.name : def.initial_results_part;
  const QuietHdf5 quiet;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw JobError(ptr + "/results", "'" + path + "' is not a results file (HDF5)");
  struct Closer {
    hid_t f;
    ~Closer() { H5Fclose(f); }
  } closer{file};
  const Frames frames = read_frames(file);
  if (frames.times.empty()) throw JobError(ptr + "/results", "'" + path + "' holds no frame");
  std::size_t k = frames.times.size() - 1;
  const double want = def.initial_results_time;
  if (want >= 0) {
    for (std::size_t j = 0; j < frames.times.size(); ++j)
      if (std::abs(frames.times[j] - want) < std::abs(frames.times[k] - want)) k = j;
    if (std::abs(frames.times[k] - want) > 1e-9 * std::max(1.0, want))
      throw JobError(ptr + "/time", "'" + path + "' has no frame at t = " + fmt_g(want) + " s; its " +
                                        std::to_string(frames.times.size()) + " frames run from " +
                                        fmt_g(frames.times.front()) + " to " + fmt_g(frames.times.back()) + " s");
  }
  const std::string where = "the frame at t = " + fmt_g(frames.times[k]) + " s of '" + path + "'";
  const std::string group = "frames/" + frames.names[k] + "/" + part + "/";
  std::vector<hsize_t> shape;
  const std::vector<double> nodes = read_values(file, group + "nodes", shape);
  if (nodes.empty())
    throw JobError(def.initial_results_part.empty() ? ptr : ptr + "/part", where + " has no part '" + part + "'");
  const int nn = st.mesh.num_nodes();
  if (static_cast<int>(nodes.size() / 3) != nn)
    throw JobError(ptr, where + ": part '" + part + "' has " + std::to_string(nodes.size() / 3) +
                            " nodes, this part " + std::to_string(nn) + " (the same mesh is needed)");
  // The frame's nodes as this part's: by their tags where the file gives
  // them (results of 0.24 and later: a mesh file's tags, else the numbers
  // from 1), else in order; then the same triangles, so that a mesh of the
  // same size but another shape or numbering is refused, not taken.
  std::vector<int> ours(nn);  // this part's node of each frame node
  const std::vector<double> tags = read_values(file, "parts/" + part + "/node_tags", shape);
  const bool by_tags = tags.size() == static_cast<std::size_t>(nn);
  if (by_tags) {
    std::unordered_map<long long, int> index;
    for (int i = 0; i < nn; ++i) index.emplace(node_tag(st.mesh, i), i);
    std::vector<char> taken(nn, 0);
    for (int j = 0; j < nn; ++j) {
      const auto it = index.find(static_cast<long long>(tags[j]));
      if (it == index.end() || taken[it->second])
        throw JobError(ptr, where + ": node " + fmt_g(tags[j], 17) + " of part '" + part +
                                "' is not a node of this part's mesh (the same mesh is needed)");
      taken[it->second] = 1;
      ours[j] = it->second;
    }
  } else {
    for (int j = 0; j < nn; ++j) ours[j] = j;
  }
  {
    const std::vector<double> tri = read_values(file, "parts/" + part + "/triangles", shape);
    const int ne = st.mesh.num_elements();
    auto sorted = [](std::array<int, 3> t) {
      std::sort(t.begin(), t.end());
      return t;
    };
    std::vector<std::array<int, 3>> a(ne), b;
    for (int e = 0; e < ne; ++e)
      a[e] = sorted({st.mesh.triangles[3 * e], st.mesh.triangles[3 * e + 1], st.mesh.triangles[3 * e + 2]});
    bool same = tri.size() == a.size() * 3;
    for (std::size_t e = 0; same && e < a.size(); ++e) {
      std::array<int, 3> t;
      for (int k = 0; k < 3; ++k) {
        const double n = tri[3 * e + k];
        same = same && n >= 0 && n < nn;
        t[k] = same ? ours[static_cast<int>(n)] : 0;
      }
      b.push_back(sorted(t));
    }
    if (same) {
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      same = a == b;
    }
    if (!same)
      throw JobError(ptr, where + ": the triangles of part '" + part + "' are not those of this part's mesh (the same mesh is needed" +
                              (!by_tags && def.mesh.kind == MeshDef::Kind::File && def.mesh.reorder
                                   ? "; results of ThermoStamp 0.23 and earlier number the nodes of a mesh file as "
                                     "\"reorder\": false does)"
                                   : ")"));
  }
  const std::vector<double> v = read_values(file, group + "temperature", shape);
  if (v.empty())
    throw JobError(ptr, where + " has no temperature of part '" + part +
                            "' (the run that wrote it needs \"temperature\" in output.fields)");
  // Levels bottom to top, evenly spaced through the thickness (a single
  // value per node is written on two levels).
  const int nl = static_cast<int>(v.size()) / nn, nz = st.nz;
  if (nl < 2 || v.size() != static_cast<std::size_t>(nl) * nn)
    throw JobError(ptr, where + ": the temperature of part '" + part + "' has " + std::to_string(v.size()) +
                            " values, not a whole number of levels (2 or more) for its " + std::to_string(nn) +
                            " nodes");
  // The frame's nl levels per node onto this part's nz values.
  auto levels = [&](const std::vector<double>& from, std::vector<double>& to) {
    for (int j = 0; j < nn; ++j) {
      const double* src = &from[static_cast<std::size_t>(j) * nl];
      double* dst = &to[static_cast<std::size_t>(ours[j]) * nz];
      if (nz == nl) {
        std::copy(src, src + nl, dst);
      } else if (nz == 1) {  // the mean through the thickness (linear between the levels)
        double m = 0;
        for (int l = 0; l < nl; ++l) m += (l == 0 || l == nl - 1 ? 0.5 : 1.0) * src[l];
        dst[0] = m / (nl - 1);
      } else {  // linear between the levels, at this part's
        for (int q = 0; q < nz; ++q) {
          const double s = static_cast<double>(q) * (nl - 1) / (nz - 1);
          const int l = std::min(static_cast<int>(s), nl - 2);
          dst[q] = src[l] + (s - l) * (src[l + 1] - src[l]);
        }
      }
    }
  };
  levels(v, st.T);
  logger("solve")->info("part '{}': initial temperatures from {} (part '{}', {} values per node)", def.name, where,
                        part, nl);
  // With crystallisation kinetics, the crystallinity of the same frame,
  // where it has one (the field crystallinity).
  if (st.kin.empty()) return;
  const std::vector<double> x = read_values(file, group + "crystallinity", shape);
  if (x.size() != v.size()) {
    logger("solve")->info("part '{}': {} has no crystallinity of part '{}': the crystallinity starts at {}", def.name,
                          where, part, fmt_g(job_.materials[def.material].crystallisation.initial));
    return;
  }
  levels(x, st.X);
  for (std::size_t k = 0; k < st.X.size(); ++k) st.theta[k] = st.kin.integral(std::clamp(st.X[k], 0.0, 1.0));
  logger("solve")->info("part '{}': initial crystallinity from the same frame", def.name);
}

// The tools of the part's contact pairs; all of them where it has none.
std::vector<int> Simulation::gap_tools(int part) const {
  std::vector<int> tools;
  for (const ContactDef& c : job_.contacts) {
    if (c.second.is_tool && !c.first.is_tool && c.first.index == part) tools.push_back(c.second.index);
    if (c.first.is_tool && !c.second.is_tool && c.second.index == part) tools.push_back(c.first.index);
  }
  if (tools.empty())
    for (std::size_t t = 0; t < tools_.size(); ++t) tools.push_back(static_cast<int>(t));
  return tools;
}

// The gaps of n nodes of part p (positions x, 3 per node) into gap.
void Simulation::tool_gaps(int p, std::size_t n, const double* x, double* gap) const {
  const PartState& st = *parts_[p];
  const double h2 = 0.5 * st.def->thickness;
  std::vector<double> d(n), normal(3 * n);
  std::fill(gap, gap + n, kToolGapLimit);
  for (const int t : gap_tools(p)) {
    tools_[t]->query(n, x, kToolGapLimit + h2, d.data(), normal.data());
    for (std::size_t i = 0; i < n; ++i) gap[i] = std::min(gap[i], d[i] - h2);
  }
}

void Simulation::update_tool_gap() {
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    st.tool_gap.resize(st.mesh.num_nodes());
    tool_gaps(static_cast<int>(p), st.tool_gap.size(), st.x.data(), st.tool_gap.data());
  }
}

void Simulation::update_face_conductance() {
  if (!job_.thermal) return;  // no heat exchange: zero
  for (auto& st : parts_) {
    st->conductance_bottom = st->h_bottom;
    st->conductance_top = st->h_top;
  }
  auto add = [&](int part, int node, int face, double g) {  // g in W/K
    PartState& st = *parts_[part];
    if (st.area[node] > 0) (face == sdk::kTop ? st.conductance_top : st.conductance_bottom)[node] += g / st.area[node];
  };
  for (const auto& l : contact_map_.links) {
    add(l.part_a, l.node_a, l.face_a, l.conductance);
    for (int j = 0; j < 3; ++j) add(l.part_b, l.nodes_b[j], l.face_b, l.conductance * l.w_b[j]);
  }
}

namespace {

// Keys of the contact sums: a tool contact by its part, node, face and
// tool; a link by the first ply's part, node and face and the second ply's
// part and face (its triangle may change from sample to sample).
std::uint64_t tool_key(const sdk::ToolHeatContact& c) {
  return (static_cast<std::uint64_t>(c.part) << 44) | (static_cast<std::uint64_t>(c.tool) << 33) |
         (static_cast<std::uint64_t>(c.face & 1) << 32) | static_cast<std::uint32_t>(c.node);
}
std::uint64_t link_key(const sdk::HeatLink& l) {
  return (static_cast<std::uint64_t>(l.part_a) << 44) | (static_cast<std::uint64_t>(l.part_b) << 34) |
         (static_cast<std::uint64_t>(l.face_a & 1) << 33) | (static_cast<std::uint64_t>(l.face_b & 1) << 32) |
         static_cast<std::uint32_t>(l.node_a);
}

}  // namespace

void Simulation::thermal_contacts(double t, sdk::ThermalContactMap& out) {
  out.tool_contacts.clear();
  out.links.clear();
  std::vector<std::span<const double>> areas;
  for (auto& st : parts_) areas.emplace_back(st->area);
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    if (auto s = contacts_[c]->thermal_contacts(part_views_, tool_views_, areas, out); !s)
      throw RunError("contact handler of " + job_.contacts[c].pointer + " at t = " + fmt_g(t) + " s: " + s.message);
  }
}

void Simulation::sample_contacts(double t, double w) {
  if (parts_.size() >= 1024 || tool_views_.size() >= 1024)
    throw RunError("contact samples: at most 1023 parts and 1023 tools (solvers.thermal.contact_samples 1 takes more)");
  thermal_contacts(t, contact_sample_);
  // The trapezoidal rule over [t - w, t]: half of w with the last sample's
  // conductances, half with this one's. A contact that begins between two
  // samples so counts from the middle of their interval.
  ContactSums& sums = contact_sums_;
  auto add = [&](const sdk::ThermalContactMap& m, double weight) {
    for (const sdk::ToolHeatContact& c : m.tool_contacts) {
      const auto [at, fresh] = sums.tool_at.try_emplace(tool_key(c), sums.map.tool_contacts.size());
      if (fresh) {
        sums.map.tool_contacts.push_back(c);
        sums.map.tool_contacts.back().conductance = 0;
        sums.touched.push_back(0.0);
      }
      sums.map.tool_contacts[at->second].conductance += c.conductance * weight;
      sums.touched[at->second] += weight;
    }
    for (const sdk::HeatLink& l : m.links) {
      const auto [at, fresh] = sums.link_at.try_emplace(link_key(l), sums.map.links.size());
      if (fresh) {
        sums.map.links.push_back(l);
        sums.link_touched.push_back(0.0);
      }
      sdk::HeatLink& s = sums.map.links[at->second];
      const double g = (fresh ? 0.0 : s.conductance) + l.conductance * weight;
      s = l;  // the latest triangle and weights
      s.conductance = g;
      sums.link_touched[at->second] += weight;
    }
  };
  add(contact_last_, 0.5 * w);
  add(contact_sample_, 0.5 * w);
  std::swap(contact_last_, contact_sample_);
  sums.time += w;
}

void Simulation::index_contact_sums() {
  ContactSums& sums = contact_sums_;
  sums.tool_at.clear();
  sums.link_at.clear();
  for (std::size_t k = 0; k < sums.map.tool_contacts.size(); ++k) sums.tool_at[tool_key(sums.map.tool_contacts[k])] = k;
  for (std::size_t k = 0; k < sums.map.links.size(); ++k) sums.link_at[link_key(sums.map.links[k])] = k;
}

void Simulation::assemble_faces(double t, double sampled) {
  for (auto& st : parts_) {
    std::fill(st->h_bottom.begin(), st->h_bottom.end(), 0.0);
    std::fill(st->h_top.begin(), st->h_top.end(), 0.0);
    std::fill(st->t_bottom.begin(), st->t_bottom.end(), 0.0);
    std::fill(st->t_top.begin(), st->t_top.end(), 0.0);
    std::fill(st->contact_status.begin(), st->contact_status.end(), 0.0);
  }
  // Per part, 2 per node (bottom, top): the heat exchange there whose face
  // conditions are renewed at every thermal step (update_far_temperatures:
  // it radiates or follows ambient rows; its index), -1 where none is or a
  // tool contact covers it.
  auto renewed_at_steps = [](const HeatExchangeDef& h) { return h.emissivity > 0 || !h.ambient_table.empty(); };
  const bool renewed = std::any_of(job_.heat_exchanges.begin(), job_.heat_exchanges.end(), renewed_at_steps);
  std::vector<std::vector<int>> renews(renewed ? parts_.size() : 0);
  for (std::size_t p = 0; p < renews.size(); ++p) renews[p].assign(2 * parts_[p]->mesh.num_nodes(), -1);
  for (std::size_t k = 0; k < job_.heat_exchanges.size(); ++k) {
    const auto& h = job_.heat_exchanges[k];
    const int renew = renewed_at_steps(h) ? static_cast<int>(k) : -1;
    for (int p : h.parts) {
      PartState& st = *parts_[p];
      for (int i = 0; i < st.mesh.num_nodes(); ++i) {
        if (!h.region.contains(st.x0[3 * i], st.x0[3 * i + 1])) continue;
        if (h.top) {
          st.h_top[i] = h.h;
          st.t_top[i] = h.ambient;
          if (renewed) renews[p][2 * i + 1] = renew;
        }
        if (h.bottom) {
          st.h_bottom[i] = h.h;
          st.t_bottom[i] = h.ambient;
          if (renewed) renews[p][2 * i] = renew;
        }
      }
    }
  }
  if (sampled >= 0) {  // the mean of the step's samples
    sample_contacts(t, sampled);
    ContactSums& sums = contact_sums_;
    std::swap(contact_map_, sums.map);  // (the old map, cleared below, keeps its storage)
    contact_touch_.assign(contact_map_.tool_contacts.size(), 1.0);
    link_touch_.assign(contact_map_.links.size(), 1.0);
    if (sums.time > 0) {
      for (auto& c : contact_map_.tool_contacts) c.conductance /= sums.time;
      for (auto& l : contact_map_.links) l.conductance /= sums.time;
      for (std::size_t k = 0; k < contact_touch_.size() && k < sums.touched.size(); ++k)
        contact_touch_[k] = std::min(1.0, sums.touched[k] / sums.time);
      for (std::size_t k = 0; k < link_touch_.size() && k < sums.link_touched.size(); ++k)
        link_touch_[k] = std::min(1.0, sums.link_touched[k] / sums.time);
    }
    sums.map.tool_contacts.clear();
    sums.map.links.clear();
    sums.touched.clear();
    sums.link_touched.clear();
    sums.tool_at.clear();
    sums.link_at.clear();
    sums.time = 0;
  } else {
    thermal_contacts(t, contact_map_);
    contact_touch_.assign(contact_map_.tool_contacts.size(), 1.0);
    link_touch_.assign(contact_map_.links.size(), 1.0);
  }
  // Another ply covers a face as a tool does: a heat exchange there acts
  // on the share of the face and step without that ply. The share covered
  // (cover, per part 2 per node, empty where none): for a link's node, the
  // share of the step its samples find the link; for the nodes of the
  // facing triangle, that share times their weight in the link times the
  // linked node's area over theirs (each node's area covered by the nodes
  // that face it).
  std::vector<std::vector<double>> cover;
  if (!job_.heat_exchanges.empty() && !contact_map_.links.empty()) {
    cover.resize(parts_.size());
    auto add = [&](int part, int node, int face, double c) {
      std::vector<double>& v = cover[part];
      if (v.empty()) v.assign(2 * parts_[part]->mesh.num_nodes(), 0.0);
      v[2 * node + (face == sdk::kTop ? 1 : 0)] += c;
    };
    for (std::size_t k = 0; k < contact_map_.links.size(); ++k) {
      const sdk::HeatLink& l = contact_map_.links[k];
      add(l.part_a, l.node_a, l.face_a, link_touch_[k]);
      const double area_a = parts_[l.part_a]->area[l.node_a];
      for (int j = 0; j < 3; ++j) {
        const double area_b = parts_[l.part_b]->area[l.nodes_b[j]];
        if (l.w_b[j] > 0 && area_b > 0)
          add(l.part_b, l.nodes_b[j], l.face_b, link_touch_[k] * l.w_b[j] * area_a / area_b);
      }
    }
    for (std::size_t p = 0; p < cover.size(); ++p) {
      PartState& st = *parts_[p];
      for (std::size_t f = 0; f < cover[p].size(); ++f) {
        double& c = cover[p][f];
        c = std::max(0.0, 1.0 - c);  // from here on: the share not covered
        (f % 2 ? st.h_top : st.h_bottom)[f / 2] *= c;
      }
    }
  }
  auto uncovered = [&](int part, int slot) { return cover.empty() || cover[part].empty() ? 1.0 : cover[part][slot]; };
  // The faces the tools touch. A face touched by one tool over the whole
  // step takes its conductance and temperature; one touched by several, or
  // by a tool for part of the step where a heat exchange covers it, mixes
  // them (MixedFace).
  mixed_faces_.clear();
  mixed_contacts_.clear();
  const std::size_t nc = contact_map_.tool_contacts.size();
  std::vector<int> entry(nc);  // each contact's face, an index into `touched`
  struct Touched {
    int part, node, face, count = 0, exchange = -1, mixed = -1;
    double h_ex = 0, t_ex = 0, share = 0;  // the face's exchange before the tools; the tools' shares summed
  };
  std::vector<Touched> touched;
  {
    std::vector<std::vector<int>> at(parts_.size());  // per part, 2 per node: the face's entry in `touched`
    for (std::size_t c = 0; c < nc; ++c) {
      const sdk::ToolHeatContact& tc = contact_map_.tool_contacts[c];
      std::vector<int>& a = at[tc.part];
      if (a.empty()) a.assign(2 * parts_[tc.part]->mesh.num_nodes(), -1);
      const int slot = 2 * tc.node + (tc.face == sdk::kTop ? 1 : 0);
      if (a[slot] < 0) {
        a[slot] = static_cast<int>(touched.size());
        const PartState& st = *parts_[tc.part];
        Touched f{tc.part, tc.node, tc.face};
        f.h_ex = (tc.face == sdk::kTop ? st.h_top : st.h_bottom)[tc.node];
        f.t_ex = (tc.face == sdk::kTop ? st.t_top : st.t_bottom)[tc.node];
        if (renewed) f.exchange = renews[tc.part][slot];
        touched.push_back(f);
      }
      entry[c] = a[slot];
      Touched& f = touched[static_cast<std::size_t>(a[slot])];
      ++f.count;
      f.share += contact_touch_[c];
    }
  }
  for (Touched& f : touched) {
    const bool exchanged = f.h_ex > 0 || f.exchange >= 0;
    if (f.count > 1 || (exchanged && f.share < 1.0)) {
      f.mixed = static_cast<int>(mixed_faces_.size());
      MixedFace m;
      m.part = f.part, m.node = f.node, m.face = f.face, m.free = std::max(0.0, 1.0 - f.share);
      m.exchange = f.exchange;
      m.scale = uncovered(f.part, 2 * f.node + (f.face == sdk::kTop ? 1 : 0));
      if (m.exchange < 0) m.h_ex = f.h_ex, m.t_ex = f.t_ex;
      mixed_faces_.push_back(m);
    }
  }
  // The mixed faces' contacts, grouped by face.
  for (MixedFace& m : mixed_faces_) m.begin = m.end = 0;
  for (std::size_t c = 0; c < nc; ++c)
    if (const int k = touched[static_cast<std::size_t>(entry[c])].mixed; k >= 0) ++mixed_faces_[k].end;
  for (int k = 0, at = 0; k < static_cast<int>(mixed_faces_.size()); ++k) {
    const int n = mixed_faces_[k].end;
    mixed_faces_[k].begin = mixed_faces_[k].end = at;
    at += n;
  }
  mixed_contacts_.resize(nc);
  for (std::size_t c = 0; c < nc; ++c)
    if (const int k = touched[static_cast<std::size_t>(entry[c])].mixed; k >= 0)
      mixed_contacts_[mixed_faces_[k].end++] = static_cast<int>(c);
  for (std::size_t c = 0; c < nc; ++c) {
    const sdk::ToolHeatContact& tc = contact_map_.tool_contacts[c];
    PartState& st = *parts_[tc.part];
    const Touched& f = touched[static_cast<std::size_t>(entry[c])];
    if (f.mixed < 0) {
      (tc.face == sdk::kTop ? st.h_top : st.h_bottom)[tc.node] = tc.conductance;
      (tc.face == sdk::kTop ? st.t_top : st.t_bottom)[tc.node] = tool_views_[tc.tool].temperature;
    }
    if (renewed) renews[tc.part][2 * tc.node + (tc.face == sdk::kTop ? 1 : 0)] = -1;
    st.contact_status[tc.node] = std::max(st.contact_status[tc.node], 1.0);
  }
  // The mixed faces' values (update_far_temperatures renews them, with the
  // step's ambient and radiation).
  for (const Touched& f : touched)
    if (f.mixed >= 0) mix_face(mixed_faces_[static_cast<std::size_t>(f.mixed)], f.h_ex, f.t_ex);
  exchange_faces_.clear();
  for (std::size_t p = 0; p < renews.size(); ++p)
    for (std::size_t f = 0; f < renews[p].size(); ++f)
      if (const int k = renews[p][f]; k >= 0)
        exchange_faces_.push_back({static_cast<int>(p), static_cast<int>(f / 2), f % 2 ? sdk::kTop : sdk::kBottom, k,
                                   uncovered(static_cast<int>(p), static_cast<int>(f))});
  for (const auto& l : contact_map_.links) {
    parts_[l.part_a]->contact_status[l.node_a] = 2.0;
    for (int j = 0; j < 3; ++j)
      if (l.w_b[j] > 0) parts_[l.part_b]->contact_status[l.nodes_b[j]] = 2.0;
  }
}

sdk::ThermalStepReport Simulation::thermal_report() {
  if (face_values_.size() != parts_.size()) {
    face_values_.resize(parts_.size());
    face_value_spans_.resize(parts_.size());
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      face_values_[p].assign(2 * static_cast<std::size_t>(parts_[p]->mesh.num_nodes()), 0.0);
      face_value_spans_[p] = face_values_[p];
    }
  }
  sdk::ThermalStepReport rep;
  rep.face_values = face_value_spans_;
  return rep;
}

// The heat through the faces and links over the thermal step just taken, at
// the face values the splitter took them at (those at the end of the step
// where it does not say): a face receives dt A h (t_ext - value), of which
// each tool contact's dt A h_k (T_tool - value) and the heat exchange's
// the rest (on a face without a tool, all of it). Where the splitter gives
// its face values, the faces' sum is its heat_in and each part's stored
// change is its tools', heat exchanges' and links' heat (to round-off).
void Simulation::accumulate_face_heat(double dt, const sdk::ThermalStepReport& rep) {
  const bool given = rep.face_values_filled && face_values_.size() == parts_.size();
  auto face_value = [&](int part, int node, int face) {
    if (given) return face_values_[part][2 * static_cast<std::size_t>(node) + (face == sdk::kTop ? 1 : 0)];
    const PartState& st = *parts_[part];
    const std::size_t base = static_cast<std::size_t>(st.nz) * node;
    return face == sdk::kTop ? st.T[base + st.nz - 1] : st.T[base];
  };
  if (part_exchange_heat_.size() != parts_.size()) part_exchange_heat_.assign(parts_.size(), 0.0);
  if (part_tool_heat_.size() != parts_.size()) part_tool_heat_.assign(parts_.size(), 0.0);
  // Per part, 2 per node: 1 where a tool alone gives the face its
  // condition, 2 where tools and a heat exchange share it (MixedFace).
  if (face_kind_.size() != parts_.size()) {
    face_kind_.resize(parts_.size());
    for (std::size_t p = 0; p < parts_.size(); ++p)
      face_kind_[p].assign(2 * static_cast<std::size_t>(parts_[p]->mesh.num_nodes()), 0);
  }
  auto slot = [](int node, int face) { return 2 * static_cast<std::size_t>(node) + (face == sdk::kTop ? 1 : 0); };
  for (const auto& tc : contact_map_.tool_contacts) face_kind_[tc.part][slot(tc.node, tc.face)] = 1;
  for (const MixedFace& m : mixed_faces_) face_kind_[m.part][slot(m.node, m.face)] = 2;
  // The faces without a tool, summed in fixed blocks of nodes and the
  // blocks in order: the same bits for any thread count.
  constexpr int kBlock = 8192;
  std::vector<double>& exchange = step_exchange_;  // per part, this step (W)
  exchange.assign(parts_.size(), 0.0);
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    const PartState& st = *parts_[p];
    const int part = static_cast<int>(p), n = st.mesh.num_nodes(), blocks = (n + kBlock - 1) / kBlock;
    const char* kind = face_kind_[p].data();
    block_sums_.assign(static_cast<std::size_t>(blocks), 0.0);
#pragma omp parallel for schedule(static) if (blocks > 1)
    for (int b = 0; b < blocks; ++b) {
      double q = 0;
      for (int i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
        if (st.h_bottom[i] != 0 && kind[2 * i] != 1)
          q += st.area[i] * st.h_bottom[i] * (st.t_bottom[i] - face_value(part, i, sdk::kBottom));
        if (st.h_top[i] != 0 && kind[2 * i + 1] != 1)
          q += st.area[i] * st.h_top[i] * (st.t_top[i] - face_value(part, i, sdk::kTop));
      }
      block_sums_[static_cast<std::size_t>(b)] = q;
    }
    for (double q : block_sums_) exchange[p] += q;
  }
  for (const auto& tc : contact_map_.tool_contacts) {
    const double w = parts_[tc.part]->area[tc.node] * tc.conductance *
                     (tool_views_[tc.tool].temperature - face_value(tc.part, tc.node, tc.face));
    tool_heat_[tc.tool] += w * dt;
    part_tool_heat_[tc.part] += w * dt;
    if (face_kind_[tc.part][slot(tc.node, tc.face)] == 2)
      exchange[tc.part] -= w;  // a mixed face: the exchange's share is the rest
  }
  for (std::size_t p = 0; p < parts_.size(); ++p) part_exchange_heat_[p] += exchange[p] * dt;
  if (!given && !face_values_missing_ &&
      (!contact_map_.tool_contacts.empty() || !contact_map_.links.empty() ||
       std::any_of(exchange.begin(), exchange.end(), [](double q) { return q != 0; }))) {
    face_values_missing_ = true;
    logger("solve")->warn(
        "the thermal splitter '{}' does not report its face values (ThermalStepReport::face_values): the heat by "
        "source (tools.csv heat_J, summary.json heat) is taken at the end-of-step face temperatures; each ply's "
        "heat_J.balance_error in summary.json says how far off it is",
        job_.thermal->splitter);
  }
  for (const auto& tc : contact_map_.tool_contacts) face_kind_[tc.part][slot(tc.node, tc.face)] = 0;
  // Ply/ply: G (T_b - T_a) into a, out of b, with the facing surface values.
  if (link_heat_.size() != parts_.size()) link_heat_.assign(parts_.size(), 0.0);
  for (const auto& l : contact_map_.links) {
    double Tb = 0;
    for (int j = 0; j < 3; ++j) Tb += l.w_b[j] * face_value(l.part_b, l.nodes_b[j], l.face_b);
    const double q = l.conductance * (Tb - face_value(l.part_a, l.node_a, l.face_a)) * dt;
    link_heat_[l.part_a] += q;
    link_heat_[l.part_b] -= q;
  }
}

void Simulation::keep_step_temperatures() {
  for (auto& st : parts_) {
    if (!st->kt.empty()) {
      const long long n = static_cast<long long>(st->T.size());
      const double* T = st->T.data();
      double* k = st->k_field.data();
      const ConductivityTable& kt = st->kt;
#pragma omp parallel for schedule(static) if (n > 8192)
      for (long long v = 0; v < n; ++v) kt.value(T[v], k + 3 * v);
    }
    if (st->T_step.empty()) continue;
    const long long n = static_cast<long long>(st->T.size());
    const double* T = st->T.data();
    double* T0 = st->T_step.data();
#pragma omp parallel for schedule(static) if (n > 8192)
    for (long long k = 0; k < n; ++k) T0[k] = T[k];
  }
}

// After a splitter's step over dt: with a specific heat table, the splitter
// advanced with c_min and each value gets the heat it was given, c_min
// (T* - T_old) per kg, on the table's enthalpy curve; with crystallisation,
// each value's Nakamura integral takes the step's K at the mean of its old
// and new temperatures (the midpoint rule) times dt, and the value gets the
// latent heat of its new crystallinity.
void Simulation::finish_thermal_step(double dt) {
  for (auto& stp : parts_) {
    PartState& st = *stp;
    if (st.T_step.empty()) continue;
    const HeatCapacityTable& cp = st.cp;
    const CrystallisationKinetics& kin = st.kin;
    const bool table = !cp.empty(), crystallising = !kin.empty();
    const double c_min = cp.c_min(), latent = kin.latent_heat(), per_c = st.c_latent > 0 ? 1.0 / st.c_latent : 0.0;
    // Infinity without melting. At or above the end of the melting no
    // crystal survives: such values skip the kinetics (a crystal formed
    // there would melt again at once, its heat given back).
    const double melt_onset = kin.melting_onset(), melt_end = kin.melting_end();
    const long long n = static_cast<long long>(st.T.size());
    double* T = st.T.data();
    const double* T0 = st.T_step.data();
    double* theta = st.theta.data();
    double* X = st.X.data();
#pragma omp parallel for schedule(static) if (n > 8192)
    for (long long k = 0; k < n; ++k) {
      double t = T[k];
      if (table && t != T0[k]) t = cp.advance(T0[k], c_min * (t - T0[k]));
      if (crystallising && X[k] < 1.0 && t < melt_end) {
        const double r = kin.rate(0.5 * (T0[k] + t));
        if (r > 0) {
          // theta < 0: the value melted since it last crystallised; theta
          // is then the integral that gives its X (taken here, where it is
          // needed, not at every step of a melting value).
          if (theta[k] < 0) theta[k] = kin.integral(X[k]);
          theta[k] += r * dt;
          const double x = kin.crystallinity(theta[k]);
          const double e = latent * (x - X[k]);  // J/kg
          X[k] = x;
          if (e > 0) t = table ? cp.advance(t, e) : t + e * per_c;
        }
      }
      // Melting: more crystals than survive at t melt down to s(T'), at the
      // temperature T' their heat of melting leaves the value at.
      if (crystallising && t > melt_onset && X[k] > kin.solid_share(t)) {
        const double x0 = X[k], t0 = t;
        const auto [x, t1] = kin.melt(
            x0, t0, [&](double tt) { return table ? cp.enthalpy(tt) : st.c_latent * tt; },
            [&](double xm) {
              const double e = latent * (xm - x0);  // J/kg, <= 0
              return table ? cp.advance(t0, e) : t0 + e * per_c;
            });
        X[k] = x;
        theta[k] = -1.0;  // the integral of x, when the value next crystallises
        t = t1;
      }
      T[k] = t;
    }
  }
}

double Simulation::stored_heat() const {
  double e = 0;
  for (std::size_t p = 0; p < parts_.size(); ++p) e += stored_heat(static_cast<int>(p));
  return e;
}

double Simulation::stored_heat(int part) const {
  const PartState& st = *parts_.at(part);
  double e = 0;
  if (!st.cp.empty()) {  // the capacities are those of c_min: mass x c_min
    const double per_c = 1.0 / st.cp.c_min();
    for (std::size_t k = 0; k < st.T.size(); ++k) e += st.cap[k] * per_c * st.cp.enthalpy(st.T[k]);
  } else {
    for (std::size_t k = 0; k < st.T.size(); ++k) e += st.cap[k] * st.T[k];
  }
  // The latent heat still held by the melt: mass x latent_heat x (1 - X),
  // counted from the crystallinity 0 (the constant is irrelevant to changes).
  if (!st.kin.empty()) {
    const double per_c = 1.0 / (st.cp.empty() ? st.c_latent : st.cp.c_min());
    for (std::size_t k = 0; k < st.X.size(); ++k) e -= st.cap[k] * per_c * st.kin.latent_heat() * st.X[k];
  }
  return e;
}

void Simulation::set_initial_temperature(int part, std::span<const double> per_node) {
  PartState& st = *parts_.at(part);
  if (static_cast<int>(per_node.size()) != st.mesh.num_nodes())
    throw std::invalid_argument("set_initial_temperature: one value per node expected");
  for (int i = 0; i < st.mesh.num_nodes(); ++i)
    for (int k = 0; k < st.nz; ++k) st.T[static_cast<std::size_t>(st.nz) * i + k] = per_node[i];
}

std::span<const double> Simulation::initial_coordinates(int part) const { return parts_.at(part)->x0; }
std::span<const double> Simulation::temperature(int part) const { return parts_.at(part)->T; }
std::span<const double> Simulation::crystallinity(int part) const { return parts_.at(part)->X; }

std::string describe_crystallisation(const MaterialDef& m) {
  const auto& c = m.crystallisation;
  const CrystallisationKinetics kin(c.latent_heat, c.avrami_exponent, c.rate_rows, c.k_max, c.t_max, c.half_width,
                                    c.melting_rows);
  std::ostringstream os;
  os << "crystallisation (Nakamura, n = " << fmt_g(c.avrami_exponent) << ", latent heat " << fmt_g(c.latent_heat)
     << " J/kg";
  if (c.matrix_latent_heat >= 0)
    os << " of ply: " << fmt_g(c.matrix_latent_heat) << " J/kg of matrix x its mass fraction "
       << fmt_g(m.mixture_matrix_mass_fraction, 4);
  os << "), rate ";
  if (!c.rate_rows.empty()) {
    double k_max = 0;
    for (const auto& r : c.rate_rows) k_max = std::max(k_max, r[1]);
    os << "from " << c.rate_rows.size() << " rows between " << fmt_g(c.rate_rows.front()[0]) << " and "
       << fmt_g(c.rate_rows.back()[0]) << " degC, up to " << fmt_g(k_max) << " 1/s";
  } else {
    os << fmt_g(c.k_max) << " 1/s at " << fmt_g(c.t_max) << " degC, half width " << fmt_g(c.half_width) << " K";
  }
  // The half-crystallisation temperature at the usual DSC cooling rate.
  const double t_half = kin.temperature_at(0.5, 10.0 / 60.0, kin.upper_temperature());
  if (std::isfinite(t_half)) os << "; cooled at 10 K/min, half crystallised at " << fmt_g(t_half, 4) << " degC";
  if (kin.melts()) {
    os << "; melting from " << fmt_g(kin.melting_onset()) << " to " << fmt_g(kin.melting_end())
       << " degC, half melted at " << fmt_g(kin.melting_temperature(0.5), 4) << " degC";
    if (std::isfinite(t_half) && t_half > kin.melting_onset())
      os << " (the half crystallisation is above the melting's onset: crystals formed there melt again at once; "
            "check the rate and the melting rows)";
  }
  else
    os << "; no melting (the crystallinity never decreases)";
  return os.str();
}
int Simulation::values_per_node(int part) const { return parts_.at(part)->nz; }

void Simulation::check_field(double time, long long step) {
  const auto& thresholds = job_.output.temperature_threshold;  // per part, empty: none
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState* st = parts_[p].get();
    // Branch-free pass (vectorised): range, and whether every value is
    // finite; the slow search for the culprit runs only then.
    const double* T = st->T.data();
    const std::size_t n = st->T.size();
    // v - v is 0 for a finite value, NaN otherwise (in any summation order).
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, z = 0;
#pragma omp simd reduction(min : lo) reduction(max : hi) reduction(+ : z)
    for (std::size_t k = 0; k < n; ++k) {
      const double v = T[k];
      lo = v < lo ? v : lo;
      hi = v > hi ? v : hi;
      z += v - v;
    }
    const bool bad = !(z == 0.0);
    seen_min_ = std::min(seen_min_, lo);
    seen_max_ = std::max(seen_max_, hi);
    if (!thresholds.empty() && below_from_[p] < 0 && lo < thresholds[p]) below_from_[p] = time;
    if (!thresholds.empty() && all_below_from_[p] < 0 && hi < thresholds[p]) all_below_from_[p] = time;
    if (!st->below_from.empty() && lo < thresholds[p] && !(all_below_from_[p] >= 0 && all_below_from_[p] < time)) {
      // Node by node, until every node has set through (then nothing changes).
      const int nz = st->nz;
      const double th = thresholds[p];
      double* below = st->below_from.data();
      double* all_below = st->all_below_from.data();
      const long long nn = st->mesh.num_nodes();
#pragma omp parallel for schedule(static) if (n > 65536)
      for (long long i = 0; i < nn; ++i) {
        if (!std::isnan(all_below[i])) continue;
        const double* Ti = T + static_cast<std::size_t>(nz) * i;
        double mn = Ti[0], mx = Ti[0];
        for (int k = 1; k < nz; ++k) {
          mn = Ti[k] < mn ? Ti[k] : mn;
          mx = Ti[k] > mx ? Ti[k] : mx;
        }
        if (std::isnan(below[i]) && mn < th) below[i] = time;
        if (mx < th) all_below[i] = time;
      }
    }
    if (!bad) continue;
    for (std::size_t k = 0; k < n; ++k) {
      if (!std::isfinite(st->T[k])) {
        const int i = static_cast<int>(k / st->nz);
        throw RunError("non-finite temperature in part '" + st->def->name + "' at " + node_label(st->mesh, i) + " (" +
                       fmt_g(st->x0[3 * i], 4) + ", " + fmt_g(st->x0[3 * i + 1], 4) + ", " +
                       fmt_g(st->x0[3 * i + 2], 4) + "), layer value " + std::to_string(k % st->nz) + ", at t = " +
                       fmt_g(time) + " s (thermal step " + std::to_string(step) + ")");
      }
    }
  }
}

}  // namespace ts
