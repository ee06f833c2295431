#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "job/job.hpp"
#include "plugins/registry.hpp"
#include "solve/simulation.hpp"
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


// materials.*.mixture: the ply's thermal data from its matrix and fibres.
// The rules (density and rho c parallel, k11 parallel, k22 = k33 in
// series) written out here from the constituents, and the values of the
// card pa66_cf_ud.json, which are those rules rounded.
const MaterialDef& mixture_material(const json& mixture, Job& keep) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  d["materials"]["ply"] = {{"mixture", mixture}};
  keep = parse_job(d, "job.json");
  return keep.materials[0];
}

TEST(Mixture, CardConstituentsGiveTheCardsValues) {
  const json mix = test::pa66_carbon_mixture();
  Job keep;
  const MaterialDef& m = mixture_material(mix, keep);
  const double vf = 0.4, rho_m = 970, rho_f = 1780, c_m = 2600, c_f = 1100, k_m = 0.22, k_a = 9.4, k_t = 0.84;
  const double rho = vf * rho_f + (1 - vf) * rho_m;
  const double c = (vf * rho_f * c_f + (1 - vf) * rho_m * c_m) / rho;
  const double k11 = vf * k_a + (1 - vf) * k_m, k22 = 1.0 / (vf / k_t + (1 - vf) / k_m);
  EXPECT_NEAR(m.density, rho, 1e-14 * rho);
  EXPECT_NEAR(m.specific_heat, c, 1e-14 * c);
  EXPECT_EQ(m.specific_heat_max, m.specific_heat);
  EXPECT_TRUE(m.specific_heat_table.empty());
  EXPECT_TRUE(m.conductivity_table.empty());
  EXPECT_NEAR(m.conductivity[0], k11, 1e-14 * k11);
  EXPECT_NEAR(m.conductivity[1], k22, 1e-14 * k22);
  EXPECT_EQ(m.conductivity[2], m.conductivity[1]);
  EXPECT_TRUE(m.has_thermal);
  EXPECT_EQ(m.mixture_fibre_fraction, 0.4);
  EXPECT_NEAR(m.mixture_matrix_mass_fraction, (1 - vf) * rho_m / rho, 1e-15);
  EXPECT_NE(describe_mixture(m).find("(matrix mass fraction 0.4498): density 1294 kg/m3, specific heat 1774.65 J/(kg K), conductivity 3.892, "
                                     "0.312162, 0.312162 W/(m K)"),
            std::string::npos)
      << describe_mixture(m);

  // pa66_cf_ud.json gives these values to its printed digits.
  const json card = read_job_document(test::source_dir() / "share" / "materials" / "pa66_cf_ud.json");
  EXPECT_EQ(card["density"].get<double>(), m.density);
  EXPECT_LE(std::abs(card["specific_heat"].get<double>() - m.specific_heat), 0.5);
  for (int d = 0; d < 3; ++d) EXPECT_LE(std::abs(card["conductivity"][d].get<double>() - m.conductivity[d]), 0.005) << d;

  // pa66_cf_ud_mixture.json is that card with its thermal data from the
  // mixture: the same laws.
  const json mixture_card = read_job_document(test::source_dir() / "share" / "materials" / "pa66_cf_ud_mixture.json");
  json whole = test::ply_job("adi", 8, 1.0, 0.1);
  whole["materials"]["ply"] = mixture_card;
  EXPECT_EQ(parse_job(whole, "job.json").materials[0].density, m.density);
  EXPECT_EQ(mixture_card["membrane"], card["membrane"]);
  EXPECT_EQ(mixture_card["bending"], card["bending"]);

  // A fibre fraction of 0 is the matrix, of 1 the fibres.
  json none = mix, all = mix;
  none["fibre_volume_fraction"] = 0.0;
  all["fibre_volume_fraction"] = 1.0;
  const MaterialDef& mn = mixture_material(none, keep);
  EXPECT_EQ(mn.density, rho_m);
  EXPECT_DOUBLE_EQ(mn.specific_heat, c_m);
  for (int d = 0; d < 3; ++d) EXPECT_DOUBLE_EQ(mn.conductivity[d], k_m) << d;
  const MaterialDef& ma = mixture_material(all, keep);
  EXPECT_EQ(ma.density, rho_f);
  EXPECT_DOUBLE_EQ(ma.specific_heat, c_f);
  EXPECT_DOUBLE_EQ(ma.conductivity[0], k_a);
  EXPECT_DOUBLE_EQ(ma.conductivity[1], k_t);
  EXPECT_DOUBLE_EQ(ma.conductivity[2], k_t);
}

