#include "localizer/pose/absolute_pose.h"

#include <gtest/gtest.h>

#include <iostream>
#include <limits>
#include <numbers>

#include "base/angles.h"
#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// Recall and precision of the reported inlier set against the true one.
void ExpectInlierSet(const AbsolutePoseResult& result, const test::SyntheticPoseProblem& problem) {
  ASSERT_EQ(result.inliers.size(), problem.is_inlier.size());
  int true_positive = 0, reported = 0;
  for (size_t i = 0; i < problem.is_inlier.size(); ++i) {
    reported += result.inliers[i];
    true_positive += result.inliers[i] && problem.is_inlier[i];
  }
  EXPECT_EQ(reported, result.num_inliers);
  EXPECT_GE(true_positive, 0.97 * problem.num_inliers);  // 1 px noise: nearly all within 6 px
  EXPECT_GE(true_positive, reported - 2);                // random outliers rarely land within 6 px
}

class KnownFocal : public testing::TestWithParam<double> {};

TEST_P(KnownFocal, FindsPoseAndInliersAmongOutliers) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.outlier_ratio = GetParam();
  for (int trial = 0; trial < 5; ++trial) {
    const auto problem = test::MakeSyntheticProblem(options, rng);
    const AbsolutePoseResult result =
        EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px);
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_TRUE(result.failure_reason.empty());
    EXPECT_LT(test::RotationErrorDeg(result.pose, problem.pose), 0.1);
    EXPECT_LT((result.pose.Center() - problem.pose.Center()).norm(), 0.01 * problem.mean_depth);
    EXPECT_EQ(result.focal_length_px, problem.focal_px);
    EXPECT_TRUE(result.refined);
    EXPECT_GT(result.mean_reprojection_error_px, 0.5);  // ~1.25 px for 1 px Gaussian noise
    EXPECT_LT(result.mean_reprojection_error_px, 2.0);
    EXPECT_GT(result.stats.iterations, 0u);
    EXPECT_GT(result.stats.refinements, 0u);
    ExpectInlierSet(result, problem);
  }
}

INSTANTIATE_TEST_SUITE_P(OutlierRatios, KnownFocal, testing::Values(0.6, 0.7, 0.8));

class UnknownFocal : public testing::TestWithParam<double> {};

TEST_P(UnknownFocal, RecoversFocalWithinOnePercent) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.outlier_ratio = GetParam();
  for (int trial = 0; trial < 4; ++trial) {
    options.focal_px = test::Uniform(rng, 600.0, 2400.0);
    const auto problem = test::MakeSyntheticProblem(options, rng);
    const AbsolutePoseResult result =
        EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D);
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_NEAR(result.focal_length_px, problem.focal_px, 0.01 * problem.focal_px);
    EXPECT_LT(test::RotationErrorDeg(result.pose, problem.pose), 0.2);
    EXPECT_LT((result.pose.Center() - problem.pose.Center()).norm(), 0.02 * problem.mean_depth);
    ExpectInlierSet(result, problem);
  }
}

INSTANTIATE_TEST_SUITE_P(OutlierRatios, UnknownFocal, testing::Values(0.5, 0.7));

// Uncalibrated cameras: SIMPLE_RADIAL observations; the focal length is unknown (P4Pf) or a
// prior 5% short (P3P with the prior). The refinement must recover f within 0.1% and k within
// 1e-3 under 0.5 px noise and half outliers, and re-score the distorted corners as inliers.
class Uncalibrated : public testing::TestWithParam<std::tuple<double, bool>> {};

AbsolutePoseResult EstimateUncalibrated(const test::SyntheticPoseProblem& problem, bool prior,
                                        const AbsolutePoseOptions& options = {},
                                        const PoseContext& context = {}) {
  return prior
             ? EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D,
                                              0.95 * problem.focal_px, options, context)
             : EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
}

