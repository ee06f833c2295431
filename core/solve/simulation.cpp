#include "solve/simulation.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <type_traits>
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
#include "io/results_reader.hpp"
#include "io/results_writer.hpp"
#include "solve/crystallisation.hpp"
#include "solve/heat_capacity.hpp"
#include "solve/interrupt.hpp"
#include "solve/tools.hpp"
#include "solve/subnormals.hpp"
#include "version.hpp"

namespace ts {

using sdk::Vec3;

namespace {
// The smallest and largest E11 (the strain along the initial fibre
// direction) of a part's elements, from their strains [E11, E22, E12].
std::pair<double, double> fibre_strain_range(const std::vector<double>& strain) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < strain.size(); i += 3) {
    lo = std::min(lo, strain[i]);
    hi = std::max(hi, strain[i]);
  }
  return {lo, hi};
}
}  // namespace

struct MechPart {
  std::unique_ptr<sdk::ElementKernel> element;
  std::vector<const sdk::MaterialLaw*> membrane;
  std::vector<double> curvature;
  std::vector<double> strain;  // Green-Lagrange membrane strain, 3 per element (ElementFields::strain)
  std::vector<double> load;  // applied nodal forces at full value (N), 3 per node
  sdk::large_vector<double> f_con;  // contact forces (N)
  std::vector<double> k_contact;     // contact stiffness bound (N/m)
  // The arrays every step streams through: on huge pages where the system
  // offers them (sdk/memory.hpp).
  sdk::large_vector<double> v, f_int, elem_sqrt_scale, node_temperature;
  // The faces' temperatures the contact handlers see (ContactForceInput::
  // face_temperature): bottom and top per node, degC.
  std::vector<double> face_temperature;
  bool scaled = false;  // some elem_sqrt_scale is not 1 (else the elements get no step factors)
  std::vector<double> mass, mass_node_physical, elem_dt, elem_scale, stress;
  // Half of the next step's internal, external, damping and contact works,
  // known at this step (see integrate_body).
  double pending_work[4] = {0, 0, 0, 0};
  // Per element block, reused every step.
  std::vector<int> block_fail;
  std::vector<std::string> block_error;
  // Element blocks: the partition follows the element count only, never the
  // thread count, so the results are the same for any number of threads.
  int block_size = 0, blocks = 0;
  int passes = 1;  // the element's passes over the blocks per force evaluation
  // In the one-thread order (Simulation::one_thread_order): the blocks
  // whose values between passes may be needed at once
  // (ElementForceInput::pass_window), 0 for no bound below the block count.
  int pass_window = 0;
  std::vector<double> block_dt;
  // The bending's own stable steps (mass scaling included): per block from
  // the last evaluation with bending, and their smallest.
  std::vector<double> block_bdt;
  double bend_dt = std::numeric_limits<double>::infinity();
  // Node forces of each block, added by the element into the block's own
  // slots (ElementForceInput::patch_slot): the local nodes of block b are entries
  // block_node_start[b] .. block_node_start[b + 1] of block_node (ascending
  // global ids); slot_local holds each element slot's local index (-1: no
  // node). A node of one block only is written to f_int by that block; a
  // node shared by several blocks is summed after them, in block order:
  // the forces of shared node s from its blocks are entries shared_start[s]
  // .. shared_start[s + 1] of block_force (3 values each), and local slot l
  // writes entry shared_entry[l] (-1 for a node of one block only).
  std::vector<int> block_node_start, block_node, shared_node, shared_start, shared_entry;
  sdk::large_vector<int> slot_local;
  std::vector<double> block_force;
  std::vector<char> fixed;          // 3 per node
  std::vector<int> edge_condition;  // 3 per element (sdk::kEdgeFree / kEdgeClamped)
  std::vector<int> constraint_of;   // 3 per node: index of the constraint holding the dof, -1 if none
  std::vector<double> prescribed;   // 3 per node: velocity where fixed (0 for fix / symmetry)
  // Per dof, for the integration's vector pass: mass (negated where held or
  // driven) and gravity force; the held or driven dofs in ascending order.
  sdk::large_vector<double> mass3, gravity3;
  std::vector<int> fixed_dofs;
  bool external = false;  // gravity or applied loads act on the part
  double mass_physical = 0, mass_added = 0;
  double mass_added_contact = 0;  // the part of mass_added that the contact springs asked for
};

struct PartState {
  const PartDef* def = nullptr;
  ShellMesh mesh;
  std::vector<double> x0, fibre, area, normals, displacement, shear_angle, contact_status;
  // Per node, Pa: the largest contact pressure on its faces at the last
  // contact force evaluation (only where a field or probe asks for it).
  std::vector<double> contact_pressure;
  sdk::large_vector<double> x;  // positions (m), on huge pages where offered (sdk/memory.hpp)
  int nz = 1;
  std::vector<double> T, cap, mean, top, bottom;
  // A specific heat that depends on the temperature (empty: constant), and
  // the temperatures before the thermal step under way (solve/heat_capacity.hpp).
  HeatCapacityTable cp;
  std::vector<double> T_step;
  // The matrix's crystallisation (solve/crystallisation.hpp; empty: none):
  // per value, the Nakamura integral theta and the relative crystallinity
  // X; per node, X's mean through the thickness (for the frames); and the
  // specific heat the latent heat is given with where c is constant (J/(kg K)).
  CrystallisationKinetics kin;
  std::vector<double> theta, X, X_mean;
  double c_latent = 0;
  std::vector<double> h_bottom, t_bottom, h_top, t_top;
  // Per node, W/(m^2 K): the conductance of each face at the last thermal
  // step (tool contact, convection and radiation, ply/ply links per unit
  // area), for the field and probe quantity `conductance`.
  std::vector<double> conductance_bottom, conductance_top;
  // Per node, m: the gap from the ply's face to the nearest of its tools
  // (Simulation::update_tool_gap), for the field and probe quantity `tool_gap`.
  std::vector<double> tool_gap;
  // Per node, s: the first time a value of the node, and every value, was
  // below output.temperature_threshold (NaN: not yet), for the field
  // `below_threshold_from` (empty unless asked for).
  std::vector<double> below_from, all_below_from;
  // degC: the initial temperature (with initial temperatures from a results
  // file, their mean by heat capacity), for the laws probed at set-up.
  double t0 = 20.0;
};