// Constituents whose values follow the temperature: the ply's rows are the
// mixture at every temperature of the constituents' rows (each held beyond
// its own rows), sorted, each once.
TEST(Mixture, RowsAtEveryTemperatureOfTheConstituents) {
  json mix = test::pa66_carbon_mixture();
  mix["matrix"]["specific_heat"] = {{200.0, 2000.0}, {260.0, 2600.0}};
  mix["matrix"]["conductivity"] = {{200.0, 0.30}, {280.0, 0.22}};
  mix["fibre"]["conductivity"] = {{250.0, 9.4, 0.84}, {300.0, 10.0, 0.90}};
  Job keep;
  const MaterialDef& m = mixture_material(mix, keep);
  auto lin = [](double t, double t0, double v0, double t1, double v1) {
    const double s = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    return v0 + s * (v1 - v0);
  };
  const double vf = 0.4, rho = 1294;
  auto c_at = [&](double t) { return (vf * 1780 * 1100 + (1 - vf) * 970 * lin(t, 200, 2000, 260, 2600)) / rho; };
  auto k_at = [&](double t) {
    const double km = lin(t, 200, 0.30, 280, 0.22), ka = lin(t, 250, 9.4, 300, 10.0), kt = lin(t, 250, 0.84, 300, 0.90);
    return std::array<double, 2>{vf * ka + (1 - vf) * km, 1.0 / (vf / kt + (1 - vf) / km)};
  };
  ASSERT_EQ(m.specific_heat_table.size(), 2u);
  for (const auto& row : m.specific_heat_table) EXPECT_NEAR(row[1], c_at(row[0]), 1e-12 * row[1]) << row[0];
  EXPECT_EQ(m.specific_heat_table[0][0], 200.0);
  EXPECT_EQ(m.specific_heat_table[1][0], 260.0);
  EXPECT_EQ(m.specific_heat, m.specific_heat_table[0][1]);
  EXPECT_EQ(m.specific_heat_max, m.specific_heat_table[1][1]);
  const std::vector<double> tk = {200, 250, 280, 300};
  ASSERT_EQ(m.conductivity_table.size(), tk.size());
  std::array<double, 3> largest{0, 0, 0};
  for (std::size_t i = 0; i < tk.size(); ++i) {
    const auto& row = m.conductivity_table[i];
    EXPECT_EQ(row[0], tk[i]);
    const auto k = k_at(tk[i]);
    EXPECT_NEAR(row[1], k[0], 1e-12 * k[0]) << tk[i];
    EXPECT_NEAR(row[2], k[1], 1e-12 * k[1]) << tk[i];
    EXPECT_EQ(row[3], row[2]);
    for (int d = 0; d < 3; ++d) largest[d] = std::max(largest[d], row[d + 1]);
  }
  EXPECT_EQ(m.conductivity, largest);  // the thermal steps are chosen with these
  // Between its rows the heat capacity per volume is linear in the
  // constituents', so the ply's rows hold the mixture at every temperature.
  for (double t : {150.0, 215.0, 237.5, 290.0}) {
    const auto& r = m.specific_heat_table;
    const double rows = t <= r[0][0] ? r[0][1] : t >= r[1][0] ? r[1][1] : lin(t, r[0][0], r[0][1], r[1][0], r[1][1]);
    EXPECT_NEAR(rows, c_at(t), 1e-12 * rows) << t;
  }

  // Rows of one value are a constant.
  json flat = test::pa66_carbon_mixture();
  flat["matrix"]["specific_heat"] = {{200.0, 2600.0}, {260.0, 2600.0}};
  flat["matrix"]["conductivity"] = {{200.0, 0.22}, {280.0, 0.22}};
  const MaterialDef& mf = mixture_material(flat, keep);
  EXPECT_TRUE(mf.specific_heat_table.empty());
  EXPECT_TRUE(mf.conductivity_table.empty());
  Job keep_card;
  const MaterialDef& card = mixture_material(test::pa66_carbon_mixture(), keep_card);
  EXPECT_EQ(mf.specific_heat, card.specific_heat);
  EXPECT_EQ(mf.conductivity, card.conductivity);
}

