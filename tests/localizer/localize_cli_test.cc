// cwloc-localize as a user runs it: JSON lines against the schema, the poses file, exit codes,
// and an error record per bad query while the others finish.
#include <gmock/gmock.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "indexer/index_builder.h"
#include "localizer/pose/refine_pose.h"
#include "tests/indexer/indexer_fixture.h"
#include "tests/localization_check.h"
#include "tests/test_png.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

std::vector<nlohmann::json> JsonLines(const std::string& text) {
  std::vector<nlohmann::json> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '{') lines.push_back(nlohmann::json::parse(line));
  }
  return lines;
}

int ValidateAgainstSchema(const std::filesystem::path& json_lines, std::string* output) {
  return test::ValidateJson("localization-result.schema.json", json_lines, true, output);
}

class LocalizeCliTest : public test::IndexerFixture {
 protected:
  void SetUp() override {
    IndexerFixture::SetUp();
    BuildFixtureIndex();
  }

  int Run(const std::string& args, std::string* output) const {
    return test::RunCommand(
        test::ToolPath("cwloc-localize").string() + " --index " + index_path_.string() + " " + args,
        output);
  }

  std::string FirstImageName() const { return model_.images.begin()->second.name; }
};

TEST_F(LocalizeCliTest, BadQueryGetsAnErrorRecordAndTheOthersFinish) {
  std::string output;
  const auto jsonl = dir_ / "out.jsonl";
  const int code = Run("--database " + database_path_.string() + " --query nope.jpg --query " +
                           FirstImageName() + " -o " + jsonl.string(),
                       &output);
  EXPECT_EQ(code, 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + database_path_.string() +
                                ": no image named 'nope.jpg'"));
  std::ifstream in(jsonl);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto lines = JsonLines(text);
  ASSERT_EQ(lines.size(), 2u) << text;
  int errors = 0, results = 0;
  for (const auto& line : lines) {
    if (line.contains("error")) {
      ++errors;
      EXPECT_EQ(line["name"], "nope.jpg");
    } else {
      ++results;
      EXPECT_EQ(line["name"], FirstImageName());
    }
  }
  EXPECT_EQ(errors, 1) << text;
  EXPECT_EQ(results, 1);
  std::string validation;
  EXPECT_EQ(ValidateAgainstSchema(jsonl, &validation), 0) << validation;
}

// A query named for the database needs --database; the error names the query.
TEST_F(LocalizeCliTest, ADatabaseQueryWithoutADatabaseIsNamedInItsError) {
  std::string output;
  const auto jsonl = dir_ / "out.jsonl";
  EXPECT_EQ(Run("--query " + FirstImageName() + " -o " + jsonl.string(), &output), 2) << output;
  const std::string error = "query '" + FirstImageName() + "': give --database to read it from";
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + error));
  const auto records = test::ReadJsonLines(jsonl);
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0]["error"], error);
}

TEST_F(LocalizeCliTest, EveryMatcherNameRunsAndIsReported) {
  for (const std::string matcher : {"cluster-wise", "global-ratio", "cluster-exhaustive"}) {
    std::string output;
    const auto jsonl = dir_ / (matcher + ".jsonl");
    EXPECT_LE(Run("--database " + database_path_.string() + " --query " + FirstImageName() +
                      " --matcher " + matcher + " -o " + jsonl.string(),
                  &output),
              1)
        << output;
    std::ifstream in(jsonl);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    const auto lines = JsonLines(text);
    ASSERT_EQ(lines.size(), 1u) << text;
    EXPECT_EQ(lines[0]["parameters"]["matcher"], matcher);
    std::string validation;
    EXPECT_EQ(ValidateAgainstSchema(jsonl, &validation), 0) << validation;
  }
}

