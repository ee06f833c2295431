// shell_rf_t3 membrane through the plugin interface: rigid motions give no
// force, a homogeneous deformation of an irregular patch gives the same
// stress in every element and no force at interior nodes (patch test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include <thermostamp/sdk/math.hpp>

#include "mesh/shell_mesh.hpp"
#include "plugins/registry.hpp"
#include "test_support.hpp"

namespace ts {
namespace {

struct Patch {
  PluginRegistry registry;
  ShellMesh mesh;
  std::vector<double> x, fibre, temperature;
  sdk::PartView view;
  std::unique_ptr<sdk::MaterialLaw> law;
  std::unique_ptr<sdk::ElementKernel> element;
  std::vector<const sdk::MaterialLaw*> laws;

  std::unique_ptr<sdk::MaterialLaw> bend;
  std::vector<int> edges;
  explicit Patch(double fibre_angle, bool with_bending = false, std::array<int, 2> div = {4, 3},
                 bool irregular = true, bool crossed = false, double jiggle = 1.0) {
    mesh = rectangle_mesh({0, 0, 0}, {0.02, 0.01}, div, crossed);
    // Move interior nodes to make the patch irregular.
    for (int i = 0; irregular && i < mesh.num_nodes(); ++i) {
      const double X = mesh.x[3 * i], Y = mesh.x[3 * i + 1];
      if (X > 1e-9 && X < 0.02 - 1e-9 && Y > 1e-9 && Y < 0.01 - 1e-9) {
        mesh.x[3 * i] += jiggle * 0.0011 * std::sin(7 * i);
        mesh.x[3 * i + 1] += jiggle * 0.0007 * std::cos(5 * i);
      }
    }
    x = mesh.x;
    for (int e = 0; e < mesh.num_elements(); ++e)
      fibre.insert(fibre.end(), {std::cos(fibre_angle), std::sin(fibre_angle), 0.0});
    temperature.assign(mesh.num_nodes(), 280.0);
    view = test::part_view(mesh);
    view.x = x;
    view.fibre = fibre;
    const auto& lr = registry.require(sdk::PluginKind::Material, "ud_hyperelastic", "/law");
    law.reset(reinterpret_cast<sdk::MaterialLaw* (*)()>(lr.create)());
    law->configure(validate_params(json{{"k_fibre", 5e4}, {"p_ct", 5e3}, {"k_sh", {100.0, 50.0, 0.0}}}, "/m",
                                   lr.descriptor));
    laws = {law.get()};
    const auto& er = registry.require(sdk::PluginKind::Element, "shell_rf_t3", "/element");
    element.reset(reinterpret_cast<sdk::ElementKernel* (*)()>(er.create)());
    sdk::ElementSetup setup;
    setup.part = &view;
    setup.membrane = laws;
    setup.density = 1294.0;
    edges.assign(3 * mesh.num_elements(), sdk::kEdgeFree);
    for (int e = 0; e < mesh.num_elements(); ++e)  // left boundary clamped
      for (int k = 0; k < 3; ++k)
        if (mesh.neighbours[3 * e + k] < 0 && mesh.x[3 * mesh.triangles[3 * e + (k + 1) % 3]] < 1e-12 &&
            mesh.x[3 * mesh.triangles[3 * e + (k + 2) % 3]] < 1e-12)
          edges[3 * e + k] = sdk::kEdgeClamped;
        else if (mesh.neighbours[3 * e + k] < 0 && mesh.x[3 * mesh.triangles[3 * e + (k + 1) % 3] + 1] < 1e-12 &&
                 mesh.x[3 * mesh.triangles[3 * e + (k + 2) % 3] + 1] < 1e-12)
          edges[3 * e + k] = sdk::kEdgeSymmetryX + 1;  // bottom boundary on the plane y = 0
    setup.edge_condition = edges;
    if (with_bending) {
      const auto& br = registry.require(sdk::PluginKind::Material, "thermo_linear_bending", "/bending");
      bend.reset(reinterpret_cast<sdk::MaterialLaw* (*)()>(br.create)());
      bend->configure(validate_params(json{{"beta1_B", 1e-3}, {"beta2_B", 3e-4}, {"twist_ratio", 0.2}}, "/b",
                                      br.descriptor));
      setup.bending = bend.get();
    }
    EXPECT_TRUE(element->configure(validate_params(json::object(), "/e", er.descriptor), setup).ok);
  }
  // Configures the element again with other membrane laws (the patch's
  // edges as before, and its bending law unless another is given).
  void configure_with(const std::vector<const sdk::MaterialLaw*>& membrane,
                      const sdk::MaterialLaw* bending = nullptr, const sdk::MaterialLaw* in_plane = nullptr) {
    const auto& er = registry.require(sdk::PluginKind::Element, "shell_rf_t3", "/element");
    sdk::ElementSetup setup;
    setup.part = &view;
    setup.membrane = membrane;
    setup.density = 1294.0;
    setup.edge_condition = edges;
    setup.bending = bending ? bending : bend.get();
    setup.in_plane_bending = in_plane;
    ASSERT_TRUE(element->configure(validate_params(json::object(), "/e", er.descriptor), setup).ok);
  }
  // The 6-node patch of every element (its nodes, then the node across each
  // edge, -1 if none), as global node ids: forces go straight to the nodes.
  std::vector<int> patch() const {
    std::vector<int> slots(6 * mesh.num_elements(), -1);
    for (int e = 0; e < mesh.num_elements(); ++e) {
      int* nodes = &slots[6 * e];
      for (int a = 0; a < 3; ++a) nodes[a] = mesh.triangles[3 * e + a];
      for (int k = 0; k < 3; ++k) {
        const int nb = mesh.neighbours[3 * e + k];
        if (nb < 0) continue;
        for (int a = 0; a < 3; ++a) {
          const int o = mesh.triangles[3 * nb + a];
          if (o != nodes[(k + 1) % 3] && o != nodes[(k + 2) % 3]) nodes[3 + k] = o;
        }
      }
    }
    return slots;
  }
  // The elements are evaluated in `blocks` consecutive ranges, as the
  // kernel calls them (hinges across a range border are seen from both).
  int blocks = 1;
  // With uniform_ranges: ranges of one size (the last smaller), as the
  // kernel's blocks, each called with ElementForceInput::pass_window =
  // ring_window (0: none).
  bool uniform_ranges = false;
  int ring_window = 0;
  bool commit = false;  // update the laws' history
  std::uint64_t temperature_version = 0;  // ElementForceInput::temperature_version
  double bending_weight = 1.0;            // ElementForceInput::bending_weight
  double dt = 0.0;                        // ElementForceInput::dt
  int slot_offset = 0;  // added to every slot (node i's forces at slot i + slot_offset)
  // Each corner its own slot (corner a of element e at slot 3 e + a): the
  // forces of every element apart, instead of the nodes' sums.
  bool corner_slots = false;
  std::vector<double> dt_scale;  // ElementForceInput::dt_scale (empty: none)
  // The smallest ElementForceOutput::stable_dt and bending_dt of the ranges
  // (of the last evaluation).
  double stable_dt = 0, bending_dt = 0;
  // Node forces and energy of all elements.
  double evaluate(std::vector<double>& nf) {
    nf.assign(3 * (mesh.num_nodes() + static_cast<std::size_t>(slot_offset)), 0.0);
    std::vector<int> slots = patch();
    if (corner_slots) {
      nf.assign(9 * static_cast<std::size_t>(mesh.num_elements()), 0.0);
      for (int e = 0; e < mesh.num_elements(); ++e)
        for (int a = 0; a < 3; ++a) slots[6 * e + a] = 3 * e + a;
    }
    for (int& s : slots) s += s >= 0 ? slot_offset : 0;
    const int ne = mesh.num_elements();
    double energy = 0;
    stable_dt = bending_dt = std::numeric_limits<double>::infinity();
    const int passes = element->passes();
    for (int pass = 0; pass < passes; ++pass)
      for (int k = 0; k < blocks; ++k) {
        sdk::ElementForceInput in;
        in.range = {k * ne / blocks, (k + 1) * ne / blocks};
        if (uniform_ranges) {
          const int bs = (ne + blocks - 1) / blocks;
          in.range = {std::min(ne, k * bs), std::min(ne, (k + 1) * bs)};
          if (ring_window > 0) {
            in.pass_window = ring_window;
            in.block = k;
            in.block_size = bs;
          }
        }
        in.node_temperature = temperature;
        in.temperature_version = temperature_version;
        in.commit = commit;
        in.bending_weight = bending_weight;
        in.dt = dt;
        in.dt_scale = dt_scale;
        in.pass = pass;
        in.patch_slot = std::span<const int>(slots).subspan(6 * in.range.begin, 6 * (in.range.end - in.range.begin));
        sdk::ElementForceOutput out;
        out.node_force = nf;
        EXPECT_TRUE(element->internal_forces(in, out).ok);
        EXPECT_EQ(out.failed_element, -1);
        energy += out.energy;
        if (pass == passes - 1) {
          stable_dt = std::min(stable_dt, out.stable_dt);
          bending_dt = std::min(bending_dt, out.bending_dt);
        }
      }
    nf.erase(nf.begin(), nf.begin() + 3 * static_cast<std::ptrdiff_t>(slot_offset));
    return energy;
  }
  double energy() {
    std::vector<double> nf;
    return evaluate(nf);
  }
  std::vector<double> forces(std::vector<double>* stress = nullptr, std::vector<double>* curvature = nullptr) {
    std::vector<double> nf;
    evaluate(nf);
    if (stress || curvature) {
      std::vector<double> dummy;
      if (stress) stress->assign(3 * mesh.num_elements(), 0.0);
      if (curvature) curvature->assign(3 * mesh.num_elements(), 0.0);
      sdk::ElementFields f;
      if (stress) f.stress = *stress;
      if (curvature) f.curvature = *curvature;
      element->fields(f);
    }
    return nf;
  }
  void map(const double R[3][3], const double t[3]) {
    for (int i = 0; i < mesh.num_nodes(); ++i)
      for (int d = 0; d < 3; ++d)
        x[3 * i + d] = t[d] + R[d][0] * mesh.x[3 * i] + R[d][1] * mesh.x[3 * i + 1] + R[d][2] * mesh.x[3 * i + 2];
  }
};

TEST(ShellRfT3, RigidRotationsAreForceFree) {
  Patch p(0.5);
  for (double angle : {M_PI / 2, M_PI, 2.0}) {
    for (int axis = 0; axis < 3; ++axis) {
      const double c = std::cos(angle), s = std::sin(angle);
      double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      R[i][i] = c;
      R[i][j] = -s;
      R[j][i] = s;
      R[j][j] = c;
      const double t[3] = {0.3, -0.1, 0.05};
      p.map(R, t);
      for (double f : p.forces()) EXPECT_NEAR(f, 0.0, 1e-9) << "axis " << axis << " angle " << angle;
    }
  }
}

TEST(ShellRfT3, PatchTestHomogeneousDeformation) {
  Patch p(0.5);
  const double F[3][3] = {{1.08, 0.05, 0}, {-0.02, 0.97, 0}, {0, 0, 1}};
  const double t[3] = {0, 0, 0};
  p.map(F, t);
  std::vector<double> stress;
  const auto f = p.forces(&stress);
  for (int e = 1; e < p.mesh.num_elements(); ++e)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(stress[3 * e + k], stress[k], 1e-9 * std::abs(stress[0]) + 1e-9);
  double fmax = 0;
  for (double v : f) fmax = std::max(fmax, std::abs(v));
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    if (X > 1e-9 && X < 0.02 - 1e-9 && Y > 1e-9 && Y < 0.01 - 1e-9) {
      for (int d = 0; d < 3; ++d) EXPECT_NEAR(f[3 * i + d], 0.0, 1e-9 * fmax) << "interior node " << i;
    }
  }
}

// The strain field (ElementFields::strain) of a homogeneous deformation
// F, followed by a rigid rotation and translation in space: in every
// element of the irregular patch E = (F^T F - I) / 2 written in the
// material frame (a = the fibre at 0.5 rad, b = z x a), the same for every
// rotation (the strain does not see rigid motions). Tolerance 1e-12
// absolute (strains of order 0.1 from differences of positions of order
// 0.01 m: round-off of order 1e-15). Also: the shear angle of the same
// fields is asin(C_ab / sqrt(C_aa C_bb)).
TEST(ShellRfT3, StrainIsHalfOfCMinusIdentityInTheMaterialFrame) {
  const double th = 0.5;
  Patch p(th);
  const double F[3][3] = {{1.08, 0.05, 0}, {-0.02, 0.97, 0}, {0, 0, 1}};
  const double a[2] = {std::cos(th), std::sin(th)}, b[2] = {-std::sin(th), std::cos(th)};
  // C = F^T F (in-plane), then its components in (a, b).
  double C[2][2];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) C[i][j] = F[0][i] * F[0][j] + F[1][i] * F[1][j] + F[2][i] * F[2][j];
  auto cab = [&](const double* u, const double* v) {
    double s = 0;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) s += u[i] * C[i][j] * v[j];
    return s;
  };
  const double expected[3] = {0.5 * (cab(a, a) - 1), 0.5 * (cab(b, b) - 1), 0.5 * cab(a, b)};
  const double gamma = std::asin(cab(a, b) / std::sqrt(cab(a, a) * cab(b, b))) * 180 / M_PI;
  ASSERT_GT(std::abs(expected[2]), 0.01);  // a case with shear, stretch and compression
  ASSERT_GT(expected[0], 0.01);
  ASSERT_LT(expected[1], -0.01);
  for (double angle : {0.0, 0.7, 2.5}) {
    // x = R F X + t, R about the axis (1, 2, 2) / 3
    const double u[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, c = std::cos(angle), s = std::sin(angle);
    double R[3][3], RF[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        R[i][j] = (i == j ? c : 0.0) + (1 - c) * u[i] * u[j] +
                  s * (i == j ? 0.0 : ((j - i + 3) % 3 == 1 ? -u[3 - i - j] : u[3 - i - j]));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) RF[i][j] = R[i][0] * F[0][j] + R[i][1] * F[1][j] + R[i][2] * F[2][j];
    const double t[3] = {0.3, -0.1, 0.05};
    p.map(RF, t);
    p.forces();
    const int ne = p.mesh.num_elements();
    std::vector<double> strain(3 * ne, 0.0), shear(ne, 0.0);
    sdk::ElementFields f;
    f.strain = strain;
    f.shear_angle = shear;
    p.element->fields(f);
    for (int e = 0; e < ne; ++e) {
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(strain[3 * e + k], expected[k], 1e-12) << "element " << e << ", component " << k << ", rotation "
                                                           << angle;
      EXPECT_NEAR(shear[e], gamma, 1e-10) << "element " << e;
    }
  }
}

