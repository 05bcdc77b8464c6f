// cwloc-eval on the ground and on the globe: errors in a georeference's ENU frame (--index),
// results' "geo" against true positions (--gt-geo), and the readers' messages.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "base/error.h"
#include "tests/test_util.h"
#include "tests/tools/eval/eval_fixtures.h"
#include "tools/eval/geo_error.h"
#include "tools/eval/ground_truth.h"
#include "tools/eval/report.h"
#include "tools/eval/result_reader.h"

namespace cwloc::eval {
namespace {

using cwloc::test::InputErrorOf;
using test::PoseFromCenter;
using test::Radians;

// WGS84's radii of curvature at a latitude, from the ellipsoid's definition (not through
// GeographicLib): metres per radian of latitude (meridian) and of longitude (prime vertical,
// times cos latitude), at a height above the ellipsoid.
constexpr double kWgs84A = 6378137.0;
constexpr double kWgs84F = 1 / 298.257223563;

double MetresPerRadianNorth(double latitude_deg, double height_m) {
  const double e2 = kWgs84F * (2 - kWgs84F);
  const double s = std::sin(Radians(latitude_deg));
  return kWgs84A * (1 - e2) / std::pow(1 - e2 * s * s, 1.5) + height_m;
}

double MetresPerRadianEast(double latitude_deg, double height_m) {
  const double e2 = kWgs84F * (2 - kWgs84F);
  const double s = std::sin(Radians(latitude_deg));
  return (kWgs84A / std::sqrt(1 - e2 * s * s) + height_m) * std::cos(Radians(latitude_deg));
}

constexpr double kDegrees = 180 / std::numbers::pi;

// A model frame that is rotated, scaled and shifted against ENU.
Georeference RotatedScaledGeoreference() {
  Georeference g;
  g.origin = {48.8, 2.3, 60};
  g.scale = 2.5;
  g.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, -2, 0.7).normalized()));
  g.translation = Eigen::Vector3d(120, -40, 3);
  return g;
}

// A pose whose camera centre is `enu_offset` metres (in the georeference's ENU frame) from
// `truth`'s, with a rotation of its own.
Pose OffsetInEnu(const Georeference& g, const Pose& truth, const Eigen::Vector3d& enu_offset) {
  const Eigen::Vector3d center = g.EnuToModel(g.ModelToEnu(truth.Center()) + enu_offset);
  return PoseFromCenter(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())) * truth.qvec, center);
}

TEST(GeoError, EnuFrameOfARotatedScaledModel) {
  const Georeference g = RotatedScaledGeoreference();
  const Pose truth = PoseFromCenter(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())), {3, -1, 7});
  // 3 m east and 4 m up: ground 3, height 4, 5 m in all.
  GroundError e = ErrorInIndexFrame(g, OffsetInEnu(g, truth, {3, 0, 4}), truth);
  EXPECT_NEAR(e.distance, 5, 1e-9);
  EXPECT_NEAR(e.ground, 3, 1e-9);
  EXPECT_NEAR(e.height, 4, 1e-9);
  // Down counts as much as up; north and east together make the ground error.
  e = ErrorInIndexFrame(g, OffsetInEnu(g, truth, {-6, 8, -2}), truth);
  EXPECT_NEAR(e.ground, 10, 1e-9);
  EXPECT_NEAR(e.height, 2, 1e-9);
  EXPECT_NEAR(e.distance, std::sqrt(104.0), 1e-9);
  // The 3D error is the scaled model distance, whatever the rotation.
  EXPECT_NEAR(e.distance, g.scale * PositionError(OffsetInEnu(g, truth, {-6, 8, -2}), truth), 1e-9);
  // In the model frame the same offset points elsewhere: model "up" is not ENU up.
  const Eigen::Vector3d model_offset = OffsetInEnu(g, truth, {3, 0, 4}).Center() - truth.Center();
  EXPECT_GT(std::abs(model_offset.z() * g.scale - 4), 0.5);
}

