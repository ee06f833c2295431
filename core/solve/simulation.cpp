// The model of a job and its mechanical step: the parts, tools, probes and
// mechanics set up from the job, the element blocks and their order on the
// threads, the contact forces as tasks, and the explicit step with its
// energy audit (docs/mechanics-method.md). The thermal side is in
// solve/thermal_coupling.cpp, the time loop in solve/run.cpp.
#include "solve/simulation.hpp"
#include "solve/simulation_internal.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <map>
#include <thread>
#ifdef _OPENMP
#include <omp.h>
#endif
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include <thermostamp/sdk/memory.hpp>
#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/parallel.hpp>
#include <thermostamp/sdk/simd.hpp>

#include "io/logging.hpp"
#include "solve/rigid_body.hpp"
#include "solve/stability.hpp"
#include "solve/tools.hpp"

namespace ts {

using detail::Clock;
using detail::fmt_g;
using detail::fmt_vec3;
using detail::seconds_since;
using detail::thickness_mean;
using sdk::Vec3;

namespace {

// Whether the point X lies in the constraint's box (its faces included).
bool in_box(const ConstraintDef& c, const double* X) {
  for (int d = 0; d < 3; ++d)
    if (!(X[d] >= c.lo[d] && X[d] <= c.hi[d])) return false;
  return true;
}

// One explicit step of n dofs (central differences, lumped mass): the new
// half-step velocities and positions, and the works of the previous step
// by the trapezoid rule (internal, external, damping, contact) with the
// kinetic energies at t^n, summed into sums[0..6] (w_int, w_ext, w_damp,
// w_con, kinetic, kinetic at the half step, and x * 0, which is zero unless
// a position is not finite). A held or driven dof (listed in fixed[0..nfixed),
// its mass3 negated to mark it) takes its prescribed velocity; the constraint supplies
// R = f_int - f_ext - f_con there, and its work enters w_ext. The vector
// pass leaves those dofs as they are; a scalar pass over the list moves
// them (so that the pass reads neither a per-dof flag nor the prescribed
// velocities).
//
// The trapezoid work of a force f over the step from x^{n-1} to x^n is
// 1/2 (f^{n-1} + f^n) . (x^n - x^{n-1}). Its first half is known one step
// early: pending[0..3] carries 1/2 f^n . (x^{n+1} - x^n) of each work to the
// next call, which adds it (so no force of the previous step is stored per
// dof). The increment x^n - x^{n-1} is dt_prev v^{n-1/2}, the same product
// that moved the dof (0 at the first step: dt_prev = 0). Elementwise, so the
// trajectory does not depend on the vector width; the sums are taken lane
// by lane (a fixed order, but not the one of a scalar loop). Instantiated
// with and without contact forces and external forces (gravity, loads),
// so that a run without them reads neither.
template <bool kContact, bool kExternal, bool kNormalDamping>
[[gnu::always_inline]] inline void integrate_body(std::size_t n, double dt, double dt_prev, double dt_avg,
                                                  double damping, const double* __restrict damped_v,
                                                  const double* __restrict mass3,
                                                  const double* __restrict gravity3, const double* __restrict load,
                                                  const double* __restrict f_int, const double* __restrict f_con,
                                                  const int* __restrict fixed, std::size_t nfixed,
                                                  const double* __restrict prescribed, double* __restrict v,
                                                  double* __restrict x, double* __restrict pending,
                                                  double* __restrict sums) {
  double w_int = 0, w_ext = 0, w_damp = 0, w_con = 0, kin = 0, kin_half = 0, nonfinite = 0;
  double p_int = 0, p_ext = 0, p_damp = 0, p_con = 0;
#pragma omp simd reduction(+ : w_int, w_ext, w_damp, w_con, kin, kin_half, nonfinite, p_int, p_ext, p_damp, p_con)
  for (std::size_t k = 0; k < n; ++k) {
    const double mi = mass3[k], vo = v[k], dxo = dt_prev * vo;
    const bool is_free = !(mi < 0);
    const double fi = f_int[k];
    const double f_ext = kExternal ? gravity3[k] + load[k] : 0.0;
    const double fc = kContact ? f_con[k] : 0.0;
    const double f_damp = damping * mi * (kNormalDamping ? damped_v[k] : vo);
    const double v_new = vo + dt_avg * (f_ext + fc - fi - f_damp) / mi;
    const double dxn = dt * v_new;
    const double xo = x[k], xn = xo + dxn;
    w_int += is_free ? 0.5 * fi * dxo : 0.0;
    p_int += is_free ? 0.5 * fi * dxn : 0.0;
    // The loads' work by the trapezoidal rule, as the internal forces'
    // (a gripper's follows the positions); gravity's is exact as it is.
    const double f_load = kExternal ? load[k] : 0.0;
    w_ext += is_free ? (f_ext - 0.5 * f_load) * dxo : 0.0;
    p_ext += is_free ? 0.5 * f_load * dxn : 0.0;
    w_damp += is_free ? 0.5 * f_damp * dxo : 0.0;
    p_damp += is_free ? 0.5 * f_damp * dxn : 0.0;
    if (kContact) {
      w_con += is_free ? 0.5 * fc * dxo : 0.0;
      p_con += is_free ? 0.5 * fc * dxn : 0.0;
    }
    // Kinetic energy at t^n as the product of the half-step velocities: the
    // energy that central differences conserve exactly for a linear system.
    kin += is_free ? 0.5 * mi * vo * v_new : 0.0;
    kin_half += is_free ? 0.5 * mi * v_new * v_new : 0.0;
    v[k] = is_free ? v_new : vo;
    x[k] = is_free ? xn : xo;
    nonfinite += is_free ? xn * 0.0 : 0.0;
  }
  for (std::size_t j = 0; j < nfixed; ++j) {
    const int k = fixed[j];
    const double vo = v[k], dxo = dt_prev * vo, fi = f_int[k];
    const double f_ext = kExternal ? gravity3[k] + load[k] : 0.0;
    const double fc = kContact ? f_con[k] : 0.0;
    const double reaction = fi - f_ext - fc;
    const double v_new = prescribed[k], dxn = dt * v_new;
    w_int += 0.5 * fi * dxo;
    p_int += 0.5 * fi * dxn;
    w_ext += (0.5 * reaction + f_ext) * dxo;
    p_ext += 0.5 * reaction * dxn;
    if (kContact) {
      w_con += 0.5 * fc * dxo;
      p_con += 0.5 * fc * dxn;
    }
    v[k] = v_new;
    const double xn = x[k] + dxn;
    x[k] = xn;
    nonfinite += xn * 0.0;
  }
  sums[0] = w_int + pending[0];
  sums[1] = w_ext + pending[1];
  sums[2] = w_damp + pending[2];
  sums[3] = w_con + pending[3];
  sums[4] = kin;
  sums[5] = kin_half;
  sums[6] = nonfinite;
  pending[0] = p_int;
  pending[1] = p_ext;
  pending[2] = p_damp;
  pending[3] = p_con;
}
#define TS_INTEGRATE(NAME, CONTACT, EXTERNAL, NORMAL)                                                                \
  TS_VECTOR_CLONES void NAME(std::size_t n, double dt, double dt_prev, double dt_avg, double damping,                \
                             const double* damped_v, const double* mass3, const double* gravity3,                   \
                             const double* load, const double* f_int, const double* f_con, const int* fixed,         \
                             std::size_t nfixed, const double* prescribed, double* v, double* x, double* pending,    \
                             double* sums) {                                                                         \
    integrate_body<CONTACT, EXTERNAL, NORMAL>(n, dt, dt_prev, dt_avg, damping, damped_v, mass3, gravity3, load,      \
                                              f_int, f_con, fixed, nfixed, prescribed, v, x, pending, sums);         \
  }
TS_INTEGRATE(integrate_dofs, false, false, false)
TS_INTEGRATE(integrate_dofs_contact, true, false, false)
TS_INTEGRATE(integrate_dofs_external, false, true, false)
TS_INTEGRATE(integrate_dofs_contact_external, true, true, false)
TS_INTEGRATE(integrate_dofs_normal, false, false, true)
TS_INTEGRATE(integrate_dofs_contact_normal, true, false, true)
TS_INTEGRATE(integrate_dofs_external_normal, false, true, true)
TS_INTEGRATE(integrate_dofs_contact_external_normal, true, true, true)
#undef TS_INTEGRATE
using IntegrateDofs = void (*)(std::size_t, double, double, double, double, const double*, const double*,
                               const double*, const double*, const double*, const double*, const int*,
                               std::size_t, const double*, double*, double*, double*, double*);
// By [damping along the normals only][contact][external forces].
constexpr IntegrateDofs kIntegrateDofs[2][2][2] = {
    {{integrate_dofs, integrate_dofs_external}, {integrate_dofs_contact, integrate_dofs_contact_external}},
    {{integrate_dofs_normal, integrate_dofs_external_normal},
     {integrate_dofs_contact_normal, integrate_dofs_contact_external_normal}}};

// Each node's summed normal made a unit vector ((0, 0, 1) exactly on a
// flat ply), and the part of its velocity along it, per dof. One vector
// pass; the velocity's loads are not under a select (GCC 12.2 makes them
// masked loads in the x86-64-v4 version and gets that version wrong).
TS_VECTOR_CLONES void project_on_normals(std::size_t nn, double* __restrict normal, const double* __restrict v,
                                         double* __restrict out) {
#pragma omp simd
  for (std::size_t i = 0; i < nn; ++i) {
    const double a = normal[3 * i], b = normal[3 * i + 1], c = normal[3 * i + 2];
    const double len = std::sqrt(a * a + b * b + c * c);
    const double na = len > 0 ? a / len : 0.0, nb = len > 0 ? b / len : 0.0, nc = len > 0 ? c / len : 0.0;
    normal[3 * i] = na;
    normal[3 * i + 1] = nb;
    normal[3 * i + 2] = nc;
    const double vn = v[3 * i] * na + v[3 * i + 1] * nb + v[3 * i + 2] * nc;
    out[3 * i] = vn * na;
    out[3 * i + 1] = vn * nb;
    out[3 * i + 2] = vn * nc;
  }
}

// Each triangle's (x1 - x0) x (x2 - x0): twice its area times its unit
// normal. One vector pass.
TS_VECTOR_CLONES void triangle_cross(std::size_t ne, const int* __restrict tri, const double* __restrict x,
                                     double* __restrict cross) {
#pragma omp simd
  for (std::size_t e = 0; e < ne; ++e) {
    const std::size_t a = 3 * static_cast<std::size_t>(tri[3 * e]), b = 3 * static_cast<std::size_t>(tri[3 * e + 1]),
                      c = 3 * static_cast<std::size_t>(tri[3 * e + 2]);
    const double u0 = x[b] - x[a], u1 = x[b + 1] - x[a + 1], u2 = x[b + 2] - x[a + 2];
    const double w0 = x[c] - x[a], w1 = x[c + 1] - x[a + 1], w2 = x[c + 2] - x[a + 2];
    cross[3 * e] = u1 * w2 - u2 * w1;
    cross[3 * e + 1] = u2 * w0 - u0 * w2;
    cross[3 * e + 2] = u0 * w1 - u1 * w0;
  }
}

// The part of each node's velocity along its normal, per dof: the normal
// of a node is the sum of the cross products of its triangles (in
// ascending order), made a unit vector; the same for any thread count.
void normal_velocities(const ShellMesh& mesh, const double* x, const double* v, MechPart& m) {
  const std::size_t nn = static_cast<std::size_t>(mesh.num_nodes()), ne = mesh.triangles.size() / 3;
  if (m.node_tri_start.size() != nn + 1) {  // each node's triangles, once
    m.node_tri_start.assign(nn + 1, 0);
    for (const int i : mesh.triangles) ++m.node_tri_start[static_cast<std::size_t>(i) + 1];
    for (std::size_t i = 0; i < nn; ++i) m.node_tri_start[i + 1] += m.node_tri_start[i];
    m.node_tri.assign(mesh.triangles.size(), 0);
    std::vector<int> fill(m.node_tri_start.begin(), m.node_tri_start.end() - 1);
    for (std::size_t e = 0; e < ne; ++e)
      for (int k = 0; k < 3; ++k) m.node_tri[static_cast<std::size_t>(fill[static_cast<std::size_t>(mesh.triangles[3 * e + k])]++)] = static_cast<int>(e);
    m.tri_cross.resize(3 * ne);
    m.node_normal.resize(3 * nn);
    m.normal_velocity.resize(3 * nn);
  }
  triangle_cross(ne, mesh.triangles.data(), x, m.tri_cross.data());
  for (std::size_t i = 0; i < nn; ++i) {
    double a = 0, b = 0, c = 0;
    for (int k = m.node_tri_start[i]; k < m.node_tri_start[i + 1]; ++k) {
      const double* cr = &m.tri_cross[3 * static_cast<std::size_t>(m.node_tri[static_cast<std::size_t>(k)])];
      a += cr[0];
      b += cr[1];
      c += cr[2];
    }
    m.node_normal[3 * i] = a;
    m.node_normal[3 * i + 1] = b;
    m.node_normal[3 * i + 2] = c;
  }
  project_on_normals(nn, m.node_normal.data(), v, m.normal_velocity.data());
}

// A spin-wait hint to the processor (a shorter wait on x86 than a plain
// loop, and the sibling hyperthread gets the core).
inline void spin_pause() {
#if defined(__SSE2__)
  _mm_pause();
#endif
}

// Waits until ready() holds: spinning, then yielding (with more threads
// than cores, the thread being waited for needs the core).
template <class Ready>
void spin_until(Ready ready) {
  for (int spins = 0; !ready(); ++spins)
    if (spins < 4096)
      spin_pause();
    else
      std::this_thread::yield();
}

// dst = src, written with streaming (non-temporal) stores: the lines go to
// memory without being read into this core's cache, and another core's
// copies of them are dropped without this core waiting for each.
// Ordered before later stores by the sfence at the end.
void stream_copy(const double* src, double* dst, std::size_t n) {
#if defined(__SSE2__)
  std::size_t i = 0;
  if (reinterpret_cast<std::uintptr_t>(dst) % 16 != 0 && n > 0) {
    dst[0] = src[0];
    i = 1;
  }
  for (; i + 2 <= n; i += 2) _mm_stream_pd(dst + i, _mm_loadu_pd(src + i));
  for (; i < n; ++i) dst[i] = src[i];
  _mm_sfence();
#else
  std::copy(src, src + n, dst);
#endif
}

void compute_normals(const ShellMesh& m, std::span<const double> x, std::vector<double>& nn) {
  nn.assign(x.size(), 0.0);
  for (int e = 0; e < m.num_elements(); ++e) {
    const int* t = &m.triangles[3 * e];
    const Vec3 a = sdk::load3(x.data(), t[0]), b = sdk::load3(x.data(), t[1]), c = sdk::load3(x.data(), t[2]);
    const Vec3 n = sdk::cross(sdk::sub(b, a), sdk::sub(c, a));
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) nn[3 * t[k] + d] += n[d];
  }
  for (std::size_t i = 0; i < nn.size() / 3; ++i) {
    const Vec3 u = sdk::normalized(sdk::load3(nn.data(), static_cast<int>(i)));
    for (int d = 0; d < 3; ++d) nn[3 * i + d] = u[d];
  }
}

}  // namespace

