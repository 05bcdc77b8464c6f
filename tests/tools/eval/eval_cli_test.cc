// cwloc-eval as a program: exit codes, messages, the JSON report against its schema, real data.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "cwloc/version.h"
#include "format/index_file.h"
#include "geo/index_georeference.h"
#include "tests/test_util.h"
#include "tests/tools/eval/eval_fixtures.h"

namespace cwloc::eval {
namespace {

namespace fs = std::filesystem;
using test::Scenario;

using cwloc::test::Quote;

int Eval(const std::string& args, std::string* output) {
  return cwloc::test::RunCommand(Quote(cwloc::test::ToolPath("cwloc-eval")) + " " + args, output);
}

// stdout only, so JSON can be parsed without stderr mixed in.
int EvalStdout(const std::string& args, const fs::path& out_file) {
  std::string ignored;
  return cwloc::test::RunCommand(
      Quote(cwloc::test::ToolPath("cwloc-eval")) + " " + args + " > " + Quote(out_file), &ignored);
}

int ValidateReport(const fs::path& report, std::string* output) {
  return cwloc::test::ValidateJson("eval-report.schema.json", report, false, output);
}

nlohmann::json ReadJson(const fs::path& path) { return nlohmann::json::parse(std::ifstream(path)); }

TEST(EvalCli, HelpAndVersion) {
  std::string output;
  EXPECT_EQ(Eval("--help", &output), 0);
  EXPECT_NE(output.find("--results"), std::string::npos);
  EXPECT_EQ(Eval("--version", &output), 0);
  EXPECT_EQ(output, std::string("cwloc-eval ") + kToolVersion + "\n");
}

TEST(EvalCli, ExitCodes) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WriteJsonLines(dir / "run.jsonl");
  std::string output;
  EXPECT_EQ(
      Eval("--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "run.jsonl"), &output), 0)
      << output;
  EXPECT_NE(output.find("4/5"), std::string::npos) << output;
  EXPECT_NE(output.find("model units"), std::string::npos) << output;

  // Usage errors.
  EXPECT_EQ(Eval("--results " + Quote(dir / "run.jsonl"), &output), 2) << output;
  EXPECT_EQ(Eval("--gt " + Quote(dir / "gt.txt") + " --bogus", &output), 2) << output;
  EXPECT_EQ(Eval("--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "run.jsonl") +
                     " --label a --label b",
                 &output),
            2);
  EXPECT_EQ(output, "cwloc-eval: error: got 2 --label for 1 --results; give one per run or none\n");

  // A missing file and a malformed line name the file (and line).
  EXPECT_EQ(
      Eval("--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "none.jsonl"), &output),
      2);
  EXPECT_EQ(output, "cwloc-eval: error: " + (dir / "none.jsonl").string() +
                        ": cannot open (No such file or directory)\n");
  std::ofstream(dir / "bad.jsonl") << "{\"name\": \"q0.jpg\", \"success\": false}\n\n{oops\n";
  EXPECT_EQ(
      Eval("--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "bad.jsonl"), &output), 2);
  EXPECT_EQ(output, "cwloc-eval: error: " + (dir / "bad.jsonl").string() + ":3: not valid JSON\n");
  std::ofstream(dir / "bad_gt.txt") << "# header\nq0.jpg 1 0 0 0 1 2\n";
  EXPECT_EQ(
      Eval("--gt " + Quote(dir / "bad_gt.txt") + " --results " + Quote(dir / "run.jsonl"), &output),
      2);
  EXPECT_EQ(output, "cwloc-eval: error: " + (dir / "bad_gt.txt").string() +
                        ":2: expected NAME QW QX QY QZ TX TY TZ\n");
}

TEST(EvalCli, JsonReportMatchesSchemaAndComparesRuns) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WriteJsonLines(dir / "run.jsonl");
  s.WritePoses(dir / "run.txt");
  std::ofstream(dir / "scale.txt") << "scale 2\n";
  const std::string common = "--gt " + Quote(dir / "gt.txt") + " --results " +
                             Quote(dir / "run.jsonl") + " --results " + Quote(dir / "run.txt") +
                             " --label cwr --label poses";
  ASSERT_EQ(EvalStdout(common + " --json", dir / "units.json"), 0);
  ASSERT_EQ(
      EvalStdout(common + " --scale " + Quote(dir / "scale.txt") + " --json", dir / "metres.json"),
      0);
  for (const char* name : {"units.json", "metres.json"}) {
    std::string output;
    EXPECT_EQ(ValidateReport(dir / name, &output), 0) << name << "\n" << output;
  }
  const nlohmann::json units = ReadJson(dir / "units.json");
  EXPECT_EQ(units["unit"], "model units");
  EXPECT_TRUE(units["scale_path"].is_null());
  ASSERT_EQ(units["runs"].size(), 2u);
  EXPECT_EQ(units["runs"][0]["label"], "cwr");
  EXPECT_EQ(units["runs"][0]["format"], "json-lines");
  EXPECT_EQ(units["runs"][1]["format"], "poses");
  EXPECT_TRUE(units["runs"][1]["times_ms"].is_null());
  EXPECT_NEAR(units["runs"][0]["position_error"]["median"].get<double>(), 0.65, 1e-9);
  EXPECT_NEAR(units["runs"][1]["position_error"]["median"].get<double>(), 0.65, 1e-9);
  EXPECT_DOUBLE_EQ(units["runs"][0]["within"][1]["share"].get<double>(), 0.4);
  const nlohmann::json& total = units["runs"][0]["times_ms"]["total"];
  EXPECT_DOUBLE_EQ(total["q1"].get<double>(), 17.5);
  EXPECT_DOUBLE_EQ(total["median"].get<double>(), 25.0);
  EXPECT_DOUBLE_EQ(total["q3"].get<double>(), 32.5);
  EXPECT_DOUBLE_EQ(total["p90"].get<double>(), 37.0);
  for (const auto& [stage, quantiles] : units["runs"][0]["times_ms"].items()) {
    EXPECT_EQ(quantiles.size(), 4u) << stage;
    EXPECT_TRUE(quantiles.contains("p90")) << stage;
  }
  EXPECT_DOUBLE_EQ(units["runs"][0]["times_ms"]["pose"]["p90"].get<double>(), 4.0);
  const nlohmann::json metres = ReadJson(dir / "metres.json");
  EXPECT_EQ(metres["unit"], "m");
  EXPECT_NEAR(metres["runs"][0]["position_error"]["median"].get<double>(), 1.3, 1e-9);

  // The table shows both runs.
  std::string table;
  EXPECT_EQ(Eval(common + " --scale " + Quote(dir / "scale.txt"), &table), 0);
  EXPECT_NE(table.find("cwr "), std::string::npos) << table;
  EXPECT_NE(table.find("poses "), std::string::npos) << table;
  EXPECT_NE(table.find("distances in metres (scale 2 from"), std::string::npos) << table;
  EXPECT_NE(table.find("forward_knn"), std::string::npos) << table;
  EXPECT_NE(table.find("times (ms), Q1 / median / Q3 / p90"), std::string::npos) << table;
  EXPECT_NE(table.find("17.5 / 25.0 / 32.5 / 37.0"), std::string::npos) << table;

  // The schema requires p90 in every stage's times.
  nlohmann::json without_p90 = units;
  without_p90["runs"][0]["times_ms"]["ratio_test"].erase("p90");
  std::ofstream(dir / "without_p90.json") << without_p90.dump(2);
  std::string output;
  EXPECT_EQ(ValidateReport(dir / "without_p90.json", &output), 1) << output;
  // times_ms is oneOf null or the stages, so the error is reported on times_ms as a whole.
  EXPECT_NE(output.find("document 1: /runs/0/times_ms: "), std::string::npos) << output;
}

// The golden 1.0 index, which has no GEOR section.
fs::path GoldenIndex() {
  return cwloc::test::SourceDir() / "tests" / "data" / "golden" / "index-1.0.cwl";
}

// The golden index with a GEOR section added: cwloc-eval reads only the georeference.
void WriteGeoreferencedIndex(const fs::path& path, const Georeference& georeference) {
  const IndexFile golden = IndexFile::Open(GoldenIndex());
  std::vector<SectionData> sections;
  for (const SectionEntry& entry : golden.sections()) {
    sections.push_back({entry.tag, entry.flags, entry.element_size, entry.count,
                        golden.bytes().subspan(entry.offset, entry.size)});
  }
  IndexGeoreference geor = SectionOfGeoreference(georeference);
  geor.source = static_cast<uint32_t>(GeoreferenceSource::kFile);
  sections.push_back(MakeSection(section::kGeoreference,
                                 std::span<const IndexGeoreference>(&geor, 1),
                                 /*flags=*/0));
  WriteIndexFile(path, sections);
}

TEST(EvalCli, IndexMustBeGeoreferencedAndExcludesScale) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WriteJsonLines(dir / "run.jsonl");
  std::ofstream(dir / "scale.txt") << "scale 2\n";
  const std::string common =
      "--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "run.jsonl");
  std::string output;
  EXPECT_EQ(Eval(common + " --index " + Quote(GoldenIndex()), &output), 2);
  EXPECT_EQ(output, "cwloc-eval: error: " + GoldenIndex().string() +
                        ": the index is not georeferenced (no GEOR section); --index needs one "
                        "built with --georef, --georef-images or --model-frame\n");
  Georeference g;
  g.origin = {48.8, 2.3, 35};
  WriteGeoreferencedIndex(dir / "geo.cwl", g);
  EXPECT_EQ(
      Eval(common + " --index " + Quote(dir / "geo.cwl") + " --scale " + Quote(dir / "scale.txt"),
           &output),
      2);
  EXPECT_NE(output.find("--scale excludes --index"), std::string::npos) << output;
  EXPECT_EQ(Eval(common + " --index " + Quote(dir / "none.cwl"), &output), 2);
  EXPECT_NE(output.find((dir / "none.cwl").string()), std::string::npos) << output;
}

TEST(EvalCli, GroundErrorsThroughTheIndexAndGeoAgainstTruePositions) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  // Scale 2, a quarter turn about the model's z axis: model z is up, so the scenario's offsets
  // along (2, -1, 2) / 3 are 2/3 up and sqrt(5)/3 on the ground, times 2.
  Georeference g;
  g.origin = {48.8, 2.3, 35};
  g.scale = 2;
  g.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()));
  g.translation = Eigen::Vector3d(10, 20, 30);
  WriteGeoreferencedIndex(dir / "geo.cwl", g);

