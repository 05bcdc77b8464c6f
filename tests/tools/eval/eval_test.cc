// cwloc-eval's library: quartiles, pose errors, readers and the run report.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "base/error.h"
#include "tests/test_util.h"
#include "tests/tools/eval/eval_fixtures.h"
#include "tools/eval/ground_truth.h"
#include "tools/eval/recognition.h"
#include "tools/eval/report.h"
#include "tools/eval/result_reader.h"

namespace cwloc::eval {
namespace {

using cwloc::test::InputErrorOf;
using test::PoseFromCenter;
using test::Radians;
using test::Scenario;

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

TEST(Quartiles, LinearInterpolationBetweenClosestRanks) {
  // numpy.quantile([1, 2, 3, 4], [.25, .5, .75]) = 1.75, 2.5, 3.25
  auto q = ComputeQuartiles({4, 1, 3, 2});
  ASSERT_TRUE(q);
  EXPECT_DOUBLE_EQ(q->q1, 1.75);
  EXPECT_DOUBLE_EQ(q->median, 2.5);
  EXPECT_DOUBLE_EQ(q->q3, 3.25);
  // Odd count: ranks fall on elements (h = 1, 2, 3 of 1 2 3 5 10).
  q = ComputeQuartiles({10, 3, 1, 5, 2});
  EXPECT_DOUBLE_EQ(q->q1, 2);
  EXPECT_DOUBLE_EQ(q->median, 3);
  EXPECT_DOUBLE_EQ(q->q3, 5);
  q = ComputeQuartiles({0, 10});
  EXPECT_DOUBLE_EQ(q->q1, 2.5);
  EXPECT_DOUBLE_EQ(q->median, 5);
  EXPECT_DOUBLE_EQ(q->q3, 7.5);
  q = ComputeQuartiles({7});
  EXPECT_DOUBLE_EQ(q->q1, 7);
  EXPECT_DOUBLE_EQ(q->q3, 7);
  EXPECT_FALSE(ComputeQuartiles({}));
}

TEST(Quartiles, TimeQuantilesAddThe90thPercentile) {
  // numpy.quantile([1, 2, 3, 4], [.25, .5, .75, .9]) = 1.75, 2.5, 3.25, 3.7 (h = 2.7)
  auto q = ComputeTimeQuantiles({4, 1, 3, 2});
  ASSERT_TRUE(q);
  EXPECT_DOUBLE_EQ(q->q1, 1.75);
  EXPECT_DOUBLE_EQ(q->median, 2.5);
  EXPECT_DOUBLE_EQ(q->q3, 3.25);
  EXPECT_DOUBLE_EQ(q->p90, 3.7);
  // 1 2 3 5 10: h = 3.6, 5 + 0.6 (10 - 5) = 8.
  q = ComputeTimeQuantiles({10, 3, 1, 5, 2});
  EXPECT_DOUBLE_EQ(q->median, 3);
  EXPECT_DOUBLE_EQ(q->p90, 8);
  // Eleven values 0..100 step 10: h = 9 falls on an element.
  q = ComputeTimeQuantiles({100, 90, 80, 70, 60, 50, 40, 30, 20, 10, 0});
  EXPECT_DOUBLE_EQ(q->median, 50);
  EXPECT_DOUBLE_EQ(q->p90, 90);
  q = ComputeTimeQuantiles({0, 10});
  EXPECT_DOUBLE_EQ(q->p90, 9);
  q = ComputeTimeQuantiles({7});
  EXPECT_DOUBLE_EQ(q->p90, 7);
  EXPECT_FALSE(ComputeTimeQuantiles({}));
}

TEST(PoseError, RotationAngleOfRelativeRotation) {
  const Eigen::Quaterniond gt(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const Pose truth = PoseFromCenter(gt, Eigen::Vector3d(1, 2, 3));
  for (const double degrees : {0.0, 0.01, 2.0, 45.0, 179.0, 180.0}) {
    const Eigen::Quaterniond delta(
        Eigen::AngleAxisd(Radians(degrees), Eigen::Vector3d(0.3, 0.4, -1).normalized()));
    const Pose estimate = PoseFromCenter(delta * gt, Eigen::Vector3d(1, 2, 3));
    EXPECT_NEAR(RotationErrorDeg(estimate, truth), degrees, 1e-9) << degrees;
    EXPECT_NEAR(PositionError(estimate, truth), 0, 1e-12);
  }
  // q and -q are one rotation.
  Pose flipped = truth;
  flipped.qvec.coeffs() = -flipped.qvec.coeffs();
  EXPECT_NEAR(RotationErrorDeg(flipped, truth), 0, 1e-12);
}

TEST(PoseError, PositionIsDistanceOfCameraCentres) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(1.2, Eigen::Vector3d(0, 0, 1)));
  const Pose a = PoseFromCenter(q, Eigen::Vector3d(1, 1, 1));
  const Pose b = PoseFromCenter(Eigen::Quaterniond::Identity(), Eigen::Vector3d(4, 5, 1));
  EXPECT_NEAR((a.Center() - Eigen::Vector3d(1, 1, 1)).norm(), 0, 1e-12);
  EXPECT_NEAR(PositionError(a, b), 5.0, 1e-12);
  // The translation alone is not the centre: identity rotation, t = (0, 0, -3) puts C at (0, 0, 3).
  Pose c;
  c.tvec = Eigen::Vector3d(0, 0, -3);
  EXPECT_NEAR(PositionError(c, Pose{}), 3.0, 1e-12);
}

TEST(Report, KnownErrorsGiveKnownQuartilesAndShares) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WriteJsonLines(dir / "run.jsonl");
  const RunReport r =
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "run.jsonl"), 1.0, "run");
  EXPECT_EQ(r.queries, 5);
  EXPECT_EQ(r.localized, 4);
  EXPECT_EQ(r.missing, 1);
  EXPECT_EQ(r.unknown_names, 0);
  // {0.1, 0.3, 1, 6}: h = 0.75, 1.5, 2.25.
  ASSERT_TRUE(r.position_error);
  EXPECT_NEAR(r.position_error->q1, 0.25, 1e-9);
  EXPECT_NEAR(r.position_error->median, 0.65, 1e-9);
  EXPECT_NEAR(r.position_error->q3, 2.25, 1e-9);
  // {1, 3, 8, 20} degrees.
  ASSERT_TRUE(r.rotation_error_deg);
  EXPECT_NEAR(r.rotation_error_deg->q1, 2.5, 1e-9);
  EXPECT_NEAR(r.rotation_error_deg->median, 5.5, 1e-9);
  EXPECT_NEAR(r.rotation_error_deg->q3, 11.0, 1e-9);
  // (0.25, 2): q0; (0.5, 5): q0, q1; (5, 10): q0, q1, q2.
  EXPECT_EQ(r.within, (std::array<int, 3>{1, 2, 3}));
  ASSERT_TRUE(r.times_ms);
  EXPECT_EQ(r.timed_records, 4);
  EXPECT_DOUBLE_EQ((*r.times_ms)[6].q1, 17.5);
  EXPECT_DOUBLE_EQ((*r.times_ms)[6].median, 25);
  EXPECT_DOUBLE_EQ((*r.times_ms)[6].q3, 32.5);
  // {10, 20, 30, 40}: h = 0.9 * 3 = 2.7, 30 + 0.7 * 10.
  EXPECT_DOUBLE_EQ((*r.times_ms)[6].p90, 37);
  EXPECT_DOUBLE_EQ((*r.times_ms)[1].median, 1.0);
  EXPECT_DOUBLE_EQ((*r.times_ms)[1].p90, 1.0);
  // Records without "extraction" (written before photo queries) count it as 0.
  EXPECT_STREQ(kStageNames[0], "extraction");
  EXPECT_DOUBLE_EQ((*r.times_ms)[0].p90, 0.0);
  EXPECT_EQ(r.per_query[4].status, QueryStatus::kMissing);
}

