// Issue #41: the pose covariance that `cwloc-index build` calibrates on the model (model images
// left out and localized, PCAL) holds the true centres of the real captures' held-out queries,
// which the keypoints' covariance alone missed (herz_jesu_p25: 9 of 15 inside, sceaux_castle 4
// of 9).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "app/camera_spec.h"
#include "app/database/database_queries.h"
#include "base/chi_square.h"
#include "camera/camera_models.h"
#include "format/index.h"
#include "localizer/localizer.h"
#include "tests/localization_check.h"
#include "tests/shared_data_index.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

class CovarianceCalibrationTest : public testing::TestWithParam<std::string> {};

TEST_P(CovarianceCalibrationTest, HeldOutQueriesFallInsideTheirCalibrated95PercentRegion) {
  const auto shared = test::BuildSharedDataIndex(GetParam(), 0, /*calibrated=*/true);
  if (!shared) GTEST_SKIP() << "shared data '" << GetParam() << "' not found; skipping";
  const Index index = Index::Open(shared->index);
  const IndexCovarianceCalibration* calibration = index.covariance_calibration();
  ASSERT_NE(calibration, nullptr);
  // Fewer model images than the default 30 samples: every one was left out once.
  EXPECT_EQ(calibration->sampled, index.images().size());
  const auto manifest = nlohmann::json::parse(index.manifest_json())["covariance_calibration"];
  EXPECT_EQ(manifest["sampled_images"], index.images().size());

  const DatabaseQueries database(shared->data / "database.db");
  const Localizer localizer(index);
  int total = 0, inside = 0, inside_uncalibrated = 0;
  for (const auto& [name, truth] : test::ReadGroundTruth(shared->data / "queries_gt.txt")) {
    const QueryCamera camera = ParseCameraSpec(truth.camera, "queries_gt.txt");
    for (const QueryCamera& mode :
         {camera,
          FocalPriorCamera(MeanFocalLength(camera.model_id, camera.params), camera.width,
                           camera.height, IntrinsicsSource::kFocalOption),
          UnknownFocalCamera(camera.width, camera.height, IntrinsicsSource::kNone)}) {
      Query query = database.Load(name);
      query.camera = mode;
      const LocalizationResult result = localizer.Localize(query, LocalizerOptions{});
      ASSERT_TRUE(result.success) << name << ": " << result.failure_reason;
      ASSERT_TRUE(result.covariance && result.covariance->calibration) << name;
      const auto m = static_cast<size_t>(mode.calibration);
      EXPECT_EQ(result.covariance->calibration->position, calibration->position_scale[m]);
      EXPECT_EQ(result.covariance->calibration->rotation, calibration->rotation_scale[m]);
      EXPECT_GE(result.covariance->calibration->position, 1.0);
      const Eigen::Vector3d offset = Eigen::Vector3d(result.center.data()) - truth.pose.Center();
      const Eigen::Matrix3d position = PositionBlock(*result.covariance);
      const double d2 = offset.dot(position.ldlt().solve(offset));
      ++total;
      inside += d2 <= kChiSquare3Dof95;
      inside_uncalibrated += d2 * result.covariance->calibration->position <= kChiSquare3Dof95;
    }
  }
  // Measured: herz_jesu_p25 14 of 15 (9 uncalibrated), sceaux_castle 9 of 9 (4).
  EXPECT_GE(inside, total - 1) << inside << " of " << total;
  EXPECT_LT(inside_uncalibrated, inside);
}

INSTANTIATE_TEST_SUITE_P(RealCaptures, CovarianceCalibrationTest,
                         testing::Values("herz_jesu_p25", "sceaux_castle"));

}  // namespace
}  // namespace cwloc