TEST(GeoError, NorthEastAndUpOnTheGlobe) {
  const Geodetic truth{48.8, 2.3, 35};
  // 0.3 m north along the meridian.
  Geodetic north = truth;
  north.latitude_deg += 0.3 / MetresPerRadianNorth(truth.latitude_deg, truth.height_m) * kDegrees;
  GroundError e = ErrorOnGlobe(north, truth);
  EXPECT_NEAR(e.ground, 0.3, 1e-6);
  EXPECT_NEAR(e.height, 0, 1e-6);
  EXPECT_NEAR(e.distance, 0.3, 1e-6);
  // 2 m east along the parallel.
  Geodetic east = truth;
  east.longitude_deg += 2 / MetresPerRadianEast(truth.latitude_deg, truth.height_m) * kDegrees;
  e = ErrorOnGlobe(east, truth);
  EXPECT_NEAR(e.ground, 2, 1e-6);
  EXPECT_NEAR(e.height, 0, 1e-6);
  // 1.5 m lower, same place.
  Geodetic below = truth;
  below.height_m -= 1.5;
  e = ErrorOnGlobe(below, truth);
  EXPECT_NEAR(e.ground, 0, 1e-9);
  EXPECT_NEAR(e.height, 1.5, 1e-9);
  EXPECT_NEAR(e.distance, 1.5, 1e-9);
  // Both: 3 m ground and 4 m height, 5 m in all; far south and across the antimeridian.
  const Geodetic south{-33.9, 179.9999, 10};
  Geodetic both = south;
  both.longitude_deg += 3 / MetresPerRadianEast(south.latitude_deg, south.height_m) * kDegrees;
  both.height_m += 4;
  e = ErrorOnGlobe(both, south);
  EXPECT_NEAR(e.ground, 3, 1e-5);
  EXPECT_NEAR(e.height, 4, 1e-5);
  EXPECT_NEAR(e.distance, 5, 1e-5);
}

// Two queries 5 and 10 m off in a rotated, scaled model; the third is not localized.
TEST(GeoReport, IndexFrameErrorsPerQueryAndQuartiles) {
  const Georeference g = RotatedScaledGeoreference();
  std::vector<NamedPose> truth;
  RunResults run;
  const std::vector<Eigen::Vector3d> offsets = {{3, 0, 4}, {0, -6, -8}};
  for (int i = 0; i < 3; ++i) {
    const Pose pose =
        PoseFromCenter(Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitZ())),
                       {double(i), 2.0 * i, 1});
    // Appending rather than "q" + string sidesteps a GCC 12 -Wrestrict false positive.
    std::string name = "q";
    name += std::to_string(i);
    truth.push_back({name, pose, i + 1});
    QueryResult result;
    result.name = truth.back().name;
    if (i < 2) {
      result.status = ResultStatus::kLocalized;
      result.pose = OffsetInEnu(g, pose, offsets[i]);
    }
    run.queries.push_back(result);
  }
  run.format = ResultFormat::kJsonLines;
  const RunReport r = EvaluateRun(truth, run, g.scale, "run", {.georeference = &g});
  ASSERT_TRUE(r.enu_errors);
  EXPECT_NEAR(r.per_query[0].position_error, 5, 1e-9);
  EXPECT_NEAR(r.per_query[1].position_error, 10, 1e-9);
  ASSERT_TRUE(r.per_query[0].enu_error && r.per_query[1].enu_error);
  EXPECT_NEAR(r.per_query[0].enu_error->ground, 3, 1e-9);
  EXPECT_NEAR(r.per_query[0].enu_error->height, 4, 1e-9);
  EXPECT_NEAR(r.per_query[1].enu_error->ground, 6, 1e-9);
  EXPECT_NEAR(r.per_query[1].enu_error->height, 8, 1e-9);
  EXPECT_FALSE(r.per_query[2].enu_error);
  // {3, 6}: 3.75 / 4.5 / 5.25; {4, 8}: 5 / 6 / 7.
  ASSERT_TRUE(r.ground_error && r.height_error);
  EXPECT_NEAR(r.ground_error->q1, 3.75, 1e-9);
  EXPECT_NEAR(r.ground_error->median, 4.5, 1e-9);
  EXPECT_NEAR(r.ground_error->q3, 5.25, 1e-9);
  EXPECT_NEAR(r.height_error->q1, 5, 1e-9);
  EXPECT_NEAR(r.height_error->median, 6, 1e-9);
  EXPECT_NEAR(r.height_error->q3, 7, 1e-9);
  EXPECT_FALSE(r.geo);

  EvalReport report;
  report.ground_truth_path = "gt.txt";
  report.queries = 3;
  report.index_path = "city.cwl";
  report.georeference = g;
  report.scale = g.scale;
  report.runs = {r};
  const nlohmann::ordered_json json = ReportToJson(report);
  EXPECT_EQ(json["unit"], "m");
  EXPECT_TRUE(json["scale_path"].is_null());
  EXPECT_EQ(json["index"]["path"], "city.cwl");
  EXPECT_EQ(json["index"]["scale"], 2.5);
  EXPECT_EQ(json["index"]["origin"]["latitude_deg"], 48.8);
  EXPECT_FALSE(json.contains("ground_truth_geo"));
  const auto& run_json = json["runs"][0];
  EXPECT_NEAR(run_json["ground_error"]["median"].get<double>(), 4.5, 1e-9);
  EXPECT_NEAR(run_json["height_error"]["q3"].get<double>(), 7, 1e-9);
  EXPECT_NEAR(run_json["per_query"][1]["ground_error"].get<double>(), 6, 1e-9);
  EXPECT_NEAR(run_json["per_query"][1]["height_error"].get<double>(), 8, 1e-9);
  EXPECT_FALSE(run_json["per_query"][2].contains("ground_error"));
  EXPECT_FALSE(run_json.contains("geo"));
  const std::string table = FormatTable(report);
  EXPECT_NE(table.find("distances in metres (scale 2.5 from the georeference of index city.cwl)"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("on the ground, in the index's east-north-up frame"), std::string::npos)
      << table;
  EXPECT_NE(table.find("3.750 / 4.500 / 5.250  5.000 / 6.000 / 7.000"), std::string::npos) << table;

  // Without a georeference nothing of this appears.
  report.index_path.reset();
  report.georeference.reset();
  report.runs = {EvaluateRun(truth, run, 1.0, "run")};
  EXPECT_FALSE(ReportToJson(report)["runs"][0].contains("ground_error"));
  EXPECT_FALSE(ReportToJson(report).contains("index"));
  EXPECT_EQ(FormatTable(report).find("on the ground"), std::string::npos);
}