// Offsets 0.1, 0.3, 1 and 6 against isotropic position sigmas 0.5, 0.5, 0.2, 0.5: squared
// normalised errors 0.04, 0.36, 25, 144, of which the first two lie within 7.81.
TEST(Report, CoverageCountsTruthsInsideTheCovariancesEllipsoid) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  const double sigmas[] = {0.5, 0.5, 0.2, 0.5};
  {
    std::ofstream out(dir / "run.jsonl");
    for (size_t i = 0; i < s.estimates.size(); ++i) {
      nlohmann::json record = Scenario::JsonRecord(s.names[i], s.estimates[i], 10.0);
      nlohmann::json pose = nlohmann::json::array();
      for (int r = 0; r < 6; ++r) {
        pose.push_back(nlohmann::json::array());
        for (int c = 0; c < 6; ++c) {
          pose[r].push_back(r != c ? 0.0 : r < 3 ? 1e-4 : sigmas[i] * sigmas[i]);
        }
      }
      // The rotation block and its coupling are not part of the position's ellipsoid.
      pose[0][3] = pose[3][0] = 5e-5;
      if (i != 1) record["covariance"] = {{"pose", pose}, {"position_radius95", 1.0}};
      out << record.dump() << "\n";
    }
  }
  const RunReport r =
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "run.jsonl"), 1.0, "run");
  EXPECT_EQ(r.with_covariance, 3);  // q1's record has none
  EXPECT_EQ(r.inside95, 1);
  EXPECT_EQ(r.per_query[0].inside95, std::optional<bool>(true));
  EXPECT_FALSE(r.per_query[1].inside95.has_value());
  EXPECT_EQ(r.per_query[2].inside95, std::optional<bool>(false));
  EXPECT_EQ(r.per_query[3].inside95, std::optional<bool>(false));
  EvalReport report;
  report.runs.push_back(r);
  const auto json = ReportToJson(report);
  EXPECT_EQ(json["runs"][0]["coverage95"]["inside"], 1);
  EXPECT_EQ(json["runs"][0]["coverage95"]["with_covariance"], 3);
  EXPECT_THAT(FormatTable(report),
              testing::HasSubstr("run: true position inside the 95 % ellipsoid: 1/3 (33.3%)"));

  std::ofstream(dir / "bad.jsonl")
      << R"({"name": "q0.jpg", "success": false, "covariance": {"pose": [[1, 2]]}})"
      << "\n";
  EXPECT_EQ(InputErrorOf([&] { ReadResults(dir / "bad.jsonl"); }),
            (dir / "bad.jsonl").string() + ":1: \"covariance.pose\" must be 6 x 6 finite numbers");
}