// The membrane stable step of every element is its smallest current height
// (2 A / longest edge, from the current positions) times sqrt(rho_A /
// k_max), on an irregular patch moved to random, non-homogeneous positions
// in space. The element forms the height from C and its set-up gradients;
// both forms agree to round-off (1e-10 relative). A wrong edge or factor
// in either fails it.
TEST(ShellRfT3, MembraneStableStepIsTheSmallestCurrentHeight) {
  Patch p(0.3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < p.mesh.num_nodes(); ++i)
    for (int d = 0; d < 3; ++d) p.x[3 * i + d] = p.mesh.x[3 * i + d] + 0.0012 * u(rng);
  const int ne = p.mesh.num_elements();
  std::vector<double> nf(3 * p.mesh.num_nodes(), 0.0), edt(ne, 0.0);
  const std::vector<int> slots = p.patch();
  sdk::ElementForceInput in;
  in.range = {0, ne};
  in.node_temperature = p.temperature;
  in.commit = false;
  in.patch_slot = slots;
  sdk::ElementForceOutput out;
  out.node_force = nf;
  out.element_dt = edt;
  ASSERT_EQ(p.element->passes(), 1);
  ASSERT_TRUE(p.element->internal_forces(in, out).ok);
  ASSERT_EQ(out.failed_element, -1);
  const double kmax = p.law->max_stiffness(280.0);
  ASSERT_GT(kmax, 0.0);
  const double scale = std::sqrt(1294.0 * p.view.thickness / kmax);
  double smallest = 1e300;
  for (int e = 0; e < ne; ++e) {
    const int* t = &p.mesh.triangles[3 * e];
    const sdk::Vec3 a = sdk::load3(p.x.data(), t[0]), b = sdk::load3(p.x.data(), t[1]), c = sdk::load3(p.x.data(), t[2]);
    const double two_area = sdk::norm(sdk::cross(sdk::sub(b, a), sdk::sub(c, a)));
    const double longest =
        std::max({sdk::norm(sdk::sub(b, a)), sdk::norm(sdk::sub(c, a)), sdk::norm(sdk::sub(c, b))});
    const double expected = two_area / longest * scale;
    EXPECT_NEAR(edt[e], expected, 1e-10 * expected) << "element " << e;
    smallest = std::min(smallest, expected);
  }
  EXPECT_NEAR(out.stable_dt, smallest, 1e-10 * smallest);
}

