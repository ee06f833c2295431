#include <gtest/gtest.h>

#include "job/job.hpp"
#include "test_support.hpp"

namespace ts {
namespace {

TEST(DidYouMean, SuggestsCloseWordsOnly) {
  EXPECT_EQ(did_you_mean("solver", {"solvers", "output", "parts"}), "did you mean 'solvers'?");
  EXPECT_EQ(did_you_mean("thicknes", {"thickness", "material"}), "did you mean 'thickness'?");
  EXPECT_EQ(did_you_mean("zzzzzz", {"thickness", "material"}), "");
}

TEST(Set, OverridesByPathWithWildcards) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  d["parts"].push_back(d["parts"][0]);
  d["parts"][1]["name"] = "b";
  apply_set(d, "solvers.thermal.splitter=shell2d");
  apply_set(d, "parts.*.thickness_layers=20");
  apply_set(d, "parts.0.thickness=0.001");
  EXPECT_EQ(d["solvers"]["thermal"]["splitter"], "shell2d");
  EXPECT_EQ(d["parts"][0]["thickness_layers"], 20);
  EXPECT_EQ(d["parts"][1]["thickness_layers"], 20);
  EXPECT_DOUBLE_EQ(d["parts"][0]["thickness"].get<double>(), 0.001);
  EXPECT_THROW(apply_set(d, "parts.7.thickness=1"), JobError);
  EXPECT_THROW(apply_set(d, "novalue"), JobError);
}

std::string job_error(const json& d) {
  try {
    parse_job(d, "job.json");
  } catch (const JobError& e) {
    return e.what();
  }
  return "";
}

TEST(ParseJob, DefaultsAreFilled) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  d["parts"][0].erase("thickness_layers");
  const Job j = parse_job(d, "job.json");
  EXPECT_EQ(j.parts[0].thickness_layers, 8);
  EXPECT_EQ(j.parts[0].element, "shell_rf_t3");
  EXPECT_EQ(j.parts[0].fibre_direction[0], 1.0);
}

TEST(ParseJob, ErrorsCarryThePointer) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  json bad = d;
  bad["parts"][0]["thickness"] = -0.001;
  EXPECT_EQ(job_error(bad).rfind("/parts/0/thickness: must be > 0", 0), 0u) << job_error(bad);
  bad = d;
  bad["parts"][0]["thickness_layers"] = 0;
  EXPECT_EQ(job_error(bad).rfind("/parts/0/thickness_layers: must be >= 1", 0), 0u) << job_error(bad);
  bad = d;
  bad["parts"][0]["material"] = "pa6";
  EXPECT_NE(job_error(bad).find("/parts/0/material: unknown material 'pa6'"), std::string::npos);
  bad = d;
  bad["solver"] = 1;
  EXPECT_NE(job_error(bad).find("did you mean 'solvers'"), std::string::npos) << job_error(bad);
  bad = d;
  bad["parts"][0]["thickness"] = "thin";
  EXPECT_NE(job_error(bad).find("/parts/0/thickness: expected a number, found a string"), std::string::npos);
  bad = d;
  bad["output"]["probes"][0]["quantities"] = {"temperature_profil"};
  EXPECT_NE(job_error(bad).find("did you mean 'temperature_profile'"), std::string::npos);
}

}  // namespace
}  // namespace ts