// Results with "geo" against the true positions: q0 0.3 m north, q1 1.5 m high, q2 2 m east,
// q3 localized without "geo", q4 not localized.
struct GlobeScenario {
  std::vector<std::string> names = {"q0.jpg", "q1.jpg", "q2.jpg", "q3.jpg", "q4.jpg"};
  std::vector<Geodetic> truth;
  std::vector<Geodetic> estimates;  // q0..q2

  GlobeScenario() {
    for (int i = 0; i < 5; ++i) truth.push_back({48.8 + 1e-4 * i, 2.3 - 1e-4 * i, 40.0 + i});
    Geodetic north = truth[0], high = truth[1], east = truth[2];
    north.latitude_deg += 0.3 / MetresPerRadianNorth(north.latitude_deg, north.height_m) * kDegrees;
    high.height_m += 1.5;
    east.longitude_deg += 2 / MetresPerRadianEast(east.latitude_deg, east.height_m) * kDegrees;
    estimates = {north, high, east};
  }

  void WriteTruth(const std::filesystem::path& path) const {
    std::ofstream out(path);
    out << "# NAME LAT LON HEIGHT\n\n";
    char line[256];
    for (size_t i = 0; i < truth.size(); ++i) {
      std::snprintf(line, sizeof(line), "%s %.17g %.17g %.17g\n", names[i].c_str(),
                    truth[i].latitude_deg, truth[i].longitude_deg, truth[i].height_m);
      out << line;
    }
  }

  // JSON lines; the poses are arbitrary (they only make the queries localized).
  void WriteResults(const std::filesystem::path& path) const {
    std::ofstream out(path);
    const test::Scenario poses;
    for (size_t i = 0; i < 4; ++i) {
      nlohmann::json record = test::Scenario::JsonRecord(names[i], poses.estimates[i], 10);
      if (i < estimates.size()) {
        record["geo"] = {{"latitude_deg", estimates[i].latitude_deg},
                         {"longitude_deg", estimates[i].longitude_deg},
                         {"height_m", estimates[i].height_m},
                         {"enu", {1.0, 2.0, 3.0}},
                         {"heading_deg", 10.0},
                         {"pitch_deg", -5.0},
                         {"roll_deg", 0.5}};
      }
      out << record.dump() << "\n";
    }
    out << R"({"name":"q4.jpg","success":false,"failure_reason":"too few inliers"})"
        << "\n";
  }
};