Simulation::Simulation(const Job& job, PluginRegistry& registry) try : job_(job), registry_(registry) {
  for (const auto& p : job_.plugin_paths) registry_.add_search_dir(p);
  if (!job_.thermal && !job_.mechanics)
    throw JobError("/solvers", "nothing to run: set solvers.thermal (a thermal splitter such as \"adi\")");
  want_tool_gap_ = std::find(job_.output.fields.begin(), job_.output.fields.end(), "tool_gap") !=
                  job_.output.fields.end();
  want_below_from_ = std::find(job_.output.fields.begin(), job_.output.fields.end(), "below_threshold_from") !=
                     job_.output.fields.end();
  want_conductance_ = std::find(job_.output.fields.begin(), job_.output.fields.end(), "conductance") !=
                      job_.output.fields.end();
  want_pressure_ = std::find(job_.output.fields.begin(), job_.output.fields.end(), "contact_pressure") !=
                   job_.output.fields.end();
  want_thickness_ = std::find(job_.output.fields.begin(), job_.output.fields.end(), "thickness") !=
                    job_.output.fields.end();
  for (const auto& pr : job_.output.probes) {
    want_thickness_ = want_thickness_ ||
                      std::find(pr.quantities.begin(), pr.quantities.end(), "thickness") != pr.quantities.end();
    probe_pressure_.push_back(std::find(pr.quantities.begin(), pr.quantities.end(), "contact_pressure") !=
                              pr.quantities.end());
    want_pressure_ = want_pressure_ || probe_pressure_.back();
  }
  build_parts();
  build_tools();
  // Before the thermal and mechanical set-up, whose checks such values
  // often fail first (a step too small to reach the end).
  warn_large_meshes();
  refuse_impossible_plies();
  warn_unlikely_units();
  build_thermal();
  if (!job_.thermal) {  // isothermal: one constant value per node
    for (auto& st : parts_) {
      if (!st->def->initial_results.empty())
        throw JobError(st->def->pointer + "/initial_temperature",
                       "temperatures from a results file need the thermal solver (solvers.thermal)");
      st->t0 = st->def->initial_temperature;
      st->nz = 1;
      st->T.assign(st->mesh.num_nodes(), st->def->initial_temperature);
      st->cap.assign(st->mesh.num_nodes(), 0.0);
      st->mean.assign(st->mesh.num_nodes(), 0.0);
      st->top.assign(st->mesh.num_nodes(), 0.0);
      st->bottom.assign(st->mesh.num_nodes(), 0.0);
    }
  }
  if (job_.mechanics) {
    build_mechanics();
    if (!contacts_.empty()) build_contact_tasks();
  }
  build_probes();
  warn_plies_behind_tools();
} catch (const JobError& e) {
  // A value a material took from its card: the error names the card.
  throw with_material_card(job, e);
}

Simulation::~Simulation() = default;

std::vector<std::string> Simulation::mesh_file_lines() const {
  std::vector<std::string> lines;
  for (const auto& st : parts_) {
    const MeshDef& m = st->def->mesh;
    if (m.kind != MeshDef::Kind::File) continue;
    lines.push_back("part '" + st->def->name + "': " + std::to_string(st->mesh.num_elements()) + " triangles, " +
                    std::to_string(st->mesh.num_nodes()) + " nodes from " + m.file.string() +
                    (m.scale != 1.0 ? " (its coordinates times " + fmt_g(m.scale) + ")" : std::string()) + ", " +
                    (m.reorder ? "numbered so that neighbours are close (mesh.reorder)" : "in the file's order") +
                    " (neighbouring triangles at most " + std::to_string(element_bandwidth(st->mesh)) +
                    " places apart)");
  }
  for (const auto& tool : tools_)
    if (std::string line = tool->describe(); !line.empty()) lines.push_back(std::move(line));
  return lines;
}

// ", rigid jaws" or ", swivelling jaws", the directions in which they are
// held and how swivelling jaws may turn; or nothing.
std::string Simulation::jaw_words(const Gripper& g) const {
  const ConstraintDef& c = job_.constraints[g.constraint];
  if (!c.rigid) return "";
  std::string held;
  for (int d = 0; d < 3; ++d)
    if (g.held_by[d] >= 0)
      held += (held.empty() ? "" : ", ") + std::string(1, static_cast<char>('x' + d)) + " by " +
              job_.constraints[g.held_by[d]].pointer;
  std::string turning;  // swivelling: about which axes, and where
  if (c.swivelling) {
    std::string axes;
    for (int d = 0; d < 3; ++d)
      if (g.on_symmetry[d]) axes += std::string(axes.empty() ? "" : " and ") + static_cast<char>('x' + d);
    const int planes = static_cast<int>(g.on_symmetry[0]) + g.on_symmetry[1] + g.on_symmetry[2];
    turning = planes >= 2 ? "; on two symmetry planes, so only translating"
              : planes == 1 ? "; turning about " + axes + " only (a symmetry plane)"
                            : "";
    if (g.pin_node >= 0)
      turning += "; turning about " + node_label(parts_[g.pin_part]->mesh, g.pin_node) + " of part '" +
                 parts_[g.pin_part]->def->name + "'";
  }
  return std::string(c.swivelling ? ", swivelling jaws" : ", rigid jaws") +
         (held.empty() ? std::string() : " (held in " + held + ")") + turning;
}

std::vector<std::string> Simulation::gripper_lines() const {
  std::vector<std::string> lines;
  for (const Gripper& g : grippers_) {
    const ConstraintDef& c = job_.constraints[g.constraint];
    std::string names;
    for (const int p : c.parts)
      for (const auto& [gp, gi] : g.nodes)
        if (gp == p) {
          names += (names.empty() ? "'" : ", '") + parts_[p]->def->name + "'";
          break;
        }
    lines.push_back(fmt::format(
        "gripper '{}' ({}): {} node(s) of {} ({:.4g} g), a spring of {:.4g} mm from the anchor ({}, {}, {}) m to their "
        "centre, {:.4g} N/m (alone with them, a period of {:.3g} ms), preload {:.4g} N{}, {}{}{}{}",
        c.name, c.pointer, g.nodes.size(), names, 1e3 * g.mass, 1e3 * g.length0, fmt_g(c.anchor[0]),
        fmt_g(c.anchor[1]), fmt_g(c.anchor[2]), c.stiffness, 2e3 * M_PI * std::sqrt(g.mass / c.stiffness), c.preload,
        c.ramp > 0 ? " over " + fmt_g(c.ramp) + " s" : "", c.tension_only ? "pulling only" : "pulling and pushing",
        c.anchor_motion.kind == MotionDef::Kind::Fixed ? "" : ", the anchor moving",
        std::isfinite(c.release) ? ", released at " + fmt_g(c.release) + " s" : "", jaw_words(g)));
  }
  return lines;
}

std::vector<std::string> Simulation::tool_motion_lines() const {
  std::vector<std::string> lines;
  if (!job_.mechanics) return lines;
  for (const ToolDef& t : job_.tools) {
    const MotionDef& m = t.motion;
    const std::string head = "tool '" + t.name + "': ";
    if (m.kind == MotionDef::Kind::Velocity) {
      lines.push_back(head + "moves at " + fmt_vec3(m.velocity[0], m.velocity[1], m.velocity[2]) +
                      " m/s from its surface's position");
    } else if (m.kind == MotionDef::Kind::Displacement) {
      const auto& a = m.table.front();
      const auto& z = m.table.back();
      std::string line = head + "displaced by " + fmt_vec3(a[1], a[2], a[3]) + " m from its surface's position at t = 0";
      if (m.table.size() > 1)
        line += " (the first row), " + fmt_vec3(z[1], z[2], z[3]) + " m from t = " + fmt_g(z[0], 4) + " s (the last of " +
                std::to_string(m.table.size()) + " rows)";
      lines.push_back(line);
    } else if (m.kind == MotionDef::Kind::Force) {
      std::string by = fmt_vec3(m.force[0], m.force[1], m.force[2]) + " N";
      if (!m.force_table.empty()) {
        const auto& a = m.force_table.front();
        const auto& z = m.force_table.back();
        by = fmt_vec3(a[1], a[2], a[3]) + " N at t = 0 (the first row)";
        if (m.force_table.size() > 1)
          by += ", " + fmt_vec3(z[1], z[2], z[3]) + " N from t = " + fmt_g(z[0], 4) + " s (the last of " +
                std::to_string(m.force_table.size()) + " rows)";
      }
      lines.push_back(head + "pressed by " + by + ", mass " + fmt_g(m.mass, 4) + " kg, damper " + fmt_g(m.damping, 4) +
                      " N s/m, from its surface's position");
    }
  }
  return lines;
}

void Simulation::build_parts() {
  for (std::size_t p = 0; p < job_.parts.size(); ++p) {
    const PartDef& def = job_.parts[p];
    auto st = std::make_unique<PartState>();
    st->def = &def;
    try {
      st->mesh = def.mesh.kind == MeshDef::Kind::File
                     ? read_mesh(def.mesh.file, def.mesh.reorder, def.mesh.scale)
                     : rectangle_mesh(def.mesh.origin, def.mesh.size, def.mesh.divisions, def.mesh.crossed);
    } catch (const std::exception& e) {
      throw JobError(def.pointer + "/mesh", e.what());
    }
    if (def.flip)  // the ply lies upside down: its top face looks to -z
      for (int e = 0; e < st->mesh.num_elements(); ++e) {
        std::swap(st->mesh.triangles[3 * e + 1], st->mesh.triangles[3 * e + 2]);
        std::swap(st->mesh.neighbours[3 * e + 1], st->mesh.neighbours[3 * e + 2]);
      }
    st->x0 = st->mesh.x;
    st->x.assign(st->mesh.x.begin(), st->mesh.x.end());
    const int ne = st->mesh.num_elements(), nn = st->mesh.num_nodes();
    st->area = node_areas(st->mesh);
    compute_normals(st->mesh, st->x, st->normals);
    // Fibre direction projected on each element; refuse one normal to the ply.
    st->fibre.assign(3 * ne, 0.0);
    const Vec3 f0 = sdk::normalized({def.fibre_direction[0], def.fibre_direction[1], def.fibre_direction[2]});
    for (int e = 0; e < ne; ++e) {
      const int* t = &st->mesh.triangles[3 * e];
      const Vec3 a = sdk::load3(st->x.data(), t[0]), b = sdk::load3(st->x.data(), t[1]), c = sdk::load3(st->x.data(), t[2]);
      const Vec3 n = sdk::normalized(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
      const Vec3 f = sdk::sub(f0, sdk::scale(n, sdk::dot(f0, n)));
      if (sdk::norm(f) < 1e-3)
        throw JobError(def.pointer + "/fibre_direction",
                       "the fibre direction is normal to the ply at " + element_label(st->mesh, e) +
                           "; give a direction in the ply's plane");
      const Vec3 u = sdk::normalized(f);
      for (int d = 0; d < 3; ++d) st->fibre[3 * e + d] = u[d];
    }
    st->displacement.assign(3 * nn, 0.0);
    st->shear_angle.assign(ne, 0.0);
    if (want_thickness_) {
      st->area0 = element_areas(st->mesh);
      st->thickness.assign(ne, def.thickness);
    }
    st->contact_status.assign(nn, 0.0);
    if (want_pressure_) st->contact_pressure.assign(nn, 0.0);
    for (auto* v : {&st->h_bottom, &st->t_bottom, &st->h_top, &st->t_top, &st->conductance_bottom,
                    &st->conductance_top})
      v->assign(nn, 0.0);
    parts_.push_back(std::move(st));
  }
  part_views_.resize(parts_.size());
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    const MaterialDef& mat = job_.materials[st.def->material];
    sdk::PartView& v = part_views_[p];
    v.index = static_cast<int>(p);
    v.name = st.def->name;
    v.num_nodes = st.mesh.num_nodes();
    v.num_elements = st.mesh.num_elements();
    v.x0 = st.x0;
    v.x = st.x;
    v.triangles = st.mesh.triangles;
    v.neighbours = st.mesh.neighbours;
    v.fibre = st.fibre;
    v.thickness = st.def->thickness;
    v.thickness_layers = st.def->thickness_layers;
    v.initial_temperature = st.def->initial_temperature;
    v.thermal = {mat.density,          mat.specific_heat, mat.conductivity[0], mat.conductivity[1],
                 mat.conductivity[2], !mat.conductivity_table.empty()};
  }
}

// A mesh file more than 10 m across is most often one in millimetres (STL
// files carry no unit, and CAD exports them in mm): a warning that names
// its size and the `scale` that reads it in metres.
void Simulation::warn_large_meshes() const {
  constexpr double kLarge = 10.0;  // m
  for (const auto& st : parts_)
    if (st->def->mesh.kind == MeshDef::Kind::File)
      if (const double s = box_span(st->mesh.x); s > kLarge)
        logger("job")->warn("{}/mesh: the ply's mesh is {:.4g} m across: is '{}' in millimetres? (\"scale\": 0.001 "
                            "reads it in metres)",
                            st->def->pointer, s, st->def->mesh.file.filename().string());
  for (std::size_t t = 0; t < tools_.size(); ++t)
    if (const double s = tools_[t]->mesh_span(); s > kLarge)
      logger("job")->warn("{}/surface: the tool's mesh is {:.4g} m across: is '{}' in millimetres? (\"scale\": "
                          "0.001 reads it in metres)",
                          job_.tools[t].pointer, s, job_.tools[t].surface.file.filename().string());
}

// A ply below a micrometre across, or as thick as it is wide, is no shell
// the model can take: refused at its path, before the step checks that
// such values would fail less clearly (or the run would stop on).
void Simulation::refuse_impossible_plies() const {
  constexpr double kSmall = 1e-6;  // m
  for (const auto& st : parts_) {
    const double span = box_span(st->x0);
    if (span < kSmall)
      throw JobError(st->def->pointer + "/mesh", "the ply is " + fmt_g(span, 4) +
                                                     " m across: lengths are in m, and a ply below a micrometre "
                                                     "across is no part to form");
    if (st->def->thickness >= span)
      throw JobError(st->def->pointer + "/thickness",
                     fmt_g(st->def->thickness, 4) + " m for a ply " + fmt_g(span, 4) +
                         " m across: a shell is thinner than its extent (lengths are in m)");
  }
}

