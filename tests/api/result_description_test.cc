// The result types' descriptions (results/describe.h) against every surface: the JSON record
// writes every field at its key, C reads every field by its path, the schema names every key
// with its type, and the option table's lines are the record's parameters. Python's side is
// tests/python/test_results.py.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "app/option_table.h"
#include "app/record_json.h"
#include "app/result_json.h"
#include "results/localization_result.h"
#include "results/result_paths.h"
#include "results/rig_result.h"
#include "tests/api/api_test_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// Sets every field of a value to a value of its own, engaging every optional and giving every
// list two items: numbers count up from `next`, switches are true, text is "text<n>", an enum is
// its last value.
struct Filler {
  int next = 1;

  template <typename T>
  void Fill(T* value) {
    if constexpr (IsOptional<T>::value) {
      Fill(&value->emplace());
    } else if constexpr (Described<T>) {
      ForEachField<T>([&](const auto& field) { Fill(&(value->*field.member)); });
    } else if constexpr (NamedEnum<T>) {
      *value = static_cast<T>(EnumNames<T>::names.size() - 1);
    } else if constexpr (std::is_same_v<T, bool>) {
      *value = true;
    } else if constexpr (Numeric<T>) {
      *value = static_cast<T>(next++);
    } else if constexpr (std::is_same_v<T, std::string>) {
      *value = "text" + std::to_string(next++);
    } else if constexpr (IsStdArray<T>::value) {
      for (auto& item : *value) Fill(&item);
    } else {
      static_assert(IsVector<T>::value);
      value->resize(2);
      for (auto& item : *value) Fill(&item);
    }
  }
};

// One leaf of a described value: its C path, its key path in the record (empty when the record
// leaves it out, and then why), and what the record should hold there.
struct Leaf {
  std::string path, json_path, why_not;
  nlohmann::ordered_json expected;
  FieldInfo info;
};

// Where a value sits: its C path, its key path in the record, or why the record leaves it out.
struct Place {
  std::string path, json_path, why_not;

  Place Field(const FieldInfo& info) const {
    Place child{path.empty() ? std::string(info.name) : path + "." + std::string(info.name), "",
                why_not};
    if (!why_not.empty() || info.json.empty()) {
      if (child.why_not.empty()) child.why_not = info.why_not.empty() ? "-" : info.why_not;
    } else {
      child.json_path =
          json_path.empty() ? std::string(info.json) : json_path + "." + std::string(info.json);
    }
    return child;
  }
  Place Item(size_t i) const {
    return {path + "." + std::to_string(i),
            json_path.empty() ? "" : json_path + "." + std::to_string(i), why_not};
  }
};

template <typename T>
void CollectLeaves(const T& value, const Place& place, const FieldInfo& info,
                   std::vector<Leaf>* leaves);

template <Described T>
void CollectFields(const T& value, const Place& place, std::vector<Leaf>* leaves) {
  ForEachField<T>([&](const auto& field) {
    CollectLeaves(value.*field.member, place.Field(field.info), field.info, leaves);
  });
}

template <typename T>
void CollectLeaves(const T& value, const Place& place, const FieldInfo& info,
                   std::vector<Leaf>* leaves) {
  if constexpr (IsOptional<T>::value) {
    CollectLeaves(*value, place, info, leaves);
  } else if constexpr (Described<T>) {
    CollectFields(value, place, leaves);
  } else if constexpr (IsVector<T>::value && !NumericList<T>) {
    for (size_t i = 0; i < value.size(); ++i) CollectLeaves(value[i], place.Item(i), info, leaves);
  } else {
    leaves->push_back(
        {place.path, place.json_path, place.why_not, *record_json::ValueJson(value, info), info});
  }
}

// The record's value at a dotted key path ("matches.forward", "ranked_images.1.votes").
const nlohmann::ordered_json* At(const nlohmann::ordered_json& record, const std::string& path) {
  const nlohmann::ordered_json* node = &record;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t dot = std::min(path.find('.', start), path.size());
    const std::string key = path.substr(start, dot - start);
    if (node->is_array()) {
      const size_t i = std::stoul(key);
      if (i >= node->size()) return nullptr;
      node = &(*node)[i];
    } else {
      if (!node->contains(key)) return nullptr;
      node = &(*node)[key];
    }
    start = dot + 1;
  }
  return node;
}

// What C reads at a leaf's path, as the record would write it.
nlohmann::ordered_json CReads(const PathValue& value, const FieldInfo& info) {
  using Kind = PathValue::Kind;
  if (value.kind == Kind::kText) return value.text;
  if (value.kind == Kind::kNumbers) {
    if (info.rows == 0) return value.numbers;
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    const size_t columns = value.numbers.size() / info.rows;
    for (int r = 0; r < info.rows; ++r)
      rows.push_back(std::vector<double>(value.numbers.begin() + r * columns,
                                         value.numbers.begin() + (r + 1) * columns));
    return rows;
  }
  return value.number * info.json_scale;
}