// The back-matching modes and a latency budget reach the JSON, which the schema accepts: auto
// does not guide a camera whose focal length is estimated (HerzJesuTest has it guide a known
// one); a budget spent before the first search cuts forward matching and says so.
TEST_F(LocalizeCliTest, BackMatchingModeAndBudgetAreReported) {
  const std::string query =
      "--database " + database_path_.string() + " --query " + FirstImageName();
  struct Case {
    std::string flags;
    std::string mode;
    bool guided;
    nlohmann::json budget;  // null: no "budget" key
  };
  const std::vector<Case> cases = {
      {"", "auto", false, nullptr},  // the database camera: its focal length is estimated
      {"--back-matching guided", "guided", true, nullptr},
      {"--back-matching full", "full", false, nullptr},
      {"--budget-ms 1e-6", "auto", false, {{"ms", 1e-6}, {"cut", {"forward"}}}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.flags);
    std::string output;
    const auto jsonl = dir_ / "modes.jsonl";
    EXPECT_LE(Run(query + " " + c.flags + " -o " + jsonl.string(), &output), 1) << output;
    const auto records = test::ReadJsonLines(jsonl);
    ASSERT_EQ(records.size(), 1u);
    EXPECT_EQ(records[0]["parameters"]["back_matching"], c.mode);
    EXPECT_EQ(records[0]["matches"]["guided"], c.guided);
    if (c.budget.is_null()) {
      EXPECT_FALSE(records[0].contains("budget"));
      EXPECT_TRUE(records[0]["success"].get<bool>());
    } else {
      EXPECT_EQ(records[0]["budget"], c.budget);
      EXPECT_FALSE(records[0]["success"].get<bool>());
      EXPECT_EQ(records[0]["matches"]["features_searched"], 0);
    }
    std::string validation;
    EXPECT_EQ(ValidateAgainstSchema(jsonl, &validation), 0) << validation;
  }
  std::string output;
  EXPECT_EQ(Run(query + " --back-matching psychic", &output), 2);
  EXPECT_THAT(output, HasSubstr("--back-matching psychic: expected auto, guided or full"));
  EXPECT_EQ(Run(query + " --budget-ms -1", &output), 2);
  EXPECT_THAT(output, HasSubstr("--budget-ms -1: expected"));
}

TEST_F(LocalizeCliTest, RefinerIsReportedAndCeresNeedsABuildWithIt) {
  for (const std::string_view name : kPoseRefinerNames) {
    const std::string refiner(name);
    std::string output;
    const auto jsonl = dir_ / (refiner + ".jsonl");
    const int code = Run("--database " + database_path_.string() + " --query " + FirstImageName() +
                             " --refiner " + refiner + " -o " + jsonl.string(),
                         &output);
    if (!PoseRefinerAvailable(*ParsePoseRefiner(refiner))) {
      EXPECT_EQ(code, 2) << output;
      EXPECT_THAT(output, HasSubstr("--refiner ceres: this build has no Ceres"));
      continue;
    }
    EXPECT_LE(code, 1) << output;
    const auto lines = test::ReadJsonLines(jsonl);
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(lines[0]["parameters"]["refiner"], refiner);
    std::string validation;
    EXPECT_EQ(ValidateAgainstSchema(jsonl, &validation), 0) << validation;
  }
}

TEST_F(LocalizeCliTest, CorruptOrMissingIndexIsAClearError) {
  std::string output;
  EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " +
                                 (dir_ / "none.cwl").string() + " --query x",
                             &output),
            2);
  EXPECT_THAT(output, HasSubstr("none.cwl: cannot open: No such file or directory"));

  std::fstream file(index_path_, std::ios::in | std::ios::out | std::ios::binary);
  file.seekp(200);
  file.put('\x7f');
  file.close();
  EXPECT_EQ(Run("--verify --database " + database_path_.string() + " --query " + FirstImageName(),
                &output),
            2);
  EXPECT_THAT(output, HasSubstr("checksum mismatch"));
}