// Values that are most often given in another unit than the job's (m, kg,
// J, degC): a ply as thick as a good part of its width (mm for m), a
// density of a few units (g/cm^3 for kg/m^3), a specific heat of a few
// units (J/(g K) or kJ/(kg K) for J/(kg K)), a temperature above 450 degC
// (kelvin for degC). Warnings, since none of them is impossible.
void Simulation::warn_unlikely_units() const {
  for (const auto& st : parts_)
    if (const double span = box_span(st->x0); span > 0 && st->def->thickness > 0.1 * span)
      logger("job")->warn("{}/thickness: {:.4g} m for a ply {:.4g} m across: the shell model takes plies thin against "
                          "their extent; is it in millimetres? (lengths are in m)",
                          st->def->pointer, st->def->thickness, span);
  for (const MaterialDef& m : job_.materials) {
    if (m.density > 0 && m.density < 100)
      logger("job")->warn("{}/density: {:.4g} kg/m^3: is it in g/cm^3? ({:.4g} g/cm^3 is {:.4g} kg/m^3)", m.pointer,
                          m.density, m.density, 1000 * m.density);
    if (m.specific_heat > 0 && m.specific_heat < 50)
      logger("job")->warn("{}/specific_heat: {:.4g} J/(kg K): is it in J/(g K) or kJ/(kg K)? ({:.4g} kJ/(kg K) is "
                          "{:.4g} J/(kg K))",
                          m.pointer, m.specific_heat, m.specific_heat, 1000 * m.specific_heat);
  }
  constexpr double kHot = 450.0;  // degC
  auto hot = [&](const std::string& where, double t) {
    if (t > kHot)
      logger("job")->warn("{}: {:.6g} degC: is it in kelvin? (temperatures are in degC; {:.6g} K is {:.6g} degC)", where,
                          t, t, t - 273.15);
    return t > kHot;
  };
  for (const auto& st : parts_)
    if (st->def->initial_results.empty()) hot(st->def->pointer + "/initial_temperature", st->def->initial_temperature);
  for (const ToolDef& t : job_.tools) {
    if (t.temperature_table.empty()) hot(t.pointer + "/temperature", t.temperature);
    for (std::size_t r = 0; r < t.temperature_table.size(); ++r)
      if (hot(t.pointer + "/temperature/" + std::to_string(r) + "/1", t.temperature_table[r][1])) break;
  }
  for (const HeatExchangeDef& h : job_.heat_exchanges) {
    if (h.ambient_table.empty()) hot(h.pointer + "/ambient", h.ambient);
    for (std::size_t r = 0; r < h.ambient_table.size(); ++r)
      if (hot(h.pointer + "/ambient/" + std::to_string(r) + "/1", h.ambient_table[r][1])) break;
  }
}

std::string Simulation::fastest_node() const {
  double best = -1;
  int part = -1, node = -1;
  for (std::size_t p = 0; p < mech_.size() && p < parts_.size(); ++p) {
    const auto& v = mech_[p]->v;
    for (std::size_t i = 0; 3 * i + 2 < v.size(); ++i) {
      const double s2 = v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2];
      if (s2 > best) {  // NaN never: the position check names those
        best = s2;
        part = static_cast<int>(p);
        node = static_cast<int>(i);
      }
    }
  }
  if (part < 0) return {};
  const PartState& st = *parts_[static_cast<std::size_t>(part)];
  auto at = [&](const auto& x) {
    const std::size_t k = 3 * static_cast<std::size_t>(node);
    return fmt_vec3(x[k], x[k + 1], x[k + 2]) + " m";
  };
  return node_label(st.mesh, node) + " of part '" + st.def->name + "' at " + at(st.x) + " (initially " + at(st.x0) +
         "), " + fmt_g(std::sqrt(best), 3) + " m/s";
}

// A ply whose mid-surface starts behind the surface of a tool it is in
// contact with most often means a tool that faces the wrong way: the
// penalty would push it further in.
void Simulation::warn_plies_behind_tools() const {
  for (const ContactDef& c : job_.contacts) {
    if (c.first.is_tool == c.second.is_tool) continue;
    const BodyDef& tb = c.first.is_tool ? c.first : c.second;
    const BodyDef& pb = c.first.is_tool ? c.second : c.first;
    const PartState& st = *parts_[static_cast<std::size_t>(pb.index)];
    const RigidTool& tool = *tools_[static_cast<std::size_t>(tb.index)];
    const std::size_t n = st.x0.size() / 3;
    std::vector<double> d(n), normal(3 * n);
    tool.query(n, st.x0.data(), kToolGapLimit, d.data(), normal.data());
    std::size_t behind = 0;
    double deepest = 0;
    for (const double di : d)
      if (std::isfinite(di) && di < 0) {
        ++behind;
        deepest = std::max(deepest, -di);
      }
    if (behind == 0) continue;
    logger("job")->warn(
        "{}: ply '{}' starts with {} of its {} nodes behind the surface of tool '{}' (up to {:.3g} mm deep): is the "
        "tool's outside on the other side? (`flip` for a mesh; walk a revolved profile the other way)",
        c.pointer, st.def->name, behind, n, job_.tools[static_cast<std::size_t>(tb.index)].name, 1e3 * deepest);
  }
}

void Simulation::build_tools() {
  for (std::size_t t = 0; t < job_.tools.size(); ++t) {
    auto tool = std::make_unique<RigidTool>(job_.tools[t]);
    if (job_.tools[t].motion.kind != MotionDef::Kind::Fixed && !job_.mechanics)
      logger("job")->warn("{}/motion: ignored, tools do not move in a thermal-only job", job_.tools[t].pointer);
    tools_.push_back(std::move(tool));
  }
  if (!job_.mechanics)
    for (const ConstraintDef& c : job_.constraints)
      logger("job")->warn("{}: ignored, constraints act on the mechanics and a thermal-only job has none", c.pointer);
  tool_force_.assign(3 * tools_.size(), 0.0);
  tool_heat_.assign(tools_.size(), 0.0);
  for (std::size_t t = 0; t < tools_.size(); ++t) {
    sdk::ToolView v;
    v.index = static_cast<int>(t);
    v.name = job_.tools[t].name;
    v.temperature = job_.tools[t].temperature;
    v.context = tools_[t].get();
    v.query = &RigidTool::query_fn;
    v.velocity = tools_[t]->velocity().data();
    v.displacement = tools_[t]->displacement().data();
    if (tools_[t]->is_mesh()) {
      v.query_kept = &RigidTool::query_kept_fn;
      v.kept_bytes = RigidTool::kKeptBytes;
    }
    tool_views_.push_back(v);
  }
}