// Forces (membrane + rotation-free bending) are the derivative of the
// energy: central differences on every coordinate of a curved, stretched
// configuration. Tolerance 1e-5 of the largest force (step 1e-8 m).
// Evaluated in one range and in 3 and 7 ranges (hinges across range borders
// seen from both sides, each side applying its own element's moment).
// The patch's forces and energy, evaluated in 1, 3 and 7 ranges: the same
// as in one range to round-off (1e-12), and the forces the derivative of
// the energy (central differences, h = 1e-8 m) within tol of the largest
// force. Returns the largest difference from the quotients in one range.
double expect_forces_are_the_energys_derivative(Patch& p, double tol) {
  const auto f1 = p.forces();
  const double e1 = p.energy();
  double err1 = 0;
  for (const int blocks : {1, 3, 7}) {
    p.blocks = blocks;
    const auto f = p.forces();
    double fmax = 0, dmax = 0;
    for (std::size_t k = 0; k < f.size(); ++k) {
      fmax = std::max(fmax, std::abs(f[k]));
      dmax = std::max(dmax, std::abs(f[k] - f1[k]));
    }
    EXPECT_LT(dmax, 1e-12 * fmax) << blocks << " ranges";
    EXPECT_NEAR(p.energy(), e1, 1e-12 * e1) << blocks << " ranges";
    const double h = 1e-8;
    double err = 0;
    for (std::size_t k = 0; k < p.x.size(); ++k) {
      const double keep = p.x[k];
      p.x[k] = keep + h;
      const double ep = p.energy();
      p.x[k] = keep - h;
      const double em = p.energy();
      p.x[k] = keep;
      err = std::max(err, std::abs((ep - em) / (2 * h) - f[k]));
    }
    EXPECT_LT(err, tol * fmax) << "max force " << fmax << ", " << blocks << " ranges";
    if (blocks == 1) err1 = err;
  }
  p.blocks = 1;
  return err1;
}

TEST(ShellRfT3, BendingForcesAreTheDerivativeOfTheEnergy) {
  Patch p(0.5, true);
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    p.x[3 * i] = 1.01 * X;
    p.x[3 * i + 2] = 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y + 1e-4 * std::sin(11 * i);
  }
  expect_forces_are_the_energys_derivative(p, 1e-5);
}

// (defined below)
std::unique_ptr<sdk::MaterialLaw> linear_bending(Patch& p, double r1, double r2);

// Where the kernel interleaves the passes it gives a window of blocks
// (ElementForceInput::pass_window) and the element keeps the values between
// its passes in a ring of block buffers instead of arrays over the part:
// the same forces and energy, bit for bit, with and without the fibres'
// in-plane bending. (Called pass by pass here, with a window of all the
// blocks: every block has its own buffer.)
TEST(ShellRfT3, RingOfBlockBuffersGivesTheSameBits) {
  for (const bool in_plane : {false, true}) {
    Patch p(0.5, true, {6, 5});
    auto ipb = linear_bending(p, 2e-3, 0.0);
    if (in_plane) p.configure_with(p.laws, nullptr, ipb.get());
    for (int i = 0; i < p.mesh.num_nodes(); ++i) {
      const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
      p.x[3 * i] = 1.01 * X;
      p.x[3 * i + 1] = Y + 0.3 * X * X;
      p.x[3 * i + 2] = 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y + 1e-4 * std::sin(11 * i);
    }
    p.uniform_ranges = true;
    for (const int blocks : {2, 4, 7}) {
      p.blocks = blocks;
      p.ring_window = 0;
      std::vector<double> f_full, f_ring;
      const double e_full = p.evaluate(f_full);
      p.ring_window = blocks;
      const double e_ring = p.evaluate(f_ring);
      double fmax = 0;
      for (const double v : f_full) fmax = std::max(fmax, std::abs(v));
      EXPECT_GT(fmax, 0.0);
      EXPECT_EQ(f_full, f_ring) << blocks << " blocks, in-plane bending " << in_plane;
      EXPECT_EQ(e_full, e_ring) << blocks << " blocks, in-plane bending " << in_plane;
    }
  }
}