// A batch from a query list with bad queries mixed in: each bad one gets its error record
// naming it, every good one finishes, and the exit code says some query failed (#13).
TEST_F(LocalizeCliTest, BadQueriesInABatchAreEachReportedAndTheGoodOnesFinish) {
  // The first model image's own features: it localizes against the model.
  const auto& [id, image] = *model_.images.begin();
  const colmap::Camera& camera = model_.cameras.at(image.camera_id);
  std::string camera_spec = std::string(CameraModelName(camera.model_id)) + " " +
                            std::to_string(camera.width) + " " + std::to_string(camera.height);
  for (const double param : camera.params) {
    camera_spec += ' ';
    camera_spec += std::to_string(param);
  }
  {
    std::ofstream out(dir_ / "good.txt");
    out << image.points2D.size() << " 128\n";
    for (size_t i = 0; i < image.points2D.size(); ++i) {
      out << image.points2D[i].x << " " << image.points2D[i].y << " 1 0";
      for (int d = 0; d < 128; ++d) out << " " << int(descriptors_.at(id).data[i * 128 + d]);
      out << "\n";
    }
  }
  std::ofstream(dir_ / "empty.txt") << "0 128\n";
  std::ofstream(dir_ / "garbled.txt") << "3 128\n1 2 3\n";
  const auto list = dir_ / "queries.txt";
  std::ofstream(list) << "good.txt " << camera_spec << "\n"
                      << "missing.txt " << camera_spec << "\n"
                      << "empty.txt " << camera_spec << "\n"
                      << "garbled.txt " << camera_spec << "\n"
                      << "good.txt SIMPLE_PINHOLE 0 480 500 320 240\n"
                      << "good.txt FISH 640 480 500\n";
  const auto jsonl = dir_ / "batch.jsonl";
  std::string output;
  EXPECT_EQ(Run("--query-list " + list.string() + " --threads 2 -o " + jsonl.string(), &output), 2)
      << output;
  std::vector<std::string> errors;
  int localized = 0;
  for (const auto& record : test::ReadJsonLines(jsonl)) {
    if (record.contains("error")) {
      errors.push_back(record["error"]);
    } else {
      EXPECT_EQ(record["name"], "good.txt");
      localized += record["success"].get<bool>();
    }
  }
  std::sort(errors.begin(), errors.end());
  std::string in_list = list.string();
  in_list += " (good.txt): ";
  std::vector<std::string> expected = {
      (dir_ / "missing.txt").string() + ": cannot open",
      (dir_ / "empty.txt").string() + ": the query has no features",
      (dir_ / "garbled.txt").string() +
          ":2: expected X Y SCALE ORIENTATION then 128 descriptor values",
      in_list + "expected a positive image width (at most 1000000)",
      in_list + "unknown camera model 'FISH'",
  };
  ASSERT_EQ(errors.size(), expected.size()) << output;
  for (const std::string& want : expected) {
    EXPECT_EQ(std::count_if(errors.begin(), errors.end(),
                            [&](const std::string& e) { return e.rfind(want, 0) == 0; }),
              1)
        << want << "\n"
        << output;
  }
  EXPECT_EQ(localized, 1) << output;
}

TEST_F(LocalizeCliTest, QueryWithNoFeaturesIsAnError) {
  const auto features = dir_ / "empty.txt";
  std::ofstream(features) << "0 128\n";
  std::string output;
  EXPECT_EQ(
      Run("--features " + features.string() + " --camera \"SIMPLE_PINHOLE 640 480 500 320 240\"",
          &output),
      2);
  EXPECT_THAT(output, HasSubstr(features.string() + ": the query has no features"));
  EXPECT_THAT(output, HasSubstr("\"error\""));
}

TEST_F(LocalizeCliTest, UnknownCameraModelNamesTheKnownOnes) {
  const auto features = dir_ / "one.txt";
  std::string line = "1 128\n1 2 3 4";
  for (int i = 0; i < 128; ++i) line += " 1";
  std::ofstream(features) << line << "\n";
  std::string output;
  EXPECT_EQ(Run("--features " + features.string() + " --camera \"FISH 640 480 500\"", &output), 2);
  EXPECT_THAT(output,
              HasSubstr("--camera: unknown camera model 'FISH' (known: SIMPLE_PINHOLE, PINHOLE"));
}

TEST_F(LocalizeCliTest, AbsurdParametersAreRejected) {
  std::string output;
  EXPECT_EQ(Run("--database " + database_path_.string() + " --query x --ratio 2", &output), 2);
  EXPECT_THAT(output, HasSubstr("--ratio 2: expected a value in (0, 1]"));
  EXPECT_EQ(Run("--database " + database_path_.string() + " --query x --k 0", &output), 2);
  EXPECT_THAT(output, HasSubstr("--k 0: expected 1 to 63"));
  EXPECT_EQ(Run("--database " + database_path_.string() + " --query x --matcher nearest", &output),
            2);
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: --matcher nearest: expected cluster-wise, "
                                "global-ratio or cluster-exhaustive"));
  // Refused, not failing every query later (the option table's ranges).
  EXPECT_EQ(Run("--database " + database_path_.string() + " --query x --nb 0", &output), 2);
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: --nb 0: expected at least 1\n"));
  EXPECT_EQ(
      Run("--database " + database_path_.string() + " --query x --min-vote-matches 0", &output), 2);
  EXPECT_THAT(output, HasSubstr("--min-vote-matches 0: expected at least 1"));
  EXPECT_EQ(Run("", &output), 2);
  EXPECT_THAT(output, HasSubstr("no queries"));
}