// Every leaf at its place in the record and in C. A field written only on success (the pose) or
// only on failure (its reason) is looked for in the records of both.
template <Described T>
void ExpectEveryFieldOnEverySurface(const T& filled) {
  std::vector<Leaf> leaves;
  CollectFields(filled, Place(), &leaves);
  T failed = filled;
  failed.success = false;
  const nlohmann::ordered_json localized = RecordJson(filled), not_localized = RecordJson(failed);
  ASSERT_TRUE(filled.success);
  ASSERT_GT(leaves.size(), 20u);
  for (const Leaf& leaf : leaves) {
    SCOPED_TRACE(leaf.path);
    // JSON: at its key, unless the description says why not.
    if (leaf.json_path.empty()) {
      EXPECT_NE(leaf.why_not, "-") << "left out of the record without a reason";
    } else {
      const nlohmann::ordered_json* json = At(localized, leaf.json_path);
      if (json == nullptr) json = At(not_localized, leaf.json_path);
      ASSERT_NE(json, nullptr) << "not in the record at " << leaf.json_path;
      EXPECT_EQ(*json, leaf.expected);
    }
    // C: by its path, the same value (an enum's name as text, a switch as 1).
    const PathValue value = ResolvePath(filled, leaf.path);
    nlohmann::ordered_json expected = leaf.expected;
    if (expected.is_boolean()) expected = expected.get<bool>() ? 1.0 : 0.0;
    EXPECT_EQ(CReads(value, leaf.info), expected);
  }
}

TEST(ResultDescription, EveryFieldOfAResultReachesTheRecordAndC) {
  LocalizationResult result;
  Filler().Fill(&result);
  ExpectEveryFieldOnEverySurface(result);
}

TEST(ResultDescription, EveryFieldOfARigFrameReachesTheRecordAndC) {
  RigResult result;
  Filler().Fill(&result);
  ExpectEveryFieldOnEverySurface(result);
}

// The record keeps a failed query short: no pose, no distortion; a reason instead. Absent values
// are left out or null as their field says.
TEST(ResultDescription, AbsentValuesAreLeftOutOrNull) {
  LocalizationResult result;
  result.name = "q";
  result.failure_reason = "nothing matched";
  result.covariance.emplace().position_radius95 = 2;
  result.tracking.emplace().seconds = 0.5;
  const nlohmann::ordered_json record = RecordJson(result);
  EXPECT_EQ(record["failure_reason"], "nothing matched");
  EXPECT_FALSE(record.contains("pose"));
  EXPECT_FALSE(record.contains("priors"));  // an object of absent fields
  EXPECT_FALSE(record.contains("geo"));
  EXPECT_TRUE(record["covariance"]["calibration"].is_null());
  EXPECT_FALSE(record["covariance"].contains("enu_position"));
  EXPECT_TRUE(record["tracking"]["predicted_from"].is_null());
  EXPECT_EQ(record["tracking"]["time_ms"], 500.0);
  EXPECT_FALSE(record["tracking"].contains("prediction_error"));
  EXPECT_FALSE(record["camera"].contains("distortion"));
  EXPECT_FALSE(record.contains("inliers"));

  result.success = true;
  result.failure_reason.clear();
  const nlohmann::ordered_json localized = RecordJson(result);
  EXPECT_FALSE(localized.contains("failure_reason"));
  EXPECT_EQ(localized["pose"]["qvec"], nlohmann::ordered_json({1.0, 0.0, 0.0, 0.0}));
}

// The record's parameters are the option table's lines, with their values.
TEST(ResultDescription, TheRecordEchoesEveryOption) {
  QueryOptions options;
  options.localizer.k = 7;
  const nlohmann::ordered_json record = ResultToJson(LocalizationResult(), options);
  EXPECT_EQ(record.at("parameters").size(), OptionTable().size());
  EXPECT_EQ(record.at("parameters").at("k"), 7);
  EXPECT_EQ(record.at("parameters").at("matcher"), "cluster-wise");
  EXPECT_EQ(record.at("parameters").at("use_exif_gps"), false);
}

// What the schema says of a described type's record, against its description: every key with
// its JSON type (an enum's names too), the required ones exactly those always written, and no
// key the description does not write. One line per problem.
class SchemaCheck {
 public:
  explicit SchemaCheck(const nlohmann::json& schema) : schema_(schema) {}

