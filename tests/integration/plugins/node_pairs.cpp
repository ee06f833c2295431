// A contact handler that ties node i of the pair's first ply to node i of
// the second (plies meshed alike) with a linear spring, k times the change
// of their offset since the start. It computes the whole pair in each call
// (ContactHandler::sides() stays 1) and writes forces on both plies, so that
// the kernel's handling of the forces a pair puts on its second ply can be
// tested under every contact schedule.
#include <thermostamp/sdk/plugin.hpp>

namespace {

class NodePairs final : public ts::sdk::ContactHandler {
 public:
  ts::sdk::Status configure(const ts::sdk::Params& p, const ts::sdk::ContactPair& pair,
                            std::span<const ts::sdk::PartView> parts, std::span<const ts::sdk::ToolView>) override {
    if (pair.second.type != ts::sdk::BodyRef::Type::Part)
      return ts::sdk::Status::failure("node_pairs ties two plies");
    a_ = pair.first.index;
    b_ = pair.second.index;
    if (parts[a_].num_nodes != parts[b_].num_nodes) return ts::sdk::Status::failure("node_pairs: plies meshed apart");
    k_ = p.real("stiffness");
    return ts::sdk::Status::success();
  }
  ts::sdk::Status thermal_contacts(std::span<const ts::sdk::PartView>, std::span<const ts::sdk::ToolView>,
                                   std::span<const std::span<const double>>, ts::sdk::ThermalContactMap&) override {
    return ts::sdk::Status::success();
  }
  ts::sdk::Status node_stiffness(std::span<const std::span<const double>>,
                                 std::span<const std::span<double>> k) override {
    for (double& v : k[a_]) v += k_;
    for (double& v : k[b_]) v += k_;
    return ts::sdk::Status::success();
  }
  ts::sdk::Status contact_forces(const ts::sdk::ContactForceInput& in, ts::sdk::ContactForceOutput& out) override {
    const ts::sdk::PartView& a = in.parts[a_];
    const ts::sdk::PartView& b = in.parts[b_];
    for (int i = 0; i < a.num_nodes; ++i) {
      double e = 0;
      for (int d = 0; d < 3; ++d) {
        const int k = 3 * i + d;
        const double stretch = (b.x[k] - a.x[k]) - (b.x0[k] - a.x0[k]);
        out.force[a_][k] += k_ * stretch;
        out.force[b_][k] -= k_ * stretch;
        e += 0.5 * k_ * stretch * stretch;
      }
      out.energy += e;
    }
    return ts::sdk::Status::success();
  }

 private:
  int a_ = 0, b_ = 0;
  double k_ = 0;
};

ts::sdk::ContactHandler* create() { return new NodePairs(); }

void register_all(ts::sdk::Registrar& r) {
  ts::sdk::Descriptor d;
  d.kind = ts::sdk::PluginKind::Contact;
  d.name = "node_pairs";
  d.version = "0.0.1";
  d.summary = "test plugin: node i of one ply tied to node i of the other by a linear spring";
  d.params = {ts::sdk::real_param("stiffness", "1000", "N/m", "spring stiffness per node pair", 0.0)};
  r.add_contact(d, &create);
}

}  // namespace

THERMOSTAMP_PLUGIN("contact_node_pairs", "0.0.1", register_all)