TEST(GeoReport, GeoPositionsAgainstTruePositions) {
  cwloc::test::TempDir dir;
  const GlobeScenario s;
  const test::Scenario poses;
  poses.WriteGroundTruth(dir / "gt.txt");
  s.WriteTruth(dir / "queries_geo.txt");
  s.WriteResults(dir / "run.jsonl");
  const auto gt = ReadGroundTruth(dir / "gt.txt");
  const auto positions = ReadGeoGroundTruth(dir / "queries_geo.txt");
  ASSERT_EQ(positions.size(), 5u);
  EXPECT_EQ(positions[0].line, 3);
  EXPECT_EQ(positions[1].name, "q1.jpg");
  const auto by_name = TruePositionsOfQueries(gt, positions, dir / "queries_geo.txt");
  const RunResults run = ReadResults(dir / "run.jsonl");
  ASSERT_TRUE(run.queries[0].geo);
  EXPECT_EQ(run.queries[0].geo->height_m, 40);
  EXPECT_FALSE(run.queries[3].geo);

  const RunReport r = EvaluateRun(gt, run, 1.0, "run", {.true_positions = &by_name});
  EXPECT_FALSE(r.enu_errors);
  ASSERT_TRUE(r.geo);
  EXPECT_EQ(r.localized, 4);
  EXPECT_EQ(r.geo->compared, 3);
  EXPECT_EQ(r.geo->without_geo, 1);
  ASSERT_TRUE(r.per_query[0].geo_error);
  EXPECT_NEAR(r.per_query[0].geo_error->ground, 0.3, 1e-6);
  EXPECT_NEAR(r.per_query[0].geo_error->height, 0, 1e-6);
  EXPECT_NEAR(r.per_query[0].geo_error->distance, 0.3, 1e-6);
  EXPECT_NEAR(r.per_query[1].geo_error->ground, 0, 1e-6);
  EXPECT_NEAR(r.per_query[1].geo_error->height, 1.5, 1e-6);
  EXPECT_NEAR(r.per_query[2].geo_error->ground, 2, 1e-6);
  EXPECT_FALSE(r.per_query[3].geo_error);
  EXPECT_FALSE(r.per_query[4].geo_error);
  // 3D {0.3, 1.5, 2}: h = 0.5, 1, 1.5 -> 0.9, 1.5, 1.75. Ground {0, 0.3, 2}; height {0, 0, 1.5}.
  ASSERT_TRUE(r.geo->error && r.geo->ground_error && r.geo->height_error);
  EXPECT_NEAR(r.geo->error->q1, 0.9, 1e-6);
  EXPECT_NEAR(r.geo->error->median, 1.5, 1e-6);
  EXPECT_NEAR(r.geo->error->q3, 1.75, 1e-6);
  EXPECT_NEAR(r.geo->ground_error->q1, 0.15, 1e-6);
  EXPECT_NEAR(r.geo->ground_error->median, 0.3, 1e-6);
  EXPECT_NEAR(r.geo->ground_error->q3, 1.15, 1e-6);
  EXPECT_NEAR(r.geo->height_error->median, 0, 1e-6);
  EXPECT_NEAR(r.geo->height_error->q3, 0.75, 1e-6);
  EXPECT_EQ(r.geo->within, 1);

  EvalReport report;
  report.ground_truth_path = dir / "gt.txt";
  report.queries = 5;
  report.geo_truth_path = dir / "queries_geo.txt";
  report.geo_truth_positions = 5;
  report.runs = {r};
  const nlohmann::ordered_json json = ReportToJson(report);
  EXPECT_EQ(json["ground_truth_geo"]["positions"], 5);
  EXPECT_EQ(json["ground_truth_geo"]["within_m"], 0.5);
  const auto& geo = json["runs"][0]["geo"];
  EXPECT_EQ(geo["compared"], 3);
  EXPECT_EQ(geo["without_geo"], 1);
  EXPECT_NEAR(geo["error_m"]["median"].get<double>(), 1.5, 1e-6);
  EXPECT_EQ(geo["within"]["count"], 1);
  EXPECT_DOUBLE_EQ(geo["within"]["share"].get<double>(), 0.2);
  const auto& per_query = json["runs"][0]["per_query"];
  EXPECT_NEAR(per_query[0]["geo"]["ground_error_m"].get<double>(), 0.3, 1e-6);
  EXPECT_TRUE(per_query[3]["geo"].is_null());  // localized, no "geo"
  EXPECT_FALSE(per_query[4].contains("geo"));  // not localized
  const std::string table = FormatTable(report);
  EXPECT_NE(table.find("on the globe, against the true positions in " +
                       (dir / "queries_geo.txt").string()),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("3/4"), std::string::npos) << table;
  EXPECT_NE(table.find("0.900 / 1.500 / 1.750"), std::string::npos) << table;
  EXPECT_NE(table.find("20.0%"), std::string::npos) << table;
  EXPECT_NE(table.find("run: 1 localized result(s) without \"geo\" (a poses file, or an index "
                       "without georeference): missing from this comparison"),
            std::string::npos)
      << table;

  // A poses file has no "geo": every localized query is missing from the comparison.
  poses.WritePoses(dir / "run.txt");
  const RunReport p =
      EvaluateRun(gt, ReadResults(dir / "run.txt"), 1.0, "poses", {.true_positions = &by_name});
  EXPECT_EQ(p.geo->compared, 0);
  EXPECT_EQ(p.geo->without_geo, 4);
  EXPECT_FALSE(p.geo->error);
  EXPECT_EQ(p.geo->within, 0);
}

