// penalty_node_surface: node-to-surface contact with shell thickness
// (physics.md section 4). This version provides the thermal side: which
// faces of a ply touch a tool or another ply (gap between the facing shell
// surfaces, mid-surface +- h/2, at most gap_tolerance), with the contact
// conductance. Ply/ply exchange is returned as conservative links.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include <thermostamp/sdk/math.hpp>
#include <thermostamp/sdk/plugin.hpp>

namespace ts::contact {
namespace {

using sdk::Vec3;

// Unit normals of the elements and (area-weighted) of the nodes.
void normals(const sdk::PartView& p, std::vector<double>& en, std::vector<double>& nn) {
  en.assign(3 * p.num_elements, 0.0);
  nn.assign(3 * p.num_nodes, 0.0);
  for (int e = 0; e < p.num_elements; ++e) {
    const int* t = &p.triangles[3 * e];
    const Vec3 a = sdk::load3(p.x.data(), t[0]), b = sdk::load3(p.x.data(), t[1]), c = sdk::load3(p.x.data(), t[2]);
    const Vec3 n = sdk::cross(sdk::sub(b, a), sdk::sub(c, a));
    const Vec3 u = sdk::normalized(n);
    for (int d = 0; d < 3; ++d) en[3 * e + d] = u[d];
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) nn[3 * t[k] + d] += n[d];
  }
  for (int i = 0; i < p.num_nodes; ++i) {
    const Vec3 u = sdk::normalized(sdk::load3(nn.data(), i));
    for (int d = 0; d < 3; ++d) nn[3 * i + d] = u[d];
  }
}

// Uniform bucket grid over the bounding boxes of a ply's triangles.
class TriangleGrid {
 public:
  void build(const sdk::PartView& p, double margin) {
    lo_ = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()};
    Vec3 hi = {-lo_[0], -lo_[1], -lo_[2]};
    double h = 0;
    for (int e = 0; e < p.num_elements; ++e)
      for (int k = 0; k < 3; ++k) {
        const Vec3 a = sdk::load3(p.x.data(), p.triangles[3 * e + k]);
        const Vec3 b = sdk::load3(p.x.data(), p.triangles[3 * e + (k + 1) % 3]);
        h = std::max(h, sdk::norm(sdk::sub(a, b)));
        for (int d = 0; d < 3; ++d) {
          lo_[d] = std::min(lo_[d], a[d] - margin);
          hi[d] = std::max(hi[d], a[d] + margin);
        }
      }
    cell_ = std::max(h + 2 * margin, 1e-12);
    for (int d = 0; d < 3; ++d) n_[d] = std::max(1, static_cast<int>(std::ceil((hi[d] - lo_[d]) / cell_)) + 1);
    buckets_.clear();
    for (int e = 0; e < p.num_elements; ++e) {
      Vec3 blo = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
      Vec3 bhi = {-blo[0], -blo[1], -blo[2]};
      for (int k = 0; k < 3; ++k) {
        const Vec3 a = sdk::load3(p.x.data(), p.triangles[3 * e + k]);
        for (int d = 0; d < 3; ++d) {
          blo[d] = std::min(blo[d], a[d] - margin);
          bhi[d] = std::max(bhi[d], a[d] + margin);
        }
      }
      int c0[3], c1[3];
      for (int d = 0; d < 3; ++d) {
        c0[d] = cell_of(blo[d], d);
        c1[d] = cell_of(bhi[d], d);
      }
      for (int i = c0[0]; i <= c1[0]; ++i)
        for (int j = c0[1]; j <= c1[1]; ++j)
          for (int k = c0[2]; k <= c1[2]; ++k) buckets_[key(i, j, k)].push_back(e);
    }
  }
  const std::vector<int>* candidates(const Vec3& x) const {
    const auto it = buckets_.find(key(cell_of(x[0], 0), cell_of(x[1], 1), cell_of(x[2], 2)));
    return it == buckets_.end() ? nullptr : &it->second;
  }

 private:
  int cell_of(double v, int d) const { return std::clamp(static_cast<int>((v - lo_[d]) / cell_), 0, n_[d] - 1); }
  long long key(int i, int j, int k) const { return (static_cast<long long>(k) * n_[1] + j) * n_[0] + i; }
  Vec3 lo_{};
  double cell_ = 1;
  int n_[3] = {1, 1, 1};
  std::unordered_map<long long, std::vector<int>> buckets_;
};

class PenaltyNodeSurface final : public sdk::ContactHandler {
 public:
  sdk::Status configure(const sdk::Params& params, const sdk::ContactPair& pair, std::span<const sdk::PartView> parts,
                        std::span<const sdk::ToolView>) override {
    return sdk::guarded([&] {
      pair_ = pair;
      conductance_ = params.real("conductance");
      gap_tol_ = params.real("gap_tolerance");
      if (gap_tol_ < 0) {  // default: 1 % of the thinner ply
        double h = parts[pair.first.index].thickness;
        if (pair.second.type == sdk::BodyRef::Type::Part) h = std::min(h, parts[pair.second.index].thickness);
        gap_tol_ = 0.01 * h;
      }
      return sdk::Status::success();
    });
  }