// cwloc-index on herz_jesu_p25's mapping model; uncalibrated, since these tests are about the
// CLI (covariance_calibration_test.cc tests the calibration on the shared index).
void BuildHerzJesuIndex(const std::filesystem::path& data, const std::filesystem::path& index) {
  std::string output;
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model " +
                                 (data / "mapping_model" / "bin").string() + " --database " +
                                 (data / "database.db").string() + " -o " + index.string() +
                                 " --calibration-samples 0",
                             &output),
            0)
      << output;
}

// cwloc-localize on herz_jesu_p25's database queries listed in `list`, two at a time.
int LocalizeHerzJesu(const std::filesystem::path& data, const std::filesystem::path& index,
                     const std::string& list, const std::string& args, std::string* output) {
  return test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " + index.string() +
                              " --database " + (data / "database.db").string() + " --query-list " +
                              (data / list).string() + " --threads 2 " + args,
                          output);
}

// The database's camera of herz_jesu_p25 has prior_focal_length = 0: its focal length 1843.2 is
// the feature extractor's guess 1.2 * max(w, h), which localized all 5 queries 4.4 m off (median)
// when it was taken as known. Read as an unknown focal length, they come out within centimetres.
TEST(LocalizeCliHerzJesu, DatabaseCameraWithoutPriorIsAnUnknownFocal) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  test::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(BuildHerzJesuIndex(data, dir / "hj.cwl"));
  std::string output;
  ASSERT_EQ(LocalizeHerzJesu(data, dir / "hj.cwl", "query_list.txt",
                             "-o " + (dir / "out.jsonl").string(), &output),
            0)
      << output;
  std::string validation;
  EXPECT_EQ(ValidateAgainstSchema(dir / "out.jsonl", &validation), 0) << validation;
  // The readable lines give the 95 % position radius (herz_jesu_p25's model is not
  // georeferenced: model units) and the estimated focal length with its standard deviation.
  EXPECT_THAT(output,
              testing::ContainsRegex(
                  "0002.jpg: localized, [0-9]+ inliers / [0-9]+ correspondences, position "
                  "\\+- 0.00[0-9]+ model units \\(95 %\\), f 137[0-9].[0-9] \\+- 0.[0-9] px, "));
  EXPECT_THAT(output, testing::Not(testing::HasSubstr("weakly constrained")));
  const auto truth = test::ReadGroundTruth(data / "queries_gt.txt");
  const double metres_per_unit = test::ReadMetresPerUnit(data / "scale_to_metres.txt");
  const auto lines = test::ReadJsonLines(dir / "out.jsonl");
  ASSERT_EQ(lines.size(), 5u);
  std::vector<double> positions;
  for (const auto& result : lines) {
    const std::string name = result.at("name");
    SCOPED_TRACE(name);
    ASSERT_TRUE(result.at("success").get<bool>());
    const auto& camera = result.at("camera");
    EXPECT_EQ(camera.at("calibration"), "unknown");
    EXPECT_EQ(camera.at("intrinsics_source"), "database");
    EXPECT_EQ(camera.at("model"), "SIMPLE_RADIAL");
    EXPECT_TRUE(camera.at("focal_estimated").get<bool>());
    EXPECT_NEAR(camera.at("params").at(0).get<double>(), 1375.77, 0.01 * 1375.77);
    // Which distortion model, and why: k refined with f, with its standard deviation.
    const auto& distortion = camera.at("distortion");
    EXPECT_EQ(distortion.at("model"), "SIMPLE_RADIAL");
    EXPECT_EQ(distortion.at("fit"), "estimated");
    EXPECT_EQ(distortion.at("k"), camera.at("params").at(3));
    EXPECT_GT(distortion.at("k_std").get<double>(), 0.0);
    EXPECT_EQ(
        distortion.at("k_significant").get<bool>(),
        std::abs(distortion.at("k").get<double>()) >= 2 * distortion.at("k_std").get<double>());
    EXPECT_THAT(distortion.at("why").get<std::string>(),
                HasSubstr("the camera was not known: one radial term k was refined"));
    // Full frames: the estimated focal length is known to well under a pixel.
    const auto& focal_depth = result.at("focal_depth");
    EXPECT_LT(focal_depth.at("focal_std_px").get<double>(), 1.0);
    EXPECT_GT(focal_depth.at("depth_std").get<double>(), 0.0);
    EXPECT_FALSE(focal_depth.at("weakly_constrained").get<bool>());
    const test::PoseError error =
        test::ErrorOf(test::PoseOfResult(result), truth.at(name).pose, metres_per_unit);
    EXPECT_LE(error.rotation_deg, 0.5);
    positions.push_back(error.position_m);
  }
  std::sort(positions.begin(), positions.end());
  EXPECT_LE(positions[2], 0.05);  // the bound on the median; measured 3.4 mm
}