void Simulation::build_mechanics() {
  std::map<std::string, const sdk::MaterialLaw*> made;  // one law object per material and position
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    const PartDef& def = *st.def;
    const MaterialDef& mat = job_.materials[def.material];
    auto m = std::make_unique<MechPart>();
    // Membrane laws: one object or an array whose stresses add.
    std::vector<std::pair<json, std::string>> blocks;
    if (mat.membrane.is_array()) {
      for (std::size_t i = 0; i < mat.membrane.size(); ++i)
        blocks.emplace_back(mat.membrane[i], pointer_append(mat.pointer + "/membrane", i));
    } else {
      blocks.emplace_back(mat.membrane, mat.pointer + "/membrane");
    }
    for (const auto& [obj, ptr] : blocks) {
      if (auto it = made.find(ptr); it != made.end()) {
        m->membrane.push_back(it->second);
        continue;
      }
      if (!obj.is_object()) throw JobError(ptr, "expected an object with a \"law\", found " + json_type_name(obj));
      if (!obj.contains("law") || !obj["law"].is_string()) throw JobError(ptr + "/law", "required string, missing");
      const PluginRecord& rec = registry_.require(sdk::PluginKind::Material, obj["law"], ptr + "/law");
      const sdk::Params params = validate_params(obj, ptr, rec.descriptor, {"law"});
      std::unique_ptr<sdk::MaterialLaw> law(reinterpret_cast<sdk::MaterialLaw* (*)()>(rec.create)());
      if (auto s = law->configure(params); !s) throw JobError(ptr, "material law '" + obj["law"].get<std::string>() + "': " + s.message);
      if (law->role() != sdk::LawRole::Membrane)
        throw JobError(ptr + "/law", "'" + obj["law"].get<std::string>() + "' is not a membrane law");
      made[ptr] = law.get();
      m->membrane.push_back(law.get());
      law_uses_.push_back({law.get(), ptr, obj["law"].get<std::string>()});
      laws_.push_back(std::move(law));
    }
    // Bending laws: the ply's bending and the fibres' bending in its plane.
    const auto bending_law = [&](const json& obj, const std::string& ptr) -> const sdk::MaterialLaw* {
      if (obj.is_null()) return nullptr;
      if (auto it = made.find(ptr); it != made.end()) return it->second;
      if (!obj.is_object() || !obj.contains("law") || !obj["law"].is_string())
        throw JobError(ptr + "/law", "required string, missing");
      const PluginRecord& rec = registry_.require(sdk::PluginKind::Material, obj["law"], ptr + "/law");
      const sdk::Params params = validate_params(obj, ptr, rec.descriptor, {"law"});
      std::unique_ptr<sdk::MaterialLaw> law(reinterpret_cast<sdk::MaterialLaw* (*)()>(rec.create)());
      if (auto s = law->configure(params); !s) throw JobError(ptr, "material law: " + s.message);
      if (law->role() != sdk::LawRole::Bending)
        throw JobError(ptr + "/law", "'" + obj["law"].get<std::string>() + "' is not a bending law");
      const sdk::MaterialLaw* made_law = law.get();
      made[ptr] = made_law;
      law_uses_.push_back({made_law, ptr, obj["law"].get<std::string>()});
      laws_.push_back(std::move(law));
      return made_law;
    };
    const sdk::MaterialLaw* bending = bending_law(mat.bending, mat.pointer + "/bending");
    const sdk::MaterialLaw* in_plane = bending_law(mat.in_plane_bending, mat.pointer + "/in_plane_bending");
    const PluginRecord& rec = registry_.require(sdk::PluginKind::Element, def.element, def.pointer + "/element");
    const sdk::Params eparams = validate_params(json::object(), def.pointer + "/element", rec.descriptor);
    m->element.reset(reinterpret_cast<sdk::ElementKernel* (*)()>(rec.create)());
    // Boundary edges whose two nodes are fully held by `fix` constraints are
    // clamped for bending.
    const int nn0 = st.mesh.num_nodes(), ne0 = st.mesh.num_elements();
    std::vector<char> held(nn0, 0);
    for (const auto& c : job_.constraints) {
      if (c.type != ConstraintDef::Type::Fix || !(c.dofs[0] && c.dofs[1] && c.dofs[2])) continue;
      if (std::find(c.parts.begin(), c.parts.end(), static_cast<int>(p)) == c.parts.end()) continue;
      for (int i = 0; i < nn0; ++i)
        if (in_box(c, &st.x0[3 * i])) held[i] = 1;
    }
    m->edge_condition.assign(3 * ne0, sdk::kEdgeFree);
    const double tol0 = 1e-6 * max_edge_length(st.mesh);
    for (int e = 0; e < ne0; ++e)
      for (int k = 0; k < 3; ++k) {
        if (st.mesh.neighbours[3 * e + k] >= 0) continue;
        const int a = st.mesh.triangles[3 * e + (k + 1) % 3], b = st.mesh.triangles[3 * e + (k + 2) % 3];
        if (held[a] && held[b]) {
          m->edge_condition[3 * e + k] = sdk::kEdgeClamped;
          continue;
        }
        for (const auto& c : job_.constraints) {
          if (c.type != ConstraintDef::Type::Symmetry) continue;
          if (std::find(c.parts.begin(), c.parts.end(), static_cast<int>(p)) == c.parts.end()) continue;
          if (std::abs(st.x0[3 * a + c.plane]) <= tol0 && std::abs(st.x0[3 * b + c.plane]) <= tol0)
            m->edge_condition[3 * e + k] = sdk::kEdgeSymmetryX + c.plane;
        }
      }
    sdk::ElementSetup setup;
    setup.part = &part_views_[p];
    setup.edge_condition = m->edge_condition;
    setup.membrane = m->membrane;
    setup.bending = bending;
    setup.in_plane_bending = in_plane;
    m->in_plane_bending = in_plane;
    setup.density = mat.density;
    setup.temperature = st.t0;
    if (!(mat.density > 0)) throw JobError(mat.pointer + "/density", "a density > 0 is needed by the mechanics solver");
    if (auto s = m->element->configure(eparams, setup); !s)
      throw JobError(def.pointer + "/element", "element '" + def.element + "': " + s.message);
    m->passes = std::max(1, m->element->passes());
    const int nn = st.mesh.num_nodes(), ne = st.mesh.num_elements();
    m->v.assign(3 * nn, 0.0);
    m->f_int.assign(3 * nn, 0.0);
    m->f_con.assign(3 * nn, 0.0);
    m->k_contact.assign(nn, 0.0);
    m->elem_dt.assign(ne, 0.0);
    m->elem_scale.assign(ne, 1.0);
    m->elem_sqrt_scale.assign(ne, 1.0);
    m->scaled = false;
    m->stress.assign(3 * ne, 0.0);
    m->curvature.assign(3 * ne, 0.0);
    m->strain.assign(3 * ne, 0.0);
    m->node_temperature.assign(nn, st.t0);
    m->face_temperature.assign(2 * static_cast<std::size_t>(nn), st.t0);
    // The 6-node patches: own nodes, then the node opposite each edge in
    // the neighbour (-1 at a boundary edge).
    std::vector<int> patch(6 * ne, -1);
    for (int e = 0; e < ne; ++e)
      for (int k = 0; k < 3; ++k) {
        patch[6 * e + k] = st.mesh.triangles[3 * e + k];
        const int n = st.mesh.neighbours[3 * e + k];
        if (n < 0) continue;
        const int p0 = st.mesh.triangles[3 * e + (k + 1) % 3], p1 = st.mesh.triangles[3 * e + (k + 2) % 3];
        for (int a = 0; a < 3; ++a) {
          const int o = st.mesh.triangles[3 * n + a];
          if (o != p0 && o != p1) patch[6 * e + 3 + k] = o;
        }
      }
    // Blocks of about 256 to 4096 elements, at least 16 blocks where the
    // part allows (larger blocks evaluate fewer hinges twice at their
    // borders), all of one size (the last one a little smaller), so that the
    // threads share a small part evenly. The partition depends on the part
    // only, never on the thread count. (Up to 4096: on one thread, whose
    // passes interleave (one_thread_order), 0.94-0.98 of the time of 2048 on
    // plates of 100k and 500k elements; 8192 was slower again at 100k.)
    int size = 256;
    while (size < 4096 && 16 * size < ne) size *= 2;
    m->blocks = std::max(1, (ne + size - 1) / size);
    m->block_size = std::max(1, (ne + m->blocks - 1) / m->blocks);
    m->block_dt.assign(m->blocks, 0.0);
    m->block_bdt.assign(m->blocks, std::numeric_limits<double>::infinity());
    m->block_fail.resize(m->blocks);
    m->block_error.resize(m->blocks);
    m->slot_local.assign(6 * ne, -1);
    m->block_node_start.assign(m->blocks + 1, 0);
    m->block_node.clear();
    std::vector<int> blocks_of_node(nn, 0), local(nn, -1);
    for (int b = 0; b < m->blocks; ++b) {
      const int e0 = b * m->block_size, e1 = std::min(ne, e0 + m->block_size);
      std::vector<int> nodes;
      for (int q = 6 * e0; q < 6 * e1; ++q)
        if (patch[q] >= 0) nodes.push_back(patch[q]);
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      for (std::size_t l = 0; l < nodes.size(); ++l) {
        local[nodes[l]] = static_cast<int>(l);
        ++blocks_of_node[nodes[l]];
      }
      for (int q = 6 * e0; q < 6 * e1; ++q)
        if (patch[q] >= 0) m->slot_local[q] = local[patch[q]];
      m->block_node.insert(m->block_node.end(), nodes.begin(), nodes.end());
      m->block_node_start[b + 1] = static_cast<int>(m->block_node.size());
    }
    m->shared_entry.assign(m->block_node.size(), -1);
    m->shared_node.clear();
    for (int i = 0; i < nn; ++i)
      if (blocks_of_node[i] > 1) m->shared_node.push_back(i);
    std::vector<int> shared_index(nn, -1);
    for (std::size_t s = 0; s < m->shared_node.size(); ++s) shared_index[m->shared_node[s]] = static_cast<int>(s);
    m->shared_start.assign(m->shared_node.size() + 1, 0);
    for (std::size_t l = 0; l < m->block_node.size(); ++l)
      if (shared_index[m->block_node[l]] >= 0) ++m->shared_start[shared_index[m->block_node[l]] + 1];
    for (std::size_t s = 0; s < m->shared_node.size(); ++s) m->shared_start[s + 1] += m->shared_start[s];
    m->block_force.assign(3 * static_cast<std::size_t>(m->shared_start.back()), 0.0);
    std::vector<int> fill(m->shared_start.begin(), m->shared_start.end() - 1);
    for (std::size_t l = 0; l < m->block_node.size(); ++l)  // blocks in order
      if (const int s = shared_index[m->block_node[l]]; s >= 0) m->shared_entry[l] = fill[s]++;
    // Constraints.
    m->fixed.assign(3 * nn, 0);
    m->constraint_of.assign(3 * nn, -1);
    m->prescribed.assign(3 * nn, 0.0);
    const double tol = 1e-6 * max_edge_length(st.mesh);
    for (const auto& c : job_.constraints) {
      if (std::find(c.parts.begin(), c.parts.end(), static_cast<int>(p)) == c.parts.end()) continue;
      for (int i = 0; i < nn; ++i) {
        const double* X = &st.x0[3 * i];
        if (c.type == ConstraintDef::Type::Symmetry) {
          if (std::abs(X[c.plane]) <= tol) {
            m->fixed[3 * i + c.plane] = 1;
            m->constraint_of[3 * i + c.plane] = static_cast<int>(&c - job_.constraints.data());
          }
          continue;
        }
        if (!in_box(c, X)) continue;
        if (c.type == ConstraintDef::Type::Force || c.type == ConstraintDef::Type::Gripper) continue;  // loads: below
        for (int d = 0; d < 3; ++d)
          if (c.dofs[d]) {
            m->fixed[3 * i + d] = 1;
            m->constraint_of[3 * i + d] = static_cast<int>(&c - job_.constraints.data());
            m->prescribed[3 * i + d] = c.type == ConstraintDef::Type::Velocity ? c.velocity[d] : 0.0;
          }
      }
    }
    // Loads: the total force of each `force` entry shared equally by the
    // nodes in its box (over every part it names), ramped in time.
    m->load.assign(3 * nn, 0.0);
    mech_.push_back(std::move(m));
  }
  for (std::size_t ci = 0; ci < job_.constraints.size(); ++ci) {
    const ConstraintDef& c = job_.constraints[ci];
    if (c.type != ConstraintDef::Type::Force) continue;
    std::vector<std::pair<int, int>> nodes;
    for (int p : c.parts) {
      const PartState& st = *parts_[p];
      for (int i = 0; i < st.mesh.num_nodes(); ++i)
        if (in_box(c, &st.x0[3 * i])) nodes.emplace_back(p, i);
    }
    if (nodes.empty()) throw JobError(c.pointer + "/box", "no node of the part(s) lies inside the box");
    Load l;
    l.ramp = c.ramp;
    l.nodes = std::move(nodes);
    for (int d = 0; d < 3; ++d) l.per_node[d] = c.force[d] / static_cast<double>(l.nodes.size());
    loads_.push_back(std::move(l));
  }
  // Grippers: the nodes in the box share the spring's force by their mass,
  // so that the spring alone moves them as one body.
  for (std::size_t ci = 0; ci < job_.constraints.size(); ++ci) {
    const ConstraintDef& c = job_.constraints[ci];
    if (c.type != ConstraintDef::Type::Gripper) continue;
    Gripper g;
    g.constraint = static_cast<int>(ci);
    for (int p : c.parts) {
      const PartState& st = *parts_[p];
      const double rho_h = job_.materials[st.def->material].density * st.def->thickness;
      for (int i = 0; i < st.mesh.num_nodes(); ++i) {
        if (!in_box(c, &st.x0[3 * i])) continue;
        g.nodes.emplace_back(p, i);
        g.share.push_back(rho_h * st.area[i]);
        g.mass += g.share.back();
      }
    }
    if (g.nodes.empty()) throw JobError(c.pointer + "/box", "no node of the part(s) lies inside the box");
    if (!(g.mass > 0)) throw JobError(c.pointer + "/box", "the nodes inside the box carry no mass");
    Vec3 centre{0, 0, 0};
    for (std::size_t k = 0; k < g.nodes.size(); ++k) {
      g.share[k] /= g.mass;
      const Vec3 x0 = sdk::load3(parts_[g.nodes[k].first]->x0.data(), g.nodes[k].second);
      centre = sdk::add(centre, sdk::scale(x0, g.share[k]));
    }
    g.centre = centre;
    g.length0 = sdk::norm(sdk::sub(Vec3{c.anchor[0], c.anchor[1], c.anchor[2]}, centre));
    double size = 0;  // the gripped nodes' extent
    for (const auto& [p, i] : g.nodes)
      size = std::max(size, sdk::norm(sdk::sub(sdk::load3(parts_[p]->x0.data(), i), centre)));
    if (!(g.length0 > 1e-6 * std::max(size, 1e-3)))
      throw JobError(c.pointer + "/anchor", "lies at the centre of the gripped nodes (" + fmt_g(centre[0]) + ", " +
                                                fmt_g(centre[1]) + ", " + fmt_g(centre[2]) +
                                                ") m: the spring has no direction; place the anchor where the "
                                                "spring pulls from");
    if (c.rigid) {
      // A gripped node held in a direction holds the jaw in it; one that
      // is driven would drive the jaw, which is then no gripper.
      const std::string kind = c.swivelling ? "swivelling jaws" : "rigid jaws";
      g.size = size > 0 ? size : 1.0;  // m: the rows' length scale
      for (const auto& [p, i] : g.nodes)
        for (int d = 0; d < 3; ++d) {
          const std::size_t k = 3 * static_cast<std::size_t>(i) + d;
          if (!mech_[p]->fixed[k]) continue;
          const int by = mech_[p]->constraint_of[k];
          if (mech_[p]->prescribed[k] != 0)
            throw JobError(c.pointer + "/box", kind + ": the box holds " + node_label(parts_[p]->mesh, i) +
                                                   " of part '" + parts_[p]->def->name + "', which " +
                                                   job_.constraints[by].pointer +
                                                   " drives; a gripper's jaws cannot be driven");
          if (g.held_by[d] < 0) g.held_by[d] = by;
          if (job_.constraints[by].type == ConstraintDef::Type::Symmetry) {
            g.on_symmetry[job_.constraints[by].plane] = true;
          } else if (g.pin_node < 0) {
            g.pin_part = p;
            g.pin_node = i;
          }
        }
      for (const Gripper& o : grippers_) {
        if (!job_.constraints[o.constraint].rigid) continue;
        for (const auto& n : g.nodes)
          if (std::find(o.nodes.begin(), o.nodes.end(), n) != o.nodes.end())
            throw JobError(c.pointer + "/box", kind + ": the box shares " + node_label(parts_[n.first]->mesh,
                                                                                          n.second) +
                                                   " of part '" + parts_[n.first]->def->name + "' with gripper '" +
                                                   job_.constraints[o.constraint].name +
                                                   "'; two rigid or swivelling jaws cannot hold one node");
      }
      g.part_nodes.assign(parts_.size(), {});
      for (const auto& [p, i] : g.nodes) g.part_nodes[p].push_back(i);
      rigid_jaws_ = true;
      swivelling_jaws_ = swivelling_jaws_ || c.swivelling;
    }
    grippers_.push_back(std::move(g));
  }
  // Contact stiffness bounds per node (for the stable step and mass scaling)
  // and, for force-controlled tools, the total stiffness they can meet.
  std::vector<std::span<const double>> areas;
  for (auto& st : parts_) areas.emplace_back(st->area);
  std::vector<double> tool_k(tools_.size(), 0.0);
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    std::vector<std::vector<double>> k(parts_.size());
    std::vector<std::span<double>> ks;
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      k[p].assign(parts_[p]->mesh.num_nodes(), 0.0);
      ks.emplace_back(k[p]);
    }
    if (auto s = contacts_[c]->node_stiffness(areas, ks); !s)
      throw JobError(job_.contacts[c].pointer, "contact handler '" + job_.contacts[c].handler + "': " + s.message);
    for (std::size_t p = 0; p < parts_.size(); ++p)
      for (std::size_t i = 0; i < k[p].size(); ++i) {
        mech_[p]->k_contact[i] += k[p][i];
        if (job_.contacts[c].second.is_tool) tool_k[job_.contacts[c].second.index] += k[p][i];
      }
  }
  // A gripper's spring, stiffness k and tension F at length d, holds node j
  // with k s_j along the spring and F s_j / d across it (s_j its share):
  // bounds that enter the stable step and mass scaling as the contact
  // springs' do, at the preload.
  for (const Gripper& g : grippers_) {
    const ConstraintDef& c = job_.constraints[g.constraint];
    const double k = std::max(c.stiffness, c.preload / g.length0);
    for (std::size_t j = 0; j < g.nodes.size(); ++j)
      mech_[g.nodes[j].first]->k_contact[g.nodes[j].second] += k * g.share[j];
  }
  // Stable steps of the initial configuration; mass scaling per element.
  const MechanicsDef& md = job_.mechanics_settings;
  want_element_dt_ = true;
  try {
    mechanics_stable_dt();
  } catch (const RunError&) {
    // A degenerate element of the initial mesh is an input error.
    for (std::size_t p = 0; p < parts_.size(); ++p)
      for (int b = 0; b < mech_[p]->blocks; ++b)
        if (mech_[p]->block_error[b].empty() && mech_[p]->block_fail[b] >= 0)
          throw JobError(parts_[p]->def->pointer + "/mesh",
                         element_label(parts_[p]->mesh, mech_[p]->block_fail[b]) + " of part '" + parts_[p]->def->name +
                             "' is degenerate in the initial mesh (zero area, a sliver beyond the precision of its "
                             "coordinates, or sizes beyond the range of numbers)");
    throw;
  }
  want_element_dt_ = false;
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    MechPart& m = *mech_[p];
    const double rho_h = job_.materials[st.def->material].density * st.def->thickness;
    const int nn = st.mesh.num_nodes();
    m.mass.assign(nn, 0.0);
    std::vector<double> phys(nn, 0.0);
    for (int e = 0; e < st.mesh.num_elements(); ++e) {
      double scale = md.mass_factor;
      if (md.target_dt > 0 && std::isfinite(m.elem_dt[e])) {
        const double dt_e = md.dt_safety * m.elem_dt[e];
        if (dt_e < md.target_dt) scale = std::max(scale, (md.target_dt / dt_e) * (md.target_dt / dt_e));
      }
      m.elem_scale[e] = scale;
      m.elem_sqrt_scale[e] = std::sqrt(scale);
      m.scaled = m.scaled || m.elem_sqrt_scale[e] != 1.0;
      const int* t = &st.mesh.triangles[3 * e];
      const Vec3 a = sdk::load3(st.x0.data(), t[0]), b = sdk::load3(st.x0.data(), t[1]), c = sdk::load3(st.x0.data(), t[2]);
      const double me = rho_h * 0.5 * sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
      for (int k = 0; k < 3; ++k) {
        m.mass[t[k]] += scale * me / 3.0;
        phys[t[k]] += me / 3.0;
      }
    }
    m.mass_node_physical = phys;
    // Contact: a node against a penalty spring k is stable for dt < 2 sqrt(m / k).
    // With mass scaling, add mass where the contact would cut the step below
    // the target (the spring bound at twice the target step, so that element
    // and contact bounds together stay within 12 % of the target).
    if (md.target_dt > 0)
      for (int i = 0; i < nn; ++i) {
        const double need = m.k_contact[i] * (md.target_dt / md.dt_safety) * (md.target_dt / md.dt_safety);
        if (m.mass[i] < need) {
          m.mass_added_contact += need - m.mass[i];
          m.mass[i] = need;
        }
      }
    m.mass_physical = 0;
    double total = 0;
    for (int i = 0; i < nn; ++i) {
      m.mass_physical += phys[i];
      total += m.mass[i];
    }
    m.mass_added = total - m.mass_physical;
    m.mass3.assign(3 * static_cast<std::size_t>(nn), 0.0);
    m.gravity3.assign(3 * static_cast<std::size_t>(nn), 0.0);
    m.fixed_dofs.clear();
    for (int i = 0; i < nn; ++i)
      for (int d = 0; d < 3; ++d) {
        const int k = 3 * i + d;
        m.mass3[k] = m.mass[i];
        m.gravity3[k] = md.gravity[d] * m.mass_node_physical[i];
        if (m.fixed[k]) {
          m.mass3[k] = -m.mass[i];
          m.fixed_dofs.push_back(k);
        }
      }
    m.external = md.gravity[0] != 0 || md.gravity[1] != 0 || md.gravity[2] != 0;
    for (const Load& l : loads_)
      for (const auto& [lp, li] : l.nodes) m.external = m.external || lp == static_cast<int>(p);
    for (const Gripper& g : grippers_)
      for (const auto& [gp, gi] : g.nodes) m.external = m.external || gp == static_cast<int>(p);
    for (int i = 0; i < nn; ++i)
      if (m.k_contact[i] > 0) contact_dt_ = std::min(contact_dt_, 2.0 * std::sqrt(m.mass[i] / m.k_contact[i]));
  }
  int limiting_tool = -1;  // the force-controlled tool that sets tool_dt_
  for (std::size_t t = 0; t < tools_.size(); ++t)
    if (tools_[t]->force_controlled() && tool_k[t] > 0) {
      const double dt = 2.0 * std::sqrt(job_.tools[t].motion.mass / tool_k[t]);
      if (dt < tool_dt_) {
        tool_dt_ = dt;
        limiting_tool = static_cast<int>(t);
      }
    }
  check_initial_step(limiting_tool, limiting_tool >= 0 ? tool_k[limiting_tool] : 0.0);
}

// The stable step of the elements' step dt with the contact springs:
// element and contact springs act on the same nodes, so 1/dt^2 adds up.
double Simulation::with_contact_springs(double dt) const {
  if (!std::isfinite(contact_dt_)) return dt;
  return 1.0 / std::sqrt(1.0 / (dt * dt) + 1.0 / (contact_dt_ * contact_dt_));
}