TEST_P(Uncalibrated, RefinementRecoversFocalAndDistortion) {
  const auto [k, prior] = GetParam();
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.num_points = 600;
  options.outlier_ratio = 0.5;
  options.noise_px = 0.5;
  options.radial_k = k;
  for (int trial = 0; trial < 4; ++trial) {
    // A field of view of 60 to 90 degrees across the 1600 px width: with a longer lens, k moves
    // the corners by too little for 0.5 px noise to pin it within 1e-3.
    options.focal_px = test::Uniform(rng, 800.0, 1400.0);
    const auto problem = test::MakeSyntheticProblem(options, rng);
    const AbsolutePoseResult result = EstimateUncalibrated(problem, prior);
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_TRUE(result.refined);
    EXPECT_GE(result.camera_refinement_rounds, 1);
    EXPECT_NEAR(result.focal_length_px, problem.focal_px, 1e-3 * problem.focal_px);
    EXPECT_NEAR(result.radial_distortion, k, 1e-3);
    EXPECT_LT(test::RotationErrorDeg(result.pose, problem.pose), 0.05);
    EXPECT_LT((result.pose.Center() - problem.pose.Center()).norm(), 0.002 * problem.mean_depth);
    ExpectInlierSet(result, problem);
  }
}

INSTANTIATE_TEST_SUITE_P(DistortionAndPrior, Uncalibrated,
                         testing::Combine(testing::Values(-0.15, 0.0, 0.08), testing::Bool()));

TEST(UncalibratedRefinement, RescoresTheDistortedCornersAsInliers) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.outlier_ratio = 0.3;
  options.radial_k = -0.15;  // corners move by 15%: 150 px at 1000 px from the centre
  for (const bool prior : {false, true}) {
    const auto problem = test::MakeSyntheticProblem(options, rng);
    const AbsolutePoseResult result = EstimateUncalibrated(problem, prior);
    ASSERT_TRUE(result.success) << result.failure_reason;
    // RANSAC's pinhole camera sees only the centre; the refined camera sees nearly all.
    EXPECT_LT(result.stats.num_inliers, 0.8 * problem.num_inliers) << prior;
    EXPECT_GE(result.camera_refinement_rounds, 2) << prior;
    ExpectInlierSet(result, problem);
  }
}

TEST(UncalibratedRefinement, KeepsOnlySaneCameras) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions synth;
  synth.outlier_ratio = 0.3;
  synth.noise_px = 0.5;
  synth.radial_k = -0.15;
  const auto problem = test::MakeSyntheticProblem(synth, rng);

  // |k| beyond the bound: no round is kept, RANSAC's pinhole camera is reported.
  AbsolutePoseOptions options;
  options.max_radial_distortion = 0.05;
  AbsolutePoseResult result = EstimateUncalibrated(problem, true, options);
  EXPECT_FALSE(result.refined);
  EXPECT_EQ(result.camera_refinement_rounds, 0);
  EXPECT_EQ(result.radial_distortion, 0.0);
  EXPECT_EQ(result.focal_length_px, 0.95 * problem.focal_px);

  // A barrel distortion that would fold the corners of a larger image back: 1 + 3 k r_c^2 < 0
  // at r_c = 1.7 (the corner 1.7 f from the centre) with k = -0.15.
  PoseContext context;
  context.image_diagonal_px = 2.0 * 1.7 * problem.focal_px;
  result = EstimateUncalibrated(problem, false, {}, context);
  EXPECT_FALSE(result.refined);
  EXPECT_EQ(result.radial_distortion, 0.0);

  // Without distortion refinement, k stays 0 and the focal length is off.
  options = {};
  options.refine_radial_distortion = false;
  result = EstimateUncalibrated(problem, false, options);
  ASSERT_TRUE(result.success);
  EXPECT_EQ(result.radial_distortion, 0.0);
  EXPECT_GT(std::abs(result.focal_length_px - problem.focal_px), 1e-3 * problem.focal_px);
}

TEST(UncalibratedRefinement, FocalPriorReportsBadInput) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem({}, rng);
  AbsolutePoseResult result = EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D, 0.0);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason, "invalid focal length prior: 0 px");
  AbsolutePoseOptions options;
  options.refine = false;
  result =
      EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D, problem.focal_px, options);
  ASSERT_TRUE(result.success);
  EXPECT_FALSE(result.refined);
  EXPECT_EQ(result.focal_length_px, problem.focal_px);
  // P4Pf for the prior: the prior plays no part.
  options.focal_prior_solver = FocalPriorSolver::kP4Pf;
  result = EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D, 1.0, options);
  ASSERT_TRUE(result.success);
  EXPECT_NEAR(result.focal_length_px, problem.focal_px, 0.01 * problem.focal_px);
}