// The element keeps the node slots of its corners in 16 bits where they
// fit, summing each node's corner forces in registers (node_forces), and
// adds them corner by corner into the kernel's slots where they do not:
// the same forces, bit for bit (the sums in the same order). Reversing
// the order of a node's corners fails this.
TEST(ShellRfT3, ForcesGoToTheirSlotsWhateverTheSlotNumbers) {
  std::vector<double> f[2];
  double e[2];
  for (const int i : {0, 1}) {
    Patch p(0.5, true, {6, 5});
    for (int n = 0; n < p.mesh.num_nodes(); ++n) {
      const double X = p.mesh.x[3 * n], Y = p.mesh.x[3 * n + 1];
      p.x[3 * n] = 1.01 * X;
      p.x[3 * n + 2] = 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y;
    }
    p.blocks = 3;
    p.slot_offset = i == 0 ? 0 : 70000;  // beyond 16 bits
    e[i] = p.evaluate(f[i]);
  }
  double fmax = 0;
  for (const double v : f[0]) fmax = std::max(fmax, std::abs(v));
  EXPECT_GT(fmax, 0.0);
  EXPECT_EQ(f[0], f[1]);
  EXPECT_EQ(e[0], e[1]);
}

// F comes from the positions relative to an element's first corner, and
// the three corners' gradients sum to zero exactly: moving a deformed,
// bent patch by a rigid translation (exact here: positions on a grid of
// 2^-24 m, a shift of whole metres) leaves every force bit for bit as it
// was, membrane and bending.
TEST(ShellRfT3, TranslationLeavesTheForcesAsTheyAre) {
  Patch p(0.5, true, {6, 5});
  for (int n = 0; n < p.mesh.num_nodes(); ++n) {
    const double X = p.mesh.x[3 * n], Y = p.mesh.x[3 * n + 1];
    const double u[3] = {1.01 * X - 0.02 * Y, Y + 0.015 * X, 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y};
    for (int d = 0; d < 3; ++d) p.x[3 * n + d] = std::ldexp(std::round(std::ldexp(u[d], 24)), -24);
  }
  std::vector<double> f0, f1;
  const double e0 = p.evaluate(f0);
  for (int n = 0; n < p.mesh.num_nodes(); ++n) {
    p.x[3 * n] += 3.0;
    p.x[3 * n + 1] -= 1024.0;
    p.x[3 * n + 2] += 17.0;
  }
  const double e1 = p.evaluate(f1);
  double fmax = 0;
  for (const double v : f0) fmax = std::max(fmax, std::abs(v));
  EXPECT_GT(fmax, 0.0);
  EXPECT_EQ(f0, f1);
  EXPECT_EQ(e0, e1);
}

// Each element's corner 0 takes minus the sum of the other two corners'
// forces: f_0 + (f_1 + f_2) is zero to the last bit for every element,
// membrane and bending across element edges, so the elements add no net
// force of round-off. (The hinges against a held edge's ghost add their
// forces apart, with their own round-off: the patch's edges are free here.)
TEST(ShellRfT3, EachElementsForcesSumToZero) {
  for (const bool bending : {false, true}) {
    Patch p(0.5, bending, {6, 5});
    std::fill(p.edges.begin(), p.edges.end(), sdk::kEdgeFree);
    p.configure_with(p.laws);
    for (int n = 0; n < p.mesh.num_nodes(); ++n) {
      const double X = p.mesh.x[3 * n], Y = p.mesh.x[3 * n + 1];
      p.x[3 * n] = 1.01 * X - 0.02 * Y;
      p.x[3 * n + 1] = Y + 0.015 * X;
      p.x[3 * n + 2] = 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y;
    }
    p.corner_slots = true;
    std::vector<double> f;
    p.evaluate(f);
    int nonzero = 0;
    for (int e = 0; e < p.mesh.num_elements(); ++e)
      for (int d = 0; d < 3; ++d) {
        const double* c = &f[9 * e + d];
        nonzero += c[0] != 0.0 && c[3] != 0.0 && c[6] != 0.0;
        EXPECT_EQ(c[0] + (c[3] + c[6]), 0.0) << "element " << e << " component " << d << " bending " << bending;
      }
    EXPECT_EQ(nonzero, 3 * p.mesh.num_elements()) << "bending " << bending;
  }
}

// Without step factors the element takes a range's smallest bending step
// from its smallest d^2 instead of from every element's step: the same
// stable steps as with factors of 1 (which take every element's), bit for
// bit.
TEST(ShellRfT3, StableStepsWithoutFactorsAreThoseWithFactorsOfOne) {
  Patch p(0.5, true, {24, 20});
  for (int i = 0; i < p.mesh.num_nodes(); ++i) p.x[3 * i] = 1.01 * p.mesh.x[3 * i];
  p.blocks = 3;
  std::vector<double> f;
  p.evaluate(f);
  const double dt_none = p.stable_dt, bdt_none = p.bending_dt;
  p.dt_scale.assign(p.mesh.num_elements(), 1.0);
  p.evaluate(f);
  EXPECT_TRUE(std::isfinite(bdt_none));
  EXPECT_GT(bdt_none, 0.0);
  EXPECT_EQ(dt_none, p.stable_dt);
  EXPECT_EQ(bdt_none, p.bending_dt);
  // The bending step is the smaller one here (elements of about 0.5 mm),
  // so the shortcut decides the stable step.
  EXPECT_EQ(dt_none, bdt_none);
}

// Without step factors (and without per-element steps asked for) the
// membrane pass keeps only the smallest det C / max Q of a range and takes
// one square root: the same stable step as with factors of 1, which form
// every element's step, bit for bit. Coarse patches, so that the membrane
// step decides also where there is bending.
TEST(ShellRfT3, MembraneStepsWithoutFactorsAreThoseWithFactorsOfOne) {
  for (const bool bending : {false, true}) {
    Patch p(0.5, bending, {5, 3});
    for (int i = 0; i < p.mesh.num_nodes(); ++i) {
      p.x[3 * i] = 1.01 * p.mesh.x[3 * i] + 0.002 * p.mesh.x[3 * i + 1];
      p.x[3 * i + 2] = 0.3 * p.mesh.x[3 * i] * p.mesh.x[3 * i];
    }
    p.blocks = 2;
    std::vector<double> f;
    p.evaluate(f);
    const double dt_none = p.stable_dt;
    p.dt_scale.assign(p.mesh.num_elements(), 1.0);
    p.evaluate(f);
    EXPECT_TRUE(std::isfinite(dt_none) && dt_none > 0) << "bending " << bending;
    EXPECT_EQ(dt_none, p.stable_dt) << "bending " << bending;
    if (bending) {
      EXPECT_LT(dt_none, p.bending_dt);  // the membrane step decides
    }
  }
}

// A range keeps the node offsets of its elements and of the hinges they
// own, and its entries of the angle changes, in 16 bits where they span
// less than 2^16 (several ranges of a large patch), and in int otherwise
// (one range over 22 000 nodes and 44 000 elements): the same forces.
TEST(ShellRfT3, SixteenBitOffsetsGiveTheSameBits) {
  Patch p(0.5, true, {200, 110}, true, false, 0.01);
  ASSERT_GT(3 * p.mesh.num_nodes(), 0xffff);
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    p.x[3 * i] = 1.01 * X;
    p.x[3 * i + 2] = 2.0 * X * X + 1.5 * X * Y - 3.0 * Y * Y + 1e-6 * std::sin(11 * i);
  }
  std::vector<double> f[2];
  double e[2];
  for (const int i : {0, 1}) {
    p.blocks = i == 0 ? 1 : 16;
    e[i] = p.evaluate(f[i]);
  }
  double fmax = 0;
  for (const double v : f[0]) fmax = std::max(fmax, std::abs(v));
  EXPECT_GT(fmax, 0.0);
  EXPECT_EQ(f[0], f[1]);
  EXPECT_NEAR(e[0], e[1], 1e-13 * e[0]);  // summed per range: the order of the sum differs
  // What a range keeps is its own: ranges of other bounds over the same
  // elements in between leave it as it was.
  std::vector<double> f7, f16;
  p.blocks = 7;
  p.evaluate(f7);
  p.blocks = 16;
  p.evaluate(f16);
  EXPECT_EQ(f7, f[0]);
  EXPECT_EQ(f16, f[1]);
}