namespace {

// The mean through the thickness h of a node's nz values (linear between
// them), or its one value.
double thickness_mean(const double* v, int nz, double h) {
  if (nz == 1) return v[0];
  const double e = h / (nz - 1);
  double s = 0;
  for (int k = 0; k < nz; ++k) s += (k == 0 || k == nz - 1 ? 0.5 * e : e) * v[k];
  return s / h;
}

// A ply's smallest, mean (by mass) and largest relative crystallinity (NaN
// for a ply whose material has no crystallisation kinetics).
std::array<double, 3> ply_crystallinity(const PartState& st) {
  if (st.X.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  double lo = 1, hi = 0, sum = 0, cap = 0;
  for (std::size_t k = 0; k < st.X.size(); ++k) {
    lo = std::min(lo, st.X[k]);
    hi = std::max(hi, st.X[k]);
    sum += st.cap[k] * st.X[k];
    cap += st.cap[k];
  }
  return {lo, cap > 0 ? sum / cap : st.X[0], hi};
}

// A ply's coldest, mean (weighted by heat capacity) and hottest value
// (degC), and the share of its heat capacity below the threshold (0
// without one): by node, the part of the thickness below it with the
// temperature linear between the values (a single value: all or nothing).
std::array<double, 4> ply_temperature(const PartState& st, const std::optional<double>& threshold) {
  const int nz = st.nz;
  const std::size_t nn = static_cast<std::size_t>(st.mesh.num_nodes());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, heat = 0, cap = 0, below = 0;
  for (std::size_t i = 0; i < nn; ++i) {
    const double* T = &st.T[i * nz];
    const double* c = &st.cap[i * nz];
    double column = 0, frac = 0;
    for (int k = 0; k < nz; ++k) {
      lo = std::min(lo, T[k]);
      hi = std::max(hi, T[k]);
      heat += c[k] * T[k];
      column += c[k];
    }
    if (threshold) {
      const double th = *threshold;
      if (nz == 1) {
        frac = T[0] < th ? 1.0 : 0.0;
      } else {
        for (int k = 0; k + 1 < nz; ++k) {
          const double a = std::min(T[k], T[k + 1]), b = std::max(T[k], T[k + 1]);
          frac += a >= th ? 0.0 : b <= th ? 1.0 : (th - a) / (b - a);
        }
        frac /= nz - 1;
      }
    }
    cap += column;
    below += column * frac;
  }
  return {lo, heat / cap, hi, below / cap};
}
using Clock = std::chrono::steady_clock;

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
template <bool kContact, bool kExternal>
[[gnu::always_inline]] inline void integrate_body(std::size_t n, double dt, double dt_prev, double dt_avg,
                                                  double damping, const double* __restrict mass3,
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
    const double f_damp = damping * mi * vo;
    const double v_new = vo + dt_avg * (f_ext + fc - fi - f_damp) / mi;
    const double dxn = dt * v_new;
    const double xo = x[k], xn = xo + dxn;
    w_int += is_free ? 0.5 * fi * dxo : 0.0;
    p_int += is_free ? 0.5 * fi * dxn : 0.0;
    w_ext += is_free ? f_ext * dxo : 0.0;
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
#define TS_INTEGRATE(NAME, CONTACT, EXTERNAL)                                                                        \
  TS_VECTOR_CLONES void NAME(std::size_t n, double dt, double dt_prev, double dt_avg, double damping,                \
                             const double* mass3, const double* gravity3,                                            \
                             const double* load, const double* f_int, const double* f_con, const int* fixed,         \
                             std::size_t nfixed, const double* prescribed, double* v, double* x, double* pending,    \
                             double* sums) {                                                                         \
    integrate_body<CONTACT, EXTERNAL>(n, dt, dt_prev, dt_avg, damping, mass3, gravity3, load, f_int, f_con,          \
                                      fixed, nfixed, prescribed, v, x, pending, sums);                               \
  }
TS_INTEGRATE(integrate_dofs, false, false)
TS_INTEGRATE(integrate_dofs_contact, true, false)
TS_INTEGRATE(integrate_dofs_external, false, true)
TS_INTEGRATE(integrate_dofs_contact_external, true, true)
#undef TS_INTEGRATE
using IntegrateDofs = void (*)(std::size_t, double, double, double, double, const double*, const double*,
                               const double*, const double*, const double*, const int*,
                               std::size_t, const double*, double*, double*, double*, double*);
// By [contact][external forces].
constexpr IntegrateDofs kIntegrateDofs[2][2] = {{integrate_dofs, integrate_dofs_external},
                                                {integrate_dofs_contact, integrate_dofs_contact_external}};

// The kinetic energy may not exceed this multiple of the energy supplied.
constexpr double kKineticGrowthLimit = 10.0;
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

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
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

// Moves a sampling time `next` past `limit` by whole intervals iv: one
// addition at a time where a few suffice (the times the schedule has always
// had), in one jump where many intervals fit in a step, and never stuck
// where iv is below the round-off of `next`.
void advance_past(double& next, double iv, double limit) {
  if (limit - next > 16 * iv) next += std::floor((limit - next) / iv) * iv;
  while (next <= limit) {
    const double n = next + iv;
    next = n > next ? n : std::nextafter(limit, std::numeric_limits<double>::infinity());
  }
}

std::string fmt_g(double v, int prec = 6) {
  std::ostringstream s;
  s << std::setprecision(prec) << v;
  return s.str();
}
}  // namespace

Simulation::Simulation(const Job& job, PluginRegistry& registry) : job_(job), registry_(registry) {
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
  for (const auto& pr : job_.output.probes) {
    probe_pressure_.push_back(std::find(pr.quantities.begin(), pr.quantities.end(), "contact_pressure") !=
                              pr.quantities.end());
    want_pressure_ = want_pressure_ || probe_pressure_.back();
  }
  build_parts();
  build_tools();
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
}

Simulation::~Simulation() = default;

void Simulation::build_parts() {
  for (std::size_t p = 0; p < job_.parts.size(); ++p) {
    const PartDef& def = job_.parts[p];
    auto st = std::make_unique<PartState>();
    st->def = &def;
    try {
      st->mesh = def.mesh.kind == MeshDef::Kind::File
                     ? read_gmsh(def.mesh.file)
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
                       "the fibre direction is normal to the ply at element " + std::to_string(e) +
                           "; give a direction in the ply's plane");
      const Vec3 u = sdk::normalized(f);
      for (int d = 0; d < 3; ++d) st->fibre[3 * e + d] = u[d];
    }
    st->displacement.assign(3 * nn, 0.0);
    st->shear_angle.assign(ne, 0.0);
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
    v.thermal = {mat.density, mat.specific_heat, mat.conductivity[0], mat.conductivity[1], mat.conductivity[2]};
  }
}

void Simulation::build_tools() {
  for (std::size_t t = 0; t < job_.tools.size(); ++t) {
    auto tool = std::make_unique<RigidTool>(job_.tools[t]);
    if (job_.tools[t].motion.kind != MotionDef::Kind::Fixed && !job_.mechanics)
      logger("job")->warn("{}/motion: ignored, tools do not move in a thermal-only job", job_.tools[t].pointer);
    tools_.push_back(std::move(tool));
  }
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
    tool_views_.push_back(v);
  }
}

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
  const sdk::Params params = validate_params(th.params, th.pointer, rec.descriptor, {"splitter", "subcycle", "dt"});
  splitter_.reset(reinterpret_cast<sdk::ThermalSplitter* (*)()>(rec.create)());
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
    if (const auto& c = mat.crystallisation; c.present) {
      st.kin = CrystallisationKinetics(c.latent_heat, c.avrami_exponent, c.rate_rows, c.k_max, c.t_max, c.half_width);
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
  assemble_faces();
  update_far_temperatures(0.0, 0.0);
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
  // Land on the frame times: an integer number of steps per output interval.
  const double interval = std::min(job_.output.interval, job_.t_end);
  const double per = std::ceil(interval / dt * (1 - 1e-12));
  thermal_dt_ = interval / std::max(1.0, per);
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
  for (const ExchangeFace& f : exchange_faces_) {
    const HeatExchangeDef& h = job_.heat_exchanges[static_cast<std::size_t>(f.exchange)];
    PartState& st = *parts_[f.part];
    const double ambient = h.ambient_over(t0, t1);
    (f.face == sdk::kTop ? st.t_top : st.t_bottom)[f.node] = ambient;
    if (!(h.emissivity > 0)) continue;
    const std::size_t base = static_cast<std::size_t>(st.nz) * f.node;
    const double T = st.T[base + (f.face == sdk::kTop ? st.nz - 1 : 0)] + kKelvin, Ta = ambient + kKelvin;
    (f.face == sdk::kTop ? st.h_top : st.h_bottom)[f.node] = h.h + h.emissivity * kSigma * (T * T + Ta * Ta) * (T + Ta);
  }
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
    for (int i = 0; i < nn; ++i) {
      const double* src = &from[static_cast<std::size_t>(i) * nl];
      double* dst = &to[static_cast<std::size_t>(i) * nz];
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

void Simulation::assemble_faces() {
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
  contact_map_.tool_contacts.clear();
  contact_map_.links.clear();
  std::vector<std::span<const double>> areas;
  for (auto& st : parts_) areas.emplace_back(st->area);
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    if (auto s = contacts_[c]->thermal_contacts(part_views_, tool_views_, areas, contact_map_); !s)
      throw RunError("contact handler of " + job_.contacts[c].pointer + ": " + s.message);
  }
  for (const auto& tc : contact_map_.tool_contacts) {
    PartState& st = *parts_[tc.part];
    const double T = tool_views_[tc.tool].temperature;
    if (tc.face == sdk::kTop) {
      st.h_top[tc.node] = tc.conductance;
      st.t_top[tc.node] = T;
    } else {
      st.h_bottom[tc.node] = tc.conductance;
      st.t_bottom[tc.node] = T;
    }
    if (renewed) renews[tc.part][2 * tc.node + (tc.face == sdk::kTop ? 1 : 0)] = -1;
    st.contact_status[tc.node] = std::max(st.contact_status[tc.node], 1.0);
  }
  exchange_faces_.clear();
  for (std::size_t p = 0; p < renews.size(); ++p)
    for (std::size_t f = 0; f < renews[p].size(); ++f)
      if (const int k = renews[p][f]; k >= 0)
        exchange_faces_.push_back({static_cast<int>(p), static_cast<int>(f / 2), f % 2 ? sdk::kTop : sdk::kBottom, k});
  for (const auto& l : contact_map_.links) {
    parts_[l.part_a]->contact_status[l.node_a] = 2.0;
    for (int j = 0; j < 3; ++j)
      if (l.w_b[j] > 0) parts_[l.part_b]->contact_status[l.nodes_b[j]] = 2.0;
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
    const sdk::MaterialLaw* bending = nullptr;
    if (!mat.bending.is_null()) {
      const std::string ptr = mat.pointer + "/bending";
      if (auto it = made.find(ptr); it != made.end()) {
        bending = it->second;
      } else {
        if (!mat.bending.is_object() || !mat.bending.contains("law") || !mat.bending["law"].is_string())
          throw JobError(ptr + "/law", "required string, missing");
        const PluginRecord& rec = registry_.require(sdk::PluginKind::Material, mat.bending["law"], ptr + "/law");
        const sdk::Params params = validate_params(mat.bending, ptr, rec.descriptor, {"law"});
        std::unique_ptr<sdk::MaterialLaw> law(reinterpret_cast<sdk::MaterialLaw* (*)()>(rec.create)());
        if (auto s = law->configure(params); !s) throw JobError(ptr, "material law: " + s.message);
        if (law->role() != sdk::LawRole::Bending)
          throw JobError(ptr + "/law", "'" + mat.bending["law"].get<std::string>() + "' is not a bending law");
        bending = law.get();
        made[ptr] = law.get();
        law_uses_.push_back({law.get(), ptr, mat.bending["law"].get<std::string>()});
        laws_.push_back(std::move(law));
      }
    }
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
      for (int i = 0; i < nn0; ++i) {
        bool inside = true;
        for (int d = 0; d < 3; ++d) inside = inside && st.x0[3 * i + d] >= c.lo[d] && st.x0[3 * i + d] <= c.hi[d];
        if (inside) held[i] = 1;
      }
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
        bool inside = true;
        for (int d = 0; d < 3; ++d) inside = inside && X[d] >= c.lo[d] && X[d] <= c.hi[d];
        if (!inside) continue;
        if (c.type == ConstraintDef::Type::Force) continue;  // loads: below
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
      for (int i = 0; i < st.mesh.num_nodes(); ++i) {
        bool inside = true;
        for (int d = 0; d < 3; ++d) inside = inside && st.x0[3 * i + d] >= c.lo[d] && st.x0[3 * i + d] <= c.hi[d];
        if (inside) nodes.emplace_back(p, i);
      }
    }
    if (nodes.empty()) throw JobError(c.pointer + "/box", "no node of the part(s) lies inside the box");
    Load l;
    l.ramp = c.ramp;
    l.nodes = std::move(nodes);
    for (int d = 0; d < 3; ++d) l.per_node[d] = c.force[d] / static_cast<double>(l.nodes.size());
    loads_.push_back(std::move(l));
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
                         "element " + std::to_string(mech_[p]->block_fail[b]) + " of part '" + parts_[p]->def->name +
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
      what = "the contact springs (penalty times node area, against the node masses)";
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
        throw RunError("element '" + st.def->element + "' of part '" + st.def->name + "': " + m.block_error[b]);
      if (m.block_fail[b] >= 0)
        throw RunError("degenerate (collapsed or inverted) element " + std::to_string(m.block_fail[b]) + " in part '" +
                       st.def->name + "'");
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
// at most every k-th step, as an impulse: the evaluation that carries it
// weighs its bending forces by the number of steps j it stands for (the
// velocity then changes by j dt f_b / m at once), the j - 1 evaluations
// after it carry none (ElementForceInput::bending_weight). j is the
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

// Heat given by every tool to the plies over the thermal step just taken
// (conductance times the jump at the end of the step, as the implicit
// face condition uses it).
void Simulation::accumulate_tool_heat(double dt) {
  for (const auto& tc : contact_map_.tool_contacts) {
    const PartState& st = *parts_[tc.part];
    const std::size_t base = static_cast<std::size_t>(st.nz) * tc.node;
    const double Tf = tc.face == sdk::kTop ? st.T[base + st.nz - 1] : st.T[base];
    tool_heat_[tc.tool] += tc.conductance * st.area[tc.node] * (tool_views_[tc.tool].temperature - Tf) * dt;
  }
  // Ply/ply: G (T_b - T_a) into a, out of b, with the facing surface values.
  if (link_heat_.size() != parts_.size()) link_heat_.assign(parts_.size(), 0.0);
  auto face_value = [&](int part, int node, int face) {
    const PartState& st = *parts_[part];
    const std::size_t base = static_cast<std::size_t>(st.nz) * node;
    return face == sdk::kTop ? st.T[base + st.nz - 1] : st.T[base];
  };
  for (const auto& l : contact_map_.links) {
    double Tb = 0;
    for (int j = 0; j < 3; ++j) Tb += l.w_b[j] * face_value(l.part_b, l.nodes_b[j], l.face_b);
    const double q = l.conductance * (Tb - face_value(l.part_a, l.node_a, l.face_a)) * dt;
    link_heat_[l.part_a] += q;
    link_heat_[l.part_b] -= q;
  }
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
  // Parts are independent here: with several, one thread each. Each part
  // sums its own works and reactions; the parts' sums are then added in
  // part order (the same for any thread count).
  const int np = static_cast<int>(parts_.size());
  const std::size_t nr = 3 * job_.constraints.size();
  part_sums_.assign(np * (6 + nr), 0.0);
  part_bad_.assign(np, -1);  // per part: first non-finite coordinate
  std::size_t nodes_all = 0;
  for (const auto& st : parts_) nodes_all += st->x.size() / 3;
  auto integrate_part = [&](int p) {
    merge_part_contact(p);
    double* reactions = &part_sums_[p * (6 + nr) + 6];
    PartState& st = *parts_[p];
    MechPart& m = *mech_[p];
    const std::size_t n = 3 * static_cast<std::size_t>(st.mesh.num_nodes());
    // The constraints' reactions at t^n, in dof order.
    for (const int k : m.fixed_dofs)
      reactions[3 * m.constraint_of[k] + k % 3] += m.f_int[k] - (m.gravity3[k] + m.load[k]) - m.f_con[k];
    double sums_p[7];
    kIntegrateDofs[contacts_.empty() ? 0 : 1][m.external ? 1 : 0](
        n, dt, step == 0 ? 0.0 : last_mech_dt_, dt_avg, md.damping, m.mass3.data(), m.gravity3.data(),
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
  // that computed its forces; otherwise dealt in turn).
  if (sdk::team_available(np > 1 && nodes_all > 512)) {
#pragma omp parallel
    {
      const int me = omp_get_thread_num(), team = omp_get_num_threads();
      for (int p = 0; p < np; ++p)
        if (thread_of_part(p, team) == me) integrate_part(p);
    }
  } else {
    for (int p = 0; p < np; ++p) integrate_part(p);
  }
  double w_int = 0, w_ext = 0, w_damp = 0, w_con = 0, kin = 0, kin_half = 0;
  for (int p = 0; p < np; ++p) {
    if (part_bad_[p] >= 0)
      throw RunError("non-finite position in part '" + parts_[p]->def->name + "' at node " +
                     std::to_string(part_bad_[p] / 3) + ", t = " + fmt_g(t + dt) + " s (mechanical step " +
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
    MechPart& m = *mech_[p];
    sdk::ElementFields f;
    f.shear_angle = st.shear_angle;
    f.stress = m.stress;
    f.curvature = m.curvature;
    f.strain = m.strain;
    f.fibre = st.fibre;
    m.element->fields(f);
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

void Simulation::keep_step_temperatures() {
  for (auto& st : parts_) {
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
    const long long n = static_cast<long long>(st.T.size());
    double* T = st.T.data();
    const double* T0 = st.T_step.data();
    double* theta = st.theta.data();
    double* X = st.X.data();
#pragma omp parallel for schedule(static) if (n > 8192)
    for (long long k = 0; k < n; ++k) {
      double t = T[k];
      if (table && t != T0[k]) t = cp.advance(T0[k], c_min * (t - T0[k]));
      if (crystallising && X[k] < 1.0) {
        const double r = kin.rate(0.5 * (T0[k] + t));
        if (r > 0) {
          theta[k] += r * dt;
          const double x = kin.crystallinity(theta[k]);
          const double e = latent * (x - X[k]);  // J/kg
          X[k] = x;
          if (e > 0) t = table ? cp.advance(t, e) : t + e * per_c;
        }
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
  const CrystallisationKinetics kin(c.latent_heat, c.avrami_exponent, c.rate_rows, c.k_max, c.t_max, c.half_width);
  std::ostringstream os;
  os << "crystallisation (Nakamura, n = " << fmt_g(c.avrami_exponent) << ", latent heat " << fmt_g(c.latent_heat)
     << " J/kg), rate ";
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
        throw RunError("non-finite temperature in part '" + st->def->name + "' at node " + std::to_string(i) + " (" +
                       fmt_g(st->x0[3 * i], 4) + ", " + fmt_g(st->x0[3 * i + 1], 4) + ", " +
                       fmt_g(st->x0[3 * i + 2], 4) + "), layer value " + std::to_string(k % st->nz) + ", at t = " +
                       fmt_g(time) + " s (thermal step " + std::to_string(step) + ")");
      }
    }
  }
}

// The job document a checkpoint stores: the run's, without the checkpoint
// settings and the compression of results.h5 (which a restart may change).
static json restart_document(const json& doc) {
  json d = doc;
  if (d.contains("output") && d["output"].is_object()) {
    d["output"].erase("checkpoint_interval");
    d["output"].erase("checkpoint_at_end");
    d["output"].erase("compression");
  }
  return d;
}

// What a restart compares: the stored document without time.end (a restart
// may move the end, to extend a finished run).
static json restart_match(json d) {
  if (d.contains("time") && d["time"].is_object()) d["time"].erase("end");
  return d;
}

// The time.end and frame interval (its output.interval, by default its
// time.end) of the run that wrote a checkpoint, s; NaN where absent.
struct CheckpointTimes {
  double t_end, interval;
};
static CheckpointTimes checkpoint_times(const Checkpoint& c) {
  const auto& bytes = c.section("job");
  const json d = json::parse(bytes.begin(), bytes.end());
  auto number = [&](const char* section, const char* key) {
    if (d.contains(section) && d[section].is_object() && d[section].contains(key) && d[section][key].is_number())
      return d[section][key].get<double>();
    return std::numeric_limits<double>::quiet_NaN();
  };
  const double t_end = number("time", "end"), interval = number("output", "interval");
  return {t_end, std::isnan(interval) ? t_end : interval};
}

double Simulation::check_restart(const Checkpoint& c) const {
  const std::string what = "--restart: ";
  try {
    // The job as run (file paths absolute; checkpoints of 0.16.0 hold the
    // document as given): the job file or the output folder's job_as_run.json.
    const auto& job = c.section("job");
    const json stored = restart_match(json::parse(job.begin(), job.end()));
    if (stored != restart_match(restart_document(job_.document_as_run)) &&
        stored != restart_match(restart_document(job_.document)))
      throw JobError("", what + "the checkpoint was written by another job (or with other --set values); a restart "
                                "needs the job of the run it continues (time.end, output.checkpoint_interval, "
                                "output.checkpoint_at_end and output.compression may differ)");
    sdk::StateReader r(c.section("run"));
    double t = 0;
    if (!r.get(t)) throw JobError("", what + "the checkpoint's run section is truncated");
    // The same margin as the run's end test (a billionth of a step or interval).
    if (t >= job_.t_end * (1 - 1e-12)) {
      const double was = checkpoint_times(c).t_end;
      throw JobError("/time/end", what + "the checkpoint is at t = " + fmt_g(t, 9) + " s" +
                                      (t >= was * (1 - 1e-12) ? ", the end of the run that wrote it" : "") +
                                      ", not before time.end = " + fmt_g(job_.t_end, 9) +
                                      " s; to extend the run, set a later time.end (--set time.end=...)");
    }
    return t;
  } catch (const JobError&) {
    throw;
  } catch (const std::exception& e) {
    throw JobError("", what + e.what());
  }
}

// The kernel's state between two steps, written (sdk::StateWriter) or read
// back (sdk::StateReader) by the same list; false where a read failed.
template <class A>
bool Simulation::state_io(A& a) {
  constexpr bool saving = std::is_same_v<A, sdk::StateWriter>;
  bool ok = a.io(last_mech_dt_) && a.io(bending_weight_) && a.io(bending_left_) && a.io(bending_largest_) &&
            a.io(bending_evaluations_) && a.io(last_stable_) && a.io(seen_min_) && a.io(seen_max_) &&
            a.io_array(below_from_) && a.io_array(all_below_from_) && a.io_array(over_from_) &&
            a.io_array(tool_force_) && a.io_array(tool_heat_) && a.io_array(link_heat_) && a.io(contact_energy_) &&
            a.io(contact_active_);
  std::vector<char> warned;
  for (const auto& u : law_uses_) warned.push_back(u.warned ? 1 : 0);
  ok = ok && a.io_array(warned);
  for (std::size_t k = 0; k < warned.size(); ++k) law_uses_[k].warned = warned[k] != 0;
  for (auto& st : parts_)
    ok = ok && a.io_array(st->x) && a.io_array(st->T) && a.io_array(st->contact_status) &&
         a.io_array(st->contact_pressure) && a.io_array(st->shear_angle) && a.io_array(st->below_from) &&
         a.io_array(st->all_below_from) && a.io_array(st->theta) && a.io_array(st->X);
  for (auto& m : mech_)
    ok = ok && a.io_array(m->v) && a.io_array(m->f_int) && a.io_array(m->f_con) && a.io(m->pending_work) &&
         a.io_array(m->block_dt) && a.io_array(m->block_bdt) && a.io(m->bend_dt) && a.io_array(m->stress) &&
         a.io_array(m->curvature) && a.io_array(m->strain);
  for (ContactTask& task : contact_tasks_) {
    // A task's forces on the other part are in cross_out where it handed
    // them over (published); a continued run reads them from cross.
    ok = ok && a.io_array(saving && task.published ? task.cross_out : task.cross);
    if (!saving) task.published = false;
    ok = ok && a.io_array(task.cross_status) && a.io_array(task.tool_force) && a.io_array(task.own_pressure) &&
         a.io_array(task.cross_pressure) && a.io(task.energy) && a.io(task.active);
  }
  for (auto& tool : tools_) {
    std::array<double, 3> u = tool->displacement(), v = tool->velocity();
    ok = ok && a.io(u) && a.io(v);
    if (!saving) tool->set_motion_state(u, v);
  }
  return ok;
}

void Simulation::save_state(Checkpoint& c) {
  sdk::StateWriter w;
  state_io(w);
  c.add("kernel", std::move(w.bytes()));
  auto plugin = [&](const std::string& name, auto&& save) {
    sdk::StateWriter pw;
    if (auto st = save(pw); !st) throw RunError("checkpoint of " + name + ": " + st.message);
    c.add(name, std::move(pw.bytes()));
  };
  for (std::size_t p = 0; p < mech_.size(); ++p)
    plugin("element/" + parts_[p]->def->name, [&](sdk::StateWriter& pw) { return mech_[p]->element->save_state(pw); });
  for (std::size_t k = 0; k < contacts_.size(); ++k)
    plugin("contact" + job_.contacts[k].pointer, [&](sdk::StateWriter& pw) { return contacts_[k]->save_state(pw); });
  if (splitter_) plugin("thermal", [&](sdk::StateWriter& pw) { return splitter_->save_state(pw); });
}

void Simulation::load_state(const Checkpoint& c) {
  auto fail = [](const std::string& what) {
    throw JobError("", "--restart: the checkpoint does not fit this job (" + what + ")");
  };
  sdk::StateReader r(c.section("kernel"));
  if (!state_io(r) || !r.done()) fail("kernel state");
  auto plugin = [&](const std::string& name, auto&& load) {
    const std::vector<unsigned char>* bytes = c.find(name);
    if (!bytes) fail("no section " + name);
    sdk::StateReader pr(*bytes);
    if (auto st = load(pr); !st) fail(name + ": " + st.message);
    if (!pr.done()) fail(name);
  };
  for (std::size_t p = 0; p < mech_.size(); ++p)
    plugin("element/" + parts_[p]->def->name, [&](sdk::StateReader& pr) { return mech_[p]->element->load_state(pr); });
  for (std::size_t k = 0; k < contacts_.size(); ++k)
    plugin("contact" + job_.contacts[k].pointer, [&](sdk::StateReader& pr) { return contacts_[k]->load_state(pr); });
  if (splitter_) plugin("thermal", [&](sdk::StateReader& pr) { return splitter_->load_state(pr); });
}

namespace {

struct Progress {
  bool tty = false, quiet = false;
  double t_end = 1;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now(), last = start;
  int last_decile = -1;
  void update(double t, long long steps, bool force = false) {
    const auto now = std::chrono::steady_clock::now();
    const double el = std::chrono::duration<double>(now - start).count();
    const double frac = std::min(1.0, t / t_end);
    const double eta = frac > 0 ? el * (1 - frac) / frac : 0;
    const double rate = el > 0 ? steps / el : 0;
    if (tty && !quiet) {
      if (!force && std::chrono::duration<double>(now - last).count() < 0.2) return;
      last = now;
      std::fprintf(stderr, "\r  t = %.4g / %.4g s  %5.1f %%  %.0f steps/s  ETA %.0f s   ", t, t_end, 100 * frac, rate,
                   eta);
      if (force) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    } else {
      const int decile = static_cast<int>(10 * frac);
      if (decile == last_decile && !force) return;
      last_decile = decile;
      if (frac < 0.01 && !force)  // the first steps (setup, caches) say nothing of the rate yet
        logger("solve")->info("t = {:.4g} / {:.4g} s ({:.0f} %)", t, t_end, 100 * frac);
      else
        logger("solve")->info("t = {:.4g} / {:.4g} s ({:.0f} %), {:.0f} steps/s, ETA {:.0f} s", t, t_end, 100 * frac,
                              rate, eta);
    }
  }
};

// The peak resident memory of the process so far (MB), 0 where the system
// does not say (Linux reports ru_maxrss in KiB).
double peak_resident_mb() {
#if defined(__linux__)
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) == 0) return static_cast<double>(u.ru_maxrss) * 1024.0 / 1e6;
#endif
  return 0.0;
}

std::string csv_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

}  // namespace

RunResult Simulation::run(const RunOptions& opt) {
  RunResult result;
  const auto wall0 = std::chrono::steady_clock::now();
#ifdef _OPENMP
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  omp_set_max_active_levels(1);  // loops inside a task run on its thread
  const int threads = omp_get_max_threads();
#else
  const int threads = 1;
#endif
  const SubnormalsFlushed flushed(opt.flush_subnormals);  // on every thread of the run, until it returns
  auto log = logger("solve");
  // The fields of a frame, per part (the same in every frame of a run).
  auto frame_fields = [&] {
    std::vector<std::vector<FrameField>> fields(parts_.size());
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      PartState& st = *parts_[p];
      for (const auto& f : job_.output.fields) {
        if (f == "temperature") {
          fields[p].push_back({"temperature", st.T.data(), 1, false, true});
          fields[p].push_back({"temperature_mean", st.mean.data()});
          fields[p].push_back({"temperature_top", st.top.data()});
          fields[p].push_back({"temperature_bottom", st.bottom.data()});
        } else if (f == "temperature_mean") {
          fields[p].push_back({"temperature_mean", st.mean.data()});
        } else if (f == "temperature_top") {
          fields[p].push_back({"temperature_top", st.top.data()});
        } else if (f == "temperature_bottom") {
          fields[p].push_back({"temperature_bottom", st.bottom.data()});
        } else if (f == "displacement") {
          fields[p].push_back({"displacement", st.displacement.data(), 3});
        } else if (f == "velocity" && p < mech_.size()) {
          // Half-step velocity v^{n-1/2} of the step that ended at the frame.
          fields[p].push_back({"velocity", mech_[p]->v.data(), 3});
        } else if (f == "shear_angle") {
          fields[p].push_back({"shear_angle", st.shear_angle.data(), 1, true});
        } else if (f == "fibre_direction") {
          fields[p].push_back({"fibre_direction", st.fibre.data(), 3, true});
        } else if (f == "contact_status") {
          fields[p].push_back({"contact_status", st.contact_status.data()});
        } else if (f == "contact_pressure") {
          fields[p].push_back({"contact_pressure", st.contact_pressure.data()});
        } else if (f == "conductance") {
          fields[p].push_back({"conductance_bottom", st.conductance_bottom.data()});
          fields[p].push_back({"conductance_top", st.conductance_top.data()});
        } else if (f == "tool_gap") {
          fields[p].push_back({"tool_gap", st.tool_gap.data()});
        } else if (f == "crystallinity" && !st.X.empty()) {
          fields[p].push_back({"crystallinity", st.X.data(), 1, false, true});
          fields[p].push_back({"crystallinity_mean", st.X_mean.data()});
        } else if (f == "below_threshold_from") {
          fields[p].push_back({"below_threshold_from", st.below_from.data()});
          fields[p].push_back({"all_below_threshold_from", st.all_below_from.data()});
        } else if ((f == "membrane_stress" || f == "curvature" || f == "membrane_strain") && p < mech_.size()) {
          // Material-frame components [11, 22, 12] per element, as vectors.
          fields[p].push_back({f,
                               f == "membrane_stress" ? mech_[p]->stress.data()
                               : f == "curvature"     ? mech_[p]->curvature.data()
                                                      : mech_[p]->strain.data(),
                               3, true});
        }
      }
      // No field twice (e.g. "temperature" and "temperature_mean").
      auto& v = fields[p];
      std::vector<FrameField> unique;
      for (const auto& ff : v)
        if (std::none_of(unique.begin(), unique.end(), [&](const FrameField& u) { return u.name == ff.name; }))
          unique.push_back(ff);
      v = std::move(unique);
    }
    return fields;
  };

  // A restart: the loop's state as the checkpoint left it (read below,
  // after the locals it restores), the frames it kept and the lengths of
  // the time series files then.
  std::optional<sdk::StateReader> resume;
  double resume_t = 0;  // s, the checkpoint's time
  double wall_before = 0;  // s, a restart: the wall time of the run up to its checkpoint (all its earlier parts)
  std::vector<double> frame_times;  // of the frames written (for checkpoints)
  std::uint64_t csv_size[4] = {0, 0, 0, 0};  // probes.csv, energy.csv, tools.csv, plies.csv
  if (opt.restart) {
    resume.emplace(opt.restart->section("run"));
    resume->get(resume_t);
    resume->get_vector(frame_times);
    for (auto& n : csv_size) resume->get(n);
    resume->get(wall_before);
    // Everything checked before any file is touched.
    const char* names[4] = {"probes.csv", "energy.csv", "tools.csv", "plies.csv"};
    const bool used[4] = {true, job_.mechanics, !job_.tools.empty(), job_.thermal.has_value()};
    for (int k = 0; k < 4; ++k) {
      const auto path = opt.out_dir / names[k];
      if (opt.write_files && used[k] &&
          (!std::filesystem::exists(path) || std::filesystem::file_size(path) < csv_size[k]))
        throw JobError("", "--restart: " + path.string() + " is missing or shorter than at the checkpoint");
    }
    if (opt.write_files && !std::filesystem::exists(opt.out_dir / "results.h5"))
      throw JobError("", "--restart: no " + (opt.out_dir / "results.h5").string() + " of the run to continue");
  }
  // A time series file: new with its header, or on a restart the run's
  // file cut back to its length at the checkpoint and continued.
  auto open_series = [&](std::ofstream& out, const char* name, int k, const std::string& header) {
    const auto path = opt.out_dir / name;
    if (opt.restart) {  // checked above
      std::filesystem::resize_file(path, csv_size[k]);
      out.open(path, std::ios::app);
    } else {
      out.open(path);
      out << header;
    }
  };
  std::unique_ptr<ResultsWriter> writer;
  std::ofstream probes_csv;
  if (opt.write_files) {
    std::filesystem::create_directories(opt.out_dir);
    // A new run replaces the folder's results: a checkpoint of an earlier
    // run there no longer fits them.
    if (!opt.restart) std::filesystem::remove(opt.out_dir / kCheckpointFile);
    // The job as run (after --set, file paths absolute): `thermostamp run
    // DIR/job_as_run.json` runs it again, from anywhere.
    if (std::ofstream jf(opt.out_dir / "job_as_run.json"); !(jf << job_.document_as_run.dump(2) << '\n'))
      throw RunError("cannot write " + (opt.out_dir / "job_as_run.json").string());
    std::vector<WriterPart> wparts;
    const bool layers = std::find(job_.output.fields.begin(), job_.output.fields.end(), "temperature") !=
                        job_.output.fields.end();
    for (const auto& st : parts_)
      wparts.push_back({st->def->name, st->mesh.num_nodes(), st->mesh.num_elements(), &st->mesh.triangles,
                        st->def->thickness, st->nz, layers});
    try {
      const int level = job_.output.compression;
      writer = opt.restart
                   ? std::make_unique<ResultsWriter>(opt.out_dir, std::move(wparts), frame_times, frame_fields(), level)
                   : std::make_unique<ResultsWriter>(opt.out_dir, std::move(wparts), level);
    } catch (const std::runtime_error& e) {
      if (opt.restart) throw JobError("", std::string("--restart: ") + e.what());
      throw;
    }
    open_series(probes_csv, "probes.csv", 0, "probe,quantity,time,z,value\n");
  }
  if (job_.thermal)
    log->info("job '{}': {} part(s), {} tool(s), splitter '{}', thermal step {:.4g} s (stable {:.4g} s, "
              "accurate {:.4g} s), {} thread(s), subnormals {}",
              job_.name, parts_.size(), tools_.size(), job_.thermal->splitter, thermal_dt_, thermal_stable_dt_,
              thermal_accurate_dt_, threads, flushed.mode());
  else
    log->info("job '{}': {} part(s), {} tool(s), isothermal, {} thread(s), subnormals {}", job_.name, parts_.size(),
              tools_.size(), threads, flushed.mode());
  if (job_.thermal)
    for (const auto& st : parts_)
      if (!st->cp.empty()) {
        const MaterialDef& m = job_.materials[st->def->material];
        const auto& rows = m.specific_heat_table;
        log->info("part '{}': specific heat from {} rows between {:g} and {:g} degC, {:g} to {:g} J/(kg K) (the "
                  "thermal steps are taken with the smallest, the heat stored follows the rows)",
                  st->def->name, rows.size(), rows.front()[0], rows.back()[0], m.specific_heat, m.specific_heat_max);
      }
  if (job_.thermal)
    for (const auto& st : parts_)
      if (!st->kin.empty())
        log->info("part '{}': {}", st->def->name, describe_crystallisation(job_.materials[st->def->material]));
  for (std::size_t p = 0; p < mech_.size(); ++p)
    log->info("part '{}': mass {:.6g} kg, added by mass scaling {:.6g} kg ({:.3g} %)", parts_[p]->def->name,
              mech_[p]->mass_physical, mech_[p]->mass_added, 100 * mech_[p]->mass_added / mech_[p]->mass_physical);
  // More than a thousand times the ply's own mass: the inertia, not the
  // material, then decides how the ply deforms.
  for (std::size_t p = 0; p < mech_.size(); ++p)
    if (const MechPart& m = *mech_[p]; m.mass_added > 1e3 * m.mass_physical)
      log->warn("mass scaling multiplies the mass of part '{}' by {:.3g}{}: its inertia will dominate the "
                "response; lower solvers.mechanics.mass_scaling{}",
                parts_[p]->def->name, (m.mass_physical + m.mass_added) / m.mass_physical,
                m.mass_added_contact > 0.5 * m.mass_added ? " (most of it for the contact springs)" : "",
                m.mass_added_contact > 0.5 * m.mass_added ? " or the contacts' penalty" : "");
  log->info("thermal contact: {} tool face node(s), {} ply/ply link(s)", contact_map_.tool_contacts.size(),
            contact_map_.links.size());
  // A probe without an interval records every thermal step: say so where
  // that is many samples (a short thermal step over a long stroke).
  if (job_.thermal && thermal_dt_ > 0)
    for (std::size_t q = 0; q < job_.output.probes.size(); ++q)
      if (const double n = job_.t_end / thermal_dt_; job_.output.probes[q].interval <= 0 && n > 1e5)
        log->warn("probe '{}' has no interval: it records at every thermal step, up to {:.3g} samples; set "
                  "{}/interval for fewer",
                  job_.output.probes[q].name, n, job_.output.probes[q].pointer);

  auto update_derived = [&] {
    for (auto& st : parts_) {
      const int nz = st->nz;
      const double h = st->def->thickness;
      for (int i = 0; i < st->mesh.num_nodes(); ++i) {
        const double* t = &st->T[static_cast<std::size_t>(nz) * i];
        st->mean[i] = thickness_mean(t, nz, h);
        st->bottom[i] = t[0];
        st->top[i] = t[nz - 1];
        if (!st->X.empty()) st->X_mean[i] = thickness_mean(&st->X[static_cast<std::size_t>(nz) * i], nz, h);
      }
    }
  };

  auto write_frame = [&](double t) {
    for (auto& st : parts_)
      for (std::size_t k = 0; k < st->x.size(); ++k) st->displacement[k] = st->x[k] - st->x0[k];
    if (!writer) return;
    update_derived();
    if (want_conductance_) update_face_conductance();
    if (want_tool_gap_) update_tool_gap();
    std::vector<const double*> xs, ns;
    for (auto& st : parts_) {
      xs.push_back(st->x.data());
      ns.push_back(st->normals.data());
    }
    writer->write_frame(t, xs, ns, frame_fields());
    frame_times.push_back(t);
  };

  auto sample_probes = [&](double t, std::size_t only = static_cast<std::size_t>(-1)) {
    for (std::size_t q = 0; q < job_.output.probes.size(); ++q) {
      if (only != static_cast<std::size_t>(-1) && q != only) continue;
      const ProbeDef& pr = job_.output.probes[q];
      const PartState& st = *parts_[pr.part];
      const int i = probe_node_[q];
      const int nz = st.nz;
      const double* T = &st.T[static_cast<std::size_t>(nz) * i];
      for (const auto& quantity : pr.quantities) {
        ProbeSample s;
        s.probe = static_cast<int>(q);
        s.time = t;
        s.quantity = quantity;
        if (quantity == "temperature_profile" || quantity == "crystallinity_profile") {
          const double* v = quantity == "temperature_profile" ? T : &st.X[static_cast<std::size_t>(nz) * i];
          for (int k = 0; k < nz; ++k) {
            s.z.push_back(nz > 1 ? -0.5 * st.def->thickness + st.def->thickness * k / (nz - 1) : 0.0);
            s.values.push_back(v[k]);
          }
        } else if (quantity == "temperature_mean") {
          double m = T[0];
          if (nz > 1) {
            m = 0;
            for (int k = 0; k < nz; ++k) m += (k == 0 || k == nz - 1 ? 0.5 : 1.0) * T[k];
            m /= (nz - 1);
          }
          s.values.push_back(m);
        } else if (quantity == "contact_pressure") {
          s.values.push_back(st.contact_pressure[i]);
        } else if (quantity == "tool_gap") {
          double gap = 0;
          tool_gaps(pr.part, 1, &st.x[3 * static_cast<std::size_t>(i)], &gap);
          s.values.push_back(gap);
        } else if (quantity == "conductance") {  // bottom and top face, at z = -h/2 and +h/2
          update_face_conductance();
          s.z = {-0.5 * st.def->thickness, 0.5 * st.def->thickness};
          s.values = {st.conductance_bottom[i], st.conductance_top[i]};
        } else if (quantity.rfind("displacement_", 0) == 0) {
          const int d = quantity.back() - 'x';
          s.values.push_back(st.x[3 * i + d] - st.x0[3 * i + d]);
        } else if (quantity == "fibre_strain") {  // E11: mean of the elements around the node (0 without mechanics)
          double a = 0;
          if (static_cast<std::size_t>(pr.part) < mech_.size())
            for (int e : probe_elements_[q]) a += mech_[pr.part]->strain[3 * static_cast<std::size_t>(e)];
          s.values.push_back(probe_elements_[q].empty() ? 0.0 : a / probe_elements_[q].size());
        } else {  // shear_angle: mean of the elements around the node (0 without mechanics)
          double a = 0;
          for (int e : probe_elements_[q]) a += st.shear_angle[e];
          s.values.push_back(probe_elements_[q].empty() ? 0.0 : a / probe_elements_[q].size());
        }
        if (probes_csv.is_open()) {
          for (std::size_t k = 0; k < s.values.size(); ++k)
            probes_csv << pr.name << ',' << quantity << ',' << csv_number(t) << ','
                       << (s.z.empty() ? "" : csv_number(s.z[k])) << ',' << csv_number(s.values[k]) << '\n';
        }
        result.probes.push_back(std::move(s));
      }
    }
    if (probes_csv.is_open()) probes_csv.flush();
  };

  const double t_end = job_.t_end;
  const double interval = job_.output.interval;
  double t = 0;
  long long steps = 0;
  double stored0 = stored_heat();
  std::vector<double> stored0_part;
  for (std::size_t p = 0; p < parts_.size(); ++p) stored0_part.push_back(stored_heat(static_cast<int>(p)));
  link_heat_.assign(parts_.size(), 0.0);
  double heat_in = 0;
  int substeps_max = 1;
  long long limited_total = 0;
  std::vector<double> next_probe(job_.output.probes.size(), 0.0);
  for (std::size_t q = 0; q < next_probe.size(); ++q) next_probe[q] = job_.output.probes[q].interval;
  long long frame_index = 1;
  Progress progress;
  progress.tty = isatty(STDERR_FILENO) && !opt.quiet;
  progress.quiet = opt.quiet;
  progress.t_end = t_end;

  std::vector<std::span<double>> Tspans;
  for (auto& st : parts_) Tspans.emplace_back(st->T);
  sdk::ThermalStepInput in;
  in.faces = faces_;
  in.links = contact_map_.links;
  in.links_changed = true;

  const double eps_t = 1e-9 * (job_.thermal ? thermal_dt_ : interval);
  EnergyAudit audit;
  std::vector<double> energy_rows;  // the energy.csv table, also written to results.h5
  std::vector<double> tool_rows;    // the tools.csv table (wide), also written to results.h5
  std::vector<double> ply_rows;     // the plies.csv table (wide), also written to results.h5
  long long mech_steps = 0;
  double mech_dt = 0;
  std::vector<std::string> energy_cols = {"time",    "kinetic", "internal",       "external_work",
                                          "damping", "contact", "contact_stored", "balance_error"};
  // Quasi-static check over the sampled energy history: kinetic (half-step)
  // / internal energy at the end, and the time from which it stays under
  // 5 % (-1: not at the end).
  auto quasi_static = [&]() -> std::pair<double, double> {
    // ratio NaN: no internal energy was ever stored (the check does not
    // apply). Internal energy at the round-off of the run's energies (plies
    // held in their plane and only pressed: 1e-20 J beside contact springs
    // of 1e-4 J) counts as none.
    const std::size_t w = energy_cols.size();
    double scale = 0;  // the largest energy of the run
    for (std::size_t r = 0; r + w <= energy_rows.size(); r += w)
      for (std::size_t c = 1; c <= 6; ++c) scale = std::max(scale, std::abs(energy_rows[r + c]));
    double ratio = std::numeric_limits<double>::quiet_NaN(), below_from = -1;
    for (std::size_t r = 0; r + w <= energy_rows.size(); r += w) {
      const double t_r = energy_rows[r], ie = energy_rows[r + 2], ke = energy_rows[r + w - 1];
      if (!(ie > 1e-9 * scale)) continue;
      ratio = ke / ie;
      if (ratio >= 0.05)
        below_from = -1;
      else if (below_from < 0)
        below_from = t_r;
    }
    return {ratio, below_from};
  };
  for (std::size_t c = 0; c < job_.constraints.size(); ++c)
    for (const char* d : {"x", "y", "z"}) energy_cols.push_back("reaction" + std::to_string(c) + "_" + d);
  // 1/2 m v^2 at the half step just computed: never negative (the
  // "kinetic" column is the product form of the balance, which turns
  // negative when nodes vibrate near the step's frequency limit).
  energy_cols.push_back("kinetic_half_step");
  std::vector<std::string> tool_cols = {"time"};
  for (const auto& td : job_.tools)
    for (const char* q : {"_ux", "_uy", "_uz", "_fx", "_fy", "_fz", "_heat_J", "_temperature"})
      tool_cols.push_back(td.name + q);
  // Per part (empty: none asked for).
  const std::vector<double>& thresholds = job_.output.temperature_threshold;
  const std::vector<double>& shear_limits = job_.output.shear_angle_limit;
  const bool threshold = !thresholds.empty(), shear_limit = !shear_limits.empty();
  auto threshold_of = [&](std::size_t p) { return threshold ? std::optional<double>(thresholds[p]) : std::nullopt; };
  // plies.csv: each ply's temperatures (with thermal) and its shear angles
  // and fibre strains (with mechanics), a row per ply.
  const bool ply_series = job_.thermal || job_.mechanics;
  // Some ply's material crystallises (the thermal solver on).
  const bool crystallising =
      job_.thermal && std::any_of(parts_.begin(), parts_.end(), [](const auto& st) { return !st->kin.empty(); });
  std::vector<std::string> ply_fields;
  if (job_.thermal) {
    ply_fields = {"temperature_min", "temperature_mean", "temperature_max"};
    if (threshold) ply_fields.push_back("fraction_below");
    if (crystallising)
      for (const char* q : {"crystallinity_min", "crystallinity_mean", "crystallinity_max"}) ply_fields.push_back(q);
  }
  if (job_.mechanics) {
    for (const char* q : {"shear_angle_min", "shear_angle_max", "fibre_strain_min", "fibre_strain_max"})
      ply_fields.push_back(q);
    if (shear_limit) ply_fields.push_back("fraction_over_shear_limit");
  }
  const std::size_t ply_per = ply_fields.size();
  std::vector<std::string> ply_cols = {"time"};
  for (const auto& st : parts_)
    for (const auto& q : ply_fields) ply_cols.push_back(st->def->name + "_" + q);
  // The elements' shear angles and strains at a row, and their initial
  // areas (the weights of the share beyond the limit).
  std::vector<std::vector<double>> row_shear(mech_.size()), row_strain(mech_.size()), elem_area(mech_.size());
  for (std::size_t p = 0; p < mech_.size(); ++p) {
    const std::size_t ne = static_cast<std::size_t>(parts_[p]->mesh.num_elements());
    row_shear[p].assign(ne, 0.0);
    row_strain[p].assign(3 * ne, 0.0);
    elem_area[p] = element_areas(parts_[p]->mesh);
  }
  // Part p's shear angle range, fibre strain range and share of its area
  // beyond the shear limit at the current positions (ElementKernel::fields,
  // as the frames show them); the first row beyond the limit is noted at t.
  auto ply_mechanics = [&](std::size_t p, double t) -> std::array<double, 5> {
    sdk::ElementFields f;
    f.shear_angle = row_shear[p];
    f.strain = row_strain[p];
    if (auto s = mech_[p]->element->fields(f); !s)
      throw RunError("element plugin of part '" + parts_[p]->def->name + "' failed at t = " + fmt_g(t) +
                     " s: " + s.message);
    const auto [smn, smx] = std::minmax_element(row_shear[p].begin(), row_shear[p].end());
    const auto [fmn, fmx] = fibre_strain_range(row_strain[p]);
    double over = 0, total = 0;
    for (std::size_t e = 0; e < row_shear[p].size(); ++e) {
      total += elem_area[p][e];
      if (shear_limit && std::abs(row_shear[p][e]) > shear_limits[p]) over += elem_area[p][e];
    }
    if (shear_limit && over > 0 && over_from_[p] < 0) over_from_[p] = t;
    return {*smn, *smx, fmn, fmx, over / total};
  };
  std::ofstream energy_csv, tools_csv, plies_csv;
  if (opt.write_files && job_.mechanics) {
    std::string header;
    for (std::size_t c = 0; c < energy_cols.size(); ++c) header += (c ? "," : "") + energy_cols[c];
    open_series(energy_csv, "energy.csv", 1, header + "\n");
  }
  if (opt.write_files && !job_.tools.empty())
    open_series(tools_csv, "tools.csv", 2, "time,tool,ux,uy,uz,fx,fy,fz,heat_J,temperature\n");
  auto sample_tools = [&](double t) {
    tool_rows.push_back(t);
    for (std::size_t q = 0; q < tools_.size(); ++q) {
      const auto& u = tools_[q]->displacement();
      const double row[8] = {u[0], u[1], u[2], tool_force_[3 * q], tool_force_[3 * q + 1], tool_force_[3 * q + 2],
                             tool_heat_[q], job_.tools[q].temperature_over(t, t)};
      tool_rows.insert(tool_rows.end(), row, row + 8);
      if (tools_csv.is_open()) {
        tools_csv << csv_number(t) << ',' << job_.tools[q].name;
        for (double v : row) tools_csv << ',' << csv_number(v);
        tools_csv << '\n';
      }
    }
    if (tools_csv.is_open()) tools_csv.flush();
  };
  if (opt.write_files && ply_series) {
    std::string header = "time,ply";
    for (const auto& q : ply_fields) header += "," + q;
    open_series(plies_csv, "plies.csv", 3, header + "\n");
  }
  // Each ply's row (ply_temperature, ply_mechanics).
  auto sample_plies = [&](double t) {
    ply_rows.push_back(t);
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const std::size_t at = ply_rows.size();
      if (job_.thermal) {
        const std::array<double, 4> row = ply_temperature(*parts_[p], threshold_of(p));
        ply_rows.insert(ply_rows.end(), row.begin(), row.begin() + (threshold ? 4 : 3));
        if (crystallising) {
          const std::array<double, 3> x = ply_crystallinity(*parts_[p]);
          ply_rows.insert(ply_rows.end(), x.begin(), x.end());
        }
      }
      if (job_.mechanics) {
        const std::array<double, 5> row = ply_mechanics(p, t);
        ply_rows.insert(ply_rows.end(), row.begin(), row.begin() + (shear_limit ? 5 : 4));
      }
      if (plies_csv.is_open()) {
        plies_csv << csv_number(t) << ',' << parts_[p]->def->name;
        for (std::size_t k = at; k < ply_rows.size(); ++k) plies_csv << ',' << csv_number(ply_rows[k]);
        plies_csv << '\n';
      }
    }
    if (plies_csv.is_open()) plies_csv.flush();
  };
  std::string failure;
  int stop_signal = 0;  // the signal of a stop request, once the loop has seen it
  double frame_t = 0;   // time of the last frame written
  seen_min_ = std::numeric_limits<double>::infinity();
  seen_max_ = -seen_min_;
  below_from_.assign(parts_.size(), -1.0);
  all_below_from_.assign(parts_.size(), -1.0);
  over_from_.assign(parts_.size(), -1.0);
  if (want_below_from_)
    for (auto& st : parts_) {
      st->below_from.assign(st->mesh.num_nodes(), std::numeric_limits<double>::quiet_NaN());
      st->all_below_from.assign(st->mesh.num_nodes(), std::numeric_limits<double>::quiet_NaN());
    }
  // The mechanics loop's own state (explicit dynamics; the thermal
  // splitter advances every `subcycle` mechanical steps over the time
  // elapsed since its last step).
  double t_thermal = 0;
  long long since_thermal = 0;
  int subcycle = job_.thermal ? job_.thermal->subcycle : 0;
  double stable = 0;
  double next_sample = 0, audit_scale = 0, supplied_max = 0;
  // s between the rows of energy.csv, tools.csv and plies.csv
  const double series_iv = job_.output.series_interval > 0 ? job_.output.series_interval : t_end / 500;
  // What a failed audit blames: an unstable step, or a start with loaded
  // contact springs, whose release at once the audit cannot follow.
  std::string unstable = "the run is unstable (step too large?)";
  // Checkpoints: the run's state after a step (the loop's, the kernel's,
  // the plugins'), with the frames and the time series so far.
  const double checkpoint_iv = job_.output.checkpoint_interval;
  double next_checkpoint = checkpoint_iv > 0 ? checkpoint_iv : std::numeric_limits<double>::infinity();
  double restarted_from = -1;  // s, a restart's checkpoint time
  auto last_checkpoint_wall = Clock::now();
  // The end checkpoint (output.checkpoint_at_end): the state before the
  // first step that depends on time.end (the mechanical steps that land on
  // it, a thermal step cut short by it), or the end state where none did.
  // A later time.end continues from it as a run to that end would have.
  bool landing_saved = false;
  // A checkpoint after this step: the end checkpoint, asked for by a stop,
  // or due by simulated or wall time. None after the end checkpoint, which
  // stays the last (a run stopped in its last steps continues from it).
  auto checkpoint_due = [&](int stop_seen) {
    const bool at_end = job_.output.checkpoint_at_end;
    if (at_end && landing_saved) return false;
    if (t >= t_end - eps_t) return at_end;
    if (stop_seen != 0) return true;
    return t >= next_checkpoint - eps_t ||
           (opt.checkpoint_wall_s > 0 && seconds_since(last_checkpoint_wall) >= opt.checkpoint_wall_s);
  };
  // The probe samples so far (RunResult::probes), as flat arrays (a reader
  // checks each array's length against what is left of the checkpoint).
  auto probes_io = [&](auto& a) {
    constexpr bool reading = std::is_same_v<std::decay_t<decltype(a)>, sdk::StateReader>;
    const auto& known = known_probe_quantities();
    std::vector<int> id, quantity;
    std::vector<double> time, z, values;
    std::vector<std::uint64_t> nz, nv;
    for (const ProbeSample& ps : result.probes) {  // none when reading
      id.push_back(ps.probe);
      quantity.push_back(static_cast<int>(std::find(known.begin(), known.end(), ps.quantity) - known.begin()));
      time.push_back(ps.time);
      nz.push_back(ps.z.size());
      nv.push_back(ps.values.size());
      z.insert(z.end(), ps.z.begin(), ps.z.end());
      values.insert(values.end(), ps.values.begin(), ps.values.end());
    }
    if (!(a.io_vector(id) && a.io_vector(quantity) && a.io_vector(time) && a.io_vector(nz) && a.io_vector(nv) &&
          a.io_vector(z) && a.io_vector(values)))
      return false;
    if constexpr (reading) {
      const std::size_t n = id.size();
      if (quantity.size() != n || time.size() != n || nz.size() != n || nv.size() != n) return false;
      std::vector<ProbeSample> read(n);
      std::size_t iz = 0, iv = 0;
      for (std::size_t k = 0; k < n; ++k) {
        if (quantity[k] < 0 || static_cast<std::size_t>(quantity[k]) >= known.size() || nz[k] > z.size() - iz ||
            nv[k] > values.size() - iv)
          return false;
        read[k].probe = id[k];
        read[k].quantity = known[quantity[k]];
        read[k].time = time[k];
        read[k].z.assign(z.begin() + iz, z.begin() + iz + nz[k]);
        read[k].values.assign(values.begin() + iv, values.begin() + iv + nv[k]);
        iz += nz[k];
        iv += nv[k];
      }
      if (iz != z.size() || iv != values.size()) return false;
      result.probes = std::move(read);
    }
    return true;
  };
  // The loop's state, written or read back by the same list.
  auto run_io = [&](auto& a) {
    return a.io(steps) && a.io(mech_steps) && a.io(mech_dt) && a.io(frame_index) && a.io(frame_t) &&
           a.io_array(next_probe) && a.io(heat_in) && a.io(substeps_max) && a.io(limited_total) && a.io(stored0) &&
           a.io_array(stored0_part) && a.io_vector(energy_rows) && a.io_vector(tool_rows) && a.io_vector(ply_rows) &&
           a.io(audit.kinetic) && a.io(audit.internal) && a.io(audit.external) && a.io(audit.damping) &&
           a.io(audit.balance_error) &&
           a.io(audit.contact) && a.io(audit.contact_stored) && a.io(audit.kinetic_half) &&
           a.io_vector(audit.reactions) && a.io(t_thermal) && a.io(since_thermal) && a.io(subcycle) &&
           a.io(stable) && a.io(next_sample) && a.io(audit_scale) && a.io(supplied_max) && a.io(next_checkpoint) &&
           a.io_vector(unstable) && probes_io(a);
  };
  auto save_checkpoint = [&](const char* what = "") {
    if (!writer) return;
    const auto tc = Clock::now();
    Checkpoint c;
    const std::string doc = restart_document(job_.document_as_run).dump();
    c.add("job", std::vector<unsigned char>(doc.begin(), doc.end()));
    sdk::StateWriter w;
    w.put(t);
    w.put_vector(frame_times);
    for (std::ofstream* f : {&probes_csv, &energy_csv, &tools_csv, &plies_csv}) {
      f->flush();
      w.put(static_cast<std::uint64_t>(f->is_open() ? static_cast<std::uint64_t>(f->tellp()) : 0));
    }
    w.put(wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count());
    run_io(w);
    c.add("run", std::move(w.bytes()));
    save_state(c);
    write_checkpoint(opt.out_dir / kCheckpointFile, c);
    timing_[kTimeOutput] += seconds_since(tc);
    last_checkpoint_wall = Clock::now();
    if (checkpoint_iv > 0 && t >= next_checkpoint - eps_t) advance_past(next_checkpoint, checkpoint_iv, t + eps_t);
    log->info("checkpoint at t = {:.6g} s (mechanical step {}, thermal step {}{}): {}", t, mech_steps, steps, what,
              (opt.out_dir / kCheckpointFile).string());
  };
  // The state before the first step that depends on time.end: the end
  // checkpoint where the job asks for one.
  auto end_checkpoint = [&](const char* what) {
    landing_saved = true;
    if (job_.output.checkpoint_at_end) save_checkpoint(what);
  };
  try {
    if (resume) {
      sdk::StateReader& r = *resume;
      if (!run_io(r) || !r.done()) throw JobError("", "--restart: the checkpoint does not fit this job (run state)");
      t = resume_t;
      restarted_from = t;
      // Another time.end (a run extended, or ended earlier): where the row
      // and frame intervals are time.end's defaults, the energy and tool
      // rows and the frames go on at this run's.
      if (const CheckpointTimes was = checkpoint_times(*opt.restart); was.t_end != t_end) {
        if (job_.output.series_interval <= 0) {
          next_sample = 0;
          advance_past(next_sample, series_iv, t + eps_t);
        }
        if (was.interval != interval) frame_index = static_cast<long long>(std::floor((t + eps_t) / interval)) + 1;
        log->info("time.end {:.6g} s instead of the checkpointed run's {:.6g} s", t_end, was.t_end);
      }
      if (checkpoint_iv > 0) {  // the interval of this run, from the checkpoint on
        next_checkpoint = 0;
        advance_past(next_checkpoint, checkpoint_iv, t + eps_t);
      } else {
        next_checkpoint = std::numeric_limits<double>::infinity();
      }
      load_state(*opt.restart);
      // The temperatures the elements see, as at the checkpoint (formed
      // from the temperatures at the last thermal step, which are those of
      // the checkpoint).
      if (job_.mechanics) update_node_temperature();
      log->info("restarted from the checkpoint at t = {:.6g} s (mechanical step {}, thermal step {}, {} frame(s) kept)",
                t, mech_steps, steps, frame_times.size());
    } else {
      check_field(0.0, 0);
      write_frame(0.0);
      if (!tools_.empty()) sample_tools(0.0);
      sample_plies(0.0);
      if (!job_.mechanics) next_sample = series_iv;  // thermal-only: the next row after the first step past it
      sample_probes(0.0);
    }
    if (job_.mechanics) {
      const MechanicsDef& md = job_.mechanics_settings;
      // Continued in the steps that land on time.end: the end checkpoint
      // is the one it continues from, or one written after it.
      if (resume) landing_saved = t_end - t < 100 * md.dt_safety * stable;
      if (!resume) {  // the forces and stable step at t = 0 (a restart has them from its checkpoint)
        update_node_temperature();
        check_law_ranges(0.0);
        stable = mechanics_stable_dt();
        compute_contact_forces(0.0, 0.0);
        finish_contact_forces();
        // Overlaps below 1e-6 of a ply's thickness (round-off where a ply
        // starts exactly on a tool) are not worth a warning.
        double k_max = 0, h_min = std::numeric_limits<double>::infinity();
        for (std::size_t p = 0; p < parts_.size(); ++p) {
          for (double k : mech_[p]->k_contact) k_max = std::max(k_max, k);
          h_min = std::min(h_min, parts_[p]->def->thickness);
        }
        if (contact_energy_ > 0.5 * k_max * (1e-6 * h_min) * (1e-6 * h_min)) {
          unstable += ", or it started with " + fmt_g(contact_energy_, 3) +
                      " J in the contact springs (a ply inside a tool or another ply at t = 0)";
          log->warn("contact springs hold {:.4g} J at t = 0 on {} node(s): a ply starts inside a tool or another ply "
                    "(check the tools' positions and the side their profile faces)",
                    contact_energy_, contact_active_);
        }
        if (!std::isfinite(stable)) throw RunError("no element has a stiffness: the mechanical step is undefined");
      }
      // The stresses and curvatures are asked of the elements only for the
      // frames that show them, and for the last frame of an interrupted run.
      const auto& out_fields = job_.output.fields;
      const bool frames_need_fields =
          std::find(out_fields.begin(), out_fields.end(), "membrane_stress") != out_fields.end() ||
          std::find(out_fields.begin(), out_fields.end(), "curvature") != out_fields.end();
      while (t < t_end - eps_t) {
        const double next_frame = std::min(t_end, frame_index * interval);
        // Over its last 100 steps the run lands on t_end in equal steps (at
        // most 1 % shorter than the stable one), not with one step cut short:
        // a sudden change of step upsets the kinetic energy of the audit (the
        // product of the half-step velocities) by the change times the
        // damping and contact forces.
        double dt = md.dt_safety * stable;
        const double remaining = t_end - t;
        if (remaining < 100 * dt) {
          if (!landing_saved) end_checkpoint(", before the steps that land on time.end");
          dt = remaining / std::max(1.0, std::ceil(remaining / dt - 1e-9));
        }
        // The stable step, not the last steps cut to land on t_end (those may
        // be as short as the time left).
        if (md.dt_safety * stable < 1e-14)
          throw RunError("the mechanical step fell below 1e-14 s at t = " + fmt_g(t) + " s");
        auto tc = Clock::now();
        mechanics_step(dt, t, mech_steps, audit);
        timing_[kTimeIntegrate] += seconds_since(tc);
        ++mech_steps;
        t += dt;
        mech_dt = dt;
        // Forces and stable step at the new positions (also for the next
        // step). A stop request seen here ends the loop after this step.
        const int stop_seen = stop_requested();
        fields_due_ = frames_need_fields && (t >= next_frame - eps_t || stop_seen != 0);
        if (want_pressure_) {
          pressure_due_ = t >= next_frame - eps_t || stop_seen != 0;
          for (std::size_t q = 0; q < next_probe.size(); ++q)
            pressure_due_ = pressure_due_ || (probe_pressure_[q] && (t >= next_probe[q] - eps_t || next_probe[q] <= 0));
        }
        stable = forces_and_stable_dt(t, dt);
        audit.contact_stored = contact_energy_;
        bool thermal_stepped = false;  // a thermal step ended at t
        if (job_.thermal) {
          ++since_thermal;
          if (subcycle <= 0)
            subcycle = static_cast<int>(std::clamp(thermal_dt_ / (md.dt_safety * stable), 1.0, 1e9));
          if (since_thermal >= subcycle || t >= t_end - eps_t) {
            tc = Clock::now();
            update_element_fields();
            assemble_faces();
            update_far_temperatures(t_thermal, t);
            in.dt = t - t_thermal;
            in.geometry_changed = true;
            in.links = contact_map_.links;
            in.links_changed = true;
            sdk::ThermalStepReport rep;
            keep_step_temperatures();
            if (auto st = splitter_->advance(in, Tspans, &rep); !st)
              throw RunError("thermal plugin '" + job_.thermal->splitter + "' failed at t = " + fmt_g(t) + " s: " + st.message);
            heat_in += rep.heat_in;
            limited_total += rep.limited;
            accumulate_tool_heat(in.dt);
            finish_thermal_step(in.dt);
            timing_[kTimeThermal] += seconds_since(tc);
            ++steps;
            t_thermal = t;
            since_thermal = 0;
            thermal_stepped = true;
            check_field(t, steps);
            update_node_temperature();
            check_law_ranges(t);
          }
        }
        // Energy audit: W_int + kinetic + damping = external work.
        // Relative to the largest energy seen so far (a vibrating body passes
        // through states where every energy is nearly zero).
        audit_scale = std::max({audit_scale, std::abs(audit.internal), audit.kinetic, std::abs(audit.external),
                                std::abs(audit.contact)});
        const double scale = std::max(audit_scale, 1e-30);
        audit.balance_error =
            std::abs(audit.internal + audit.kinetic + audit.damping + audit.contact - audit.external) / scale;
        if (audit.balance_error > md.energy_tolerance && scale > 1e-12 && mech_steps > 20)
          throw RunError("energy balance error " + fmt_g(audit.balance_error, 3) + " above energy_tolerance " +
                         fmt_g(md.energy_tolerance, 3) + " at t = " + fmt_g(t) + " s (mechanical step " +
                         std::to_string(mech_steps) + ", step " + fmt_g(dt, 3) +
                         " s): " + unstable);
        // Kinetic energy growth: the plies start at rest and stress free, so
        // their kinetic energy cannot exceed what loads, driven dofs and tools
        // have supplied (external work, plus the tools' work: the contact
        // work on the plies and the energy held in the penalty springs). An
        // unstable step grows it exponentially even where the audit stays
        // balanced (for a linear system central differences conserve the
        // product form of the kinetic energy, which turns negative instead).
        supplied_max = std::max(supplied_max, audit.external - audit.contact + audit.contact_stored);
        if (mech_steps > 20 && audit.kinetic_half > kKineticGrowthLimit * supplied_max + 1e-15)
          throw RunError("kinetic energy " + fmt_g(audit.kinetic_half, 3) + " J grew above " +
                         fmt_g(kKineticGrowthLimit, 3) + " times the energy supplied by loads, driven dofs and tools (" +
                         fmt_g(supplied_max, 3) + " J) at t = " + fmt_g(t) + " s (mechanical step " +
                         std::to_string(mech_steps) + ", step " + fmt_g(dt, 3) +
                         " s): " + unstable);
        if (t >= next_sample - eps_t) {
          const double row[8] = {t, audit.kinetic, audit.internal, audit.external, audit.damping, audit.contact,
                                 audit.contact_stored, audit.balance_error};
          energy_rows.insert(energy_rows.end(), row, row + 8);
          energy_rows.insert(energy_rows.end(), audit.reactions.begin(), audit.reactions.end());
          energy_rows.push_back(audit.kinetic_half);
          if (energy_csv.is_open()) {
            for (int c = 0; c < 8; ++c) energy_csv << (c ? "," : "") << csv_number(row[c]);
            for (double r : audit.reactions) energy_csv << ',' << csv_number(r);
            energy_csv << ',' << csv_number(audit.kinetic_half) << '\n';
          }
          if (!tools_.empty()) sample_tools(t);
          tc = Clock::now();
          sample_plies(t);
          timing_[kTimeOutput] += seconds_since(tc);
          next_sample += series_iv;
        }
        for (std::size_t q = 0; q < next_probe.size(); ++q) {
          // A probe without an interval samples at every thermal step, or
          // without the thermal solver at the frames' interval.
          const bool every_thermal = job_.thermal && job_.output.probes[q].interval <= 0;
          const double iv = job_.output.probes[q].interval > 0 ? job_.output.probes[q].interval : interval;
          if (every_thermal ? !thermal_stepped : !(t >= next_probe[q] - eps_t || next_probe[q] <= 0)) continue;
          tc = Clock::now();
          update_element_fields();
          sample_probes(t, q);
          timing_[kTimeOutput] += seconds_since(tc);
          if (!every_thermal) advance_past(next_probe[q], iv, t + eps_t);
        }
        if (t >= next_frame - eps_t) {
          tc = Clock::now();
          update_element_fields();
          write_frame(t);
          timing_[kTimeOutput] += seconds_since(tc);
          ++frame_index;
          frame_t = t;
        }
        if (checkpoint_due(stop_seen)) save_checkpoint();
        progress.update(t, mech_steps);
        if ((stop_signal = stop_seen) != 0) break;
      }
    } else {
    while (t < t_end - eps_t) {
        const double grid_frame = frame_index * interval;
        double next_frame = std::min(t_end, grid_frame);
        double step = std::min(thermal_dt_, next_frame - t);
        for (std::size_t q = 0; q < next_probe.size(); ++q)
          if (job_.output.probes[q].interval > 0) step = std::min(step, next_probe[q] - t);
        if (step <= eps_t) step = std::min(thermal_dt_, t_end - t);
        // The last step, where time.end is off the frame times: the end
        // checkpoint is the state before it.
        if (!landing_saved && t_end < grid_frame && t + step >= t_end - eps_t)
          end_checkpoint(", before the step that lands on time.end");
        in.dt = step;
        update_far_temperatures(t, t + step);
        sdk::ThermalStepReport rep;
        keep_step_temperatures();
        if (auto s = splitter_->advance(in, Tspans, &rep); !s)
          throw RunError("thermal plugin '" + job_.thermal->splitter + "' failed at t = " + fmt_g(t) + " s: " + s.message);
        in.links_changed = false;
        accumulate_tool_heat(step);
        finish_thermal_step(step);
        ++steps;
        t += step;
        heat_in += rep.heat_in;
        substeps_max = std::max(substeps_max, rep.substeps);
        limited_total += rep.limited;
        check_field(t, steps);
        if (std::abs(t - next_frame) <= eps_t) t = next_frame;
        if (t >= next_sample - eps_t) {
          sample_plies(t);
          if (!tools_.empty()) sample_tools(t);
          advance_past(next_sample, series_iv, t + eps_t);
        }
        bool any_step_probe = false;
        for (std::size_t q = 0; q < next_probe.size(); ++q) {
          const double iv = job_.output.probes[q].interval;
          if (iv <= 0) {
            any_step_probe = true;
          } else if (t >= next_probe[q] - eps_t) {
            sample_probes(t, q);
            advance_past(next_probe[q], iv, t + eps_t);
          }
        }
        if (any_step_probe)
          for (std::size_t q = 0; q < next_probe.size(); ++q)
            if (job_.output.probes[q].interval <= 0) sample_probes(t, q);
        if (t >= next_frame - eps_t) {
          write_frame(t);
          ++frame_index;
          frame_t = t;
        }
        const int stop_seen = stop_requested();
        if (checkpoint_due(stop_seen)) save_checkpoint();
        progress.update(t, steps);
        if ((stop_signal = stop_seen) != 0) break;
      }
    }
    if (stop_signal != 0 && t > frame_t) {  // interrupted: the state reached, as a last frame
      const auto tc = Clock::now();
      if (job_.mechanics) update_element_fields();
      write_frame(t);
      // (unless the stop came right after a row: the last row's time is t)
      if (!tools_.empty() && (tool_rows.empty() || tool_rows[tool_rows.size() - tool_cols.size()] < t))
        sample_tools(t);
      if (ply_rows.empty() || ply_rows[ply_rows.size() - ply_cols.size()] < t) sample_plies(t);
      for (std::size_t q = 0; q < next_probe.size(); ++q) {  // the probes not sampled at t yet
        const double pi = job_.output.probes[q].interval;
        if (pi <= 0 && job_.mechanics && job_.thermal) {  // sampled at every thermal step
          if (t_thermal < t - eps_t) sample_probes(t, q);
          continue;
        }
        const double iv = pi > 0 ? pi : job_.mechanics ? interval : 0.0;
        if (iv > 0 && next_probe[q] - iv < t - eps_t) sample_probes(t, q);
      }
      timing_[kTimeOutput] += seconds_since(tc);
    }
    if (!progress.tty && stop_signal == 0) progress.last_decile = 10;  // the last line was printed at 100 %
    progress.update(t, job_.mechanics ? mech_steps : steps, progress.tty || stop_signal != 0);
  } catch (const RunError& e) {
    failure = e.what();
  } catch (const std::exception& e) {
    failure = std::string("unexpected error: ") + e.what();
  }

  if (writer && job_.mechanics && energy_rows.size() % energy_cols.size() == 0)
    writer->write_series("energy", energy_cols, energy_rows);
  if (writer && !tools_.empty() && tool_rows.size() % tool_cols.size() == 0 && !tool_rows.empty())
    writer->write_series("tools", tool_cols, tool_rows);
  if (writer && ply_series && ply_rows.size() % ply_cols.size() == 0 && !ply_rows.empty())
    writer->write_series("plies", ply_cols, ply_rows);
  const double stored_change = stored_heat() - stored0;
  const double scale = std::max({std::abs(stored_change), std::abs(heat_in), 1e-300});
  if (failure.empty() && stop_signal != 0) {
    failure = std::string("interrupted by ") + signal_name(stop_signal) + " at t = " + fmt_g(t) + " s of " +
              fmt_g(t_end) + " s (" + (job_.mechanics ? "mechanical step " + std::to_string(mech_steps)
                                                       : "thermal step " + std::to_string(steps)) +
              "); the output folder holds the frames up to that time";
    result.interrupted = stop_signal;
  }
  // Each ply's share beyond the shear limit at the end (where the run
  // stopped; a first time beyond it found here is the end's).
  std::vector<double> over_end(parts_.size(), 0.0);
  if (shear_limit) try {
      for (std::size_t p = 0; p < parts_.size(); ++p) over_end[p] = ply_mechanics(p, t)[4];
    } catch (const RunError& e) {
      if (failure.empty()) failure = e.what();
    }
  result.ok = failure.empty();
  result.error = failure;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  result.wall_time_before_s = wall_before;
  result.peak_memory_mb = peak_resident_mb();
  result.simulated_time_s = t;
  result.thermal_steps = steps;
  result.thermal_dt = thermal_dt_;
  result.heat_in = heat_in;
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    result.part_heat_change.push_back(stored_heat(static_cast<int>(p)) - stored0_part[p]);
    result.part_link_heat.push_back(link_heat_.size() > p ? link_heat_[p] : 0.0);
    // With mechanics, one range per part (every part has elements, so its
    // shear angles and strains are not empty).
    const auto& sa = parts_[p]->shear_angle;
    if (job_.mechanics) {
      const auto [smn, smx] = std::minmax_element(sa.begin(), sa.end());
      result.part_shear_min_deg.push_back(*smn);
      result.part_shear_max_deg.push_back(*smx);
      const auto [fmn, fmx] = fibre_strain_range(mech_[p]->strain);
      result.part_fibre_strain_min.push_back(fmn);
      result.part_fibre_strain_max.push_back(fmx);
    }
  }
  result.stored_change = stored_change;
  result.heat_balance_error = std::abs(stored_change - heat_in) / scale;
  result.limited_node_steps = limited_total;
  result.mechanical_steps = mech_steps;
  result.bending_evaluations = bending_evaluations_;
  result.bending_largest = bending_largest_;
  result.mechanical_dt = mech_dt;
  result.energy = audit;
  for (std::size_t q = 0; q < tools_.size(); ++q) {
    const auto& u = tools_[q]->displacement();
    result.energy.tool_displacements.insert(result.energy.tool_displacements.end(), u.begin(), u.end());
    for (int d = 0; d < 3; ++d) result.energy.tool_forces.push_back(tool_force_[3 * q + d]);
    result.energy.tool_heat.push_back(tool_heat_[q]);
  }
  if (job_.mechanics && !tools_.empty()) {  // the press force: the largest over the rows
    const std::size_t nt = tools_.size(), stride = 1 + 8 * nt;
    result.energy.tool_force_max.assign(nt, 0.0);
    result.energy.tool_force_max_at.assign(nt, 0.0);
    for (std::size_t r = 0; r + stride <= tool_rows.size(); r += stride)
      for (std::size_t q = 0; q < nt; ++q) {
        const double* f = &tool_rows[r + 1 + 8 * q + 3];
        const double m = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (m > result.energy.tool_force_max[q]) {
          result.energy.tool_force_max[q] = m;
          result.energy.tool_force_max_at[q] = tool_rows[r];
        }
      }
  }
  for (const auto& m : mech_) result.energy.added_mass_percent.push_back(100 * m->mass_added / m->mass_physical);
  result.temperature_min = seen_min_;
  result.temperature_max = seen_max_;
  // Each ply's temperatures at the end (the summary and the log's last lines).
  std::vector<std::array<double, 4>> ply_end;
  if (job_.thermal)
    for (std::size_t p = 0; p < parts_.size(); ++p) ply_end.push_back(ply_temperature(*parts_[p], threshold_of(p)));
  {
    const std::size_t w = ply_cols.size();
    for (std::size_t r = 0; r + w <= ply_rows.size(); r += w)
      for (std::size_t p = 0; p < parts_.size(); ++p) {
        const double* v = &ply_rows[r + 1 + ply_per * p];
        RunResult::PlySample s;
        s.part = static_cast<int>(p);
        s.time = ply_rows[r];
        if (job_.thermal) {
          s.min = v[0];
          s.mean = v[1];
          s.max = v[2];
          s.fraction_below = threshold ? v[3] : 0.0;
          v += threshold ? 4 : 3;
          if (crystallising) {
            s.crystallinity_min = v[0];
            s.crystallinity_mean = v[1];
            s.crystallinity_max = v[2];
            v += 3;
          }
        }
        if (job_.mechanics) {
          s.shear_min = v[0];
          s.shear_max = v[1];
          s.fibre_strain_min = v[2];
          s.fibre_strain_max = v[3];
          s.fraction_over_shear_limit = shear_limit ? v[4] : 0.0;
        }
        result.ply_history.push_back(s);
      }
    if (threshold) result.part_below_threshold_from_s = below_from_;
    if (threshold) result.part_all_below_threshold_from_s = all_below_from_;
    if (shear_limit) result.part_over_shear_limit_from_s = over_from_;
  }

  if (opt.write_files) {
    update_derived();
    json summary;
    summary["job"] = job_.name;
    summary["job_file"] = std::filesystem::absolute(job_.file).lexically_normal().string();
    summary["status"] = result.ok ? "completed" : result.interrupted ? "interrupted" : "failed";
    summary["version"] = kVersion;
    summary["threads"] = threads;
    summary["subnormals"] = flushed.mode();
    summary["wall_time_s"] = result.wall_time_s;
    summary["wall_time_total_s"] = result.wall_time_before_s + result.wall_time_s;
    summary["peak_memory_MB"] = result.peak_memory_mb > 0 ? json(result.peak_memory_mb) : json(nullptr);
    summary["simulated_time_s"] = t;
    summary["restarted_from_s"] = restarted_from >= 0 ? json(restarted_from) : json(nullptr);
    summary["steps"] = {{"mechanics", mech_steps}, {"thermal", steps}};
    summary["dt"] = {{"mechanics", job_.mechanics ? json(mech_dt) : json(nullptr)},
                     {"thermal", job_.thermal ? json(thermal_dt_) : json(nullptr)}};
    if (job_.thermal)
    summary["thermal"] = {{"splitter", job_.thermal->splitter},
                          {"stable_dt", std::isfinite(thermal_stable_dt_) ? json(thermal_stable_dt_) : json(nullptr)},
                          {"accurate_dt", thermal_accurate_dt_},
                          {"inplane_substeps_max", substeps_max},
                          {"limited_node_steps", limited_total}};
    summary["plugins_loaded"] = registry_.loaded_names();
    if (job_.mechanics)
      summary["timing_s"] = {{"elements_and_laws", timing_[kTimeElements]},
                             {"contact", timing_[kTimeContact]},
                             {"thermal", timing_[kTimeThermal]},
                             {"time_integration_and_audit", timing_[kTimeIntegrate]},
                             {"output", timing_[kTimeOutput]}};
    if (job_.mechanics) {  // share of the steps whose contact ran beside the element blocks (either way)
      const ForceSchedule& fs = schedule_;
      const double calls = static_cast<double>(std::max(fs.calls, 1LL));
      summary["contact_beside_elements"] = static_cast<double>(fs.way_calls[kBeside] + fs.way_calls[kByPart]) / calls;
      summary["contact_schedule_share"] = {{"in_turn", static_cast<double>(fs.way_calls[kInTurn]) / calls},
                                           {"beside", static_cast<double>(fs.way_calls[kBeside]) / calls},
                                           {"by_part", static_cast<double>(fs.way_calls[kByPart]) / calls}};
    }
    if (job_.mechanics && job_.mechanics_settings.bending_subcycles > 1)
      summary["bending_subcycles"] = {{"at_most", job_.mechanics_settings.bending_subcycles},
                                      {"evaluations", bending_evaluations_},
                                      {"largest", bending_largest_}};
    summary["energy"] = {{"kinetic", audit.kinetic}, {"internal", audit.internal}, {"external_work", audit.external},
                         {"contact", audit.contact}, {"contact_stored", audit.contact_stored},
                         {"damping", audit.damping}, {"balance_error", audit.balance_error},
                         {"kinetic_half_step", audit.kinetic_half}};
    if (job_.mechanics && !energy_rows.empty()) {
      const auto [ratio, below_from] = quasi_static();
      summary["energy"]["kinetic_to_internal"] = {
          {"at_end", std::isnan(ratio) ? json(nullptr) : json(ratio)},
          {"under_5_percent_from_s", below_from >= 0 ? json(below_from) : json(nullptr)}};
    }
    json tools = json::array();
    for (std::size_t q = 0; q < tools_.size(); ++q) {
      const auto& u = tools_[q]->displacement();
      tools.push_back({{"name", job_.tools[q].name},
                       {"displacement_m", {u[0], u[1], u[2]}},
                       {"force_N", {tool_force_[3 * q], tool_force_[3 * q + 1], tool_force_[3 * q + 2]}},
                       {"heat_to_plies_J", tool_heat_[q]}});
      if (q < result.energy.tool_force_max.size()) {
        tools.back()["force_max_N"] = result.energy.tool_force_max[q];
        tools.back()["force_max_at_s"] = result.energy.tool_force_max_at[q];
      }
    }
    summary["tools"] = tools;
    if (job_.mechanics) {
      json reactions = json::array();
      for (std::size_t c = 0; c < job_.constraints.size(); ++c)
        reactions.push_back({{"constraint", job_.constraints[c].pointer},
                             {"force", {audit.reactions.size() > 3 * c ? audit.reactions[3 * c] : 0.0,
                                        audit.reactions.size() > 3 * c ? audit.reactions[3 * c + 1] : 0.0,
                                        audit.reactions.size() > 3 * c ? audit.reactions[3 * c + 2] : 0.0}}});
      summary["reactions_N"] = reactions;
      json added = json::object();
      for (std::size_t p = 0; p < mech_.size(); ++p)
        added[parts_[p]->def->name] = 100 * mech_[p]->mass_added / mech_[p]->mass_physical;
      summary["mass_scaling_added_percent"] = added;
    }
    summary["heat"] = {{"stored_change_J", stored_change},
                       {"faces_in_J", heat_in},
                       {"balance_error", result.heat_balance_error}};
    json plies = json::array();
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const auto& st = parts_[p];
      const auto [mn, mx] = std::minmax_element(st->T.begin(), st->T.end());
      plies.push_back({{"name", st->def->name},
                       {"nodes", st->mesh.num_nodes()},
                       {"elements", st->mesh.num_elements()},
                       {"values_per_node", st->nz},
                       {"temperature_min", *mn},
                       {"temperature_max", *mx}});
      if (job_.thermal) {
        plies.back()["temperature_mean"] = ply_end[p][1];
        if (threshold) plies.back()["fraction_below_threshold"] = ply_end[p][3];
        if (!st->X.empty()) {
          const std::array<double, 3> x = ply_crystallinity(*st);
          plies.back()["crystallinity_min"] = x[0];
          plies.back()["crystallinity_mean"] = x[1];
          plies.back()["crystallinity_max"] = x[2];
        }
      }
      if (threshold) {
        plies.back()["temperature_threshold"] = thresholds[p];
        plies.back()["below_threshold_from_s"] = below_from_[p] >= 0 ? json(below_from_[p]) : json(nullptr);
        plies.back()["all_below_threshold_from_s"] =
            all_below_from_[p] >= 0 ? json(all_below_from_[p]) : json(nullptr);
      }
      if (job_.mechanics) {
        plies.back()["shear_angle_min_deg"] = result.part_shear_min_deg[p];
        plies.back()["shear_angle_max_deg"] = result.part_shear_max_deg[p];
        plies.back()["fibre_strain_min"] = result.part_fibre_strain_min[p];
        plies.back()["fibre_strain_max"] = result.part_fibre_strain_max[p];
      }
      if (shear_limit) {
        plies.back()["shear_angle_limit"] = shear_limits[p];
        plies.back()["fraction_over_shear_limit"] = over_end[p];
        plies.back()["over_shear_limit_from_s"] = over_from_[p] >= 0 ? json(over_from_[p]) : json(nullptr);
      }
    }
    summary["parts"] = plies;
    summary["frames"] = writer ? writer->frames() : 0;
    summary["error"] = result.ok ? json(nullptr) : json(failure);
    std::ofstream(opt.out_dir / "summary.json") << summary.dump(2) << '\n';
  }
  if (limited_total > 0)
    log->info("the thermal splitter limited {} node-step(s) to keep temperatures inside their local range "
              "(steep through-thickness profiles next to strong in-plane conduction)",
              limited_total);
  if (result.ok && job_.mechanics) {
    log->info("mechanics: {} steps (last {:.3g} s), energy balance error {:.2e}, kinetic {:.4g} J, internal {:.4g} J, "
              "contact {:.4g} J, damping {:.4g} J",
              mech_steps, mech_dt, audit.balance_error, audit.kinetic, audit.internal, audit.contact, audit.damping);
    if (!energy_rows.empty()) {
      const auto [ratio, below_from] = quasi_static();
      const std::string hint =
          ": the mass scaling makes part of the run dynamic; compare the results with a smaller "
          "solvers.mechanics.mass_scaling.target_dt";
      if (std::isnan(ratio))
        log->info("kinetic/internal energy: no internal energy was stored, the ratio does not apply");
      else if (below_from >= 0 && below_from <= 0.1 * t_end)
        log->info("kinetic/internal energy {:.2g} % at the end, under 5 % from t = {:.3g} s", 100 * ratio, below_from);
      else if (below_from >= 0)
        log->info("kinetic/internal energy {:.2g} % at the end, under 5 % only from t = {:.3g} s ({:.0f} % of the run){}",
                  100 * ratio, below_from, 100 * below_from / t_end, hint);
      else
        log->warn("kinetic/internal energy {:.2g} % at the end (above 5 %){}", 100 * ratio, hint);
    }
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const PartState& st = *parts_[p];
      const auto [mn, mx] = std::minmax_element(st.T.begin(), st.T.end());
      std::string over;
      if (shear_limit && over_from_[p] >= 0)
        over = fmt::format(", beyond {} deg from t = {} s, {:.1f} % of its area at the end", fmt_g(shear_limits[p]),
                           fmt_g(over_from_[p], 4), 100 * over_end[p]);
      else if (shear_limit)
        over = fmt::format(", never beyond {} deg", fmt_g(shear_limits[p]));
      log->info("part '{}': temperature {:.2f} to {:.2f} degC, shear angle {:.2f} to {:.2f} deg{}, fibre strain {:.3g} "
                "to {:.3g}",
                st.def->name, *mn, *mx, result.part_shear_min_deg[p], result.part_shear_max_deg[p], over,
                result.part_fibre_strain_min[p], result.part_fibre_strain_max[p]);
    }
    for (std::size_t q = 0; q < result.energy.tool_force_max.size(); ++q)
      log->info("tool '{}': largest force {:.4g} N at t = {} s", job_.tools[q].name, result.energy.tool_force_max[q],
                fmt_g(result.energy.tool_force_max_at[q], 4));
  }
  if (job_.thermal) {
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const std::array<double, 4>& now = ply_end[p];
      std::ostringstream line;
      line << std::fixed << std::setprecision(2) << "part '" << parts_[p]->def->name << "': ";
      if (!job_.mechanics) line << "temperature " << now[0] << " to " << now[2] << " degC, ";
      line << "mean " << now[1] << " degC";
      if (threshold && below_from_[p] >= 0)
        line << ", below " << fmt_g(thresholds[p]) << " degC from t = " << fmt_g(below_from_[p], 4) << " s"
             << (all_below_from_[p] >= 0 ? ", all of it from t = " + fmt_g(all_below_from_[p], 4) + " s" : "")
             << ", " << std::setprecision(1) << 100 * now[3] << " % of it below at the end";
      else if (threshold)
        line << ", never below " << fmt_g(thresholds[p]) << " degC";
      if (!parts_[p]->X.empty()) {
        const std::array<double, 3> x = ply_crystallinity(*parts_[p]);
        line << std::setprecision(3) << ", relative crystallinity " << x[0] << " to " << x[2] << " (mean " << x[1]
             << ")";
      }
      log->info("{}", line.str());
    }
  }
  if (result.ok) {
    log->info("completed: {} thermal steps in {:.3g} s wall; heat into the plies {:.6g} J, stored change {:.6g} J "
              "(balance error {:.2e}); peak memory {:.0f} MB",
              steps, result.wall_time_s, heat_in, stored_change, result.heat_balance_error, result.peak_memory_mb);
  } else if (result.interrupted) {
    log->warn("{}", failure);
  } else {
    log->error("run failed: {}", failure);
  }
  return result;
}

}  // namespace ts