  // "geo" from the same georeference: the estimated centres on the globe. The true positions
  // are the ground-truth centres through it, so the errors on the globe are the ones in ENU.
  const GeoFrame frame(g);
  {
    std::ofstream out(dir / "run.jsonl");
    for (size_t i = 0; i < s.estimates.size(); ++i) {
      nlohmann::json record = Scenario::JsonRecord(s.names[i], s.estimates[i], 10);
      const Geodetic geo = frame.ModelToGeodetic(s.estimates[i].Center());
      record["geo"] = {{"latitude_deg", geo.latitude_deg},
                       {"longitude_deg", geo.longitude_deg},
                       {"height_m", geo.height_m},
                       {"enu", {0, 0, 0}},
                       {"heading_deg", 0},
                       {"pitch_deg", 0},
                       {"roll_deg", 0}};
      out << record.dump() << "\n";
    }
    std::ofstream truth(dir / "queries_geo.txt");
    truth << "# NAME LAT LON HEIGHT\n";
    for (size_t i = 0; i < s.truth.size(); ++i) {
      const Geodetic geo = frame.ModelToGeodetic(s.truth[i].Center());
      char line[256];
      std::snprintf(line, sizeof(line), "%s %.17g %.17g %.17g\n", s.names[i].c_str(),
                    geo.latitude_deg, geo.longitude_deg, geo.height_m);
      truth << line;
    }
  }
  s.WritePoses(dir / "run.txt");
  const std::string common = "--gt " + Quote(dir / "gt.txt") + " --results " +
                             Quote(dir / "run.jsonl") + " --results " + Quote(dir / "run.txt") +
                             " --label cwr --label poses --index " + Quote(dir / "geo.cwl") +
                             " --gt-geo " + Quote(dir / "queries_geo.txt");
  ASSERT_EQ(EvalStdout(common + " --json", dir / "report.json"), 0);
  std::string output;
  EXPECT_EQ(ValidateReport(dir / "report.json", &output), 0) << output;
  const nlohmann::json report = ReadJson(dir / "report.json");
  EXPECT_EQ(report["unit"], "m");
  EXPECT_EQ(report["scale"], 2.0);
  EXPECT_TRUE(report["scale_path"].is_null());
  EXPECT_EQ(report["index"]["path"], (dir / "geo.cwl").string());
  EXPECT_EQ(report["ground_truth_geo"]["positions"], 5);
  // Errors 0.1, 0.3, 1, 6 in model units: median 0.65, times 2.
  const nlohmann::json& cwr = report["runs"][0];
  const double ground = 2 * std::sqrt(5.0) / 3, height = 4.0 / 3;
  EXPECT_NEAR(cwr["position_error"]["median"].get<double>(), 1.3, 1e-9);
  EXPECT_NEAR(cwr["ground_error"]["median"].get<double>(), 0.65 * ground, 1e-9);
  EXPECT_NEAR(cwr["height_error"]["median"].get<double>(), 0.65 * height, 1e-9);
  EXPECT_NEAR(cwr["per_query"][3]["ground_error"].get<double>(), 6 * ground, 1e-9);
  EXPECT_NEAR(cwr["per_query"][3]["height_error"].get<double>(), 6 * height, 1e-9);
  // On the globe, within micrometres (the local frame at each true position is not quite the
  // index's).
  EXPECT_EQ(cwr["geo"]["compared"], 4);
  EXPECT_EQ(cwr["geo"]["without_geo"], 0);
  EXPECT_NEAR(cwr["geo"]["error_m"]["median"].get<double>(), 1.3, 1e-5);
  EXPECT_NEAR(cwr["geo"]["ground_error_m"]["median"].get<double>(), 0.65 * ground, 1e-5);
  EXPECT_NEAR(cwr["geo"]["height_error_m"]["median"].get<double>(), 0.65 * height, 1e-5);
  // Within 0.5 m: 0.2 and 0.6 m -> q0 only, of 5 ground-truth queries.
  EXPECT_EQ(cwr["geo"]["within"]["count"], 1);
  EXPECT_DOUBLE_EQ(cwr["geo"]["within"]["share"].get<double>(), 0.2);
  EXPECT_TRUE(cwr["per_query"][4].contains("status"));
  EXPECT_FALSE(cwr["per_query"][4].contains("geo"));
  // The poses file has the ENU errors but no "geo".
  const nlohmann::json& poses = report["runs"][1];
  EXPECT_NEAR(poses["ground_error"]["median"].get<double>(), 0.65 * ground, 1e-9);
  EXPECT_EQ(poses["geo"]["compared"], 0);
  EXPECT_EQ(poses["geo"]["without_geo"], 4);
  EXPECT_TRUE(poses["geo"]["error_m"].is_null());
  EXPECT_TRUE(poses["per_query"][0]["geo"].is_null());