// The builtin refiner takes Ceres' steps (refine_pose_builtin.cc), so the whole pipeline gives
// the same poses, cameras and inlier counts with either: known intrinsics refine the pose, the
// database cameras (prior_focal_length 0) the pose, f and k. Measured: the same inlier counts,
// poses and cameras at most 2e-15 apart (relative).
TEST(LocalizeCliHerzJesu, BuiltinRefinerGivesCeresPoses) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  if (!PoseRefinerAvailable(PoseRefiner::kCeres)) GTEST_SKIP() << "a build without Ceres";
  test::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(BuildHerzJesuIndex(data, dir / "hj.cwl"));
  std::string output;
  // |a - b| relative to |a| (or to 1 where a may be near 0, as k and the quaternion).
  const auto expect_close = [](const nlohmann::json& a, const nlohmann::json& b, bool relative,
                               const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    double diff = 0.0, norm = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
      diff += std::pow(a[i].get<double>() - b[i].get<double>(), 2);
      norm += std::pow(a[i].get<double>(), 2);
    }
    EXPECT_LE(std::sqrt(diff), 1e-7 * (relative ? std::sqrt(norm) : 1.0)) << what;
  };
  for (const std::string list : {"queries_with_intrinsics.txt", "query_list.txt"}) {
    SCOPED_TRACE(list);
    std::map<std::string, nlohmann::json> results[2];
    for (int r = 0; r < 2; ++r) {
      const std::string refiner(kPoseRefinerNames[r]);
      const auto jsonl = dir / (refiner + "_" + list + ".jsonl");
      ASSERT_EQ(LocalizeHerzJesu(data, dir / "hj.cwl", list,
                                 "--refiner " + refiner + " -o " + jsonl.string(), &output),
                0)
          << output;
      for (const auto& result : test::ReadJsonLines(jsonl)) {
        EXPECT_EQ(result.at("parameters").at("refiner"), refiner);
        results[r][result.at("name")] = result;
      }
    }
    ASSERT_EQ(results[0].size(), 5u);
    ASSERT_EQ(results[1].size(), 5u);
    for (const auto& [name, ceres] : results[0]) {
      SCOPED_TRACE(name);
      ASSERT_TRUE(results[1].contains(name));
      const nlohmann::json& builtin = results[1].at(name);
      ASSERT_EQ(ceres.at("success"), builtin.at("success"));
      EXPECT_EQ(ceres.at("num_inliers"), builtin.at("num_inliers"));
      if (!ceres.at("success").get<bool>()) continue;
      expect_close(ceres["pose"]["qvec"], builtin["pose"]["qvec"], false, "qvec");
      expect_close(ceres["pose"]["tvec"], builtin["pose"]["tvec"], true, "tvec");
      expect_close(ceres["pose"]["center"], builtin["pose"]["center"], true, "center");
      const auto& params_a = ceres["camera"]["params"];
      const auto& params_b = builtin["camera"]["params"];
      ASSERT_EQ(params_a.size(), params_b.size());
      for (size_t i = 0; i < params_a.size(); ++i) {
        const double a = params_a[i].get<double>(), b = params_b[i].get<double>();
        EXPECT_LE(std::abs(a - b), 1e-7 * std::max(1.0, std::abs(a))) << "camera param " << i;
      }
    }
  }
}