TEST(GeoReaders, GeoGroundTruthMessagesNameFileAndLine) {
  cwloc::test::TempDir dir;
  const auto path = dir / "queries_geo.txt";
  const auto expect = [&](const std::string& text, const std::string& message) {
    std::ofstream(path) << text;
    EXPECT_EQ(InputErrorOf([&] { ReadGeoGroundTruth(path); }), path.string() + message) << text;
  };
  expect("# c\nq0.jpg 48.8 2.3 x\n", ":2: HEIGHT 'x' is not a finite number");
  expect("q0.jpg 48.8 2.3e 35\n", ":1: LON '2.3e' is not a finite number");
  expect("q0.jpg nan 2.3 35\n", ":1: LAT 'nan' is not a finite number");
  expect("q0.jpg 48.8 2.3\n", ":1: expected NAME LAT LON HEIGHT, got 3 value(s)");
  // A pose line (queries_gt.txt given by mistake) is not a position.
  expect("q0.jpg 1 0 0 0 1 2 3\n", ":1: expected NAME LAT LON HEIGHT, got 8 value(s)");
  expect("\nq0.jpg 91 2.3 35\n", ":2: latitude 91 is outside [-90, 90]");
  expect("q0.jpg -90.5 2.3 35\n", ":1: latitude -90.5 is outside [-90, 90]");
  expect("q0.jpg 48.8 360 35\n", ":1: longitude 360 is outside [-180, 360)");
  expect("q0.jpg 48.8 2.3 35\n# again\nq0.jpg 48.8 2.3 36\n",
         ":3: duplicate query q0.jpg (first on line 1)");
  expect("# nothing\n\n", ": no positions (expected NAME LAT LON HEIGHT lines)");

  // Every ground-truth query needs a true position.
  std::ofstream(path) << "q0.jpg 48.8 2.3 35\nother.jpg 48.8 2.3 35\n";
  const std::vector<NamedPose> gt = {{"q0.jpg", Pose{}, 1}, {"q1.jpg", Pose{}, 2}};
  EXPECT_EQ(
      InputErrorOf([&] { TruePositionsOfQueries(gt, ReadGeoGroundTruth(path), path); }),
      path.string() + ": no position for ground-truth query q1.jpg (line 2 of the --gt file)");
}

TEST(GeoReaders, ResultGeoIsCheckedWhenPresent) {
  cwloc::test::TempDir dir;
  const auto path = dir / "results.jsonl";
  const auto expect = [&](const std::string& geo, const std::string& message) {
    std::ofstream(path) << R"({"name": "a", "success": false, "geo": )" << geo << "}\n";
    EXPECT_EQ(InputErrorOf([&] { ReadResults(path); }), path.string() + message) << geo;
  };
  expect("[1, 2, 3]", ":1: \"geo\" must be an object");
  expect(R"({"latitude_deg": 48.8, "longitude_deg": 2.3})",
         ":1: \"geo.height_m\" must be a finite number");
  expect(R"({"latitude_deg": "48.8", "longitude_deg": 2.3, "height_m": 1})",
         ":1: \"geo.latitude_deg\" must be a finite number");
  expect(R"({"latitude_deg": 95, "longitude_deg": 2.3, "height_m": 1})",
         ":1: \"geo\": latitude 95 is outside [-90, 90]");
  // Without "geo" there is none; enu and the angles are not needed.
  std::ofstream(path) << R"({"name": "a", "success": false})"
                      << "\n"
                      << R"({"name": "b", "success": false, "geo": {"latitude_deg": -1, )"
                      << R"("longitude_deg": 181, "height_m": -20}})"
                      << "\n";
  const RunResults run = ReadResults(path);
  EXPECT_FALSE(run.queries[0].geo);
  ASSERT_TRUE(run.queries[1].geo);
  EXPECT_EQ(run.queries[1].geo->longitude_deg, 181);
  EXPECT_EQ(run.queries[1].geo->height_m, -20);
}

}  // namespace
}  // namespace cwloc::eval