TEST(AbsolutePose, ReportsTooFewInliers) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.num_points = 100;
  options.outlier_ratio = 0.91;  // 9 true correspondences
  const auto problem = test::MakeSyntheticProblem(options, rng);
  ASSERT_EQ(problem.num_inliers, 9);
  const AbsolutePoseResult result =
      EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px);
  EXPECT_FALSE(result.success);
  EXPECT_LT(result.num_inliers, 12);
  EXPECT_EQ(result.failure_reason,
            "best pose has " + std::to_string(result.num_inliers) + " inliers < 12");
  EXPECT_EQ(result.inliers.size(), problem.pixels.size());

  const AbsolutePoseResult unknown =
      EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D);
  EXPECT_FALSE(unknown.success);
  EXPECT_NE(unknown.failure_reason.find("inliers < 12"), std::string::npos)
      << unknown.failure_reason;
}

TEST(AbsolutePose, ReportsBadInput) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options;
  options.num_points = 7;
  options.outlier_ratio = 0.0;
  const auto problem = test::MakeSyntheticProblem(options, rng);
  AbsolutePoseResult result = EstimateAbsolutePose(problem.normalized, problem.points3D, 1000.0);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason, "too few correspondences: 7 < 12");
  result = EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D);
  EXPECT_EQ(result.failure_reason, "too few correspondences: 7 < 12");

  // A lower min_inliers accepts the 7 exact correspondences.
  AbsolutePoseOptions few;
  few.min_inliers = 5;
  result = EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px, few);
  EXPECT_TRUE(result.success) << result.failure_reason;
  EXPECT_EQ(result.num_inliers, 7);

  const std::span<const Eigen::Vector3d> fewer(problem.points3D.data(), 6);
  result = EstimateAbsolutePose(problem.normalized, fewer, 1000.0, few);
  EXPECT_EQ(result.failure_reason, "size mismatch: 7 image points vs 6 3D points");

  result = EstimateAbsolutePose(problem.normalized, problem.points3D, -1.0, few);
  EXPECT_EQ(result.failure_reason, "invalid focal length: -1 px");
}

TEST(AbsolutePose, DeterministicForASeed) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem({}, rng);
  const AbsolutePoseOptions options;
  PoseContext context;
  context.ransac.seed = 7;
  const auto a = EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px,
                                      options, context);
  const auto b = EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px,
                                      options, context);
  EXPECT_EQ(a.pose.rotation.coeffs(), b.pose.rotation.coeffs());
  EXPECT_EQ(a.pose.translation, b.pose.translation);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.stats.iterations, b.stats.iterations);
  const auto c =
      EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
  const auto d =
      EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
  EXPECT_EQ(c.focal_length_px, d.focal_length_px);
  EXPECT_EQ(c.pose.translation, d.pose.translation);
  // Another seed takes other samples but finds the same pose.
  context.ransac.seed = 8;
  const auto e = EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px,
                                      options, context);
  ASSERT_TRUE(e.success);
  EXPECT_LT(test::RotationErrorDeg(e.pose, a.pose), 0.01);
}

TEST(AbsolutePose, FocalRangeRejectsAbsurdFocalLengths) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions synth;
  synth.outlier_ratio = 0.5;
  const auto problem = test::MakeSyntheticProblem(synth, rng);
  AbsolutePoseOptions options;
  options.min_focal_px = 3000.0;  // the true focal length (1000 px) is outside
  options.max_focal_px = 5000.0;
  const auto result = EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options);
  if (result.num_inliers > 0) {
    EXPECT_GE(result.focal_length_px, 3000.0);
    EXPECT_LE(result.focal_length_px, 5000.0);
  }
  EXPECT_FALSE(result.success && result.num_inliers > problem.num_inliers / 2);
}

TEST(AbsolutePose, WorksWithoutFinalRefinement) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem({}, rng);
  AbsolutePoseOptions options;
  options.refine = false;
  const auto result =
      EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px, options);
  ASSERT_TRUE(result.success);
  EXPECT_FALSE(result.refined);
  EXPECT_LT(test::RotationErrorDeg(result.pose, problem.pose), 0.1);
}

}  // namespace
}  // namespace cwloc

