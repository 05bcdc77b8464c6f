#include "localizer/pose/rig_pose.h"

#include <gtest/gtest.h>

#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// A rig of cameras looking outwards from within a metre of its origin (as a car's or a 360
// rig's), f = 1000 px, 1600 x 1200 images; camera c sees points[c] correspondences, of which
// `outlier_ratio` are wrong matches; 1 px noise.
struct RigScene {
  RigPose truth;
  std::vector<RigCamera> cameras;
  std::vector<RigObservation> observations;
  std::vector<char> is_inlier;
};

RigScene MakeRigScene(SplitMix64& rng, const std::vector<int>& points, double outlier_ratio,
                      double scale = 1.0) {
  RigScene scene;
  scene.truth.rig_from_world = test::RandomPose(rng);
  scene.truth.scale = scale;
  const int n = static_cast<int>(points.size());
  test::NormalSampler<SplitMix64> noise(0.0, 1.0);
  for (int c = 0; c < n; ++c) {
    // Yaw c * 360 / n about the rig's y axis, centre on a circle of radius 0.5.
    const double yaw = 2.0 * std::numbers::pi * c / n;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d center = 0.5 * (q.conjugate() * Eigen::Vector3d::UnitZ());
    RigCamera camera;
    camera.cam_from_rig = CameraPose(q, -(q * center));  // unit scale
    camera.camera = {1000.0, 0.0};
    scene.cameras.push_back(camera);
    const CameraPose cam_from_world = scene.truth.CameraFromWorld(camera.cam_from_rig);
    for (int i = 0; i < points[c]; ++i) {
      const Eigen::Vector2d pixel(test::Uniform(rng, -800, 800), test::Uniform(rng, -600, 600));
      const Eigen::Vector3d in_cam = test::Uniform(rng, 5.0, 50.0) * (pixel / 1000.0).homogeneous();
      RigObservation o;
      o.camera = static_cast<uint32_t>(c);
      o.point3D = cam_from_world.rotation.conjugate() * (in_cam - cam_from_world.translation);
      const bool inlier = test::UnitUniform(rng) >= outlier_ratio;
      o.pixel = inlier
                    ? pixel + Eigen::Vector2d(noise(rng), noise(rng))
                    : Eigen::Vector2d(test::Uniform(rng, -800, 800), test::Uniform(rng, -600, 600));
      scene.observations.push_back(o);
      scene.is_inlier.push_back(inlier);
    }
  }
  return scene;
}

double CentreError(const RigPose& a, const RigPose& b) {
  return (a.rig_from_world.Center() - b.rig_from_world.Center()).norm();
}

TEST(EstimateRigPose, LocalizesRandomRigsWithHalfTheMatchesWrong) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  for (int trial = 0; trial < 20; ++trial) {
    const RigScene scene = MakeRigScene(rng, {150, 150, 150, 150}, 0.5);
    const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, false, {});
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_TRUE(result.refined);
    EXPECT_LT(CentreError(result.pose, scene.truth), 0.05) << "trial " << trial;
    EXPECT_LT(test::RotationErrorDeg(result.pose.rig_from_world, scene.truth.rig_from_world), 0.2);
    int wrong = 0;
    for (size_t i = 0; i < scene.observations.size(); ++i)
      wrong += result.inliers[i] && !scene.is_inlier[i];
    EXPECT_LE(wrong, 15);  // a wrong match can land within 6 px by chance
    EXPECT_EQ(result.inliers_per_camera.size(), 4u);
    ASSERT_TRUE(result.covariance.has_value());
    EXPECT_FALSE(result.scale_std.has_value());
  }
}

// Only one camera sees anything: the rig is localized as that camera would be alone.
TEST(EstimateRigPose, LocalizesARigWhoseOnlyMatchesAreInOneCamera) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  const RigScene scene = MakeRigScene(rng, {0, 0, 200}, 0.3);
  const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, false, {});
  ASSERT_TRUE(result.success) << result.failure_reason;
  EXPECT_LT(CentreError(result.pose, scene.truth), 0.1);
  EXPECT_EQ(result.inliers_per_camera[0], 0u);
  EXPECT_GE(result.inliers_per_camera[2], 120u);
}

TEST(EstimateRigPose, EstimatesTheScaleOfAWindowWithUnknownScale) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  for (const double scale : {0.3, 1.0, 4.0}) {
    const RigScene scene = MakeRigScene(rng, {150, 150, 150}, 0.4, scale);
    const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, true, {});
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_NEAR(result.pose.scale / scale, 1.0, 0.05) << scale;
    EXPECT_LT(CentreError(result.pose, scene.truth), 0.05 * std::max(1.0, scale));
    ASSERT_TRUE(result.scale_std.has_value());
    EXPECT_GT(*result.scale_std, 0.0);
  }
}

TEST(EstimateRigPose, AnUnknownScaleWithMatchesInOneImageFails) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  const RigScene scene = MakeRigScene(rng, {200, 0}, 0.2, 2.0);
  const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, true, {});
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason,
            "no pose hypothesis: an unknown scale needs three correspondences in one image and "
            "one in another");
}

TEST(EstimateRigPose, TooFewCorrespondencesSayHowMany) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  const RigScene scene = MakeRigScene(rng, {5, 4}, 0.0);
  const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, false, {});
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason, "too few correspondences over all images: 9 < 12");
}

// The focal-prior camera's f is refined with the pose: it starts 2 % off (a usual EXIF error).
TEST(EstimateRigPose, RefinesTheFocalLengthOfAFocalPriorCamera) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  RigScene scene = MakeRigScene(rng, {200, 200}, 0.2);
  scene.cameras[1].camera.focal_length_px = 1020.0;
  scene.cameras[1].refine_intrinsics = true;
  const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, false, {});
  ASSERT_TRUE(result.success) << result.failure_reason;
  EXPECT_NEAR(result.cameras[1].focal_length_px, 1000.0, 5.0);
  EXPECT_EQ(result.cameras[0].focal_length_px, 1000.0);  // a known camera is held
  EXPECT_LT(CentreError(result.pose, scene.truth), 0.05);
}

// The covariance is honest on synthetic rigs: the truth lies within the 95 % region of the 6-D
// pose error (chi2(6) < 12.59) for about 95 % of the problems.
TEST(EstimateRigPose, TheCovarianceCoversTheTruth) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  constexpr int kTrials = 200;
  int covered = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const RigScene scene = MakeRigScene(rng, {60, 60, 60}, 0.3);
    const RigPoseResult result = EstimateRigPose(scene.cameras, scene.observations, false, {});
    ASSERT_TRUE(result.success && result.covariance.has_value());
    const Eigen::Matrix3d world_from_rig = result.pose.rig_from_world.RotationMatrix().transpose();
    const Eigen::Matrix3d truth = scene.truth.rig_from_world.RotationMatrix().transpose();
    const Eigen::AngleAxisd theta(world_from_rig * truth.transpose());
    Eigen::Matrix<double, 6, 1> e;
    e << theta.angle() * theta.axis(),
        result.pose.rig_from_world.Center() - scene.truth.rig_from_world.Center();
    covered += e.dot(PoseBlock(*result.covariance).ldlt().solve(e)) < 12.59;
  }
  std::printf("%d of %d truths inside the 95 %% region\n", covered, kTrials);
  EXPECT_GE(covered, 0.88 * kTrials);
  EXPECT_LE(covered, 0.99 * kTrials);
}

}  // namespace
}  // namespace cwloc