// Frames of a sequence (records with "tracking"): counted by mode in the file's order, errors by
// the mode that gave the pose, the longest run without a pose.
TEST(Report, ASequenceIsCountedByModeInTheFilesOrder) {
  cwloc::test::TempDir dir;
  // Six frames at centres (i, 0, 0), identity rotations.
  std::ofstream gt(dir / "gt.txt");
  for (int i = 0; i < 6; ++i)
    gt << "f" << i << " 1 0 0 0 " << -i << " 0 0 SIMPLE_PINHOLE 100 100 50 50 50\n";
  gt.close();
  // Found at centre (i + offset, 0, 0); frames 2 and 3 lost, frame 4 not in the ground truth's
  // order but the file's.
  const auto frame = [](int i, const char* mode, double offset) {
    if (offset < 0)
      return "{\"name\": \"f" + std::to_string(i) +
             "\", \"success\": false, \"tracking\": {\"mode\": \"" + mode + "\"}}\n";
    return "{\"name\": \"f" + std::to_string(i) +
           "\", \"success\": true, \"pose\": {\"qvec\": [1, 0, 0, 0], \"tvec\": [" +
           std::to_string(-(i + offset)) + ", 0, 0]}, \"tracking\": {\"mode\": \"" + mode +
           "\"}}\n";
  };
  std::ofstream(dir / "run.jsonl")
      << frame(0, "relocalized", 0.0) << frame(1, "tracked", 0.1) << frame(2, "lost", -1)
      << frame(3, "lost", -1) << frame(4, "tracked", 0.3) << frame(5, "relocalized", 0.2);
  const RunReport r =
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "run.jsonl"), 1.0, "run");
  ASSERT_TRUE(r.sequence);
  EXPECT_EQ(r.sequence->frames, 6);
  EXPECT_EQ(r.sequence->tracked, 2);
  EXPECT_EQ(r.sequence->relocalized, 2);
  EXPECT_EQ(r.sequence->lost, 2);
  EXPECT_EQ(r.sequence->longest_without_pose, 2);
  EXPECT_DOUBLE_EQ(r.sequence->with_pose_share, 4.0 / 6.0);
  EXPECT_NEAR(r.sequence->tracked_error->median, 0.2, 1e-9);      // {0.1, 0.3}
  EXPECT_NEAR(r.sequence->relocalized_error->median, 0.1, 1e-9);  // {0, 0.2}
  EvalReport report;
  report.runs.push_back(r);
  EXPECT_EQ(ReportToJson(report)["runs"][0]["sequence"]["longest_without_pose"], 2);
  EXPECT_THAT(FormatTable(report),
              testing::HasSubstr("run: sequence of 6 frames: 2 tracked, 2 relocalized, 2 lost; "
                                 "66.7% with a pose, at most 2 in a row without; median position "
                                 "error tracked 0.200, relocalized 0.100 (model units)"));
  // Plain queries have no sequence.
  std::ofstream(dir / "plain.jsonl") << "{\"name\": \"f0\", \"success\": false}\n";
  EXPECT_FALSE(
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "plain.jsonl"), 1.0, "run")
          .sequence);
  std::ofstream(dir / "bad.jsonl")
      << "{\"name\": \"f0\", \"success\": false, \"tracking\": {\"mode\": \"drifting\"}}\n";
  EXPECT_EQ(
      InputErrorOf([&] { ReadResults(dir / "bad.jsonl"); }),
      (dir / "bad.jsonl").string() + ":1: \"tracking.mode\" must be tracked, relocalized or lost");
}