// A run with a mixture is the run with the rows it forms, written out as
// `specific_heat` and `conductivity`: two linked plies (adi), bit for bit.
TEST(Mixture, RunsAsTheRowsItForms) {
  json mix = test::pa66_carbon_mixture();
  mix["matrix"]["specific_heat"] = {{250.0, 2300.0}, {300.0, 2600.0}};
  mix["matrix"]["conductivity"] = {{250.0, 0.26}, {300.0, 0.22}};
  json with_mixture = test::two_ply_job("adi", 6, 1000.0);
  with_mixture["materials"]["ply"] = {{"mixture", mix}};
  Job keep;
  const MaterialDef& m = mixture_material(mix, keep);
  json rows = with_mixture;
  json c = json::array(), k = json::array();
  for (const auto& r : m.specific_heat_table) c.push_back({r[0], r[1]});
  for (const auto& r : m.conductivity_table) k.push_back({r[0], r[1], r[2], r[3]});
  rows["materials"]["ply"] = {{"density", m.density}, {"specific_heat", c}, {"conductivity", k}};
  const auto a = test::run_json(with_mixture), b = test::run_json(rows);
  ASSERT_EQ(a.result.probes.size(), b.result.probes.size());
  ASSERT_GT(a.result.probes.size(), 4u);
  for (std::size_t i = 0; i < a.result.probes.size(); ++i) EXPECT_EQ(a.result.probes[i].values, b.result.probes[i].values) << i;
  // The rows move the profiles (0.54 K from the card's constants): the comparison
  // above is not one of two runs that the rows leave alike.
  json constant = with_mixture;
  constant["materials"]["ply"] = {{"mixture", test::pa66_carbon_mixture()}};
  const auto d = test::run_json(constant);
  double moved = 0;
  for (std::size_t i = 0; i < a.result.probes.size(); ++i)
    for (std::size_t z = 0; z < a.result.probes[i].values.size(); ++z)
      moved = std::max(moved, std::abs(a.result.probes[i].values[z] - d.result.probes[i].values[z]));
  std::printf("rows against the card's constants: %.3g K\n", moved);
  EXPECT_GT(moved, 0.25);
}