  template <Described T>
  void Object(const nlohmann::json& object, const std::string& where,
              const std::set<std::string>& extra_keys = {}) {
    const nlohmann::json& node = Resolve(object);
    std::set<std::string> written = extra_keys, required = extra_keys;
    std::map<std::string, std::pair<std::set<std::string>, std::set<std::string>>> groups;
    ForEachField<T>([&](const auto& field) {
      using V = typename std::decay_t<decltype(field)>::value_type;
      const std::string json(field.info.json);
      if (json.empty()) return;
      const size_t dot = json.find('.');
      // Written whenever its object is: a value, or null for an absent one that says so.
      const bool in_object =
          (!IsOptional<V>::value || field.info.when_absent == WhenAbsent::kNull) &&
          AlwaysWritten<V>();
      const bool always = in_object && field.written == nullptr;
      if (dot != std::string::npos) {
        // A key inside the record's object of that name (matches.forward).
        const std::string group = json.substr(0, dot), key = json.substr(dot + 1);
        written.insert(group);
        if (always) required.insert(group);
        auto& [group_written, group_required] = groups[group];
        group_written.insert(key);
        if (in_object) group_required.insert(key);
        Value<V>(Property(node, group + "." + key, where), where + "." + json, field.info);
        return;
      }
      written.insert(json);
      if (always) required.insert(json);
      Value<V>(Property(node, json, where), where + "." + json, field.info);
    });
    Keys(node, written, required, where);
    for (const auto& [group, keys] : groups)
      Keys(Property(node, group, where), keys.first, keys.second, where + "." + group);
  }

  std::vector<std::string> problems;

 private:
  // An object whose every field is optional is left out when all are absent (priors).
  template <typename T>
  static bool AlwaysWritten() {
    if constexpr (IsOptional<T>::value) {
      return AlwaysWritten<typename T::value_type>();
    } else if constexpr (Described<T>) {
      bool any = false;
      ForEachField<T>([&](const auto& field) {
        using V = typename std::decay_t<decltype(field)>::value_type;
        any = any || (!IsOptional<V>::value && !field.info.json.empty());
      });
      return any;
    } else {
      return true;
    }
  }

  const nlohmann::json& Resolve(const nlohmann::json& node) const {
    if (!node.contains("$ref")) return node;
    const std::string ref = node["$ref"];  // "#/$defs/a/properties/b"
    const nlohmann::json* target = &schema_;
    for (size_t start = 2; start < ref.size();) {
      const size_t slash = std::min(ref.find('/', start), ref.size());
      target = &(*target)[ref.substr(start, slash - start)];
      start = slash + 1;
    }
    return Resolve(*target);
  }

  const nlohmann::json& Property(const nlohmann::json& object, const std::string& path,
                                 const std::string& where) {
    static const nlohmann::json kMissing;
    const nlohmann::json* node = &Resolve(object);
    for (size_t start = 0; start < path.size();) {
      const size_t dot = std::min(path.find('.', start), path.size());
      const std::string key = path.substr(start, dot - start);
      if (!(*node)["properties"].contains(key)) {
        problems.push_back(where + "." + path + ": not in the schema");
        return kMissing;
      }
      node = &Resolve((*node)["properties"][key]);
      start = dot + 1;
    }
    return *node;
  }

  void Keys(const nlohmann::json& object, const std::set<std::string>& written,
            const std::set<std::string>& required, const std::string& where) {
    const nlohmann::json& node = Resolve(object);
    if (node.is_null()) return;
    for (const auto& [key, value] : node["properties"].items())
      if (!written.count(key)) problems.push_back(where + "." + key + ": no field writes it");
    std::set<std::string> listed;
    if (node.contains("required")) listed = node["required"].get<std::set<std::string>>();
    if (listed != required)
      problems.push_back(where + ": requires other keys than are always written");
  }

  // The schema's type names of a node ("type": "x" or ["x", "null"]).
  static std::set<std::string> Types(const nlohmann::json& node) {
    if (!node.contains("type")) return {};
    if (node["type"].is_string()) return {node["type"].get<std::string>()};
    return node["type"].get<std::set<std::string>>();
  }