// Input that makes the explicit step unusable, refused before the run:
// a step so short that the run would take more than kMaxSteps steps (an
// estimate from the initial configuration, mass scaling included), and a
// mass-proportional damping c with c dt >= 2, where the update of a free
// node's velocity, v (1 - c dt) + ..., grows without bound. The error names
// what sets the step.
void Simulation::check_initial_step(int limiting_tool, double tool_stiffness) const {
  constexpr double kMaxSteps = 2e8;
  const MechanicsDef& md = job_.mechanics_settings;
  double elements = std::numeric_limits<double>::infinity();
  for (const auto& m : mech_)
    for (std::size_t e = 0; e < m->elem_dt.size(); ++e)
      if (std::isfinite(m->elem_dt[e])) elements = std::min(elements, m->elem_dt[e] * m->elem_sqrt_scale[e]);
  double stable = with_contact_springs(elements);
  const bool by_tool = tool_dt_ < stable;
  stable = std::min(stable, tool_dt_);
  if (!std::isfinite(stable) || !(stable > 0)) return;  // no stiffness: the run says so at its start
  const double dt = md.dt_safety * stable;
  if (const double steps = job_.t_end / dt; steps > kMaxSteps) {
    std::string what = "the elements", where = md.dt_safety < 1e-3 ? "/solvers/mechanics/dt_safety" : "/solvers/mechanics";
    if (by_tool) {
      const ToolDef& tool = job_.tools[limiting_tool];
      what = "the force-controlled tool '" + tool.name + "' (mass " + fmt_g(tool.motion.mass) +
             " kg) on the contact springs under it (" + fmt_g(tool_stiffness) + " N/m)";
      if (md.dt_safety >= 1e-3) where = tool.pointer + "/motion/mass";
    } else if (contact_dt_ < elements) {
      what = grippers_.empty() ? "the contact springs (penalty times node area, against the node masses)"
                               : "the contact springs (penalty times node area, against the node masses) or the "
                                 "grippers' springs (their stiffness against the gripped nodes' mass)";
    }
    throw JobError(where, "the mechanical step " + fmt_g(dt, 3) + " s (dt_safety " + fmt_g(md.dt_safety) +
                              " times the stable step " + fmt_g(stable, 3) + " s, set by " + what +
                              ") would need about " + fmt_g(steps, 3) + " steps to reach " + fmt_g(job_.t_end) +
                              " s (at most " + fmt_g(kMaxSteps, 3) + ")");
  }
  if (md.damping * dt >= 2.0)
    throw JobError("/solvers/mechanics/damping",
                   "damping " + fmt_g(md.damping) + " /s times the initial step " + fmt_g(dt, 3) + " s is " +
                       fmt_g(md.damping * dt, 3) +
                       ": the explicit update is unstable from 2 (a free node's velocity changes sign and grows "
                       "every step); use a damping below " + fmt_g(2.0 / dt, 3) + " /s");
}

// Warns once per law when a ply the law belongs to leaves the temperature
// range its parameters are given for (the law holds them at the range end).
void Simulation::check_law_ranges(double t) {
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    const MechPart& m = *mech_[p];
    if (m.node_temperature.empty()) continue;
    const auto [lo, hi] = std::minmax_element(m.node_temperature.begin(), m.node_temperature.end());
    const MaterialDef& mat = job_.materials[parts_[p]->def->material];
    for (auto& use : law_uses_) {
      if (use.warned || use.pointer.rfind(mat.pointer + "/", 0) != 0) continue;
      const auto [tmin, tmax] = use.law->temperature_range();
      const double T = *lo < tmin ? *lo : *hi > tmax ? *hi : tmin;
      if (*lo >= tmin && *hi <= tmax) continue;
      logger("solve")->warn("{}: ply '{}' reaches {:.1f} degC at t = {:.4g} s, outside the range [{:g}, {:g}] degC of "
                            "law '{}'; its temperature-dependent parameters are held at the range end",
                            use.pointer, parts_[p]->def->name, T, t, tmin, tmax, use.name);
      use.warned = true;
    }
  }
}

void Simulation::update_node_temperature() {
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    MechPart& m = *mech_[p];
    const int nz = st.nz;
    const double h = st.def->thickness;
    for (int i = 0; i < st.mesh.num_nodes(); ++i) {
      const double* t = &st.T[static_cast<std::size_t>(nz) * i];
      m.node_temperature[i] = thickness_mean(t, nz, h);
      m.face_temperature[2 * static_cast<std::size_t>(i)] = t[0];
      m.face_temperature[2 * static_cast<std::size_t>(i) + 1] = t[nz - 1];
    }
  }
  ++temperature_version_;
}

// Pass `pass` of the internal forces of element block b of part p at the
// current positions. In the last pass the block adds its elements' forces
// into its own node slots, and nodes of this block alone get their force
// at once; earlier passes only prepare (ElementForceInput::pass).
void Simulation::element_block(std::size_t p, int b, int pass, bool interleaved) {
  PartState& st = *parts_[p];
  MechPart& m = *mech_[p];
  const int ne = st.mesh.num_elements();
  const int l0 = m.block_node_start[b], l1 = m.block_node_start[b + 1];
  if (pass == 0) m.block_error[b].clear();
  if (!m.block_error[b].empty()) return;  // an earlier pass failed
  // The block's node slots in a buffer of the calling thread (it stays in
  // cache); those of nodes shared with other blocks go to block_force for
  // finish_elements.
  thread_local std::vector<double> slots;
  if (slots.size() < 3 * static_cast<std::size_t>(l1 - l0)) slots.resize(3 * static_cast<std::size_t>(l1 - l0));
  double* bf = slots.data();
  const bool last = pass == m.passes - 1;
  if (last) std::fill(bf, bf + 3 * (l1 - l0), 0.0);
  sdk::ElementForceInput in;
  in.range = {b * m.block_size, std::min(ne, (b + 1) * m.block_size)};
  in.dt = last_mech_dt_;
  in.node_temperature = m.node_temperature;
  in.patch_slot = std::span<const int>(m.slot_local.data() + 6 * static_cast<std::size_t>(in.range.begin),
                                       6 * static_cast<std::size_t>(in.range.end - in.range.begin));
  in.pass = pass;
  in.fields_due = fields_due_;
  if (m.scaled) in.dt_scale = m.elem_sqrt_scale;  // factors of 1 change no step: none
  in.temperature_version = temperature_version_;
  in.bending_weight = bending_weight_;
  if (interleaved && m.pass_window > 0) {
    in.pass_window = m.pass_window;
    in.block = b;
    in.block_size = m.block_size;
  }
  sdk::ElementForceOutput out;
  out.node_force = std::span<double>(bf, 3 * static_cast<std::size_t>(l1 - l0));
  if (want_element_dt_) out.element_dt = m.elem_dt;
  if (auto s = m.element->internal_forces(in, out); !s) m.block_error[b] = s.message;
  if (!last) return;
  m.block_fail[b] = out.failed_element;
  if (!m.block_error[b].empty() || m.block_fail[b] >= 0) return;
  m.block_dt[b] = out.stable_dt;
  if (bending_weight_ > 0) m.block_bdt[b] = out.bending_dt;
  for (int l = l0; l < l1; ++l) {
    const int se = m.shared_entry[l];
    double* to = se >= 0 ? &m.block_force[3 * static_cast<std::size_t>(se)] : &m.f_int[3 * m.block_node[l]];
    for (int d = 0; d < 3; ++d) to[d] = bf[3 * (l - l0) + d];
  }
}

// After every block of every part: errors in block order, the forces of
// nodes of several blocks (their blocks' sums, in block order) and the
// smallest stable step of the elements (mass scaling included) with the
// contact springs.
double Simulation::finish_elements() {
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    MechPart& m = *mech_[p];
    double bend_dt = std::numeric_limits<double>::infinity();
    for (int b = 0; b < m.blocks; ++b) {
      if (!m.block_error[b].empty())
        throw RunError("element '" + st.def->element + "' of part '" + st.def->name + "' at t = " + fmt_g(forces_t_) +
                       " s: " + m.block_error[b]);
      if (m.block_fail[b] >= 0)
        throw RunError("degenerate (collapsed or inverted) " + element_label(st.mesh, m.block_fail[b]) + " in part '" +
                       st.def->name + "' at t = " + fmt_g(forces_t_) + " s");
      dt = std::min(dt, m.block_dt[b]);
      bend_dt = std::min(bend_dt, m.block_bdt[b]);
    }
    // Between evaluations of the bending the elements' steps are the
    // membrane's: the bending's last ones bound them too.
    if (bending_weight_ > 0) m.bend_dt = bend_dt;
    dt = std::min(dt, m.bend_dt);
    const int ns = static_cast<int>(m.shared_node.size());
    sdk::for_each_index(ns, ns > 2048, 0, [&m](int s) {
      double f[3] = {0, 0, 0};
      for (int q = m.shared_start[s]; q < m.shared_start[s + 1]; ++q)
        for (int d = 0; d < 3; ++d) f[d] += m.block_force[3 * static_cast<std::size_t>(q) + d];
      for (int d = 0; d < 3; ++d) m.f_int[3 * m.shared_node[s] + d] = f[d];
    });
  }
  dt = with_contact_springs(dt);
  last_stable_ = std::min(dt, tool_dt_);
  return last_stable_;
}

double Simulation::initial_mechanical_step() {
  if (!job_.mechanics) return 0.0;
  const double stable = mechanics_stable_dt();
  return std::isfinite(stable) ? job_.mechanics_settings.dt_safety * stable : 0.0;
}

// Every pass of every element block at the current positions, and with
// `contact` the contact forces beside them. Beside: the contact on the
// first thread, and the blocks of a pass claimed one at a time by every
// thread (the first joins when its contact is done). By part: every thread
// the blocks and contact tasks of the parts it owns (part_threads), which
// keeps each part's data in one core's cache. Without contact, the blocks
// are dealt round robin. A thread done with its blocks of a pass waits until
// the pass's last block is done, since the next pass reads what this one
// wrote for neighbouring blocks of the part. No OpenMP task or barrier
// inside the region: libgomp ends each of those with a system call
// (sdk/parallel.hpp). Where no second thread can help, the blocks run in
// order on this one.
void Simulation::element_passes(BesideContact* contact) {
  ForceSchedule& fs = schedule_;
  int passes = 0;
  for (const auto& m : mech_) passes = std::max(passes, m->passes);
  if (static_cast<int>(fs.work.size()) != passes) {
    fs.work.assign(passes, {});
    for (int pass = 0; pass < passes; ++pass)
      for (std::size_t p = 0; p < parts_.size(); ++p)
        if (pass < mech_[p]->passes)
          for (int b = 0; b < mech_[p]->blocks; ++b) fs.work[pass].emplace_back(static_cast<int>(p), b);
    fs.claimed = std::make_unique<ForceSchedule::Counter[]>(passes);
    fs.done = std::make_unique<ForceSchedule::Counter[]>(passes);
    one_thread_order(passes);
  }
  if (!contact && !sdk::team_available(passes > 0 && fs.work[0].size() > 1)) {
    for (const ForceSchedule::Step& s : fs.one_thread) element_block(s.part, s.block, s.pass, true);
    return;
  }
  for (int pass = 0; pass < passes; ++pass) {
    fs.claimed[pass].value.store(0, std::memory_order_relaxed);
    fs.done[pass].value.store(0, std::memory_order_relaxed);
  }
  const bool by_part = contact && contact->by_part;
#ifdef _OPENMP
  part_threads(omp_get_max_threads());
#endif
  double contact_seconds = 0;
  const long long round = by_part ? ++exchange_round_ : 0;  // of the exchange copies
#pragma omp parallel reduction(max : contact_seconds)
  {
    const int me = omp_get_thread_num(), team = omp_get_num_threads();
    if (by_part) {
      auto mine = [&](int p) { return thread_of_part(p, team) == me; };
      const auto tc = Clock::now();
      for (std::size_t p = 0; p < parts_.size(); ++p) {
        if (!mine(static_cast<int>(p))) continue;
        start_part_contact(static_cast<int>(p));
        // The part's exchange copies, where a task on another thread reads them.
        bool publish = false;
        for (const ContactTask& task : contact_tasks_)
          publish = publish || (task.other == static_cast<int>(p) && crosses_threads(task, team));
        if (Exchange* ex = exchange_[p].get(); ex && publish) {
          stream_copy(parts_[p]->x.data(), ex->x.data(), ex->x.size());
          stream_copy(mech_[p]->v.data(), ex->v.data(), ex->v.size());
          ex->round.store(round, std::memory_order_release);
        }
      }
      for (ContactTask& task : contact_tasks_) {
        if (!mine(task.owner)) continue;
        task.published = crosses_threads(task, team);
        if (task.published)  // until the other part's thread has written its copies
          spin_until([&] { return exchange_[task.other]->round.load(std::memory_order_acquire) == round; });
        try {
          task.error = nullptr;
          run_contact_task(task, contact->t, contact->dt);
        } catch (...) {
          task.error = std::current_exception();
        }
        if (task.published) stream_copy(task.cross.data(), task.cross_out.data(), task.cross.size());
      }
      contact_seconds = seconds_since(tc);
      for (const ForceSchedule::Step& s : fs.one_thread)
        if (mine(s.part)) element_block(s.part, s.block, s.pass, true);
    } else {
      if (contact && me == 0) {
        const auto tc = Clock::now();
        try {
          compute_contact_forces(contact->t, contact->dt);
        } catch (...) {
          contact->error = std::current_exception();
        }
        contact_seconds = seconds_since(tc);
      }
      // One thread alone takes the blocks in the one-thread order. Without
      // contact beside, every thread takes the same blocks at every pass and
      // step (round robin), so that a block's data stays in one core's
      // cache; with it, blocks go to whichever thread is free.
      if (team == 1) {
        for (const ForceSchedule::Step& s : fs.one_thread) element_block(s.part, s.block, s.pass, true);
      } else {
        for (int pass = 0; pass < passes; ++pass) {
          const auto& work = fs.work[pass];
          const int n = static_cast<int>(work.size());
          for (int j = 0;; ++j) {
            const int k = contact ? fs.claimed[pass].value.fetch_add(1, std::memory_order_relaxed) : me + j * team;
            if (k >= n) break;
            element_block(work[k].first, work[k].second, pass, false);
            fs.done[pass].value.fetch_add(1, std::memory_order_release);
          }
          spin_until([&] { return fs.done[pass].value.load(std::memory_order_acquire) >= n; });
        }
      }
    }
  }
  if (contact) {
    contact->seconds = contact_seconds;
    if (by_part)  // the first error in task order, whichever thread met it
      for (const ContactTask& task : contact_tasks_)
        if (task.error) {
          contact->error = task.error;
          break;
        }
  }
}