// A law (membrane, or bending with `as`) that returns no stress and records
// the strains it is given (of its last call), and the element temperatures
// and the history steps (of every call since they were last cleared, block
// after block).
struct RecordingLaw final : sdk::MaterialLaw {
  explicit RecordingLaw(bool reads, sdk::LawRole as = sdk::LawRole::Membrane) : reads(reads), as(as) {}
  bool reads;
  sdk::LawRole as;
  mutable std::vector<double> strain, strain_old, temperature, dt;
  sdk::Status configure(const sdk::Params&) override { return sdk::Status::success(); }
  sdk::LawRole role() const override { return as; }
  sdk::Status evaluate(const sdk::MaterialBlock& b) const override {
    strain.assign(b.strain.begin(), b.strain.end());
    strain_old.assign(b.strain_old.begin(), b.strain_old.end());
    temperature.insert(temperature.end(), b.temperature.begin(), b.temperature.end());
    dt.push_back(b.dt);
    std::fill(b.stress.begin(), b.stress.end(), 0.0);
    std::fill(b.energy.begin(), b.energy.end(), 0.0);
    return sdk::Status::success();
  }
  double max_stiffness(double) const override { return 0.0; }
  bool uses_strain_old() const override { return reads; }
};

// The element hands a law the strains of the previous committed step when
// the law says it reads them (C = I before the first step), and none when
// no law does.
TEST(ShellRfT3, PreviousStrainsOnlyForLawsThatReadThem) {
  for (const bool reads : {true, false}) {
    Patch p(0.3);
    RecordingLaw rec(reads);
    p.configure_with({p.law.get(), &rec});
    p.commit = true;
    std::vector<double> before;
    for (int step = 0; step < 3; ++step) {
      for (int i = 0; i < p.mesh.num_nodes(); ++i) p.x[3 * i] = (1.0 + 0.01 * step) * p.mesh.x[3 * i];
      p.forces();
      const std::size_t m = 3 * static_cast<std::size_t>(p.mesh.num_elements());
      ASSERT_EQ(rec.strain.size(), m);
      if (!reads) {
        EXPECT_TRUE(rec.strain_old.empty());
        continue;
      }
      ASSERT_EQ(rec.strain_old.size(), m);
      for (std::size_t k = 0; k < m; ++k)
        EXPECT_EQ(rec.strain_old[k], step == 0 ? (k % 3 == 2 ? 0.0 : 1.0) : before[k]) << "step " << step << ", " << k;
      before = rec.strain;
    }
  }
}

// The element temperatures the laws get are the means of their nodes',
// formed again whenever ElementForceInput::temperature_version changes, is
// 0 (unknown) or the ranges change; with the same nonzero version the
// element keeps those it formed (the host promises the same node
// temperatures), with and without bending.
TEST(ShellRfT3, ElementTemperaturesFollowTheTemperatureVersion) {
  for (const bool bending : {false, true}) {
    Patch p(0.3, bending);
    RecordingLaw rec(false);
    p.configure_with({p.law.get(), &rec});
    const int ne = p.mesh.num_elements();
    auto means = [&] {
      std::vector<double> m(ne);
      for (int e = 0; e < ne; ++e) {
        const int* t = &p.mesh.triangles[3 * e];
        m[e] = p.temperature[t[0]] / 3.0 + p.temperature[t[1]] / 3.0 + p.temperature[t[2]] / 3.0;
      }
      return m;
    };
    auto seen = [&](std::uint64_t version, int blocks) {
      p.temperature_version = version;
      p.blocks = blocks;
      rec.temperature.clear();
      p.forces();
      return rec.temperature;
    };
    auto heat = [&](double base) {
      for (int i = 0; i < p.mesh.num_nodes(); ++i) p.temperature[i] = base + 3.0 * std::sin(1.7 * i);
    };
    const char* what = bending ? "with bending" : "membrane only";
    heat(280.0);
    const std::vector<double> t1 = means();
    EXPECT_EQ(seen(1, 1), t1) << what;
    heat(300.0);  // new temperatures under a new version: formed again
    const std::vector<double> t2 = means();
    EXPECT_EQ(seen(2, 1), t2) << what;
    EXPECT_EQ(seen(2, 1), t2) << what;
    heat(320.0);  // the same version: the host says nothing changed, the element keeps its values
    EXPECT_EQ(seen(2, 1), t2) << what;
    EXPECT_EQ(seen(2, 3), means()) << what << ": other ranges";
    heat(340.0);
    EXPECT_EQ(seen(0, 3), means()) << what << ": version unknown";
    heat(360.0);
    EXPECT_EQ(seen(0, 3), means()) << what << ": version unknown";
    EXPECT_NE(t1, t2);
  }
}

// ElementForceInput::bending_weight: 0 leaves the bending out (membrane
// forces only, the energy with the bending energy of the last evaluation
// with bending), w scales the bending forces by w (to round-off: the
// dW/ds values are multiplied by w before the hinge moments), on a bent
// patch with clamped and symmetry edges, in one range and in three.
// A bending law gets as its history step the time since the last
// evaluation with bending.
TEST(ShellRfT3, BendingWeightScalesOrSkipsTheBending) {
  for (const int blocks : {1, 3}) {
    Patch p(0.3, true);
    p.blocks = blocks;
    for (int i = 0; i < p.mesh.num_nodes(); ++i) {  // bent about y and a little about x
      const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
      p.x[3 * i + 2] = 4.0 * X * X + 1.0 * X * Y;
    }
    auto at = [&](double w, double* energy = nullptr) {
      p.bending_weight = w;
      std::vector<double> f;
      const double e = p.evaluate(f);
      if (energy) *energy = e;
      return f;
    };
    double e1 = 0, e0 = 0;
    const auto f1 = at(1.0, &e1), f0 = at(0.0, &e0), f3 = at(3.0);
    double scale = 0, worst = 0;
    for (std::size_t k = 0; k < f1.size(); ++k) scale = std::max(scale, std::abs(f1[k] - f0[k]));
    for (std::size_t k = 0; k < f1.size(); ++k) worst = std::max(worst, std::abs((f3[k] - f0[k]) - 3.0 * (f1[k] - f0[k])));
    EXPECT_GT(scale, 1e-6) << "the bending forces of the bent patch";
    EXPECT_LT(worst, 1e-12 * scale) << blocks << " ranges";
    EXPECT_NEAR(e0, e1, 1e-12 * std::abs(e1)) << blocks << " ranges";
    std::printf("%d range(s): bending forces up to %.3e N, w = 3 against 3 x w = 1: %.1e N apart; energy %.6e / %.6e J\n",
                blocks, scale, worst, e1, e0);
  }
  Patch p(0.3, true);
  RecordingLaw rec(false, sdk::LawRole::Bending);
  p.configure_with({p.law.get()}, &rec);
  rec.dt.clear();  // (the element probes the law's rigidities at set-up)
  p.commit = true;
  const std::pair<double, double> steps[] = {{1.0, 0.1}, {0.0, 0.2}, {0.0, 0.3}, {3.0, 0.4}, {1.0, 0.5}};
  for (const auto& [w, dt] : steps) {
    p.bending_weight = w;
    p.dt = dt;
    p.energy();
  }
  ASSERT_EQ(rec.dt.size(), 3u);
  EXPECT_DOUBLE_EQ(rec.dt[0], 0.1);
  EXPECT_DOUBLE_EQ(rec.dt[1], 0.2 + 0.3 + 0.4);
  EXPECT_DOUBLE_EQ(rec.dt[2], 0.5);
}