TEST(Report, ScaleMultipliesDistancesOnly) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WritePoses(dir / "run.txt");
  WriteFile(dir / "scale.txt", "# comment\nscale 2\nR 1 0 0 0 1 0 0 0 1\nt 5 6 7\n");
  const double scale = ReadScale(dir / "scale.txt");
  EXPECT_EQ(scale, 2.0);
  const RunReport r =
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "run.txt"), scale, "run");
  EXPECT_NEAR(r.position_error->median, 1.3, 1e-9);
  EXPECT_NEAR(r.rotation_error_deg->median, 5.5, 1e-9);
  // Doubled distances 0.2, 0.6, 2, 12: only q0 within 0.5 now.
  EXPECT_EQ(r.within, (std::array<int, 3>{1, 1, 3}));
}

TEST(Report, PosesFileAndJsonLinesGiveTheSameReport) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  s.WritePoses(dir / "run.txt");
  s.WriteJsonLines(dir / "run.jsonl");
  const auto gt = ReadGroundTruth(dir / "gt.txt");
  const RunResults poses = ReadResults(dir / "run.txt");
  const RunResults lines = ReadResults(dir / "run.jsonl");
  EXPECT_EQ(poses.format, ResultFormat::kPoses);
  EXPECT_EQ(lines.format, ResultFormat::kJsonLines);
  EvalReport a, b;
  a.runs = {EvaluateRun(gt, poses, 1.0, "run")};
  b.runs = {EvaluateRun(gt, lines, 1.0, "run")};
  auto ja = ReportToJson(a)["runs"][0];
  auto jb = ReportToJson(b)["runs"][0];
  // Only where the run came from and the timings (poses files have none) may differ.
  for (const char* key : {"path", "format", "timed_records", "times_ms"}) {
    ja.erase(key);
    jb.erase(key);
  }
  // Both texts round-trip doubles exactly, so the errors agree to the last bit or nearly.
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(ja["per_query"][i]["position_error"].get<double>(),
                jb["per_query"][i]["position_error"].get<double>(), 1e-12);
    EXPECT_NEAR(ja["per_query"][i]["rotation_error_deg"].get<double>(),
                jb["per_query"][i]["rotation_error_deg"].get<double>(), 1e-9);
  }
  ja.erase("per_query");
  jb.erase("per_query");
  for (auto* j : {&ja, &jb}) {
    for (const char* key : {"position_error", "rotation_error_deg"}) {
      for (const char* q : {"q1", "median", "q3"})
        (*j)[key][q] = std::round((*j)[key][q].get<double>() * 1e9) / 1e9;
    }
  }
  EXPECT_EQ(ja.dump(), jb.dump());
}