// The order of the element evaluations of a step on one thread, (part,
// block, pass). Where the element declares how far a pass reads what the
// pass before wrote (ElementKernel::pass_reach, r steps across edges),
// pass k of a block comes as soon as pass k - 1 is done for every block
// holding an element within r steps of the block's, the latest pass first,
// so that a block's values are still in cache for its next pass instead of
// every block of the part passing through in between. Otherwise, and on
// several threads (where a thread would wait for another's blocks at every
// block), the passes go one after the other. A block computes the same in
// any order, so the results do not depend on it.
void Simulation::one_thread_order(int passes) {
  ForceSchedule& fs = schedule_;
  fs.one_thread.clear();
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    const MechPart& m = *mech_[p];
    const ShellMesh& mesh = parts_[p]->mesh;
    const int ne = mesh.num_elements(), np = std::min(passes, m.passes), nb = m.blocks;
    if (np <= 0 || nb <= 0) continue;
    // reach[b]: the last block holding an element that a pass of blocks
    // 0 .. b reads; lo[b], hi[b]: the first and last block holding an
    // element that a pass of block b reads.
    std::vector<int> reach(nb, nb - 1), lo(nb, 0), hi(nb, nb - 1);
    const int r = m.element->pass_reach();
    if (r >= 0) {
      // per element, the first and last block within i steps
      std::vector<int> near(ne), far(ne), next_near(ne), next_far(ne);
      for (int e = 0; e < ne; ++e) near[e] = far[e] = e / m.block_size;
      for (int i = 0; i < r; ++i) {
        for (int e = 0; e < ne; ++e) {
          next_near[e] = near[e];
          next_far[e] = far[e];
          for (int k = 0; k < 3; ++k)
            if (const int n = mesh.neighbours[3 * e + k]; n >= 0) {
              next_near[e] = std::min(next_near[e], near[n]);
              next_far[e] = std::max(next_far[e], far[n]);
            }
        }
        near.swap(next_near);
        far.swap(next_far);
      }
      std::fill(lo.begin(), lo.end(), nb - 1);
      std::fill(hi.begin(), hi.end(), 0);
      for (int e = 0; e < ne; ++e) {
        const int b = e / m.block_size;
        lo[b] = std::min(lo[b], near[e]);
        hi[b] = std::max(hi[b], far[e]);
      }
      reach = hi;
      for (int b = 1; b < nb; ++b) reach[b] = std::max(reach[b], reach[b - 1]);
    }
    const std::size_t first_step = fs.one_thread.size();
    std::vector<int> done(np, 0);  // per pass, the blocks done (in block order)
    while (done[np - 1] < nb) {
      int k = np - 1;
      while (k > 0 && !(done[k] < nb && done[k - 1] > reach[done[k]])) --k;
      fs.one_thread.push_back({static_cast<int>(p), done[k]++, k});
    }
    // The window: block b's values are read until the last pass of the
    // last block that reads b (one within [lo, hi] of b) is done; W is one
    // more than the largest number of blocks after b whose pass 0 comes
    // before that.
    MechPart& mw = *mech_[p];
    mw.pass_window = 0;
    if (r >= 0 && np > 1) {
      std::vector<long long> first(nb, 0), last(nb, 0), end(nb, 0);
      for (std::size_t t = first_step; t < fs.one_thread.size(); ++t) {
        const ForceSchedule::Step& s = fs.one_thread[t];
        if (s.pass == 0) first[s.block] = static_cast<long long>(t);
        if (s.pass == np - 1) last[s.block] = static_cast<long long>(t);
      }
      for (int b = 0; b < nb; ++b) end[b] = last[b];
      for (int b = 0; b < nb; ++b)  // reader b reads blocks lo[b] .. hi[b]
        for (int c = lo[b]; c <= hi[b]; ++c) end[c] = std::max(end[c], last[b]);
      int w = 1;
      for (int b = 0, j = 0; b < nb; ++b) {
        while (j + 1 < nb && first[j + 1] <= end[b]) ++j;
        w = std::max(w, j - b + 1);
      }
      if (w < nb) mw.pass_window = w;
    }
  }
}

// The thread that owns each part for a team of `team` threads: parts
// dealt largest first to the thread with the fewest elements so far.
void Simulation::part_threads(int team) {
  ForceSchedule& fs = schedule_;
  if (fs.team == team && fs.part_thread.size() == parts_.size()) return;
  fs.team = team;
  fs.part_thread.assign(parts_.size(), 0);
  std::vector<int> order(parts_.size());
  for (std::size_t p = 0; p < order.size(); ++p) order[p] = static_cast<int>(p);
  auto elements = [&](int p) { return parts_[p]->mesh.num_elements(); };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return elements(a) > elements(b); });
  std::vector<long long> load(std::max(team, 1), 0);
  for (const int p : order) {
    const int t = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    fs.part_thread[p] = t;
    load[t] += elements(p);
  }
}

// The thread of `team` that owns the part: as part_threads dealt it, or,
// in a team of another size than the one dealt for, by the part's number.
int Simulation::thread_of_part(int part, int team) const {
  const ForceSchedule& fs = schedule_;
  const bool dealt = team == fs.team && fs.part_thread.size() == parts_.size();
  return dealt ? fs.part_thread[part] : part % team;
}

// Internal forces of every part at the current positions; returns the
// smallest stable step.
double Simulation::mechanics_stable_dt() {
  element_passes(nullptr);
  return finish_elements();
}

// With solvers.mechanics.bending_subcycles k > 1 the bending is evaluated
// at most every k-th step: the evaluation that carries it stands for the
// number of steps j it is given (ElementForceInput::bending_weight j; the
// element delivers j times its bending forces over those steps, as an
// impulse or in part at each step), the j - 1 evaluations after it carry
// none (weight 0). j is the
// largest whole number of steps that keeps j dt within dt_safety times the
// bending's own stable step (j dt_safety stable <= dt_safety bend_dt), at
// most k: where the bending governs the step, j = 1 (every step).
void Simulation::choose_bending_weight() {
  const int k = job_.mechanics_settings.bending_subcycles;
  if (k <= 1) return;  // bending_weight_ stays 1
  if (bending_left_ > 0) {
    bending_weight_ = 0.0;
    --bending_left_;
    return;
  }
  double bend_dt = std::numeric_limits<double>::infinity();
  for (const auto& m : mech_) bend_dt = std::min(bend_dt, m->bend_dt);
  int j = k;
  if (std::isfinite(bend_dt) && last_stable_ > 0)
    j = static_cast<int>(std::clamp(std::floor(bend_dt / last_stable_), 1.0, static_cast<double>(k)));
  bending_weight_ = j;
  bending_left_ = j - 1;
  ++bending_evaluations_;
  bending_largest_ = std::max(bending_largest_, j);
}

// Element forces and contact forces at the current positions (they write
// separate arrays); returns the smallest stable step. Three ways of sharing
// them out over the threads, with the same results (every force is computed
// and summed the same way in all):
// - in turn: the element blocks, then the contact tasks, each shared out
//   in its own loops;
// - beside: the contact tasks on the first thread (their handlers' loops
//   then run on that thread) while the other threads take the element
//   blocks, which the first joins when its contact is done; one parallel
//   region per step instead of one per loop, best where contact costs about
//   as much as the elements;
// - by part (two parts or more): every thread the element blocks and the
//   contact tasks of its own parts, each part's data staying in one core's
//   cache, best where the parts and their contacts cost about the same.
// Which one is faster depends on the scene and the machine: with
// "contact_schedule": "auto" the run times each over its first calls
// (kTrial each), keeps the fastest (by part unless another way is faster
// by more than the factor kByPartMargin), and times them again every kRecheck
// calls; "beside", "in_turn" and "by_part" fix the way.
double Simulation::forces_and_stable_dt(double t, double dt) {
  forces_t_ = t;
  choose_bending_weight();
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
#else
  const int threads = 1;
#endif
  // A trial: kRounds rounds of kTrial calls each way; each way keeps the
  // mean of its fastest round (a round that met a busy spell of the host
  // does not count against a way). The first kWarm calls of a round are
  // not timed: they move the parts' data to where this way keeps it, a
  // cost the way does not pay once it runs on.
  constexpr int kTrial = 32, kWarm = 8, kRounds = 4;
  constexpr double kByPartMargin = 1.05;
  constexpr long long kRecheck = 20000;
  ForceSchedule& fs = schedule_;
  const std::string& choice_name = job_.mechanics_settings.contact_schedule;
  const bool shared = threads > 1 && !contacts_.empty();
  const bool parts_apart = shared && parts_.size() > 1;
  const bool choice = shared && choice_name == "auto";
  int way = kInTurn;
  if (choice_name == "beside" && shared) way = kBeside;
  if (choice_name == "by_part" && parts_apart) way = kByPart;
  // The ways a trial times, in its order within a round.
  const int trial_ways[kWays] = {kBeside, kInTurn, kByPart};
  const int ways = parts_apart ? 3 : 2;
  const int round_calls = ways * kTrial;
  // A call of a trial is timed from its start to the next call's: the
  // step's integration and audit count too, since where a way leaves the
  // plies' data decides what they cost.
  const auto t0 = Clock::now();
  if (fs.pending_way >= 0) {
    const int w = fs.pending_way;
    fs.pending_way = -1;
    if (fs.count[w] >= kWarm) fs.time[w] += std::chrono::duration<double>(t0 - fs.pending_start).count();
    if (++fs.count[w] == kTrial) {  // the way's round is over
      fs.best[w] = std::min(fs.best[w], fs.time[w] / (kTrial - kWarm));
      fs.time[w] = 0;
      fs.count[w] = 0;
    }
    if (--fs.trial_left == 0) {
      fs.way = trial_ways[0];
      for (int j = 1; j < ways; ++j)
        if (fs.best[trial_ways[j]] < fs.best[fs.way]) fs.way = trial_ways[j];
      // By part, unless another way is clearly faster: where they are
      // within a few per cent, by part is the one that loses least when
      // the host gets slower at moving lines between cores.
      if (ways > 2 && fs.way != kByPart && fs.best[kByPart] < kByPartMargin * fs.best[fs.way]) fs.way = kByPart;
      fs.next_trial = fs.calls + kRecheck;
      static const char* const kName[kWays] = {"in_turn", "beside", "by_part"};
      logger("solve")->debug("contact_schedule auto at t = {:.4g} s: {} (best round per step: beside {:.0f} us, "
                             "in_turn {:.0f} us{})",
                             t, kName[fs.way], 1e6 * fs.best[kBeside], 1e6 * fs.best[kInTurn],
                             ways > 2 ? fmt::format(", by_part {:.0f} us", 1e6 * fs.best[kByPart]) : "");
    }
  }
  if (choice) {
    if (fs.trial_left == 0 && fs.calls >= fs.next_trial) {
      fs.trial_left = kRounds * round_calls;
      for (int w = 0; w < kWays; ++w) {
        fs.time[w] = 0;
        fs.count[w] = 0;
        fs.best[w] = std::numeric_limits<double>::infinity();
      }
    }
    way = fs.trial_left > 0 ? trial_ways[(kRounds * round_calls - fs.trial_left) % round_calls / kTrial] : fs.way;
  }
  double stable;
  if (way == kInTurn) {
    auto tc = Clock::now();
    stable = mechanics_stable_dt();
    timing_[kTimeElements] += seconds_since(tc);
    tc = Clock::now();
    compute_contact_forces(t, dt);
    timing_[kTimeContact] += seconds_since(tc);
  } else {
    BesideContact contact{t, dt, way == kByPart, 0.0, nullptr};
    element_passes(&contact);
    if (contact.error) std::rethrow_exception(contact.error);
    stable = finish_elements();
    // The contact ran within the elements' wall time: elements_and_laws is
    // the wall time of both, contact its own share (the longest thread's).
    timing_[kTimeElements] += seconds_since(t0) - contact.seconds;
    timing_[kTimeContact] += contact.seconds;
  }
  finish_contact_forces();
  ++fs.calls;
  ++fs.way_calls[way];
  if (choice && fs.trial_left > 0) {
    fs.pending_way = way;
    fs.pending_start = t0;
  }
  return stable;
}

void Simulation::build_contact_tasks() {
  const std::size_t np = parts_.size();
  cross_into_.assign(np, {});
  contact_tasks_.clear();
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    const ContactDef& def = job_.contacts[c];
    const int first = def.first.index, second = def.second.is_tool ? -1 : def.second.index;
    const int sides = second >= 0 && contacts_[c]->sides() == 2 ? 2 : 1;
    for (int s = 0; s < sides; ++s) {
      ContactTask task;
      task.contact = static_cast<int>(c);
      task.side = sides == 2 ? s : -1;
      task.owner = s == 0 ? first : second;
      task.other = s == 0 ? second : first;
      contact_tasks_.push_back(std::move(task));
    }
  }
  pressure_sum_.assign(want_pressure_ ? np : 0, {});
  for (std::size_t p = 0; p < pressure_sum_.size(); ++p)
    pressure_sum_[p].assign(static_cast<std::size_t>(parts_[p]->mesh.num_nodes()), 0.0);
  for (std::size_t k = 0; k < contact_tasks_.size(); ++k) {
    ContactTask& task = contact_tasks_[k];
    task.tool_force.assign(3 * tools_.size(), 0.0);
    task.force.assign(np, {});
    task.status.assign(job_.thermal ? 0 : np, {});
    task.pressure.assign(want_pressure_ ? np : 0, {});
    task.force[task.owner] = mech_[task.owner]->f_con;
    if (!job_.thermal) task.status[task.owner] = parts_[task.owner]->contact_status;
    if (want_pressure_) {
      task.own_pressure.assign(static_cast<std::size_t>(parts_[task.owner]->mesh.num_nodes()), 0.0);
      task.pressure[task.owner] = task.own_pressure;
    }
    if (task.other >= 0 && task.other != task.owner) {
      const std::size_t nn = static_cast<std::size_t>(parts_[task.other]->mesh.num_nodes());
      task.cross.assign(3 * nn, 0.0);
      task.force[task.other] = task.cross;
      if (!job_.thermal) {
        task.cross_status.assign(nn, 0.0);
        task.status[task.other] = task.cross_status;
      }
      if (want_pressure_) {
        task.cross_pressure.assign(nn, 0.0);
        task.pressure[task.other] = task.cross_pressure;
      }
      cross_into_[task.other].push_back(static_cast<int>(k));
    }
  }
  ContactSpans& cs = contact_spans_;
  for (std::size_t p = 0; p < np; ++p) {
    cs.vel.emplace_back(mech_[p]->v);
    cs.mass.emplace_back(mech_[p]->mass);
    cs.areas.emplace_back(parts_[p]->area);
    cs.temp.emplace_back(mech_[p]->face_temperature);
  }
  // The exchange copies of the parts that tasks of other parts read, and
  // the views of such tasks (used where the two parts' threads differ).
  exchange_.resize(np);
  for (ContactTask& task : contact_tasks_) {
    if (task.other < 0 || task.other == task.owner) continue;
    const int o = task.other;
    if (!exchange_[o]) {
      exchange_[o] = std::make_unique<Exchange>();
      exchange_[o]->x.assign(parts_[o]->x.begin(), parts_[o]->x.end());
      exchange_[o]->v.assign(mech_[o]->v.begin(), mech_[o]->v.end());
    }
    task.views = part_views_;
    task.views[o].x = exchange_[o]->x;
    task.vel = cs.vel;
    task.vel[o] = exchange_[o]->v;
    task.cross_out.assign(task.cross.size(), 0.0);
  }
}

// by_part on `team` threads: whether the task's other part is integrated
// on another thread than the task's own.
bool Simulation::crosses_threads(const ContactTask& task, int team) const {
  return task.other >= 0 && task.other != task.owner &&
         thread_of_part(task.other, team) != thread_of_part(task.owner, team);
}

// Before the first task that moves the part's nodes: its contact forces
// (and, isothermal, its contact status) start from zero.
void Simulation::start_part_contact(int part) {
  std::fill(mech_[part]->f_con.begin(), mech_[part]->f_con.end(), 0.0);
  if (!job_.thermal)  // isothermal: the status field shows the mechanical contact
    std::fill(parts_[part]->contact_status.begin(), parts_[part]->contact_status.end(), 0.0);
}

