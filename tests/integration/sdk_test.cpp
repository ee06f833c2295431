// The plugin SDK as an in-house team uses it: install ThermoStamp into a
// prefix, build examples/plugin-template against it with find_package,
// run the example's own test, load the plugin through
// THERMOSTAMP_PLUGIN_PATH and compare its job with the analytic answer.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "job/job.hpp"
#include "test_support.hpp"

namespace ts::test {
namespace {

int sh(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// Installs the build into DIR/prefix (once per DIR), builds the template
// with the C++ compiler CXX in DIR/BUILD_NAME, runs the example's own test
// and its job through THERMOSTAMP_PLUGIN_PATH, and checks the end force
// against the homogeneous solution.
void template_against_installed_sdk(const std::filesystem::path& dir, const std::string& cxx,
                                    const std::string& build_name) {
  const auto prefix = dir / "prefix", build = dir / build_name;
  const std::string log = " >>" + (dir / "log.txt").string() + " 2>&1";
  if (!std::filesystem::exists(prefix / "bin" / "thermostamp")) {
    ASSERT_EQ(sh("cmake --install '" + binary_dir().string() + "' --prefix '" + prefix.string() + "'" + log), 0);
  }
  ASSERT_TRUE(std::filesystem::exists(prefix / "lib" / "cmake" / "ThermoStamp" / "ThermoStampConfig.cmake"));
  const auto src = source_dir() / "examples" / "plugin-template";
  ASSERT_EQ(sh("cmake -S '" + src.string() + "' -B '" + build.string() + "' -DCMAKE_PREFIX_PATH='" + prefix.string() +
               "' -DCMAKE_CXX_COMPILER='" + cxx + "'" + log),
            0);
  ASSERT_EQ(sh("cmake --build '" + build.string() + "'" + log), 0);
  EXPECT_EQ(sh("ctest --test-dir '" + build.string() + "'" + log), 0) << "the example's own test";
  ASSERT_TRUE(std::filesystem::exists(build / "thermostamp_material_neo_hookean_membrane.so"));
  // Run its job with the installed executable, the plugin found through the environment.
  const auto out = dir / ("results-" + build_name);
  ASSERT_EQ(sh("THERMOSTAMP_PLUGIN_PATH='" + build.string() + "' '" + (prefix / "bin" / "thermostamp").string() +
               "' run '" + (src / "job.json").string() + "' --out '" + out.string() + "' --quiet" + log),
            0);
  const json s = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["status"], "completed");
  const auto loaded = s["plugins_loaded"].get<std::vector<std::string>>();
  EXPECT_NE(std::find(loaded.begin(), loaded.end(), "material/neo_hookean_membrane"), loaded.end());
  // Homogeneous solution: F = diag(a, d), S22 = 0 solved for d, force W a S11.
  const double mu = 1.0e4, lambda = 2.0e4, W = 0.02, a = 1.0 + 0.05 * 0.2 / 0.1;
  double d = 1.0;
  for (int it = 0; it < 100; ++it) {
    auto f = [&](double dd) { return mu * (1 - 1 / (dd * dd)) + lambda * std::log(a * a * dd * dd) / (dd * dd); };
    d -= f(d) / ((f(d + 1e-8) - f(d - 1e-8)) / 2e-8);
  }
  const double s11 = mu * (1 - 1 / (a * a)) + lambda * std::log(a * a * d * d) / (a * a);
  const double force = W * a * s11;
  const double measured = s["reactions_N"][2]["force"][0].get<double>();
  EXPECT_NEAR(measured / force, 1.0, 0.01) << measured << " N vs " << force << " N";
  std::printf("neo-Hookean strip (plugin built with %s): end force %.5g N, homogeneous %.5g N (lateral stretch %.5f)\n",
              cxx.c_str(), measured, force, d);
}

TEST(Sdk, OutOfTreePluginAgainstTheInstalledSdk) {
  const auto dir = temp_dir("sdk");
  template_against_installed_sdk(dir, THERMOSTAMP_TEST_CXX_COMPILER, "example-build");
  // The installed report script is found next to the installed executable.
  EXPECT_TRUE(std::filesystem::exists(dir / "prefix" / "share" / "thermostamp" / "scripts" / "report.py"));
}

// A team may build its plugins with another compiler than the one that
// built ThermoStamp (both use the system's C++ library): the template built
// with Clang when ThermoStamp was built with GCC, and the reverse. Skipped
// where the other compiler is not installed (scripts/check-clang installs
// Clang).
TEST(Sdk, PluginBuiltWithTheOtherCompiler) {
  const std::string id = THERMOSTAMP_TEST_CXX_COMPILER_ID;
  const std::string other = id == "Clang" ? "g++" : "clang++";
  if (sh("command -v " + other + " >/dev/null 2>&1") != 0) GTEST_SKIP() << other << " is not installed";
  template_against_installed_sdk(temp_dir("sdk_other_compiler"), other, "example-build-" + other);
}

}  // namespace
}  // namespace ts::test