namespace cwloc {
namespace {

// A prior for the problem's camera: a random world gravity, the camera's error_deg off.
GravityPrior PriorFor(const test::SyntheticPoseProblem& problem, double error_deg, double sigma_deg,
                      SplitMix64& rng) {
  GravityPrior prior;
  prior.in_world = test::RandomUnitVector(rng);
  const Eigen::Vector3d in_camera = problem.pose.rotation * prior.in_world;
  const Eigen::Vector3d axis = in_camera.cross(test::RandomUnitVector(rng)).normalized();
  prior.in_camera = Eigen::AngleAxisd(error_deg * kDegree, axis) * in_camera;
  prior.sigma_deg = sigma_deg;
  return prior;
}

void ExpectAccurate(const AbsolutePoseResult& result, const test::SyntheticPoseProblem& problem) {
  ASSERT_TRUE(result.success) << result.failure_reason;
  EXPECT_LT(test::RotationErrorDeg(result.pose, problem.pose), 0.1);
  EXPECT_LT((result.pose.Center() - problem.pose.Center()).norm(), 0.01 * problem.mean_depth);
  ExpectInlierSet(result, problem);
}

TEST(GravityPrior, KnownFocalSamplesTwoPoints) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  test::SyntheticPoseOptions synth;
  synth.outlier_ratio = 0.8;
  for (int trial = 0; trial < 5; ++trial) {
    const auto problem = test::MakeSyntheticProblem(synth, rng);
    AbsolutePoseOptions options;
    PoseContext context;
    const AbsolutePoseResult without = EstimateAbsolutePose(problem.normalized, problem.points3D,
                                                            problem.focal_px, options, context);
    context.gravity = PriorFor(problem, 0.5, 1.0, rng);
    const AbsolutePoseResult with = EstimateAbsolutePose(problem.normalized, problem.points3D,
                                                         problem.focal_px, options, context);
    ExpectAccurate(without, problem);
    ExpectAccurate(with, problem);
    EXPECT_FALSE(with.gravity_fallback);
    EXPECT_TRUE(with.refined);
    // 20% inliers: log(1e-4) / log(1 - 0.2^s) is 226 for s = 2, 1147 for s = 3.
    EXPECT_LE(with.stats.iterations, 300u);
    EXPECT_GE(without.stats.iterations, 1000u);
    // The pose follows the points, not the prior 0.5 degrees off.
    EXPECT_NEAR(with.gravity_angle_deg, 0.5, 0.1);
    EXPECT_EQ(without.gravity_angle_deg, 0.0);
  }
}

TEST(GravityPrior, KnownFocalSurvivesAPriorFarOffItsSigma) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  test::SyntheticPoseOptions synth;
  synth.num_points = 150;
  synth.outlier_ratio = 0.8;
  int fallbacks[2] = {0, 0};
  for (int trial = 0; trial < 10; ++trial) {
    const auto problem = test::MakeSyntheticProblem(synth, rng);
    AbsolutePoseOptions options;
    PoseContext context;
    // 3 sigma: GravityP2P's hypotheses keep few inliers, its local optimisation mostly
    // recovers; 20 sigma: mostly P3P after it finds the pose.
    for (int k = 0; k < 2; ++k) {
      const double error_deg = k == 0 ? 3.0 : 20.0;
      SCOPED_TRACE(error_deg);
      context.gravity = PriorFor(problem, error_deg, 1.0, rng);
      const AbsolutePoseResult result = EstimateAbsolutePose(problem.normalized, problem.points3D,
                                                             problem.focal_px, options, context);
      ExpectAccurate(result, problem);
      EXPECT_NEAR(result.gravity_angle_deg, error_deg, 0.2);
      fallbacks[k] += result.gravity_fallback;
    }
  }
  std::cout << "P3P after GravityP2P: " << fallbacks[0] << "/10 with the prior 3 sigma off, "
            << fallbacks[1] << "/10 20 sigma off\n";
  EXPECT_LE(fallbacks[0], 3);
  EXPECT_GE(fallbacks[1], 5);
}