// crystallisation.matrix_latent_heat: a heat of crystallisation per kg of
// matrix, as a DSC run of the neat polymer gives it, taken per kg of ply by
// the matrix's mass fraction (1 - V_f) rho_m / rho, written out here from
// the card's constituents; the same material as with latent_heat given as
// that product. Refused beside latent_heat, without a mixture, and below 0.
TEST(Mixture, LatentHeatPerKilogramOfMatrix) {
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  const json kin = {{"matrix_latent_heat", 70000.0}, {"avrami_exponent", 3.0}, {"rate", {{200.0, 1.0}, {250.0, 0.0}}}};
  d["materials"]["ply"] = {{"mixture", test::pa66_carbon_mixture()}, {"crystallisation", kin}};
  const Job j = parse_job(d, "job.json");
  const double vf = 0.4, rho_m = 970, rho_f = 1780;
  const double share = (1 - vf) * rho_m / (vf * rho_f + (1 - vf) * rho_m);
  const auto& c = j.materials[0].crystallisation;
  EXPECT_NEAR(c.latent_heat, 70000.0 * share, 1e-12 * 70000.0);
  EXPECT_EQ(c.matrix_latent_heat, 70000.0);
  const std::string said = describe_crystallisation(j.materials[0]);
  EXPECT_NE(said.find(" J/kg of ply: 70000 J/kg of matrix x its mass fraction 0.4498), rate from 2 rows"),
            std::string::npos)
      << said;
  json per_ply = d;
  per_ply["materials"]["ply"]["crystallisation"].erase("matrix_latent_heat");
  per_ply["materials"]["ply"]["crystallisation"]["latent_heat"] = c.latent_heat;
  const Job jp = parse_job(per_ply, "job.json");
  EXPECT_EQ(jp.materials[0].crystallisation.latent_heat, c.latent_heat);
  EXPECT_LT(jp.materials[0].crystallisation.matrix_latent_heat, 0.0);
  EXPECT_EQ(describe_crystallisation(jp.materials[0]).find("of matrix"), std::string::npos);

  json both = d;
  both["materials"]["ply"]["crystallisation"]["latent_heat"] = 30000.0;
  EXPECT_EQ(job_error(both), "/materials/ply/crystallisation/matrix_latent_heat: give either latent_heat (J/kg of ply) "
                             "or matrix_latent_heat (J/kg of matrix), not both");
  json no_mixture = test::ply_job("adi", 8, 1.0, 0.1);
  no_mixture["materials"]["ply"]["crystallisation"] = kin;
  EXPECT_EQ(job_error(no_mixture), "/materials/ply/crystallisation/matrix_latent_heat: needs the material's 'mixture' "
                                   "(the matrix's share of the ply's mass); without one, give latent_heat in J/kg of "
                                   "ply");
  json negative = d;
  negative["materials"]["ply"]["crystallisation"]["matrix_latent_heat"] = -1.0;
  EXPECT_EQ(job_error(negative).rfind("/materials/ply/crystallisation/matrix_latent_heat: must be >= 0", 0), 0u)
      << job_error(negative);
}

