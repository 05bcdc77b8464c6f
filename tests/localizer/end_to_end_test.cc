// The main job end to end, as the README's demo runs it and with no shared data: cwloc-synth
// writes a small city (COLMAP model, database, queries with exact poses), cwloc-index builds the
// index, cwloc-localize localizes every query from the database. Every query must be localized,
// near its ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <set>

#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// Measured with `cwloc-synth --preset demo --seed S`, S = 1..16 (20 queries each, all
// localized): worst error per seed 0.020-0.185 m and 0.11-0.43 deg; seed 1, used here: 0.095 m
// and 0.24 deg. The bounds are 5x and 8x seed 1's worst and 2.7x and 4.7x the worst of any seed;
// the position bound stays below 1 m so that a pose a metre off fails.
constexpr double kMaxPositionErrorM = 0.5;
constexpr double kMaxRotationErrorDeg = 2.0;

TEST(EndToEndTest, EveryQueryOfTheDemoCityIsLocalizedNearItsGroundTruth) {
  test::TempDir dir;
  const auto city = dir / "city";
  const auto index = dir / "city.cwl";
  const auto results = dir / "results.jsonl";
  std::string output;
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-synth").string() +
                                 " --preset demo --seed 1 --threads 2 -o " + city.string(),
                             &output),
            0)
      << output;
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model " +
                                 (city / "mapping_model" / "bin").string() + " --database " +
                                 (city / "database.db").string() + " -o " + index.string() +
                                 " --threads 2",
                             &output),
            0)
      << output;
  // The covariance calibration localizes the folds' images on threads; the file is the same.
  const auto one_thread = dir / "one_thread.cwl";
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model " +
                                 (city / "mapping_model" / "bin").string() + " --database " +
                                 (city / "database.db").string() + " -o " + one_thread.string() +
                                 " --threads 1",
                             &output),
            0)
      << output;
  EXPECT_EQ(test::ReadBytes(index), test::ReadBytes(one_thread));
  // Exit 0 means every query was localized (1 would be "some query not localized").
  EXPECT_EQ(
      test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " + index.string() +
                           " --database " + (city / "database.db").string() + " --query-list " +
                           (city / "queries_with_intrinsics.txt").string() + " --threads 2 -o " +
                           results.string(),
                       &output),
      0)
      << output;

  const auto truth = test::ReadGroundTruth(city / "queries_gt.txt");
  const double metres_per_unit = test::ReadMetresPerUnit(city / "scale_to_metres.txt");
  ASSERT_EQ(truth.size(), 20u);  // the demo preset's query count
  const auto lines = test::ReadJsonLines(results);
  ASSERT_EQ(lines.size(), truth.size());
  std::set<std::string> seen;
  double worst_position = 0, worst_rotation = 0;
  for (const auto& result : lines) {
    const std::string name = result.at("name");
    SCOPED_TRACE(name);
    ASSERT_TRUE(truth.contains(name));
    EXPECT_TRUE(seen.insert(name).second) << "reported twice";
    ASSERT_TRUE(result.value("success", false)) << result.dump();
    // Calibrated by the build in every mode (30 samples of 134 images; 5 must localize).
    EXPECT_GE(result.at("covariance").at("calibration").at("position_scale").get<double>(), 1.0);
    const test::PoseError error =
        test::ErrorOf(test::PoseOfResult(result), truth.at(name).pose, metres_per_unit);
    EXPECT_LT(error.position_m, kMaxPositionErrorM);
    EXPECT_LT(error.rotation_deg, kMaxRotationErrorDeg);
    worst_position = std::max(worst_position, error.position_m);
    worst_rotation = std::max(worst_rotation, error.rotation_deg);
  }
  std::cout << "worst of " << lines.size() << " queries: position " << worst_position
            << " m, rotation " << worst_rotation << " deg\n";
}

}  // namespace
}  // namespace cwloc