TEST(LocalizeCliHerzJesu, LocalizesEveryQueryWithValidJsonAndPoses) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  test::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(BuildHerzJesuIndex(data, dir / "hj.cwl"));
  std::string output;
  const int code = LocalizeHerzJesu(
      data, dir / "hj.cwl", "queries_with_intrinsics.txt",
      "-o " + (dir / "out.jsonl").string() + " --poses " + (dir / "poses.txt").string(), &output);
  EXPECT_EQ(code, 0) << output;
  EXPECT_THAT(output, HasSubstr("localized 5 of 5 queries"));
  std::string validation;
  EXPECT_EQ(ValidateAgainstSchema(dir / "out.jsonl", &validation), 0) << validation;
  for (const auto& result : test::ReadJsonLines(dir / "out.jsonl")) {
    EXPECT_EQ(result.at("camera").at("distortion"),
              nlohmann::json({{"model", "SIMPLE_RADIAL"},
                              {"fit", "given"},
                              {"why",
                               "the camera was known: its own model and parameters, "
                               "held fixed"}}));
  }
  std::ifstream poses(dir / "poses.txt");
  int lines = 0;
  for (std::string line; std::getline(poses, line); ++lines) {
    std::istringstream fields(line);
    std::string name;
    double values[7];
    fields >> name;
    for (double& value : values) ASSERT_TRUE(fields >> value) << line;
  }
  EXPECT_EQ(lines, 5);
}

// -o and --poses in a folder that does not exist fail before any query, naming the file.
TEST(LocalizeOutputTest, AnOutputThatCannotBeWrittenFailsAtStart) {
  const std::filesystem::path golden = test::SourceDir() / "tests" / "data" / "golden";
  test::TempDir dir;
  const std::filesystem::path missing = dir / "missing" / "out.txt";
  for (const std::string option : {"-o", "--poses"}) {
    std::string output;
    EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " +
                                   (golden / "index-1.1.cwl").string() + " --features " +
                                   (golden / "index-1.1-queries" / "query_00001.jpg.txt").string() +
                                   " --camera 'SIMPLE_RADIAL 1024 768 900 512 384 -0.01' " +
                                   option + " " + missing.string(),
                               &output),
              2)
        << option;
    EXPECT_EQ(output, "cwloc-localize: error: " + missing.string() +
                          ": cannot create a temporary file next to it: No such file or "
                          "directory\n");
  }
}

// The records of a JSON lines text without their timings, which differ from run to run; false
// when a line is not a whole record.
bool ParseRecords(const std::string& text, std::vector<nlohmann::json>* records) {
  records->clear();
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    nlohmann::json record = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (!record.is_object() || !record.contains("name")) return false;
    record.erase("times_ms");
    records->push_back(std::move(record));
  }
  return text.empty() || text.back() == '\n';
}

// cwloc-localize killed at random moments while it writes -o and --poses (docs/reliability.md,
// "Interrupted writers"): each holds its previous file byte for byte, or whole records that an
// uninterrupted run begins with, never an empty or a partial file; the next complete run leaves
// nothing beside them.
// The golden index's 4 queries 40 times over (about 2 s; one thread keeps their order) run by
// cwloc-localize into -o json_ and --poses poses_, once to the end: the records, pose lines and
// duration that interrupted runs are compared with.
class GoldenBatchTest : public testing::Test {
 protected:
  // The golden index's 4 queries, 40 times over (10 under a sanitizer: 40 took 31 s there).
  static constexpr size_t kQueries = test::kSanitized ? 40 : 160;

  void SetUp() override {
    const std::filesystem::path golden = test::SourceDir() / "tests" / "data" / "golden";
    {
      std::ofstream list(dir_ / "queries.txt");
      for (size_t round = 0; round < kQueries / 4; ++round) {
        for (int query = 1; query <= 4; ++query) {
          list << (golden / "index-1.1-queries" /
                   ("query_0000" + std::to_string(query) + ".jpg.txt"))
                      .string()
               << " SIMPLE_RADIAL 1024 768 900 512 384 -0.01\n";  // their camera (queries_gt.txt)
        }
      }
    }
    args_ = {test::ToolPath("cwloc-localize").string(),
             "--index",
             (golden / "index-1.1.cwl").string(),
             "--query-list",
             (dir_ / "queries.txt").string(),
             "--threads",
             "1",
             "-q",
             "-o",
             json_.string(),
             "--poses",
             poses_.string()};
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(test::Wait(test::Spawn(args_)), 0);
    duration_ = std::chrono::steady_clock::now() - start;
    ASSERT_TRUE(ParseRecords(test::ReadFile(json_), &complete_));
    ASSERT_EQ(complete_.size(), kQueries);
    complete_poses_ = test::ReadFile(poses_);
    ASSERT_EQ(size_t(std::count(complete_poses_.begin(), complete_poses_.end(), '\n')), kQueries);
  }

