// The result's tables (localizer/result_fields.inc, localizer/stage_times.inc) and the option
// table against what names their lines by hand, the JSON schema and the Python stubs; and what
// the tables generate, the JSON record and the C API, against the tables.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "cwloc/cwloc.h"
#include "io/option_table.h"
#include "io/result_json.h"
#include "tests/api/api_test_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

struct ResultField {
  std::string name, type, group, key;
};

std::vector<ResultField> ResultFields() {
  return {
#define CWLOC_RESULT_FIELD(name, type, group, key, help) {#name, #type, group, key},
#include "localizer/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  };
}

std::vector<std::string> StageNames() {
  return {
#define CWLOC_STAGE_TIME(name, help) #name,
#include "localizer/stage_times.inc"
#undef CWLOC_STAGE_TIME
  };
}

std::set<std::string> Keys(const nlohmann::json& object) {
  std::set<std::string> keys;
  for (const auto& [key, value] : object.items()) keys.insert(key);
  return keys;
}

// What the schema and the stubs (python/cwloc/__init__.pyi) get wrong about the tables, one
// line per problem; none when they agree. The record's "matches", "times_ms" and "parameters"
// objects hold exactly the tables' lines; the top level holds the top-level lines among others.
std::vector<std::string> TableMismatches(const nlohmann::json& schema, const std::string& stubs) {
  std::vector<std::string> problems;
  const nlohmann::json& record = schema["$defs"]["result"];
  const auto expect_same = [&](const std::string& object, const std::set<std::string>& table) {
    const std::set<std::string> listed = Keys(record["properties"][object]["properties"]);
    for (const std::string& key : table)
      if (!listed.count(key)) problems.push_back("schema: " + object + "." + key + " missing");
    for (const std::string& key : listed)
      if (!table.count(key))
        problems.push_back("schema: " + object + "." + key + " is in no table");
    const auto& required = record["properties"][object]["required"];
    if (std::set<std::string>(required.begin(), required.end()) != table)
      problems.push_back("schema: " + object + " requires other keys than the table's");
  };
  // The type of the stubs' `name: TYPE` in the body of `class stub_class:`, or "missing".
  const auto stub_type = [&](const std::string& stub_class, const std::string& name) {
    const size_t start = stubs.find("\nclass " + stub_class + ":\n");
    if (start == std::string::npos) return std::string("missing");
    std::smatch match;
    const std::regex body("\nclass \\w+:\n((?:    .*\n|\n)*)");
    const std::string rest = stubs.substr(start);
    if (!std::regex_search(rest, match, body)) return std::string("missing");
    const std::string lines = match[1].str();
    const std::regex line("(^|\n)    " + name + ": (\\w+)\n");
    return std::regex_search(lines, match, line) ? match[2].str() : std::string("missing");
  };

  std::set<std::string> matches;
  for (const ResultField& field : ResultFields()) {
    const std::string json_type = field.type == "bool"     ? "boolean"
                                  : field.type == "double" ? "number"
                                                           : "integer";
    const std::string python_type = field.type == "bool"     ? "bool"
                                    : field.type == "double" ? "float"
                                                             : "int";
    const nlohmann::json& properties = field.group.empty()
                                           ? record["properties"]
                                           : record["properties"][field.group]["properties"];
    const std::string path = (field.group.empty() ? "" : field.group + ".") + field.key;
    if (field.group == "matches") matches.insert(field.key);
    if (!properties.contains(field.key)) {
      if (field.group != "matches") problems.push_back("schema: " + path + " missing");
    } else if (properties[field.key].value("type", "") != json_type) {
      problems.push_back("schema: " + path + " is not of type " + json_type);
    }
    const std::string stub = stub_type("Result", field.name);
    if (stub != python_type)
      problems.push_back("stubs: Result." + field.name + ": " + stub + ", expected " + python_type);
  }
  expect_same("matches", matches);

  const std::vector<std::string> stages = StageNames();
  expect_same("times_ms", {stages.begin(), stages.end()});
  for (const std::string& stage : stages)
    if (stub_type("StageTimes", stage) != "float")
      problems.push_back("stubs: StageTimes." + stage + " missing");

  std::set<std::string> options;
  for (const OptionSpec& spec : OptionTable()) options.insert(std::string(spec.name));
  expect_same("parameters", options);
  return problems;
}

nlohmann::json Schema() {
  return nlohmann::json::parse(
      test::ReadFile(test::SourceDir() / "schemas/localization-result.schema.json"));
}

std::string Stubs() { return test::ReadFile(test::SourceDir() / "python/cwloc/__init__.pyi"); }

TEST(ResultTable, TheSchemaAndTheStubsNameEveryLine) {
  EXPECT_THAT(TableMismatches(Schema(), Stubs()), testing::IsEmpty());
}

// The check above can fail: a field the schema lost, a stub of the wrong type, a stage the stubs
// lost and an option the schema still names after the table dropped it.
TEST(ResultTable, AStaleSchemaOrStubIsNamed) {
  nlohmann::json schema = Schema();
  nlohmann::json& record = schema["$defs"]["result"]["properties"];
  record["matches"]["properties"].erase("forward");
  record["parameters"]["properties"]["max_back_clusters"] = {{"type", "integer"}};
  std::string stubs = Stubs();
  stubs = std::regex_replace(stubs, std::regex("\n    guided: bool\n"), "\n    guided: int\n");
  stubs = std::regex_replace(stubs, std::regex("\n    query_tree: float\n"), "\n");
  EXPECT_THAT(TableMismatches(schema, stubs),
              testing::ElementsAre("stubs: Result.guided: int, expected bool",
                                   "schema: matches.forward missing",
                                   "stubs: StageTimes.query_tree missing",
                                   "schema: parameters.max_back_clusters is in no table"));
}

// Every line's value lands at its place in the record, as the table's type, and the record
// echoes every option of the table.
TEST(ResultTable, TheRecordWritesEveryLineAtItsPlace) {
  LocalizationResult result;
  double value = 1;
#define CWLOC_RESULT_FIELD(name, type, group, key, help) result.name = type(value++);
#include "localizer/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  value = 1;
#define CWLOC_STAGE_TIME(name, help) result.times.name = 0.25 * value++;
#include "localizer/stage_times.inc"
#undef CWLOC_STAGE_TIME
  QueryOptions options;
  options.localizer.k = 7;
  const nlohmann::ordered_json record = ResultToJson(result, options);

  value = 1;
  for (const ResultField& field : ResultFields()) {
    const nlohmann::ordered_json& json =
        field.group.empty() ? record.at(field.key) : record.at(field.group).at(field.key);
    if (field.type == "bool")
      EXPECT_EQ(json, true) << field.name;
    else
      EXPECT_EQ(json.get<double>(), value) << field.name;
    value++;
  }
  value = 1;
  for (const std::string& stage : StageNames())
    EXPECT_EQ(record.at("times_ms").at(stage).get<double>(), 250 * value++) << stage;
  EXPECT_EQ(record.at("parameters").size(), OptionTable().size());
  EXPECT_EQ(record.at("parameters").at("k"), 7);
  EXPECT_EQ(record.at("parameters").at("matcher"), "cluster-wise");
  EXPECT_EQ(record.at("parameters").at("use_exif_gps"), false);
}

// C reads every line by its name, the value the JSON record holds.
TEST(ResultTable, CReadsEveryLineByItsName) {
  cwloc_localizer* localizer = nullptr;
  ASSERT_EQ(cwloc_localizer_open(GoldenIndex().c_str(), 0, &localizer), CWLOC_OK)
      << cwloc_last_error();
  const api::Features features = ReadQueryFeatures(QueryDir(), "query_00001.jpg");
  const double params[] = {900, 512, 384, -0.01};
  const cwloc_camera camera = {"SIMPLE_RADIAL", 1024, 768, params, 4, CWLOC_CALIBRATION_KNOWN};
  cwloc_result* result = nullptr;
  ASSERT_EQ(cwloc_localize_features(
                localizer, features.keypoints.data(), features.descriptors.data(),
                static_cast<uint32_t>(features.keypoints.size() / 2), &camera, nullptr, &result),
            CWLOC_OK)
      << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1);
  const nlohmann::json record = nlohmann::json::parse(cwloc_result_json(result));
  for (const ResultField& field : ResultFields()) {
    double value = -1;
    ASSERT_EQ(cwloc_result_value(result, field.name.c_str(), &value), CWLOC_OK) << field.name;
    const nlohmann::json& json =
        field.group.empty() ? record.at(field.key) : record.at(field.group).at(field.key);
    EXPECT_EQ(value, json.is_boolean() ? double(json.get<bool>()) : json.get<double>())
        << field.name;
  }
  double value = -1;
  EXPECT_EQ(cwloc_result_value(result, "num_inlier", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "unknown result value 'num_inlier'");
  EXPECT_EQ(value, -1);
  cwloc_result_destroy(result);
  cwloc_localizer_close(localizer);
}

}  // namespace
}  // namespace cwloc