void Simulation::run_contact_task(ContactTask& task, double t, double dt) {
  std::fill(task.cross.begin(), task.cross.end(), 0.0);
  std::fill(task.cross_status.begin(), task.cross_status.end(), 0.0);
  std::fill(task.tool_force.begin(), task.tool_force.end(), 0.0);
  sdk::ContactForceInput in;
  in.parts = part_views_;
  in.tools = tool_views_;
  in.time = t;
  in.dt = dt;
  in.velocity = contact_spans_.vel;
  if (task.published) {  // by_part across threads: the other part's exchange copies
    in.parts = task.views;
    in.velocity = task.vel;
  }
  in.node_area = contact_spans_.areas;
  in.mass = contact_spans_.mass;
  in.side = task.side;
  in.face_temperature = contact_spans_.temp;
  in.temperature_version = temperature_version_;
  sdk::ContactForceOutput out;
  out.force = task.force;
  out.tool_force = task.tool_force;
  out.status = task.status;
  if (pressure_due_) {
    std::fill(task.own_pressure.begin(), task.own_pressure.end(), 0.0);
    std::fill(task.cross_pressure.begin(), task.cross_pressure.end(), 0.0);
    out.pressure = task.pressure;
  }
  if (auto s = contacts_[task.contact]->contact_forces(in, out); !s)
    throw RunError("contact handler of " + job_.contacts[task.contact].pointer + " at t = " + fmt_g(t) +
                   " s: " + s.message);
  task.energy = out.energy;
  task.active = out.active;
}

// The forces of the tasks that moved other parts' nodes onto this one,
// in task order (by the thread that integrates the part).
void Simulation::merge_part_contact(int part) {
  if (part >= static_cast<int>(cross_into_.size())) return;
  sdk::large_vector<double>& f = mech_[part]->f_con;
  for (const int k : cross_into_[part]) {
    const ContactTask& task = contact_tasks_[k];
    const std::vector<double>& cross = task.published ? task.cross_out : task.cross;
    for (std::size_t i = 0; i < f.size(); ++i) f[i] += cross[i];
  }
}

// The contact fields of the last contact force evaluation. Isothermal:
// the status the tasks gave the nodes of their pair's other part (the
// tasks wrote their own part's directly). The parts' contact pressure from
// the tasks' arrays of the last evaluation with pressure_due_: per node,
// the largest over the pairs of what each pair's tasks added.
void Simulation::update_contact_fields() {
  for (const ContactTask& task : contact_tasks_) {
    if (task.cross_status.empty()) continue;
    std::vector<double>& st = parts_[task.other]->contact_status;
    for (std::size_t i = 0; i < st.size(); ++i) st[i] = std::max(st[i], task.cross_status[i]);
  }
  for (std::size_t part = 0; part < pressure_sum_.size(); ++part) {
    std::vector<double>& p = parts_[part]->contact_pressure;
    std::vector<double>& sum = pressure_sum_[part];
    std::fill(p.begin(), p.end(), 0.0);
    // The tasks of one pair (its sides) are adjacent.
    for (std::size_t k = 0; k < contact_tasks_.size();) {
      const int pair = contact_tasks_[k].contact;
      bool touches = false;
      std::fill(sum.begin(), sum.end(), 0.0);
      for (; k < contact_tasks_.size() && contact_tasks_[k].contact == pair; ++k) {
        const ContactTask& task = contact_tasks_[k];
        const bool own = task.owner == static_cast<int>(part);
        if (!own && task.other != static_cast<int>(part)) continue;
        const std::vector<double>& a = own ? task.own_pressure : task.cross_pressure;
        touches = true;
        for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += a[i];
      }
      if (touches)
        for (std::size_t i = 0; i < p.size(); ++i) p[i] = std::max(p[i], sum[i]);
    }
  }
}

// Every task in order on this thread (their handlers' loops shared out
// where a team is free).
void Simulation::compute_contact_forces(double t, double dt) {
  if (contacts_.empty()) return;  // the contact forces stay zero
  for (std::size_t p = 0; p < parts_.size(); ++p) start_part_contact(static_cast<int>(p));
  for (ContactTask& task : contact_tasks_) {
    task.published = false;
    run_contact_task(task, t, dt);
  }
}

// The tasks' tool forces, energies and counts, summed in task order.
void Simulation::finish_contact_forces() {
  contact_energy_ = 0;
  contact_active_ = 0;
  std::fill(tool_force_.begin(), tool_force_.end(), 0.0);
  for (const ContactTask& task : contact_tasks_) {
    for (std::size_t q = 0; q < tool_force_.size(); ++q) tool_force_[q] += task.tool_force[q];
    contact_energy_ += task.energy;
    contact_active_ += task.active;
  }
}

// Each gripper at t: its spring from the anchor to the gripped nodes'
// centre c = sum_j s_j x_j, of length d, pulls with the tension
// F = preload (ramped) + k (d - d0) (not below 0 where tension_only), a
// force F (anchor - c) / d that node j takes s_j of. Serial, in the
// grippers' order: the same sums for any thread count.
void Simulation::apply_grippers(double t) {
  for (Gripper& g : grippers_) {
    const ConstraintDef& c = job_.constraints[g.constraint];
    Vec3 centre{0, 0, 0};
    for (std::size_t j = 0; j < g.nodes.size(); ++j) {
      const Vec3 x = sdk::load3(parts_[g.nodes[j].first]->x.data(), g.nodes[j].second);
      centre = sdk::add(centre, sdk::scale(x, g.share[j]));
    }
    const std::array<double, 3> u = c.anchor_motion.prescribed(t);
    const Vec3 r = sdk::sub(Vec3{c.anchor[0] + u[0], c.anchor[1] + u[1], c.anchor[2] + u[2]}, centre);
    const double d = sdk::norm(r);
    const double ramp = c.ramp > 0 ? std::min(1.0, t / c.ramp) : 1.0;
    double tension = ramp * c.preload + c.stiffness * (d - g.length0);
    if (c.tension_only) tension = std::max(tension, 0.0);
    if (t >= c.release) tension = 0.0;  // the clamp has opened
    const Vec3 f = d > 0 ? sdk::scale(r, tension / d) : Vec3{0, 0, 0};
    for (std::size_t j = 0; j < g.nodes.size(); ++j) {
      double* load = &mech_[g.nodes[j].first]->load[3 * static_cast<std::size_t>(g.nodes[j].second)];
      for (int k = 0; k < 3; ++k) load[k] += g.share[j] * f[k];
    }
    g.force = f;
    g.centre = centre;
    g.tension = tension;
    g.extension = d - g.length0;
  }
}

// Rigid jaws: the gripped nodes (free dofs j, masses m_j, velocities v_j,
// forces F_j including the damping's) take the common velocity
// V = sum_j (m_j v_j + dt_avg F_j) / sum_j m_j, or V = 0 in a direction in
// which a gripped node is held, by the force
// m_j (V - v_j) / dt_avg - F_j added to each node's load. These forces sum
// to zero (in a held direction: to the support's reaction) and do no work
// on nodes that move alike. Each part's sums by the thread that owns it;
// every thread adds them in part order (the same V for any thread count).
namespace {
// F_j with the damping's force, as integrate_body takes them.
inline double jaw_force(const MechPart& m, std::size_t k, double damping, bool normal_damping, bool contact) {
  const double f_ext = m.external ? m.gravity3[k] + m.load[k] : 0.0;
  const double fc = contact ? m.f_con[k] : 0.0;
  const double f_damp = damping * m.mass3[k] * (normal_damping ? m.normal_velocity[k] : m.v[k]);
  return f_ext + fc - m.f_int[k] - f_damp;
}
}  // namespace

// Part p's share of each closed rigid jaw's sums_j m_j v_j + dt_avg F_j and
// sum_j m_j, per direction, into jaw_sums_.
void Simulation::rigid_jaw_sums(int p, double t, double dt_avg) {
  const MechanicsDef& md = job_.mechanics_settings;
  const bool normal_damping = md.damping_normal && md.damping > 0, contact = !contacts_.empty();
  const MechPart& m = *mech_[p];
  for (std::size_t gi = 0; gi < grippers_.size(); ++gi) {
    const Gripper& g = grippers_[gi];
    const ConstraintDef& c = job_.constraints[g.constraint];
    if (!c.rigid || t >= c.release) continue;  // an open clamp ties nothing
    double* sums = &jaw_sums_[(static_cast<std::size_t>(p) * grippers_.size() + gi) * kJawSums];
    if (c.swivelling) {
      swivel_jaw_sums(g, m, parts_[p]->x.data(), g.part_nodes[p], dt_avg, normal_damping, contact, sums);
      continue;
    }
    double momentum[3] = {0, 0, 0}, mass[3] = {0, 0, 0};
    for (const int i : g.part_nodes[p])
      for (int d = 0; d < 3; ++d) {
        const std::size_t k = 3 * static_cast<std::size_t>(i) + d;
        if (m.mass3[k] < 0) continue;  // held
        momentum[d] += m.mass3[k] * m.v[k] + dt_avg * jaw_force(m, k, md.damping, normal_damping, contact);
        mass[d] += m.mass3[k];
      }
    for (int d = 0; d < 3; ++d) {
      sums[2 * d] = momentum[d];
      sums[2 * d + 1] = mass[d];
    }
  }
}

// Each closed rigid jaw's force on part p's gripped nodes, added to their
// loads; in a held direction its sum to `reactions` (part p's, per
// constraint and direction).
void Simulation::tie_rigid_jaws(int p, int slot, double t, double dt, double dt_avg, double* reactions) {
  const MechanicsDef& md = job_.mechanics_settings;
  const bool normal_damping = md.damping_normal && md.damping > 0, contact = !contacts_.empty();
  const int np = static_cast<int>(parts_.size());
  MechPart& m = *mech_[p];
  for (std::size_t gi = 0; gi < grippers_.size(); ++gi) {
    const Gripper& g = grippers_[gi];
    const ConstraintDef& c = job_.constraints[g.constraint];
    if (!c.rigid || t >= c.release) continue;
    if (c.swivelling) {
      tie_swivelling_jaw(g, &jaw_solution_[(static_cast<std::size_t>(slot) * grippers_.size() + gi) * 9], p, dt, dt_avg,
                         reactions);
      continue;
    }
    for (int d = 0; d < 3; ++d) {
      double momentum = 0, mass = 0;
      for (int q = 0; q < np; ++q) {
        momentum += jaw_sums_[(static_cast<std::size_t>(q) * grippers_.size() + gi) * kJawSums + 2 * d];
        mass += jaw_sums_[(static_cast<std::size_t>(q) * grippers_.size() + gi) * kJawSums + 2 * d + 1];
      }
      if (!(mass > 0)) continue;  // every node held
      const double V = g.held_by[d] >= 0 ? 0.0 : momentum / mass;
      double support = 0;
      for (const int i : g.part_nodes[p]) {
        const std::size_t k = 3 * static_cast<std::size_t>(i) + d;
        if (m.mass3[k] < 0) continue;
        const double tie = m.mass3[k] * (V - m.v[k]) / dt_avg - jaw_force(m, k, md.damping, normal_damping, contact);
        m.load[k] += tie;
        support += tie;
      }
      if (g.held_by[d] >= 0) reactions[3 * static_cast<std::size_t>(g.held_by[d]) + d] += support;
    }
  }
}

// Swivelling jaws: the gripped nodes move as one rigid body, by V dt and the
// rotation R(phi) about the jaw's origin o: v_j = V + (R(phi) - I) y_j / dt,
// y_j = x_j - o at t. Part p's share of the sums that give (V, phi), over
// the free dofs of each direction d: the masses, first moments sum m_j y_j
// and second moments sum m_j y_j y_j^T; the generalised momentum
// p = sum a (m_j v_j + dt_avg F_j), a = (e_d, y_j x e_d / L)
// (rigid_body.hpp); and C = sum a a^T over the dofs held otherwise than by
// a symmetry plane. Layout (kJawSums): masses 0-2, first moments 3-11,
// second moments 12-29 (xx, yy, zz, xy, xz, yz per direction), p 30-35,
// C 36-71.
void Simulation::swivel_jaw_sums(const Gripper& g, const MechPart& m, const double* x, const std::vector<int>& nodes,
                                 double dt_avg, bool normal_damping, bool contact, double* sums) const {
  const MechanicsDef& md = job_.mechanics_settings;
  const double inv_length = 1.0 / g.size;
  double* pv = sums + 30;
  double* C = sums + 36;
  for (const int i : nodes) {
    const double y[3] = {x[3 * i] - g.origin[0], x[3 * i + 1] - g.origin[1], x[3 * i + 2] - g.origin[2]};
    for (int d = 0; d < 3; ++d) {
      const std::size_t k = 3 * static_cast<std::size_t>(i) + d;
      double a[6];
      rigid_row(y, d, inv_length, a);
      if (m.mass3[k] >= 0) {
        const double mj = m.mass3[k];
        const double mom = mj * m.v[k] + dt_avg * jaw_force(m, k, md.damping, normal_damping, contact);
        for (int r = 0; r < 6; ++r) pv[r] += a[r] * mom;
        sums[d] += mj;
        for (int e = 0; e < 3; ++e) sums[3 + 3 * d + e] += mj * y[e];
        double* S = sums + 12 + 6 * d;
        S[0] += mj * y[0] * y[0];
        S[1] += mj * y[1] * y[1];
        S[2] += mj * y[2] * y[2];
        S[3] += mj * y[0] * y[1];
        S[4] += mj * y[0] * y[2];
        S[5] += mj * y[1] * y[2];
      } else if (job_.constraints[m.constraint_of[k]].type != ConstraintDef::Type::Symmetry) {
        for (int r = 0; r < 6; ++r)
          for (int s = 0; s < 6; ++s) C[6 * r + s] += a[r] * a[s];
      }
    }
  }
}

namespace {
inline Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline Vec3 axis3(int d) { return {d == 0 ? 1.0 : 0.0, d == 1 ? 1.0 : 0.0, d == 2 ? 1.0 : 0.0}; }
}  // namespace