  test::TempDir dir_;
  const std::filesystem::path json_ = dir_ / "out.jsonl", poses_ = dir_ / "poses.txt";
  std::vector<std::string> args_;
  std::chrono::steady_clock::duration duration_{};
  std::vector<nlohmann::json> complete_;
  std::string complete_poses_;
};

class LocalizeKillTest : public GoldenBatchTest {
 protected:
  // A SIGKILLed run leaves a sanitizer nothing to report, and the complete runs are the ones
  // every other test makes: under a sanitizer this test would only be 10x slower.
  void SetUp() override {
    if (test::kSanitized) GTEST_SKIP() << "kills are not a sanitizer's subject";
    GoldenBatchTest::SetUp();
  }
};
class LocalizeInterruptTest : public GoldenBatchTest {};

TEST_F(LocalizeKillTest, KilledRunsLeaveThePreviousOutputsOrWholeRecords) {
  namespace fs = std::filesystem;
  const std::string previous_json = "{\"name\": \"a previous run\"}\n";
  const std::string previous_poses = "previous.jpg 1 0 0 0 0 0 0\n";
  auto& rng = test::Rng();
  int kept_previous = 0;
  std::vector<pid_t> killed;
  for (int kill_number = 0; kill_number < 16; ++kill_number) {
    SCOPED_TRACE("kill " + std::to_string(kill_number));
    std::ofstream(json_) << previous_json;
    std::ofstream(poses_) << previous_poses;
    const pid_t pid = test::Spawn(args_);
    killed.push_back(pid);
    // Every other kill lands in the run's first 5%, where it opens its outputs and writes the
    // first records; the others anywhere.
    const int per_mille = static_cast<int>(rng() % 1000) / (kill_number % 2 == 0 ? 20 : 1);
    test::KillAfter(pid, duration_ * per_mille / 1000);

    const std::string text = test::ReadFile(json_);
    std::vector<nlohmann::json> records;
    if (text == previous_json) {
      ++kept_previous;
    } else {
      EXPECT_TRUE(ParseRecords(text, &records) && !records.empty()) << "not whole records:\n"
                                                                    << text;
      EXPECT_TRUE(records.size() <= complete_.size() &&
                  std::equal(records.begin(), records.end(), complete_.begin()))
          << "not the records a complete run begins with";
    }
    const std::string pose_text = test::ReadFile(poses_);
    if (pose_text != previous_poses) {
      EXPECT_TRUE(!pose_text.empty() && pose_text.back() == '\n' &&
                  complete_poses_.compare(0, pose_text.size(), pose_text) == 0)
          << "not the pose lines a complete run begins with:\n"
          << pose_text;
    }
    // A kill between a checkpoint's link and rename leaves `<name>.tmp-<pid>-u<n>`.
    for (const fs::path& entry : test::ListDir(dir_.path())) {
      const std::string name = entry.filename().string();
      if (entry == json_ || entry == poses_ || name == "queries.txt") continue;
      EXPECT_TRUE(test::IsKilledWritersTemporary(name, json_.filename().string(), killed) ||
                  test::IsKilledWritersTemporary(name, poses_.filename().string(), killed))
          << name;
    }
  }
  std::cout << kept_previous << " of 16 kills found the previous outputs, the others records\n";
  // A complete run writes every record and removes what killed runs left.
  ASSERT_EQ(test::Wait(test::Spawn(args_)), 0);
  std::vector<fs::path> entries = test::ListDir(dir_.path());
  std::sort(entries.begin(), entries.end());
  EXPECT_EQ(entries, (std::vector<fs::path>{json_, poses_, dir_ / "queries.txt"}));
  std::vector<nlohmann::json> records;
  EXPECT_TRUE(ParseRecords(test::ReadFile(json_), &records) && records == complete_);
  EXPECT_EQ(test::ReadFile(poses_), complete_poses_);
}