// Curvature patch test: a regular mesh wrapped on a cylinder of radius r
// (axis along y) gives kappa = 1/r along the fibres (x) and 0 across, in
// every element that has three neighbours. Tolerance 1 % (the bending
// angle between neighbouring chords is exactly their central angle;
// round-off only). Chords of 1/20 rad, and of 0.71 rad (41 degrees: hinge
// angles beyond the small-angle approximation of atan2, evaluated by the
// library).
TEST(ShellRfT3, CylinderGivesItsCurvature) {
  for (const double r : {0.05, 0.0035}) {
    Patch p(0.0, true, {8, 6}, false);
    for (int i = 0; i < p.mesh.num_nodes(); ++i) {
      const double X = p.mesh.x[3 * i];
      p.x[3 * i] = r * std::sin(X / r);
      p.x[3 * i + 2] = r * (1 - std::cos(X / r));
    }
    std::vector<double> curvature;
    p.forces(nullptr, &curvature);
    int checked = 0;
    for (int e = 0; e < p.mesh.num_elements(); ++e) {
      if (p.mesh.neighbours[3 * e] < 0 || p.mesh.neighbours[3 * e + 1] < 0 || p.mesh.neighbours[3 * e + 2] < 0) continue;
      EXPECT_NEAR(curvature[3 * e] * r, 1.0, 0.01) << "element " << e << ", r " << r;
      EXPECT_NEAR(curvature[3 * e + 1] * r, 0.0, 0.01) << "element " << e << ", r " << r;
      EXPECT_NEAR(curvature[3 * e + 2] * r, 0.0, 0.01) << "element " << e << ", r " << r;
      ++checked;
    }
    EXPECT_GT(checked, 40);
  }
}

// Curvature patch test in two dimensions: a flat sheet deflected to
// w = 1/2 X^T K X (|K| ~ 1 1/m, deflections of 0.05 mm over the 20 x 10 mm
// patch) gives K, in the fibre frame, in every element with three
// neighbours, for bending along, across and oblique to the mesh lines and
// for pure twist, on the alternating, crossed and an irregular mesh
// (elements next to the held edges x = 0 and y = 0 left out).
// Tolerance 2e-3 of |K| (the hinge angles' geometric nonlinearity is of
// order (K h)^2 ~ 1e-5). The curvature from the hinge angles alone
// (K = sum l / (2 A) theta nu (x) nu) gives a pure twist spurious normal
// curvatures of order 1 on the alternating mesh.
TEST(ShellRfT3, ConstantCurvatureIsExactOnAnyMesh) {
  const double fibre = 0.5;
  const double f[2] = {std::cos(fibre), std::sin(fibre)}, m[2] = {-std::sin(fibre), std::cos(fibre)};
  const double fields[4][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {0.7, -0.4, 0.9}};  // Kxx, Kyy, Kxy
  for (int mesh = 0; mesh < 3; ++mesh) {
    // Mesh 2: interior nodes moved by up to 0.27 x 0.25 of a cell.
    Patch p(fibre, true, {8, 6}, mesh == 2, mesh == 1, 0.6);
    for (const auto& K : fields) {
      for (int i = 0; i < p.mesh.num_nodes(); ++i) {
        const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
        p.x[3 * i] = X;
        p.x[3 * i + 1] = Y;
        p.x[3 * i + 2] = 0.5 * (K[0] * X * X + K[1] * Y * Y) + K[2] * X * Y;
      }
      const double Km[3] = {K[0] * f[0] * f[0] + K[1] * f[1] * f[1] + 2 * K[2] * f[0] * f[1],
                            K[0] * m[0] * m[0] + K[1] * m[1] * m[1] + 2 * K[2] * m[0] * m[1],
                            K[0] * f[0] * m[0] + K[1] * f[1] * m[1] + K[2] * (f[0] * m[1] + f[1] * m[0])};
      std::vector<double> curvature;
      p.forces(nullptr, &curvature);
      int checked = 0;
      for (int e = 0; e < p.mesh.num_elements(); ++e) {
        // Elements with three neighbours, none of them on the clamped or
        // symmetry edges (x = 0, y = 0), whose held slope the field breaks.
        bool inner = true;
        for (int k = 0; k < 3; ++k) {
          const int nb = p.mesh.neighbours[3 * e + k];
          inner = inner && nb >= 0;
          for (int j = 0; inner && j < 3; ++j) inner = p.edges[3 * nb + j] == sdk::kEdgeFree;
        }
        if (!inner) continue;
        for (int r = 0; r < 3; ++r)
          EXPECT_NEAR(curvature[3 * e + r], Km[r], 2e-3) << "mesh " << mesh << ", element " << e << ", component " << r
                                                          << ", K = (" << K[0] << ", " << K[1] << ", " << K[2] << ")";
        ++checked;
      }
      EXPECT_GT(checked, 50) << "mesh " << mesh;
    }
  }
}


// In-plane bending of the fibres: a law of rigidity r1 as the ply's
// in-plane fibre bending, on a patch with no membrane law and a bending law
// of zero rigidity, so that the energy and forces are the in-plane term's.
std::unique_ptr<sdk::MaterialLaw> linear_bending(Patch& p, double r1, double r2 = 0.0) {
  const auto& br = p.registry.require(sdk::PluginKind::Material, "thermo_linear_bending", "/b");
  std::unique_ptr<sdk::MaterialLaw> law(reinterpret_cast<sdk::MaterialLaw* (*)()>(br.create)());
  law->configure(validate_params(json{{"beta1_B", r1}, {"beta2_B", r2}}, "/b", br.descriptor));
  return law;
}

// The internal forces are the derivative of the energy (central differences,
// h = 1e-8 m: truncation ~ h^2, round-off ~ 1e-16 E / h, both below 1e-6 of
// the largest force), for an in-plane and out-of-plane quadratic field on
// the irregular patch (its left edge clamped, its lower edge on the
// symmetry plane y = 0, fibres crossing both), in one range and split into
// 3 and 7; the same forces and energy whatever the ranges.
TEST(ShellRfT3, InPlaneBendingForcesAreTheDerivativeOfTheEnergy) {
  Patch p(0.5, true);
  auto zero = linear_bending(p, 0.0), in_plane = linear_bending(p, 2e-3);
  p.configure_with({}, zero.get(), in_plane.get());
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    p.x[3 * i] = X + 3.0 * X * Y - 2.0 * Y * Y;
    p.x[3 * i + 1] = Y + 4.0 * X * X - 1.5 * X * Y;
    p.x[3 * i + 2] = 1.0 * X * X + 0.5 * Y * Y + 1e-4 * std::sin(11 * i);
  }
  const double e1 = p.energy();
  EXPECT_GT(e1, 0.0);
  double fmax = 0;
  for (double v : p.forces()) fmax = std::max(fmax, std::abs(v));
  const double err = expect_forces_are_the_energys_derivative(p, 1e-6);
  std::printf("energy %.6e J, forces up to %.3e N, against the difference quotients %.2e N\n", e1, fmax, err);
}