TEST(Report, CountsFailuresErrorsMissingAndUnknownNames) {
  cwloc::test::TempDir dir;
  const Scenario s;
  s.WriteGroundTruth(dir / "gt.txt");
  std::ofstream(dir / "run.jsonl")
      << Scenario::JsonRecord("q0.jpg", s.estimates[0], 5).dump() << "\n"
      << R"({"name":"q1.jpg","success":false,"failure_reason":"too few inliers","times_ms":{"forward_knn":1,"ratio_test":1,"query_tree":1,"back_matching":1,"pose":1,"total":5}})"
      << "\n"
      << R"({"name":"q2.jpg","success":false,"error":"cannot read image"})"
      << "\n\n"
      << Scenario::JsonRecord("other.jpg", s.estimates[1], 5).dump() << "\n";
  const RunReport r =
      EvaluateRun(ReadGroundTruth(dir / "gt.txt"), ReadResults(dir / "run.jsonl"), 1.0, "run");
  EXPECT_EQ(r.localized, 1);
  EXPECT_EQ(r.not_localized, 1);
  EXPECT_EQ(r.errors, 1);
  EXPECT_EQ(r.missing, 2);
  EXPECT_EQ(r.unknown_names, 1);
  EXPECT_EQ(r.timed_records, 3);
  EXPECT_EQ(r.within, (std::array<int, 3>{1, 1, 1}));
  EXPECT_EQ(r.per_query[1].status, QueryStatus::kNotLocalized);
  EXPECT_EQ(r.per_query[2].status, QueryStatus::kError);
  EXPECT_NE(FormatTable(EvalReport{"gt.txt", 5, std::nullopt, 1.0, {r}})
                .find("1 result(s) for names not in the ground truth"),
            std::string::npos);
}

TEST(Readers, MissingFileNamesTheFile) {
  cwloc::test::TempDir dir;
  const auto path = dir / "results.jsonl";
  EXPECT_EQ(InputErrorOf([&] { ReadResults(path); }),
            path.string() + ": cannot open (No such file or directory)");
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(path); }),
            path.string() + ": cannot open (No such file or directory)");
  EXPECT_EQ(InputErrorOf([&] { ReadResults(dir.path()); }),
            dir.path().string() + ": is a directory, expected a file");
}

// Issue #23: devices and files over the limit are refused before they are read.
TEST(Readers, DevicesAndHugeFilesAreRefusedUnread) {
  EXPECT_EQ(InputErrorOf([] { ReadResults("/dev/zero"); }),
            "/dev/zero: not a regular file (a character device); an evaluation input must be a "
            "regular file, not a device, a pipe, a socket or /dev/stdin");
  EXPECT_EQ(InputErrorOf([] { ReadQueryPoints("/dev/zero"); }),
            "/dev/zero: not a regular file (a character device); an evaluation input must be a "
            "regular file, not a device, a pipe, a socket or /dev/stdin");
  cwloc::test::TempDir dir;
  const auto huge = cwloc::test::WriteSparseFile(dir / "gt.txt", 5'000'000'000);
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(huge); }),
            huge.string() + ": 5 GB, more than the 4 GB limit for an evaluation input");
}