  template <typename V>
  void Value(const nlohmann::json& node, const std::string& where, const FieldInfo& info) {
    if (node.is_null()) return;  // reported
    if constexpr (IsOptional<V>::value) {
      if (info.when_absent == WhenAbsent::kNull && !Types(node).count("null"))
        problems.push_back(where + ": null when absent, the schema does not allow null");
      Value<typename V::value_type>(node, where, info);
    } else if constexpr (Described<V>) {
      if (!Types(node).count("object")) problems.push_back(where + ": not an object");
      Object<V>(node, where);
    } else if constexpr (NamedEnum<V>) {
      // The schema may allow fewer (a rig's cameras are never 'unknown'), never others.
      const auto& names = EnumNames<V>::names;
      const std::set<std::string> known(names.begin(), names.end());
      if (!node.contains("enum") || node["enum"].empty()) {
        problems.push_back(where + ": no enum");
      } else {
        for (const std::string& name : node["enum"].get<std::vector<std::string>>())
          if (!known.count(name))
            problems.push_back(where + ": '" + name + "' is no name of the field's enum");
      }
    } else if constexpr (std::is_same_v<V, bool>) {
      if (!Types(node).count("boolean")) problems.push_back(where + ": not a boolean");
    } else if constexpr (std::is_integral_v<V>) {
      if (!Types(node).count("integer")) problems.push_back(where + ": not an integer");
    } else if constexpr (std::is_floating_point_v<V>) {
      if (!Types(node).count("number")) problems.push_back(where + ": not a number");
    } else if constexpr (std::is_same_v<V, std::string>) {
      if (!Types(node).count("string")) problems.push_back(where + ": not a string");
    } else if constexpr (NumericArray<V>) {
      const size_t items = info.rows > 0 ? size_t(info.rows) : std::tuple_size_v<V>;
      if (!Types(node).count("array") || node.value("minItems", 0u) != items ||
          node.value("maxItems", 0u) != items)
        problems.push_back(where + ": not an array of " + std::to_string(items));
    } else if constexpr (DescribedList<V>) {
      if (!Types(node).count("array")) problems.push_back(where + ": not an array");
      Object<typename V::value_type>(node["items"], where + "[]");
    } else {
      if (!Types(node).count("array")) problems.push_back(where + ": not an array");
    }
  }

  const nlohmann::json& schema_;
};

nlohmann::json Schema() {
  return nlohmann::json::parse(
      test::ReadFile(test::SourceDir() / "schemas/localization-result.schema.json"));
}

std::vector<std::string> SchemaProblems(const nlohmann::json& schema) {
  SchemaCheck check(schema);
  check.Object<LocalizationResult>(schema["$defs"]["result"], "result", {"parameters"});
  check.Object<RigResult>(schema["$defs"]["rig_frame"], "rig_frame", {"parameters"});
  // The record's parameters: the option table's lines.
  std::set<std::string> options;
  for (const OptionSpec& spec : OptionTable()) options.insert(std::string(spec.name));
  const nlohmann::json& parameters = schema["$defs"]["result"]["properties"]["parameters"];
  for (const auto& [key, value] : parameters["properties"].items())
    if (!options.count(key)) check.problems.push_back("parameters." + key + ": in no option line");
  for (const std::string& option : options)
    if (!parameters["properties"].contains(option))
      check.problems.push_back("parameters." + option + ": not in the schema");
  return check.problems;
}

TEST(ResultDescription, TheSchemaNamesEveryFieldWithItsType) {
  EXPECT_THAT(SchemaProblems(Schema()), testing::IsEmpty());
}

// The check above can fail: a field the schema lost, one of the wrong type, an enum's names, a
// required key too many and an option the schema still names after the table dropped it.
TEST(ResultDescription, AStaleSchemaIsNamed) {
  nlohmann::json schema = Schema();
  nlohmann::json& record = schema["$defs"]["result"]["properties"];
  record["matches"]["properties"].erase("forward");
  record["inlier_ratio"]["type"] = "integer";
  record["tracking"]["properties"]["mode"]["enum"] = {"tracked", "lost", "frozen"};
  record["camera"]["required"].push_back("distortion");
  record["parameters"]["properties"]["max_back_clusters"] = {{"type", "integer"}};
  EXPECT_THAT(SchemaProblems(schema),
              testing::UnorderedElementsAre(
                  "result.camera: requires other keys than are always written",
                  "result.inlier_ratio: not a number", "result.matches.forward: not in the schema",
                  "result.tracking.mode: 'frozen' is no name of the field's enum",
                  "parameters.max_back_clusters: in no option line"));
}

// C reads a real result's fields by their paths: the values its JSON record holds.
TEST(ResultDescription, CReadsARealResultAsItsRecord) {
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
  EXPECT_EQ(CValue(result, "num_inliers"), record["num_inliers"].get<double>());
  EXPECT_EQ(CValue(result, "forward_matches"), record["matches"]["forward"].get<double>());
  EXPECT_EQ(CValue(result, "guided"), record["matches"]["guided"].get<bool>() ? 1 : 0);
  EXPECT_EQ(CValue(result, "times.total") * 1e3, record["times_ms"]["total"].get<double>());
  EXPECT_EQ(CValues(result, "center"), record["pose"]["center"].get<std::vector<double>>());
  EXPECT_EQ(CText(result, "camera.distortion.fit"), record["camera"]["distortion"]["fit"]);
  cwloc_result_destroy(result);
  cwloc_localizer_close(localizer);
}

}  // namespace
}  // namespace cwloc