// Rigid motions and homogeneous deformations bend no fibre: no energy, no
// force (to round-off), on the irregular patch with fibres at 0.5 rad and
// free edges (a clamp or a mirror would take a rotation as a slope: see
// InPlaneBendingAtClampedAndSymmetryEdges).
TEST(ShellRfT3, InPlaneBendingIsFreeUnderRigidMotionsAndHomogeneousDeformations) {
  Patch p(0.5, true);
  std::fill(p.edges.begin(), p.edges.end(), sdk::kEdgeFree);
  auto zero = linear_bending(p, 0.0), in_plane = linear_bending(p, 2e-3);
  p.configure_with({}, zero.get(), in_plane.get());
  // Reference: the forces of a curved state (the scale of "zero").
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    p.x[3 * i + 1] = Y + 4.0 * X * X;
  }
  double fref = 0;
  for (double v : p.forces()) fref = std::max(fref, std::abs(v));
  const double eref = p.energy();
  ASSERT_GT(fref, 0.0);
  const double c = std::cos(2.0), s = std::sin(2.0);
  const double rot[3][3] = {{c, -s, 0}, {s * 0.6, c * 0.6, 0.8}, {-s * 0.8, -c * 0.8, 0.6}};
  const double stretch[3][3] = {{1.02, 0.3, 0}, {-0.1, 0.97, 0}, {0.05, 0.02, 1}};
  const double t[3] = {0.3, -0.2, 0.1};
  for (const auto* R : {rot, stretch}) {
    p.map(R, t);
    double fmax = 0;
    for (double v : p.forces()) fmax = std::max(fmax, std::abs(v));
    EXPECT_LT(fmax, 1e-9 * fref);
    EXPECT_LT(std::abs(p.energy()), 1e-12 * eref);
  }
}

// The in-plane term is evaluated at every evaluation, whatever the bending
// weight: the same forces and energy at weights 1, 3 and 0 (the patch has
// no membrane law and a bending law of zero rigidity).
TEST(ShellRfT3, InPlaneBendingIgnoresTheBendingWeight) {
  Patch p(0.4, true);
  auto zero = linear_bending(p, 0.0), in_plane = linear_bending(p, 2e-3);
  p.configure_with({}, zero.get(), in_plane.get());
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
    p.x[3 * i + 1] = Y + 3.0 * X * X - X * Y;
  }
  std::vector<double> f1, f3, f0;
  p.bending_weight = 1.0;
  const double e1 = p.evaluate(f1);
  p.bending_weight = 3.0;
  const double e3 = p.evaluate(f3);
  p.bending_weight = 0.0;
  const double e0 = p.evaluate(f0);
  double scale = 0;
  for (double v : f1) scale = std::max(scale, std::abs(v));
  EXPECT_GT(scale, 0.0);
  EXPECT_EQ(f3, f1);
  EXPECT_EQ(f0, f1);
  EXPECT_GT(e1, 0.0);
  EXPECT_EQ(e3, e1);
  EXPECT_EQ(e0, e1);
}

// The ghosts of boundary edges for the in-plane term, on the regular 4 x 3
// patch (cells hx = 5 mm by hy = 3.33 mm, one triangle of each boundary cell
// on the boundary) with a homogeneous deformation F: every slope jump
// between elements is zero, so the energy is that of the boundary slopes
// alone. At a clamped edge (the left, fibres along x, crossing it) the
// ghost is the held grip: none for an F that keeps the fibre's initial
// direction (F e_x = e_x), and for a shear y += g x the slope
// s = g / sqrt(1 + g^2) (the fibre's rotation), each boundary element's
// K11 = l s / A0 = 2 s / hx: energy 3 (hx hy / 2) R / 2 (2 s / hx)^2 =
// 3 R s^2 hy / hx. On the symmetry plane y = 0 (the lower edge, fibres
// along y) the ghost is the mirrored element: none for a stretch along the
// axes, and for a shear x += g y the slope half the jump to the mirror,
// the same s: energy 4 R s^2 hx / hy. Both to round-off.
TEST(ShellRfT3, InPlaneBendingAtClampedAndSymmetryEdges) {
  const double rig = 2e-3, g = 0.05, s = g / std::sqrt(1 + g * g), hx = 0.005, hy = 0.01 / 3;
  for (const bool clamp : {true, false}) {
    Patch p(clamp ? 0.0 : M_PI / 2, true, {4, 3}, false);
    for (int e = 0; e < p.mesh.num_elements(); ++e)
      for (int k = 0; k < 3; ++k)
        if (p.edges[3 * e + k] != (clamp ? sdk::kEdgeClamped : sdk::kEdgeSymmetryX + 1)) p.edges[3 * e + k] = sdk::kEdgeFree;
    auto zero = linear_bending(p, 0.0), in_plane = linear_bending(p, rig);
    p.configure_with({}, zero.get(), in_plane.get());
    const auto apply = [&](double a, double b, double c, double d) {  // x = a X + b Y, y = c X + d Y
      for (int i = 0; i < p.mesh.num_nodes(); ++i) {
        const double X = p.mesh.x[3 * i], Y = p.mesh.x[3 * i + 1];
        p.x[3 * i] = a * X + b * Y;
        p.x[3 * i + 1] = c * X + d * Y;
      }
    };
    // Allowed: F e_x = e_x at the clamp; a stretch along the axes at the mirror.
    if (clamp) apply(1.0, 0.3, 0.0, 0.9);
    else apply(1.02, 0.0, 0.0, 0.97);
    const double free_energy = p.energy();
    double fmax = 0;
    for (const double v : p.forces()) fmax = std::max(fmax, std::abs(v));
    // A slope at the boundary.
    if (clamp) apply(1.0, 0.0, g, 1.0);
    else apply(1.0, g, 0.0, 1.0);
    const double energy = p.energy(), exact = clamp ? 3 * rig * s * s * hy / hx : 4 * rig * s * s * hx / hy;
    double fref = 0;
    for (const double v : p.forces()) fref = std::max(fref, std::abs(v));
    std::printf("%s: allowed F %.2e J, %.2e N; slope %.3f: %.9e J, closed form %.9e J\n", clamp ? "clamp" : "mirror",
                free_energy, fmax, s, energy, exact);
    EXPECT_LT(std::abs(free_energy), 1e-12 * exact);
    EXPECT_LT(fmax, 1e-9 * fref);
    EXPECT_NEAR(energy, exact, 1e-12 * exact);
  }
}