  sdk::Status thermal_contacts(std::span<const sdk::PartView> parts, std::span<const sdk::ToolView> tools,
                               std::span<const std::span<const double>> node_area,
                               sdk::ThermalContactMap& out) override {
    return sdk::guarded([&] {
      const sdk::PartView& a = parts[pair_.first.index];
      normals(a, en_a_, nn_a_);
      if (conductance_ <= 0) return sdk::Status::success();
      if (pair_.second.type == sdk::BodyRef::Type::Tool) {
        const sdk::ToolView& tool = tools[pair_.second.index];
        dist_.resize(a.num_nodes);
        tn_.resize(3 * a.num_nodes);
        tool.query(tool.context, a.num_nodes, a.x.data(), dist_.data(), tn_.data());
        for (int i = 0; i < a.num_nodes; ++i) {
          const double c = sdk::dot(sdk::load3(tn_.data(), i), sdk::load3(nn_a_.data(), i));
          // A tool whose outward normal opposes the ply normal lies above it.
          const int face = c < 0 ? sdk::kTop : sdk::kBottom;
          const double gap = dist_[i] - 0.5 * a.thickness;
          if (gap <= gap_tol_) out.tool_contacts.push_back({a.index, i, face, tool.index, conductance_});
        }
        return sdk::Status::success();
      }
      const sdk::PartView& b = parts[pair_.second.index];
      normals(b, en_b_, nn_b_);
      const double reach = 0.5 * (a.thickness + b.thickness) + gap_tol_;
      grid_.build(b, reach);
      const double eps = 1e-9;
      for (int i = 0; i < a.num_nodes; ++i) {
        const Vec3 x = sdk::load3(a.x.data(), i);
        const auto* cand = grid_.candidates(x);
        if (!cand) continue;
        int best = -1;
        double best_gap = std::numeric_limits<double>::infinity(), best_d = 0, best_w[3] = {0, 0, 0};
        for (int e : *cand) {
          if (a.index == b.index) {  // self contact: skip the node's own elements
            const int* t = &b.triangles[3 * e];
            if (t[0] == i || t[1] == i || t[2] == i) continue;
          }
          const int* t = &b.triangles[3 * e];
          const Vec3 p0 = sdk::load3(b.x.data(), t[0]), p1 = sdk::load3(b.x.data(), t[1]),
                     p2 = sdk::load3(b.x.data(), t[2]);
          const Vec3 n = sdk::load3(en_b_.data(), e);
          const double d = sdk::dot(sdk::sub(x, p0), n);
          const Vec3 xp = sdk::sub(x, sdk::scale(n, d));
          const double two_a = sdk::dot(sdk::cross(sdk::sub(p1, p0), sdk::sub(p2, p0)), n);
          const double w0 = sdk::dot(sdk::cross(sdk::sub(p1, xp), sdk::sub(p2, xp)), n) / two_a;
          const double w1 = sdk::dot(sdk::cross(sdk::sub(p2, xp), sdk::sub(p0, xp)), n) / two_a;
          const double w2 = 1.0 - w0 - w1;
          if (w0 < -eps || w1 < -eps || w2 < -eps) continue;
          const double gap = std::abs(d) - 0.5 * (a.thickness + b.thickness);
          if (gap > gap_tol_ || gap >= best_gap) continue;
          best = e;
          best_gap = gap;
          best_d = d;
          best_w[0] = std::max(0.0, w0);
          best_w[1] = std::max(0.0, w1);
          best_w[2] = std::max(0.0, w2);
        }
        if (best < 0) continue;
        const double s = best_w[0] + best_w[1] + best_w[2];
        sdk::HeatLink l;
        l.part_a = a.index;
        l.node_a = i;
        l.part_b = b.index;
        for (int j = 0; j < 3; ++j) {
          l.nodes_b[j] = b.triangles[3 * best + j];
          l.w_b[j] = best_w[j] / s;
        }
        const double c = sdk::dot(sdk::load3(nn_a_.data(), i), sdk::load3(en_b_.data(), best));
        if (best_d >= 0) {  // node above the target: target's top face, node's face looking down
          l.face_b = sdk::kTop;
          l.face_a = c > 0 ? sdk::kBottom : sdk::kTop;
        } else {
          l.face_b = sdk::kBottom;
          l.face_a = c > 0 ? sdk::kTop : sdk::kBottom;
        }
        l.conductance = conductance_ * node_area[a.index][i];
        out.links.push_back(l);
      }
      return sdk::Status::success();
    });
  }

 private:
  sdk::ContactPair pair_;
  double conductance_ = 0, gap_tol_ = 0;
  std::vector<double> en_a_, nn_a_, en_b_, nn_b_, dist_, tn_;
  TriangleGrid grid_;
};

sdk::ContactHandler* create() { return new PenaltyNodeSurface(); }

void register_all(sdk::Registrar& r) {
  sdk::Descriptor d;
  d.kind = sdk::PluginKind::Contact;
  d.name = "penalty_node_surface";
  d.version = "0.1.0";
  d.summary = "Node-to-surface penalty contact with shell thickness; carries heat between touching faces";
  d.params = {
      sdk::real_param("penalty", "1.0e9", "Pa/m", "contact pressure per unit penetration", 0.0),
      sdk::real_param("friction", "0.0", "-", "Coulomb friction coefficient", 0.0),
      sdk::real_param("conductance", "1000.0", "W/(m^2 K)",
                      "thermal contact conductance h_c (1 / contact resistance); 0 switches the heat exchange off",
                      0.0),
      sdk::real_param("gap_tolerance", "-1", "m",
                      "largest gap between facing shell surfaces still counted as touching when mechanics is off; "
                      "negative = 1 % of the thinner ply"),
      sdk::bool_param("self", false, "allow a body in contact with itself"),
  };
  d.example = R"({ "type": "contact", "handler": "penalty_node_surface", "between": ["die", "ply_bottom"], "conductance": 1000.0 })";
  r.add_contact(d, &create);
}

}  // namespace
}  // namespace ts::contact

THERMOSTAMP_PLUGIN("contact_penalty_node_surface", "0.1.0", ts::contact::register_all)
