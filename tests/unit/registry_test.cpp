#include <gtest/gtest.h>

#include "plugins/registry.hpp"

namespace ts {
namespace {

sdk::Descriptor demo() {
  sdk::Descriptor d;
  d.kind = sdk::PluginKind::Material;
  d.name = "demo";
  d.params = {sdk::real_param("stiffness", "", "N/m", "membrane stiffness", 0.0, 1e12, true),
              sdk::real_param("ratio", "0.5", "-", "a ratio", 0.0, 1.0),
              sdk::choice_param("mode", "a", {"a", "b"}, "a mode"),
              sdk::int_param("count", "3", "a count", 1, 10)};
  return d;
}

std::string error_of(const json& j) {
  try {
    validate_params(j, "/materials/m/membrane", demo(), {"law"});
  } catch (const JobError& e) {
    return e.what();
  }
  return "";
}

TEST(ValidateParams, DefaultsTypesBounds) {
  const sdk::Params p = validate_params(json{{"law", "demo"}, {"stiffness", 5.0}}, "/m", demo(), {"law"});
  EXPECT_EQ(p.real("stiffness"), 5.0);
  EXPECT_EQ(p.real("ratio"), 0.5);
  EXPECT_EQ(p.text("mode"), "a");
  EXPECT_EQ(p.integer("count"), 3);
  EXPECT_NE(error_of({{"ratio", 0.1}}).find("/materials/m/membrane/stiffness: required"), std::string::npos);
  EXPECT_NE(error_of({{"stiffness", -1.0}}).find("/materials/m/membrane/stiffness: must be > 0 N/m"), std::string::npos)
      << error_of({{"stiffness", -1.0}});
  EXPECT_NE(error_of({{"stiffness", 1.0}, {"stifness", 1.0}}).find("did you mean 'stiffness'"), std::string::npos);
  EXPECT_NE(error_of({{"stiffness", 1.0}, {"mode", "c"}}).find("valid values are: a, b"), std::string::npos);
  EXPECT_NE(error_of({{"stiffness", 1.0}, {"count", 2.5}}).find("expected an integer"), std::string::npos);
  EXPECT_NE(error_of({{"stiffness", "1"}}).find("expected a number, found a string"), std::string::npos);
}

TEST(Registry, FindsInTreePluginsAndListsValidNames) {
  PluginRegistry r;
  const auto& rec = r.require(sdk::PluginKind::Thermal, "adi", "/solvers/thermal/splitter");
  EXPECT_EQ(rec.descriptor.name, "adi");
  EXPECT_EQ(r.loaded_names(), std::vector<std::string>{"thermal/adi"});
  try {
    r.require(sdk::PluginKind::Thermal, "adii", "/solvers/thermal/splitter");
    FAIL();
  } catch (const JobError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("/solvers/thermal/splitter: unknown thermal plugin 'adii'; did you mean 'adi'?"), std::string::npos) << w;
    EXPECT_NE(w.find("valid types are:"), std::string::npos);
    EXPECT_NE(w.find("layered3d"), std::string::npos);
  }
}

// Each of the project's plugin libraries holds one plugin, and the version
// its descriptor shows (`thermostamp plugins`, the job reference) is the
// version the library declares.
TEST(Registry, EachPluginShowsItsLibrarysVersion) {
  PluginRegistry r;
  r.load_all();
  EXPECT_TRUE(r.load_errors().empty());
  const auto all = r.all();
  EXPECT_GE(all.size(), 9u);
  for (const PluginRecord* rec : all)
    EXPECT_EQ(rec->descriptor.version, rec->library_version) << rec->descriptor.name << " from " << rec->library;
}

}  // namespace
}  // namespace ts