// Fibres bent into concentric circles in the plane: the fibre at Y becomes
// the circle of radius rho = r0 + Y about (0, -r0), x = rho sin(X / rho),
// y = -r0 + rho cos(X / rho) (each fibre keeps its length; its curvature is
// 1 / rho). The energy against the closed form R/2 int kappa^2 dA (Gauss
// points, kappa = d2x/da0^2 . m) over the elements that carry the term (all
// but those with an edge without a neighbour that the fibres cross), on
// two meshes (h / r0 = 0.05 and 0.025). Fibres at 30 degrees to the mesh
// lines: within 0.1 % and 0.03 %, the error at least 3 times smaller on the
// finer mesh (measured 0.048 / 0.012 %: Morley's curvature is exact for
// quadratic fields). Fibres along the mesh lines: within 2 % and 1 %, the
// error at least 1.8 times smaller (measured 1.24 / 0.61 %): along the
// free edges parallel to the fibres, neighbouring elements without a
// quadratic of their own share their slopes half and half, an error of
// first order in a band one element wide.
TEST(ShellRfT3, InPlaneBendingOfConcentricFibresAgainstTheClosedForm) {
  const double r0 = 0.05, rig = 2e-3;
  for (const double angle : {0.0, M_PI / 6}) {
    const double ca = std::cos(angle), sa = std::sin(angle);
    // The map from the mesh's coordinates: X along the fibres, Y across.
    const auto phi = [&](double X0, double Y0) {
      const double X = ca * X0 + sa * Y0, Y = -sa * X0 + ca * Y0;
      const double rho = r0 + Y, u = rho * std::sin(X / rho), v = -r0 + rho * std::cos(X / rho);
      return std::array<double, 2>{ca * u - sa * v, sa * u + ca * v};
    };
    double errs[2] = {};
    int level = 0;
    for (const std::array<int, 2> div : {std::array<int, 2>{8, 4}, std::array<int, 2>{16, 8}}) {
      Patch p(angle, true, div, false);
      std::fill(p.edges.begin(), p.edges.end(), sdk::kEdgeFree);  // the map is neither mirrored nor held
      auto zero = linear_bending(p, 0.0), in_plane = linear_bending(p, rig);
      p.configure_with({}, zero.get(), in_plane.get());
      for (int i = 0; i < p.mesh.num_nodes(); ++i) {
        const auto xy = phi(p.mesh.x[3 * i], p.mesh.x[3 * i + 1]);
        p.x[3 * i] = xy[0];
        p.x[3 * i + 1] = xy[1];
        p.x[3 * i + 2] = 0.0;
      }
      const double energy = p.energy();
      // Six-point Gauss rule (degree 4) on each triangle; derivatives of
      // the map by central differences (step 1e-5 m: error ~1e-8 of kappa).
      const double gw[2] = {0.223381589678011, 0.109951743655322}, ga[2] = {0.445948490915965, 0.091576213509771};
      const double dh = 1e-5, a0[2] = {ca, sa};
      double exact = 0;
      for (int e = 0; e < p.mesh.num_elements(); ++e) {
        // Elements with an edge without a neighbour that the fibres cross
        // carry no term.
        bool off = false;
        const int* t = &p.mesh.triangles[3 * e];
        double P[3][2];
        for (int a = 0; a < 3; ++a) P[a][0] = p.mesh.x[3 * t[a]], P[a][1] = p.mesh.x[3 * t[a] + 1];
        for (int k = 0; k < 3; ++k) {
          if (p.mesh.neighbours[3 * e + k] >= 0) continue;
          const double ex = P[(k + 2) % 3][0] - P[(k + 1) % 3][0], ey = P[(k + 2) % 3][1] - P[(k + 1) % 3][1];
          const double nf = (ey * a0[0] - ex * a0[1]) / std::hypot(ex, ey);
          off = off || nf * nf > 1e-6;
        }
        if (off) continue;
        const double area = 0.5 * std::abs((P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[2][0] - P[0][0]) * (P[1][1] - P[0][1]));
        for (int g = 0; g < 2; ++g)
          for (int r = 0; r < 3; ++r) {
            double l[3] = {ga[g], ga[g], ga[g]};
            l[r] = 1 - 2 * ga[g];
            const double X0 = l[0] * P[0][0] + l[1] * P[1][0] + l[2] * P[2][0];
            const double Y0 = l[0] * P[0][1] + l[1] * P[1][1] + l[2] * P[2][1];
            // Second derivative of the map along directions d1, d2.
            const auto d2 = [&](const double* d1, const double* dd2) {
              std::array<double, 2> out{};
              const auto at = [&](double s1, double s2) { return phi(X0 + dh * (s1 * d1[0] + s2 * dd2[0]), Y0 + dh * (s1 * d1[1] + s2 * dd2[1])); };
              const auto pp = at(1, 1), pm = at(1, -1), mp = at(-1, 1), mm = at(-1, -1);
              for (int c = 0; c < 2; ++c) out[c] = (pp[c] - pm[c] - mp[c] + mm[c]) / (4 * dh * dh);
              return out;
            };
            const std::array<double, 2> kv = d2(a0, a0);
            const auto fp = phi(X0 + dh * a0[0], Y0 + dh * a0[1]), fm = phi(X0 - dh * a0[0], Y0 - dh * a0[1]);
            double fx = fp[0] - fm[0], fy = fp[1] - fm[1];
            const double fl = std::hypot(fx, fy);
            fx /= fl, fy /= fl;
            const double kappa = -kv[0] * fy + kv[1] * fx;  // k . (z x f)
            exact += gw[g] * area * 0.5 * rig * kappa * kappa;
          }
      }
      errs[level] = std::abs(energy / exact - 1);
      std::printf("fibres at %.0f deg, %dx%d cells: energy %.6e J, closed form %.6e J, %.3f %% apart\n",
                  angle * 180 / M_PI, div[0], div[1], energy, exact, 100 * errs[level]);
      ++level;
    }
    const bool along = angle == 0.0;
    EXPECT_LT(errs[0], along ? 0.02 : 0.001) << "fibres at " << angle;
    EXPECT_LT(errs[1], along ? 0.01 : 0.0003) << "fibres at " << angle;
    EXPECT_LT((along ? 1.8 : 3.0) * errs[1], errs[0]) << "fibres at " << angle;
  }
}

}  // namespace
}  // namespace ts

// The hinge angles' atan2: within two roundings of the library's on the
// rational approximation's range (tangents up to 0.66, over twelve decades),
// the library itself beyond it (x <= 0, larger angles), signs kept.
TEST(Element, Atan2SmallMatchesTheLibrary) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0;
  for (int i = 0; i < 2000000; ++i) {
    const double x = 1e-3 + u(rng) * 1e3, r = (u(rng) < 0.5 ? -0.66 : 0.66) * u(rng) * std::pow(10.0, -12 * u(rng));
    const double y = r * x, ref = std::atan2(y, x);
    worst = std::max(worst, std::abs(ts::sdk::atan2_small(y, x) - ref) / std::abs(ref));
  }
  EXPECT_LT(worst, 4.5e-16);
  std::printf("atan2_small: largest relative difference from std::atan2 %.3g\n", worst);
  for (const auto& [y, x] : std::vector<std::pair<double, double>>{{0.7, 1.0}, {-0.7, 1.0}, {1.0, -1.0}, {-1.0, -1.0},
                                                                    {0.3, -1.0}, {1.0, 0.0}, {-1.0, 0.0}, {0.0, -1.0}})
    EXPECT_EQ(ts::sdk::atan2_small(y, x), std::atan2(y, x)) << y << ", " << x;
  EXPECT_EQ(ts::sdk::atan2_small(0.0, 1.0), 0.0);
  EXPECT_TRUE(std::isnan(ts::sdk::atan2_small(std::nan(""), 1.0)));
}