// materials.*.card: a material card (share/materials) whose keys a
// material takes where it gives none itself, read relative to the job file.
TEST(MaterialCard, TakesTheCardsValuesWhereTheMaterialGivesNone) {
  const auto dir = test::temp_dir("material_card");
  std::filesystem::create_directories(dir / "cards");
  json card = read_job_document(test::source_dir() / "share" / "materials" / "pa66_cf_ud.json");
  std::ofstream(dir / "cards" / "ud.json") << card.dump(2);
  json d = test::ply_job("adi", 8, 1.0, 0.1);
  d["materials"]["ply"] = {{"card", "cards/ud.json"}, {"specific_heat", 1500.0}};
  std::ofstream(dir / "job.json") << d.dump(2);
  const Job j = load_job(dir / "job.json", {});
  const MaterialDef& m = j.materials[0];
  EXPECT_EQ(m.density, 1294.0);
  EXPECT_EQ(m.specific_heat, 1500.0);  // the material's own value
  EXPECT_EQ(m.conductivity, (std::array<double, 3>{3.89, 0.31, 0.31}));
  EXPECT_EQ(m.membrane, card["membrane"]);
  EXPECT_EQ(m.bending, card["bending"]);
  EXPECT_EQ(material_card_file(j, m), std::filesystem::absolute(dir / "cards" / "ud.json").lexically_normal());
  // The job as run holds the card's values and no card: it runs without it.
  const json& as_run = j.document_as_run["materials"]["ply"];
  EXPECT_FALSE(as_run.contains("card"));
  EXPECT_EQ(as_run["membrane"], card["membrane"]);
  EXPECT_EQ(as_run["specific_heat"], 1500.0);
  // --set reaches into what the card gave.
  const Job s = load_job(dir / "job.json", {"materials.ply.membrane.0.k_fibre=2e6", "materials.ply.density=1300"});
  EXPECT_EQ(s.materials[0].membrane[0]["k_fibre"].get<double>(), 2e6);
  EXPECT_EQ(s.materials[0].density, 1300.0);

  auto error_of = [&](const json& job) {
    std::ofstream(dir / "bad.json") << job.dump(2);
    try {
      load_job(dir / "bad.json", {});
    } catch (const JobError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string card_file = std::filesystem::absolute(dir / "cards" / "bad_card.json").lexically_normal().string();
  // A value from the card: the error names the card; the material's own value: it does not.
  json bad_card = card;
  bad_card["density"] = -1.0;
  std::ofstream(dir / "cards" / "bad_card.json") << bad_card.dump(2);
  json bad = d;
  bad["materials"]["ply"] = {{"card", "cards/bad_card.json"}};
  EXPECT_EQ(error_of(bad), "/materials/ply/density: must be > 0, found -1 (from the material card '" + card_file + "')");
  bad["materials"]["ply"]["density"] = -2.0;
  EXPECT_EQ(error_of(bad), "/materials/ply/density: must be > 0, found -2");
  bad["materials"]["ply"] = {{"card", "cards/none.json"}};
  EXPECT_EQ(error_of(bad).rfind("/materials/ply/card: material card '", 0), 0u) << error_of(bad);
  EXPECT_NE(error_of(bad).find("none.json' not found"), std::string::npos) << error_of(bad);
  bad["materials"]["ply"] = {{"card", 12}};
  EXPECT_EQ(error_of(bad), "/materials/ply/card: expected the path of a material card, found a number (12)");
  std::ofstream(dir / "cards" / "chained.json") << json{{"card", "ud.json"}}.dump();
  bad["materials"]["ply"] = {{"card", "cards/chained.json"}};
  EXPECT_NE(error_of(bad).find("names another card"), std::string::npos) << error_of(bad);
  std::ofstream(dir / "cards" / "list.json") << json::array({1, 2}).dump();
  bad["materials"]["ply"] = {{"card", "cards/list.json"}};
  EXPECT_NE(error_of(bad).find("holds an array, not a material object"), std::string::npos) << error_of(bad);
  // A law parameter from the card, refused by the plugin when the run is set up.
  json bad_law = card;
  bad_law["membrane"][1]["tau"] = {0.0, 2.0};
  std::ofstream(dir / "cards" / "bad_card.json") << bad_law.dump(2);
  json mech = read_job_document(test::source_dir() / "share" / "jobs" / "ud_strip_tension.json");
  const std::string mat = mech["parts"][0]["material"];
  mech["materials"][mat] = {{"card", (dir / "cards" / "bad_card.json").string()}};
  std::ofstream(dir / "mech.json") << mech.dump(2);
  const Job mj = load_job(dir / "mech.json", {});
  PluginRegistry registry;
  try {
    Simulation sim(mj, registry);
    ADD_FAILURE() << "a relaxation time of zero must be refused";
  } catch (const JobError& e) {
    EXPECT_EQ(std::string(e.pointer()).rfind("/materials/" + mat + "/membrane", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("(from the material card '" + card_file + "')"), std::string::npos) << e.what();
  }
}

// The hemisphere job's material is the UD card with a softer fibre: the job
// written with the card and its own membrane is the shipped job.
TEST(MaterialCard, HemisphereJobIsTheCardWithItsOwnMembrane) {
  const auto jobs = test::source_dir() / "share" / "jobs";
  json d = read_job_document(jobs / "hemisphere_ud_2ply.json");
  json& m = d["materials"]["pa66_cf_ud"];
  const json shipped = m;
  m = {{"card", (test::source_dir() / "share" / "materials" / "pa66_cf_ud.json").string()},
       {"membrane", shipped["membrane"]}};
  const Job with_card = parse_job(d, jobs / "hemisphere_ud_2ply.json");
  json a = with_card.document_as_run["materials"]["pa66_cf_ud"], b = shipped;
  for (const char* k : {"description", "source"}) {
    a.erase(k);
    b.erase(k);
  }
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace ts