TEST(GravityPrior, VaguePriorChecksP3PHypotheses) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  test::SyntheticPoseOptions synth;
  synth.outlier_ratio = 0.7;
  const auto problem = test::MakeSyntheticProblem(synth, rng);
  AbsolutePoseOptions options;
  PoseContext context;
  context.gravity = PriorFor(problem, 5.0, 2.0 * kGravityP2PMaxSigmaDeg, rng);
  const AbsolutePoseResult result = EstimateAbsolutePose(problem.normalized, problem.points3D,
                                                         problem.focal_px, options, context);
  ExpectAccurate(result, problem);
  EXPECT_FALSE(result.gravity_fallback);
  EXPECT_GE(result.stats.iterations, 300u);  // P3P: 337 for 30% inliers
}

TEST(GravityPrior, UncalibratedDropsHypothesesThatDisagree) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  test::SyntheticPoseOptions synth;
  synth.outlier_ratio = 0.6;
  synth.noise_px = 0.5;
  for (int trial = 0; trial < 3; ++trial) {
    const auto problem = test::MakeSyntheticProblem(synth, rng);
    AbsolutePoseOptions options;
    PoseContext context;
    context.gravity = PriorFor(problem, 1.0, 1.0, rng);
    AbsolutePoseResult result =
        EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
    ExpectAccurate(result, problem);
    EXPECT_NEAR(result.focal_length_px, problem.focal_px, 0.01 * problem.focal_px);
    result = EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D,
                                            0.95 * problem.focal_px, options, context);
    ExpectAccurate(result, problem);
    // A prior 30 degrees off, far beyond 4.29 sigma + 3 degrees: every hypothesis near the
    // true pose is dropped.
    context.gravity = PriorFor(problem, 30.0, 1.0, rng);
    result = EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
    EXPECT_FALSE(result.success);
    if (result.num_inliers > 0) {
      EXPECT_LE(result.gravity_angle_deg, 30.0);
    }
  }
}

TEST(GravityPrior, RejectionAngleFollowsSigmaAndConfidence) {
  // sqrt(-2 ln(1e-4)) = 4.292 sigma, plus the 3 degree allowance.
  EXPECT_NEAR(GravityRejectionAngle(1.0 * kDegree, 0.9999) / kDegree, 4.292 + 3.0, 1e-3);
  EXPECT_NEAR(GravityErrorBound(2.0 * kDegree, 0.99) / kDegree, 2.0 * 3.035, 1e-3);
  EXPECT_NEAR(CauchyScaleNoise(2.0), 0.8386, 1e-4);
  EXPECT_EQ(CauchyScaleNoise(0.0), 1.0);
}

TEST(GravityPrior, ReportsAnInvalidPrior) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  const auto problem = test::MakeSyntheticProblem(test::SyntheticPoseOptions{}, rng);
  AbsolutePoseOptions options;
  PoseContext context;
  GravityPrior prior = PriorFor(problem, 0.0, 1.0, rng);
  prior.in_camera.setZero();
  context.gravity = prior;
  AbsolutePoseResult result = EstimateAbsolutePose(problem.normalized, problem.points3D,
                                                   problem.focal_px, options, context);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason, "invalid gravity prior: in_camera is zero");
  prior = PriorFor(problem, 0.0, 1.0, rng);
  prior.in_world.x() = std::numeric_limits<double>::quiet_NaN();
  context.gravity = prior;
  result = EstimateAbsolutePoseUnknownFocal(problem.pixels, problem.points3D, options, context);
  EXPECT_EQ(result.failure_reason, "invalid gravity prior: in_world is not finite");
  prior = PriorFor(problem, 0.0, 0.0, rng);
  context.gravity = prior;
  result = EstimateAbsolutePoseFocalPrior(problem.pixels, problem.points3D, problem.focal_px,
                                          options, context);
  EXPECT_EQ(result.failure_reason, "invalid gravity prior: sigma_deg 0 is not positive and finite");
  // Directions need not be unit vectors.
  prior = PriorFor(problem, 0.0, 1.0, rng);
  prior.in_camera *= 9.81;
  prior.in_world *= 0.5;
  context.gravity = prior;
  result = EstimateAbsolutePose(problem.normalized, problem.points3D, problem.focal_px, options,
                                context);
  ExpectAccurate(result, problem);
  EXPECT_LT(result.gravity_angle_deg, 0.1);
}

}  // namespace
}  // namespace cwloc