TEST(Readers, MalformedLinesNameFileAndLine) {
  cwloc::test::TempDir dir;
  const Scenario s;
  const std::string good = Scenario::JsonRecord("q0.jpg", s.estimates[0], 5).dump();
  const auto results = dir / "results.jsonl";
  const auto expect = [&](const std::string& text, const std::string& message) {
    WriteFile(results, text);
    EXPECT_EQ(InputErrorOf([&] { ReadResults(results); }), results.string() + message) << text;
  };
  expect(good + "\n\n{\"name\": \"q1.jpg\", \"success\": tru\n", ":3: not valid JSON");
  expect("{\"name\": \"q1.jpg\"}\n", ":1: expected a boolean \"success\"");
  expect("{\"success\": true}\n", ":1: expected a non-empty string \"name\"");
  expect("{\"name\": \"a\", \"success\": true}\n",
         ":1: \"success\" is true but there is no \"pose\" object");
  expect(
      "{\"name\": \"a\", \"success\": true, \"pose\": {\"qvec\": [1, 0, 0], \"tvec\": [0, 0, "
      "0]}}\n",
      ":1: \"pose.qvec\" must be an array of 4 finite numbers");
  expect(
      "{\"name\": \"a\", \"success\": true, \"pose\": {\"qvec\": [0, 0, 0, 0], \"tvec\": [0, 0, "
      "0]}}\n",
      ":1: \"pose.qvec\" is zero");
  expect("{\"name\": \"a\", \"success\": false, \"times_ms\": {\"total\": 3}}\n",
         ":1: \"times_ms.forward_knn\" must be a number");
  expect(good + "\n[1, 2]\n", ":2: expected a JSON object (one cwloc-localize result per line)");
  expect(good + "\n" + good + "\n", ":2: duplicate result for q0.jpg (first on line 1)");
  // A poses file is detected by its first line; later lines must follow it.
  expect("q0.jpg 1 0 0 0 1 2 3\nq1.jpg 1 0 0 0 1 2\n", ":2: expected NAME QW QX QY QZ TX TY TZ");

  const auto gt = dir / "queries_gt.txt";
  WriteFile(gt, "# comment\nq0.jpg 1 0 0 x 1 2 3\n");
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(gt); }),
            gt.string() + ":2: expected NAME QW QX QY QZ TX TY TZ");
  WriteFile(gt, "q0.jpg 0 0 0 0 1 2 3\n");
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(gt); }),
            gt.string() + ":1: quaternion QW QX QY QZ is zero");
  WriteFile(gt, "q0.jpg 1 0 0 0 1 2 3\nq0.jpg 1 0 0 0 1 2 3\n");
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(gt); }),
            gt.string() + ":2: duplicate query q0.jpg (first on line 1)");
  WriteFile(gt, "# nothing\n");
  EXPECT_EQ(InputErrorOf([&] { ReadGroundTruth(gt); }),
            gt.string() + ": no ground-truth queries (expected NAME QW QX QY QZ TX TY TZ lines)");

  const auto scale = dir / "scale_to_metres.txt";
  WriteFile(scale, "R 1 0 0 0 1 0 0 0 1\n");
  EXPECT_EQ(InputErrorOf([&] { ReadScale(scale); }), scale.string() + ": no 'scale S' line");
  WriteFile(scale, "# x\nscale -1\n");
  EXPECT_EQ(InputErrorOf([&] { ReadScale(scale); }),
            scale.string() + ":2: expected 'scale S' with a number S > 0");
}

}  // namespace
}  // namespace cwloc::eval