// A swivelling jaw's force on part p's gripped nodes: each takes the rigid
// velocity V + (R(phi) - I) y_j / dt, which moves the nodes to their places
// by the rotation R(phi) about the origin, exactly for any angle. (V, phi)
// give the nodes the generalised momentum p of the sums:
//
//     M (V, L sin|phi| phi / (|phi| dt)) + Q(phi) = p,
//
// M q the momentum of the velocities' part linear in phi, Q(phi) that of
// the part (1 - cos|phi|) / |phi|^2 phi x (phi x y) / dt (from the second
// moments; it carries the turning body's gyroscopic change of momentum
// over the step), solved by fixed-point iteration from Q = 0 (each
// iteration gains a factor |phi|, under 1e-3 in a forming step). A
// symmetry plane with normal e_d that a gripped node lies on holds V_d and
// the turning about the other two axes (the jaw and its mirror image are
// one body).
void Simulation::solve_swivelling_jaw(const Gripper& g, std::size_t gi, double dt, double* solution) const {
  double sum[kJawSums] = {};
  for (std::size_t q = 0; q < parts_.size(); ++q) {
    const double* s = &jaw_sums_[(q * grippers_.size() + gi) * kJawSums];
    for (std::size_t r = 0; r < kJawSums; ++r) sum[r] += s[r];
  }
  const double L = g.size;
  // M from the moments: row d of the translation-rotation block is
  // (s1_d x e_d) / L, the rotation block sum_d [e_d]x S_d [e_d]x^T / L^2.
  double M[36] = {}, C[36], G[36];
  std::array<Vec3, 3> s1;
  std::array<std::array<double, 9>, 3> S;  // per direction, full 3 x 3
  for (int d = 0; d < 3; ++d) {
    s1[d] = {sum[3 + 3 * d], sum[4 + 3 * d], sum[5 + 3 * d]};
    const double* P = sum + 12 + 6 * d;
    S[d] = {P[0], P[3], P[4], P[3], P[1], P[5], P[4], P[5], P[2]};
    M[7 * d] = sum[d];
    const Vec3 tr = cross3(s1[d], axis3(d));
    for (int r = 0; r < 3; ++r) {
      M[6 * d + 3 + r] += tr[r] / L;
      M[6 * (3 + r) + d] += tr[r] / L;
    }
    // (y x e_d)(y x e_d)^T summed: y x e_d has y_i2 at i1 and -y_i1 at i2
    // (i1, i2 the next two axes after d).
    const int i1 = (d + 1) % 3, i2 = (d + 2) % 3;
    M[6 * (3 + i1) + 3 + i1] += S[d][4 * i2] / (L * L);
    M[6 * (3 + i2) + 3 + i2] += S[d][4 * i1] / (L * L);
    M[6 * (3 + i1) + 3 + i2] -= S[d][3 * i1 + i2] / (L * L);
    M[6 * (3 + i2) + 3 + i1] -= S[d][3 * i1 + i2] / (L * L);
  }
  for (int r = 0; r < 36; ++r) C[r] = sum[36 + r];
  for (int d = 0; d < 3; ++d)
    if (g.on_symmetry[d]) {
      C[7 * d] += 1.0;
      C[7 * (3 + (d + 1) % 3)] += 1.0;
      C[7 * (3 + (d + 2) % 3)] += 1.0;
    }
  constrained_rigid_inverse(M, C, G);
  double* q = solution;
  double* phi = solution + 6;
  phi[0] = phi[1] = phi[2] = 0.0;
  for (int it = 0; it < 4; ++it) {
    double rhs[6];
    for (int r = 0; r < 6; ++r) rhs[r] = sum[30 + r];
    if (it > 0) {  // less Q(phi)
      const double th2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
      const double th = std::sqrt(th2), h = std::sin(0.5 * th) / (0.5 * th);
      const double f2 = th > 0 ? 0.5 * h * h / dt : 0.5 / dt;
      const Vec3 ph{phi[0], phi[1], phi[2]};
      Vec3 rot{0, 0, 0};
      for (int d = 0; d < 3; ++d) {
        rhs[d] -= f2 * cross3(ph, cross3(ph, s1[d]))[d];
        const double* Sd = S[d].data();
        const Vec3 Sphi{Sd[0] * ph[0] + Sd[1] * ph[1] + Sd[2] * ph[2], Sd[3] * ph[0] + Sd[4] * ph[1] + Sd[5] * ph[2],
                        Sd[6] * ph[0] + Sd[7] * ph[1] + Sd[8] * ph[2]};
        const Vec3 Se{Sd[d], Sd[3 + d], Sd[6 + d]};
        const Vec3 t1 = cross3(Sphi, axis3(d)), t2 = cross3(Se, axis3(d));
        for (int r = 0; r < 3; ++r) rot[r] += ph[d] * t1[r] - th2 * t2[r];
      }
      for (int r = 0; r < 3; ++r) rhs[3 + r] -= f2 * rot[r] / L;
    }
    for (int r = 0; r < 6; ++r) {
      q[r] = 0;
      for (int c = 0; c < 6; ++c) q[r] += G[6 * r + c] * rhs[c];
    }
    // sin|phi| phi / |phi| = w dt: the angle whose sine that is.
    double w_dt[3] = {q[3] / L * dt, q[4] / L * dt, q[5] / L * dt};
    const double chord = std::sqrt(w_dt[0] * w_dt[0] + w_dt[1] * w_dt[1] + w_dt[2] * w_dt[2]);
    const double f = chord > 0 ? std::asin(std::min(chord, 1.0)) / chord : 1.0;
    bool same = true;  // converged to the last bit
    for (int r = 0; r < 3; ++r) {
      same = same && phi[r] == w_dt[r] * f;
      phi[r] = w_dt[r] * f;
    }
    if (same) break;
  }
}

// Each closed swivelling jaw's (V, phi) from the sums of every part, into
// the thread's slot of jaw_solution_ (9 numbers per gripper).
void Simulation::solve_swivelling_jaws(int slot, double t, double dt) {
  for (std::size_t gi = 0; gi < grippers_.size(); ++gi) {
    const ConstraintDef& c = job_.constraints[grippers_[gi].constraint];
    if (c.swivelling && t < c.release)
      solve_swivelling_jaw(grippers_[gi], gi, dt,
                           &jaw_solution_[(static_cast<std::size_t>(slot) * grippers_.size() + gi) * 9]);
  }
}

// A swivelling jaw's force on part p's gripped nodes from its solution
// (V, phi).
void Simulation::tie_swivelling_jaw(const Gripper& g, const double* solution, int p, double dt, double dt_avg,
                                    double* reactions) {
  const MechanicsDef& md = job_.mechanics_settings;
  const bool normal_damping = md.damping_normal && md.damping > 0, contact = !contacts_.empty();
  const double* q = solution;
  MechPart& m = *mech_[p];
  const double* x = parts_[p]->x.data();
  const Rotation rotation(solution + 6);
  double support[3] = {0, 0, 0};
  for (const int i : g.part_nodes[p]) {
    const double y[3] = {x[3 * i] - g.origin[0], x[3 * i + 1] - g.origin[1], x[3 * i + 2] - g.origin[2]};
    double turn[3];
    rotation.increment(y, turn);
    for (int d = 0; d < 3; ++d) {
      const std::size_t k = 3 * static_cast<std::size_t>(i) + d;
      if (m.mass3[k] < 0) continue;
      const double target = q[d] + turn[d] / dt;
      const double tie = m.mass3[k] * (target - m.v[k]) / dt_avg - jaw_force(m, k, md.damping, normal_damping, contact);
      m.load[k] += tie;
      support[d] += tie;
    }
  }
  for (int d = 0; d < 3; ++d)
    if (g.held_by[d] >= 0) reactions[3 * static_cast<std::size_t>(g.held_by[d]) + d] += support[d];
}

// Central differences: v^{n+1/2} = v^{n-1/2} + dt_avg a^n, x^{n+1} = x^n + dt v^{n+1/2}.
double Simulation::mechanics_step(double dt, double t, long long step, EnergyAudit& audit) {
  const MechanicsDef& md = job_.mechanics_settings;
  const double dt_avg = step == 0 ? 0.5 * dt : 0.5 * (last_mech_dt_ + dt);
  audit.reactions.assign(3 * job_.constraints.size(), 0.0);
  // Applied loads at t, each ramped from zero over its own time.
  if (!loads_.empty()) {
    for (auto& m : mech_) std::fill(m->load.begin(), m->load.end(), 0.0);
    for (const Load& l : loads_) {
      const double factor = l.ramp > 0 ? std::min(1.0, t / l.ramp) : 1.0;
      for (const auto& [p, i] : l.nodes)
        for (int d = 0; d < 3; ++d) mech_[p]->load[3 * i + d] += factor * l.per_node[d];
    }
  }
  if (!grippers_.empty()) {
    if (loads_.empty())  // only the gripped nodes' loads are not zero
      for (const Gripper& g : grippers_)
        for (const auto& [p, i] : g.nodes)
          std::fill_n(&mech_[p]->load[3 * static_cast<std::size_t>(i)], 3, 0.0);
    apply_grippers(t);
  }
  // Parts are independent here: with several, one thread each. Each part
  // sums its own works and reactions; the parts' sums are then added in
  // part order (the same for any thread count).
  const int np = static_cast<int>(parts_.size());
  const std::size_t nr = 3 * job_.constraints.size();
  part_sums_.assign(np * (6 + nr), 0.0);
  part_bad_.assign(np, -1);  // per part: first non-finite coordinate
  std::size_t nodes_all = 0;
  for (const auto& st : parts_) nodes_all += st->x.size() / 3;
  const bool normal_damping = md.damping_normal && md.damping > 0;
  // A part's forces complete: the contact forces from the other parts'
  // tasks, the velocities that the damping takes.
  auto prepare_part = [&](int p) {
    merge_part_contact(p);
    if (normal_damping) normal_velocities(parts_[p]->mesh, parts_[p]->x.data(), mech_[p]->v.data(), *mech_[p]);
    if (rigid_jaws_) rigid_jaw_sums(p, t, dt_avg);
  };
  if (rigid_jaws_) {
    jaw_sums_.assign(static_cast<std::size_t>(np) * kJawSums * grippers_.size(), 0.0);
    if (swivelling_jaws_)  // a slot per thread (sized once)
      jaw_solution_.resize(static_cast<std::size_t>(std::max(1, omp_get_max_threads())) * grippers_.size() * 9);
    // Swivelling jaws turn about their pin (a gripped node held otherwise
    // than by a symmetry plane), else about the gripped nodes' centre at t.
    for (Gripper& g : grippers_)
      if (job_.constraints[g.constraint].swivelling)
        g.origin = g.pin_node >= 0 ? sdk::load3(parts_[g.pin_part]->x.data(), g.pin_node) : g.centre;
  }
  auto integrate_part = [&](int p, int slot) {
    double* reactions = &part_sums_[p * (6 + nr) + 6];
    if (rigid_jaws_) tie_rigid_jaws(p, slot, t, dt, dt_avg, reactions);
    PartState& st = *parts_[p];
    MechPart& m = *mech_[p];
    const std::size_t n = 3 * static_cast<std::size_t>(st.mesh.num_nodes());
    // The constraints' reactions at t^n, in dof order.
    for (const int k : m.fixed_dofs)
      reactions[3 * m.constraint_of[k] + k % 3] += m.f_int[k] - (m.gravity3[k] + m.load[k]) - m.f_con[k];
    double sums_p[7];
    kIntegrateDofs[normal_damping ? 1 : 0][contacts_.empty() ? 0 : 1][m.external ? 1 : 0](
        n, dt, step == 0 ? 0.0 : last_mech_dt_, dt_avg, md.damping, normal_damping ? m.normal_velocity.data() : nullptr,
        m.mass3.data(), m.gravity3.data(),
        m.load.data(), m.f_int.data(), m.f_con.data(), m.fixed_dofs.data(), m.fixed_dofs.size(), m.prescribed.data(),
        m.v.data(), st.x.data(), m.pending_work, sums_p);
    const double nonfinite = sums_p[6];
    const int nn = st.mesh.num_nodes();
    if (nonfinite != 0)  // also when NaN
      for (int k = 0; k < 3 * nn; ++k)
        if (!std::isfinite(st.x[k])) {
          part_bad_[p] = k;
          break;
        }
    double* sums = &part_sums_[p * (6 + nr)];
    for (int j = 0; j < 6; ++j) sums[j] = sums_p[j];
  };
  // With several parts, each on the thread that owns it (by part, the one
  // that computed its forces; otherwise dealt in turn). Rigid jaws, which
  // may hold nodes of several parts, need every part's sums first: a spin
  // wait, not an OpenMP barrier (sdk/parallel.hpp).
  if (sdk::team_available(np > 1 && nodes_all > 512)) {
    std::atomic<int> prepared{0};
#pragma omp parallel
    {
      const int me = omp_get_thread_num(), team = omp_get_num_threads();
      if (rigid_jaws_) {
        for (int p = 0; p < np; ++p)
          if (thread_of_part(p, team) == me) prepare_part(p);
        prepared.fetch_add(1, std::memory_order_acq_rel);
        spin_until([&] { return prepared.load(std::memory_order_acquire) == team; });
        if (swivelling_jaws_) solve_swivelling_jaws(me, t, dt);  // each thread the same, from the same sums
      }
      for (int p = 0; p < np; ++p)
        if (thread_of_part(p, team) == me) {
          if (!rigid_jaws_) prepare_part(p);
          integrate_part(p, me);
        }
    }
  } else {
    for (int p = 0; p < np; ++p) prepare_part(p);
    if (swivelling_jaws_) solve_swivelling_jaws(0, t, dt);
    for (int p = 0; p < np; ++p) integrate_part(p, 0);
  }
  double w_int = 0, w_ext = 0, w_damp = 0, w_con = 0, kin = 0, kin_half = 0;
  for (int p = 0; p < np; ++p) {
    if (part_bad_[p] >= 0)
      throw RunError("non-finite position in part '" + parts_[p]->def->name + "' at " +
                     node_label(parts_[p]->mesh, part_bad_[p] / 3) + ", t = " + fmt_g(t + dt) + " s (mechanical step " +
                     std::to_string(step + 1) + ")");
    const double* sums = &part_sums_[p * (6 + nr)];
    w_int += sums[0];
    w_ext += sums[1];
    w_damp += sums[2];
    w_con += sums[3];
    kin += sums[4];
    kin_half += sums[5];
    for (std::size_t r = 0; r < nr; ++r) audit.reactions[r] += sums[6 + r];
  }
  for (const Gripper& g : grippers_)
    for (int d = 0; d < 3; ++d) audit.reactions[3 * g.constraint + d] += g.force[d];
  // Tools move to t + dt (force control with the plies' force at t).
  for (std::size_t q = 0; q < tools_.size(); ++q)
    tools_[q]->advance(t, dt, dt_avg, {tool_force_[3 * q], tool_force_[3 * q + 1], tool_force_[3 * q + 2]});
  audit.internal += w_int;
  audit.external += w_ext;
  audit.damping += w_damp;
  audit.contact -= w_con;
  audit.kinetic = kin;
  audit.kinetic_half = kin_half;
  last_mech_dt_ = dt;
  return dt;
}

// The mechanical fields that frames and probes show: the elements' (shear
// angle, stresses, curvatures, fibres) and the contact fields.
void Simulation::update_element_fields() {
  update_contact_fields();
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    PartState& st = *parts_[p];
    if (want_thickness_)
      constant_volume_thickness(st.mesh, st.area0, st.x.data(), st.def->thickness, st.thickness.data());
    MechPart& m = *mech_[p];
    sdk::ElementFields f;
    f.shear_angle = st.shear_angle;
    f.stress = m.stress;
    f.curvature = m.curvature;
    f.strain = m.strain;
    f.fibre = st.fibre;
    m.element->fields(f);
    if (std::find(job_.output.fields.begin(), job_.output.fields.end(), "membrane_stability") !=
        job_.output.fields.end())
      if (const std::string e =
              ply_stability(m.membrane, st.mesh.triangles, m.node_temperature, m.strain, m.stability, m.stability_tol);
          !e.empty())
        throw RunError("material law of part '" + st.def->name + "' failed in the stability check: " + e);
  }
}

void Simulation::build_probes() {
  for (const auto& pr : job_.output.probes) {
    const PartState& st = *parts_[pr.part];
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int i = 0; i < st.mesh.num_nodes(); ++i) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += (st.x0[3 * i + k] - pr.at[k]) * (st.x0[3 * i + k] - pr.at[k]);
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    const double reach = 2.0 * max_edge_length(st.mesh) + st.def->thickness;
    if (std::sqrt(best_d) > reach)
      throw JobError(pr.pointer + "/at", "probe '" + pr.name + "' is outside part '" + st.def->name +
                                             "': the nearest node is " + fmt_g(std::sqrt(best_d), 4) + " m away");
    probe_node_.push_back(best);
    std::vector<int> around;
    for (int e = 0; e < st.mesh.num_elements(); ++e)
      for (int k = 0; k < 3; ++k)
        if (st.mesh.triangles[3 * e + k] == best) around.push_back(e);
    probe_elements_.push_back(around);
  }
}

}  // namespace ts