// SIGINT or SIGTERM (Ctrl-C, a plain kill) at a random moment stops the batch after the running
// query and loses nothing: every finished query's record and pose line is in place, in order,
// the message says how many, and the exit code is 128 + the signal, as the shell reports it.
TEST_F(LocalizeInterruptTest, AnInterruptedRunKeepsEveryFinishedRecord) {
  const std::filesystem::path log = dir_ / "log.txt";
  auto& rng = test::Rng();
  for (int interrupt = 0; interrupt < 4; ++interrupt) {
    SCOPED_TRACE("interrupt " + std::to_string(interrupt));
    const int signal_number = interrupt % 2 == 0 ? SIGINT : SIGTERM;
    std::ofstream(json_) << "{\"name\": \"a previous run\"}\n";
    const pid_t pid = test::Spawn(args_, log);
    // Once it catches the signal (before that, as for any process, the signal ends it before it
    // has written anything; under load that can take longer than the delay below), then 5-45 %
    // into the run measured once under the same load: a run up to twice as fast as that one is
    // still running when the signal comes.
    ASSERT_TRUE(test::WaitUntilCatching(pid, signal_number, std::chrono::seconds(30)));
    std::this_thread::sleep_for(duration_ * (50 + static_cast<int>(rng() % 400)) / 1000);
    ::kill(pid, signal_number);
    EXPECT_EQ(test::Wait(pid), 128 + signal_number);

    const std::string message = test::ReadFile(log);
    std::smatch match;
    ASSERT_TRUE(std::regex_match(
        message, match,
        std::regex("cwloc-localize: interrupted by " +
                   std::string(signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
                   " after ([0-9]+) of " + std::to_string(kQueries) + " queries\n")))
        << message;
    const size_t finished = std::stoul(match[1]);
    EXPECT_LT(finished, kQueries);
    std::vector<nlohmann::json> records;
    ASSERT_TRUE(ParseRecords(test::ReadFile(json_), &records));
    ASSERT_EQ(records.size(), finished);
    EXPECT_TRUE(std::equal(records.begin(), records.end(), complete_.begin()));
    // Every golden query localizes, so each finished one has its pose line.
    size_t pose_bytes = 0;
    for (size_t line = 0; line < finished; ++line)
      pose_bytes = complete_poses_.find('\n', pose_bytes) + 1;
    EXPECT_EQ(test::ReadFile(poses_), complete_poses_.substr(0, pose_bytes));
  }
}

// A query still running a second after the signal is abandoned: the batch ends then, with the
// records finished before it, instead of waiting for a large photo's SIFT (seconds; a minute
// under the sanitizers).
// (No golden batch: this test needs none, and under ASan the batch took most of its time.)
TEST(LocalizeInterrupt, AQueryRunningASecondAfterTheSignalIsAbandoned) {
  const test::TempDir dir;
  const std::filesystem::path photo = dir / "noise.png", json = dir / "out.jsonl";
  test::WriteNoisePng(photo, 3200, 3200, 1);
  const std::filesystem::path log = dir / "log.txt";
  const std::vector<std::string> args = {test::ToolPath("cwloc-localize").string(),
                                         "--index",
                                         (test::GoldenDir() / "index-1.1.cwl").string(),
                                         "--image",
                                         photo.string(),
                                         "-o",
                                         json.string(),
                                         "-q"};
  const pid_t pid = test::Spawn(args, log);
  ASSERT_TRUE(test::WaitUntilCatching(pid, SIGTERM, std::chrono::seconds(30)));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto signalled = std::chrono::steady_clock::now();
  ::kill(pid, SIGTERM);
  EXPECT_EQ(test::Wait(pid), 128 + SIGTERM);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  EXPECT_LT(seconds, 3.0);  // 1 s of grace, and a margin for a loaded machine
  EXPECT_EQ(test::ReadFile(log),
            "cwloc-localize: interrupted by SIGTERM after 0 of 1 queries; 1 running query "
            "abandoned\n");
  EXPECT_EQ(test::ReadFile(json), "");
}

}  // namespace
}  // namespace cwloc