  std::string table;
  EXPECT_EQ(Eval(common, &table), 0) << table;
  EXPECT_NE(table.find("distances in metres (scale 2 from the georeference of index"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("ground error (m)"), std::string::npos) << table;
  EXPECT_NE(table.find("within 0.5 m"), std::string::npos) << table;
  EXPECT_NE(table.find("poses: 4 localized result(s) without \"geo\""), std::string::npos) << table;

  // A ground-truth query without a true position is an input error.
  std::ofstream(dir / "short_geo.txt") << "q0.jpg 48.8 2.3 35\n";
  EXPECT_EQ(Eval("--gt " + Quote(dir / "gt.txt") + " --results " + Quote(dir / "run.jsonl") +
                     " --gt-geo " + Quote(dir / "short_geo.txt"),
                 &output),
            2);
  EXPECT_EQ(output, "cwloc-eval: error: " + (dir / "short_geo.txt").string() +
                        ": no position for ground-truth query q1.jpg (line 3 of the --gt file)\n");
}

TEST(EvalCli, HerzJesuGroundTruthAgainstItself) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  cwloc::test::TempDir dir;
  const fs::path gt = data / "queries_gt.txt";
  ASSERT_EQ(EvalStdout("--gt " + Quote(gt) + " --results " + Quote(gt) + " --scale " +
                           Quote(data / "scale_to_metres.txt") + " --json",
                       dir / "report.json"),
            0);
  std::string output;
  EXPECT_EQ(ValidateReport(dir / "report.json", &output), 0) << output;
  const nlohmann::json report = ReadJson(dir / "report.json");
  const nlohmann::json& run = report["runs"][0];
  EXPECT_EQ(report["unit"], "m");
  EXPECT_EQ(run["format"], "poses");
  EXPECT_EQ(run["queries"], 5);
  EXPECT_EQ(run["localized"], 5);
  for (const char* key : {"position_error", "rotation_error_deg"}) {
    for (const char* q : {"q1", "median", "q3"})
      EXPECT_NEAR(run[key][q].get<double>(), 0.0, 1e-9) << key << " " << q;
  }
  for (const auto& within : run["within"]) EXPECT_EQ(within["share"], 1.0);
}

}  // namespace
}  // namespace cwloc::eval
