#include "plugins/schema.hpp"

#include <cmath>

#include "job/job.hpp"

namespace ts {

namespace {

json param_schema(const sdk::ParamSpec& p) {
  json s;
  std::string doc = p.doc;
  if (!p.unit.empty() && p.unit != "-") doc += " [" + p.unit + "]";
  s["description"] = doc;
  switch (p.type) {
    case sdk::ParamType::Real:
      s["type"] = "number";
      break;
    case sdk::ParamType::Integer:
      s["type"] = "integer";
      break;
    case sdk::ParamType::Boolean:
      s["type"] = "boolean";
      break;
    case sdk::ParamType::String:
      s["type"] = "string";
      break;
    case sdk::ParamType::Choice:
      s["enum"] = p.choices;
      break;
    case sdk::ParamType::RealList:
      s["type"] = "array";
      s["items"] = {{"type", "number"}};
      if (p.list_size >= 0) s["minItems"] = s["maxItems"] = p.list_size;
      break;
  }
  if (p.type == sdk::ParamType::Real || p.type == sdk::ParamType::Integer) {
    if (std::isfinite(p.min)) s[p.min_exclusive ? "exclusiveMinimum" : "minimum"] = p.min;
    if (std::isfinite(p.max)) s["maximum"] = p.max;
  }
  if (!p.default_json.empty()) s["default"] = json::parse(p.default_json);
  return s;
}

// Object schema of a plugin's parameters plus the kernel keys `extra`.
json plugin_schema(const PluginRecord& r, const json& extra) {
  json props = extra;
  json required = json::array();
  for (const auto& p : r.descriptor.params) {
    props[p.name] = param_schema(p);
    if (p.default_json.empty()) required.push_back(p.name);
  }
  json s = {{"type", "object"},
            {"description", r.descriptor.summary},
            {"properties", props},
            {"additionalProperties", false}};
  if (!required.empty()) s["required"] = required;
  return s;
}

json vec(int n) { return {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", n}, {"maxItems", n}}; }

// A number for every ply, or an object of such numbers by material name.
json by_material(const json& number) {
  return {{"oneOf", {number, {{"type", "object"}, {"additionalProperties", number}}}}};
}

}  // namespace

json job_schema(const std::vector<const PluginRecord*>& records) {
  json defs = json::object();
  json thermal = json::array(), contact = json::array(), materials = json::array(), elements = json::array();
  for (const auto* r : records) {
    const auto& d = r->descriptor;
    const std::string key = std::string(sdk::to_string(d.kind)) + "_" + d.name;
    json extra = json::object();
    switch (d.kind) {
      case sdk::PluginKind::Thermal:
        extra = {{"splitter", {{"const", d.name}}},
                 {"subcycle", {{"type", "integer"}, {"minimum", 0}, {"description", "mechanical steps per thermal step (0: automatic)"}}},
                 {"dt", {{"type", "number"}, {"minimum", 0}, {"description", "thermal step [s] (0: automatic)"}}},
                 {"contact_samples",
                  {{"type", "integer"},
                   {"minimum", 1},
                   {"maximum", 1000},
                   {"description",
                    "contact samples per thermal step, their conductances averaged over the step (default 8)"}}}};
        defs[key] = plugin_schema(*r, extra);
        defs[key]["required"].push_back("splitter");
        thermal.push_back({{"$ref", "#/$defs/" + key}});
        break;
      case sdk::PluginKind::Contact:
        extra = {{"type", {{"const", "contact"}}},
                 {"handler", {{"const", d.name}}},
                 {"between", {{"type", "array"}, {"items", {{"type", "string"}}}, {"minItems", 2}, {"maxItems", 2}}}};
        defs[key] = plugin_schema(*r, extra);
        defs[key]["required"] = json::array({"type", "between"});
        contact.push_back({{"$ref", "#/$defs/" + key}});
        break;
      case sdk::PluginKind::Material:
        extra = {{"law", {{"const", d.name}}}};
        defs[key] = plugin_schema(*r, extra);
        defs[key]["required"].push_back("law");
        materials.push_back({{"$ref", "#/$defs/" + key}});
        break;
      case sdk::PluginKind::Element:
        elements.push_back(d.name);
        break;
    }
  }
  const json law = {{"anyOf", materials}};
  const json conductivity = {
      {"oneOf",
       json::array({vec(3), json{{"type", "array"},
                                 {"minItems", 1},
                                 {"items",
                                  {{"type", "array"},
                                   {"items", {{"type", "number"}}},
                                   {"minItems", 4},
                                   {"maxItems", 4}}}}})},
      {"description", "k11 (fibres), k22 (across), k33 (thickness) [W/m/K], constant, or rows [T (degC), k11, "
                      "k22, k33] (linear between rows, held beyond them)"}};
  // materials.*.mixture: a constituent's value, a number or rows [T, value].
  auto number_or_rows = [](int n, const std::string& desc) {
    json number = n == 1 ? json{{"type", "number"}, {"exclusiveMinimum", 0}}
                         : json{{"type", "array"},
                                {"items", {{"type", "number"}, {"exclusiveMinimum", 0}}},
                                {"minItems", n},
                                {"maxItems", n}};
    return json{{"oneOf", json::array({number, json{{"type", "array"},
                                                    {"minItems", 1},
                                                    {"items",
                                                     {{"type", "array"},
                                                      {"items", {{"type", "number"}}},
                                                      {"minItems", n + 1},
                                                      {"maxItems", n + 1}}}}})},
                {"description", desc}};
  };
  auto constituent = [&](const std::string& k_desc, int k_values) {
    return json{{"type", "object"},
                {"required", json::array({"density", "specific_heat", "conductivity"})},
                {"additionalProperties", false},
                {"properties",
                 {{"density", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[kg/m3]"}}},
                  {"specific_heat", number_or_rows(1, "[J/kg/K], constant, or rows [T (degC), c]")},
                  {"conductivity", number_or_rows(k_values, k_desc)}}}};
  };
  const json mixture = {
      {"type", "object"},
      {"description", "the thermal data from the matrix and the fibres (instead of density, specific_heat and "
                      "conductivity): density and rho c parallel, k11 parallel, k22 = k33 in series"},
      {"required", json::array({"fibre_volume_fraction", "matrix", "fibre"})},
      {"additionalProperties", false},
      {"properties",
       {{"fibre_volume_fraction", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}}},
        {"matrix", constituent("[W/m/K], constant, or rows [T (degC), k]", 1)},
        {"fibre", constituent("[W/m/K] [axial, transverse], constant, or rows [T (degC), axial, transverse]", 2)}}}};
  json thermal_or_null = thermal;
  thermal_or_null.push_back({{"type", "null"}});
  const json material = {
      {"type", "object"},
      {"properties",
       {{"density", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[kg/m3]"}}},
        {"specific_heat",
         {{"oneOf",
           json::array({json{{"type", "number"}, {"exclusiveMinimum", 0}},
                        json{{"type", "array"},
                             {"minItems", 1},
                             {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}}}}})},
          {"description", "[J/kg/K], constant, or rows [T (degC), c (J/kg/K)] (an apparent specific heat, "
                          "linear between rows, held beyond them)"}}},
        {"conductivity", conductivity},
        {"mixture", mixture},
        {"card",
         {{"type", "string"},
          {"description", "a material card (a file holding a material object, such as share/materials/*.json; "
                          "relative to the job file) whose keys the material takes where it gives none itself"}}},
        {"crystallisation",
         {{"type", "object"},
          {"description", "Nakamura crystallisation kinetics of the matrix: X = 1 - exp(-(int K(T) dt)^n)"},
          {"required", json::array({"avrami_exponent", "rate"})},
          {"oneOf", json::array({json{{"required", json::array({"latent_heat"})}},
                                 json{{"required", json::array({"matrix_latent_heat"})}}})},
          {"additionalProperties", false},
          {"properties",
           {{"latent_heat", {{"type", "number"}, {"minimum", 0}, {"description", "[J/kg] of ply, from X = 0 to 1"}}},
            {"matrix_latent_heat",
             {{"type", "number"},
              {"minimum", 0},
              {"description", "[J/kg] of matrix, in place of latent_heat, with a mixture: latent_heat is this times "
                              "the matrix's mass fraction"}}},
            {"avrami_exponent", {{"type", "number"}, {"exclusiveMinimum", 0}, {"maximum", 10}}},
            {"initial", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}, {"default", 0}}},
            {"rate",
             {{"oneOf",
               json::array(
                   {json{{"type", "array"},
                         {"minItems", 1},
                         {"items",
                          {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}}}},
                    json{{"type", "object"},
                         {"required", json::array({"k_max", "t_max", "half_width"})},
                         {"additionalProperties", false},
                         {"properties",
                          {{"k_max", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[1/s]"}}},
                           {"t_max", {{"type", "number"}, {"description", "[degC]"}}},
                           {"half_width", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[K]"}}}}}}})},
              {"description", "[1/s], rows [T (degC), K] (linear between rows, held beyond them), or Ziabicki's "
                              "Gaussian {k_max, t_max, half_width}"}}},
            {"melting",
             {{"type", "array"},
              {"minItems", 2},
              {"items",
               {{"type", "array"},
                {"prefixItems", json::array({json{{"type", "number"}},
                                             json{{"type", "number"}, {"minimum", 0}, {"maximum", 1}}})},
                {"minItems", 2},
                {"maxItems", 2}}},
              {"description", "rows [T (degC), share of the crystals still solid], from 1 at the first row to 0 at "
                              "the last (linear between rows): the crystals melt on heating, taking the latent heat"}}}}}}},
        {"membrane", {{"anyOf", {law, {{"type", "array"}, {"items", law}}}}}},
        {"bending", law},
        {"in_plane_bending", law},
        {"description", {{"type", "string"}}},
        {"source", {{"type", "string"}}}}},
      {"not",
       {{"anyOf", json::array({json{{"required", json::array({"mixture", "density"})}},
                               json{{"required", json::array({"mixture", "specific_heat"})}},
                               json{{"required", json::array({"mixture", "conductivity"})}}})}}},
      {"additionalProperties", false}};
  const json mesh = {
      {"oneOf",
       json::array(
           {json{{"type", "object"},
                 {"required", {"file"}},
                 {"properties",
                  {{"file", {{"type", "string"}, {"description", "Gmsh ASCII 2.2 or 4.1, Abaqus input (.inp) or LS-DYNA keywords (.k, .key, .dyn): 3-node triangles, relative to the job file"}}},
                   {"reorder", {{"type", "boolean"},
                                {"description", "number the triangles so that neighbours are close in memory "
                                                "(default true)"}}},
                   {"scale", {{"type", "number"},
                              {"exclusiveMinimum", 0},
                              {"description", "factor on the file's coordinates (0.001 for millimetres; default 1)"}}}}},
                 {"additionalProperties", false}},
            json{{"type", "object"},
                 {"properties",
                  {{"generator", {{"enum", {"rectangle"}}}},
                   {"origin", vec(3)},
                   {"size", vec(2)},
                   {"divisions", {{"type", "array"}, {"items", {{"type", "integer"}, {"minimum", 1}}}, {"minItems", 2}, {"maxItems", 2}}},
                   {"pattern", {{"enum", {"alternating", "crossed"}},
                                {"description", "two triangles per cell (alternating diagonals) or four around a centre node"}}}}},
                 {"additionalProperties", false}}})}};
  json element_prop = {{"type", "string"}};
  if (!elements.empty()) element_prop["enum"] = elements;
  const json initial_temperature = {
      {"oneOf", json::array({json{{"type", "number"}},
                             json{{"type", "object"},
                                  {"required", {"results"}},
                                  {"properties",
                                   {{"results", {{"type", "string"}, {"description", "an earlier run's results.h5"}}},
                                    {"part", {{"type", "string"}}},
                                    {"time", {{"type", "number"}, {"minimum", 0}, {"description", "[s]"}}}}},
                                  {"additionalProperties", false}}})},
      {"description", "[degC], or the temperatures of a frame of an earlier run"}};
  const json part = {{"type", "object"},
                     {"required", {"name", "mesh", "thickness", "material"}},
                     {"properties",
                      {{"name", {{"type", "string"}}},
                       {"mesh", mesh},
                       {"thickness", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[m]"}}},
                       {"material", {{"type", "string"}}},
                       {"fibre_direction", vec(3)},
                       {"element", element_prop},
                       {"initial_temperature", initial_temperature},
                       {"thickness_layers", {{"type", "integer"}, {"minimum", 1}}},
                       {"flip", {{"type", "boolean"}, {"description", "reverse the orientation: the top face looks to -z"}}}}},
                     {"additionalProperties", false}};
  // A tool's temperature, a heat exchange's ambient.
  const json temperature_or_rows = {
      {"oneOf", json::array({json{{"type", "number"}},
                             json{{"type", "array"},
                                  {"minItems", 1},
                                  {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}}}}})},
      {"description", "[degC], constant, or rows [t (s), T (degC)] over time"}};
  const json heat_exchange = {{"type", "object"},
                              {"required", {"type", "part", "face", "ambient"}},
                              {"anyOf", json::array({json{{"required", {"h"}}}, json{{"required", {"emissivity"}}}})},
                              {"properties",
                               {{"type", {{"const", "heat_exchange"}}},
                                {"part", {{"type", "string"}}},
                                {"face", {{"enum", {"top", "bottom", "both"}}}},
                                {"h", {{"type", "number"}, {"minimum", 0}, {"description", "[W/m2/K]"}}},
                                {"ambient", temperature_or_rows},
                                {"emissivity", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}, {"description", "[-] radiation to the ambient"}}},
                                {"region", {{"type", "object"}}}}},
                              {"additionalProperties", false}};
  const json point2 = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}};
  const json piece = {
      {"oneOf",
       {{{"type", "object"}, {"required", {"line"}}, {"properties", {{"line", {{"type", "array"}, {"items", point2}, {"minItems", 2}, {"maxItems", 2}}}}}, {"additionalProperties", false}},
        {{"type", "object"},
         {"required", {"arc"}},
         {"properties",
          {{"arc", {{"type", "object"}, {"required", {"from", "to", "centre"}}, {"properties", {{"from", point2}, {"to", point2}, {"centre", point2}}}, {"additionalProperties", false}}}}},
         {"additionalProperties", false}}}}};
  const json surface = {
      {"oneOf",
       {{{"type", "object"}, {"required", {"type", "point", "normal"}}, {"properties", {{"type", {{"const", "plane"}}}, {"point", vec(3)}, {"normal", vec(3)}}}, {"additionalProperties", false}},
        {{"type", "object"}, {"required", {"type", "centre", "radius"}}, {"properties", {{"type", {{"const", "sphere"}}}, {"centre", vec(3)}, {"radius", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[m]"}}}}}, {"additionalProperties", false}},
        {{"type", "object"},
         {"required", {"type", "profile"}},
         {"properties",
          {{"type", {{"const", "revolved"}}},
           {"axis", {{"type", "object"}, {"properties", {{"origin", vec(3)}, {"direction", vec(3)}}}, {"additionalProperties", false}}},
           {"profile", {{"type", "array"}, {"items", piece}, {"minItems", 1}, {"description", "(r, z) pieces; the tool's outside is on the left"}}}}},
         {"additionalProperties", false}},
        {{"type", "object"}, {"required", {"type", "file"}}, {"properties", {{"type", {{"const", "mesh"}}}, {"file", {{"type", "string"}, {"description", "STL, Gmsh, Abaqus input (.inp) or LS-DYNA keywords (.k, .key, .dyn), relative to the job file"}}}, {"flip", {{"type", "boolean"}}}, {"scale", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "factor on the file's coordinates (0.001 for millimetres; default 1)"}}}}}, {"additionalProperties", false}}}}};
  const json motion = {
      {"oneOf",
       {{{"type", "object"}, {"required", {"velocity"}}, {"properties", {{"velocity", vec(3)}}}, {"additionalProperties", false}},
        {{"type", "object"}, {"required", {"displacement"}}, {"properties", {{"displacement", {{"type", "array"}, {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 4}, {"maxItems", 4}}}, {"description", "rows [t, dx, dy, dz]"}}}}}, {"additionalProperties", false}},
        {{"type", "object"}, {"required", {"force", "mass"}}, {"properties", {{"force", {{"oneOf", {vec(3), {{"type", "array"}, {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 4}, {"maxItems", 4}}}, {"description", "rows [t, fx, fy, fz]: the force over time, along one line"}}}}}}, {"mass", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[kg]"}}}, {"damping", {{"type", "number"}, {"minimum", 0}, {"description", "[N s/m]"}}}}}, {"additionalProperties", false}}}}};
  const json tool = {{"type", "object"},
                     {"required", {"name", "surface"}},
                     {"properties", {{"name", {{"type", "string"}}}, {"surface", surface}, {"motion", motion}, {"temperature", temperature_or_rows}}},
                     {"additionalProperties", false}};
  // constraints[]: one object per kind, told apart by "type".
  const json box = {{"type", "array"},
                    {"items", vec(3)},
                    {"minItems", 2},
                    {"maxItems", 2},
                    {"description", "[[x0, y0, z0], [x1, y1, z1]] (m): the nodes whose initial position is inside"}};
  const json part_name = {{"type", "string"}, {"description", "a part's name, or \"*\" for every part"}};
  const json dofs = {{"type", "array"}, {"items", {{"enum", {"x", "y", "z"}}}}};
  auto constraint_kind = [&](const char* type, std::vector<std::string> required, json properties) {
    properties["type"] = {{"const", type}};
    properties["part"] = part_name;
    required.insert(required.begin(), {"type", "part"});
    return json{
        {"type", "object"}, {"required", required}, {"properties", properties}, {"additionalProperties", false}};
  };
  const json constraint_kinds = {
      constraint_kind("symmetry", {"plane"}, {{"plane", {{"enum", {"x", "y", "z"}}}}}),
      constraint_kind("fix", {"box"}, {{"box", box}, {"dofs", dofs}}),
      constraint_kind("velocity", {"box", "velocity"}, {{"box", box}, {"velocity", vec(3)}, {"dofs", dofs}}),
      constraint_kind("force", {"box", "force"},
                      {{"box", box},
                       {"force", vec(3)},
                       {"ramp", {{"type", "number"}, {"minimum", 0}, {"description", "[s]"}}}}),
      constraint_kind(
          "gripper", {"box", "anchor", "stiffness"},
          {{"name", {{"type", "string"}, {"minLength", 1}}},
           {"box", box},
           {"anchor", vec(3)},
           {"stiffness", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[N/m]"}}},
           {"preload", {{"type", "number"}, {"minimum", 0}, {"description", "[N]"}}},
           {"ramp", {{"type", "number"}, {"minimum", 0}, {"description", "[s] of the preload"}}},
           {"tension_only", {{"type", "boolean"}}},
           {"jaws", {{"enum", {"flexible", "rigid", "swivelling"}}}},
           {"release", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "[s]"}}},
           {"anchor_motion", {{"oneOf", {motion["oneOf"][0], motion["oneOf"][1]}}}}})};
  json interaction_kinds = contact;
  interaction_kinds.push_back(heat_exchange);
  // A probe of output.probes (job.cpp reads the same keys).
  const json probe = {
      {"type", "object"},
      {"properties",
       {{"name", {{"type", "string"}}},
        {"part", {{"type", "string"}}},
        {"at", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}}},
        {"quantities", {{"type", "array"}, {"items", {{"enum", known_probe_quantities()}}}}},
        {"interval", {{"type", "number"}, {"minimum", 0}}}}},
      {"required", {"name", "part", "at"}},
      {"additionalProperties", false}};
  json schema = {
      {"$schema", "https://json-schema.org/draft/2020-12/schema"},
      {"title", "ThermoStamp job (thermostamp-job/1)"},
      {"type", "object"},
      {"required", {"format", "name", "time", "materials", "parts"}},
      {"properties",
       {{"format", {{"const", "thermostamp-job/1"}}},
        {"name", {{"type", "string"}}},
        {"description", {{"type", "string"}}},
        {"time", {{"type", "object"}, {"properties", {{"end", {{"type", "number"}, {"exclusiveMinimum", 0}}}}}, {"required", {"end"}}, {"additionalProperties", false}}},
        {"plugin_paths", {{"type", "array"}, {"items", {{"type", "string"}}}}},
        {"materials", {{"type", "object"}, {"additionalProperties", material}}},
        {"parts", {{"type", "array"}, {"items", part}}},
        {"tools", {{"type", "array"}, {"items", tool}}},
        {"interactions", {{"type", "array"}, {"items", {{"anyOf", interaction_kinds}}}}},
        {"constraints", {{"type", "array"}, {"items", {{"oneOf", constraint_kinds}}}}},
        {"solvers",
         {{"type", "object"},
          {"properties", {{"mechanics", {{"type", {"object", "null"}}}}, {"thermal", {{"anyOf", thermal_or_null}}}}},
          {"additionalProperties", false}}},
        {"output",
         {{"type", "object"},
          {"properties",
           {{"interval", {{"type", "number"}, {"exclusiveMinimum", 0}}},
            {"checkpoint_interval", {{"type", "number"}, {"minimum", 0}}},
            {"checkpoint_at_end", {{"type", "boolean"}}},
            {"keep_checkpoints", {{"type", "boolean"}}},
            {"series_interval", {{"type", "number"}, {"minimum", 0}}},
            {"compression", {{"type", "integer"}, {"minimum", 0}, {"maximum", 9}}},
            {"tool_surfaces", {{"anyOf", {{{"type", "boolean"}}, {{"enum", {"whole"}}}}}}},
            {"temperature_threshold", by_material({{"type", "number"}, {"exclusiveMinimum", -273.15}})},
            {"shear_angle_limit", by_material({{"type", "number"}, {"exclusiveMinimum", 0}, {"exclusiveMaximum", 90}})},
            {"fields", {{"type", "array"}, {"items", {{"enum", known_fields()}}}}},
            {"probes", {{"type", "array"}, {"items", probe}}}}},
          {"additionalProperties", false}}}}},
      {"additionalProperties", false},
      {"$defs", defs}};
  return schema;
}

}  // namespace ts
