#include "localizer/pose/refine_pose.h"

#include <gtest/gtest.h>

#include <numbers>
#include <numeric>

#include "localizer/pose/local_optimization.h"
#include "tests/localizer/pose/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

std::vector<uint32_t> AllIndices(size_t n) {
  std::vector<uint32_t> indices(n);
  std::iota(indices.begin(), indices.end(), 0u);
  return indices;
}

CameraPose Perturb(const CameraPose& pose, double angle_rad, double shift, std::mt19937_64& rng) {
  const Eigen::Vector3d axis = Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                                               test::Uniform(rng, -1, 1))
                                   .normalized();
  const Eigen::Vector3d dir = Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                                              test::Uniform(rng, -1, 1))
                                  .normalized();
  return CameraPose(Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis)) * pose.rotation,
                    pose.translation + shift * dir);
}

test::SyntheticPoseOptions Clean() {
  test::SyntheticPoseOptions options;
  options.num_points = 100;
  options.outlier_ratio = 0.0;
  options.noise_px = 0.0;
  return options;
}

TEST(RefinePose, ConvergesFromAPerturbedPose) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 10; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.02, 0.3, rng);
    double f = problem.focal_px;
    PoseRefinementSummary summary;
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()), {},
                           &pose, &f, &summary));
    EXPECT_TRUE(summary.usable);
    EXPECT_LT(summary.final_cost, summary.initial_cost);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
    EXPECT_LT((pose.Center() - problem.pose.Center()).norm(), 1e-6);
    EXPECT_EQ(f, problem.focal_px);  // held constant
  }
}

TEST(RefinePose, RefinesFocalLength) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem(Clean(), rng);
  CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
  double f = 1.05 * problem.focal_px;
  PoseRefinementOptions options;
  options.refine_focal_length = true;
  ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                         options, &pose, &f));
  EXPECT_NEAR(f, problem.focal_px, 1e-6 * problem.focal_px);
  EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
}

TEST(RefinePoseAndCamera, RecoversFocalAndRadialDistortion) {
  auto& rng = test::Rng();
  for (const double k : {-0.15, 0.0, 0.1}) {
    test::SyntheticPoseOptions synth = Clean();
    synth.radial_k = k;
    const auto problem = test::MakeSyntheticProblem(synth, rng);
    CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
    RadialCamera camera{0.95 * problem.focal_px, 0.0};
    PoseRefinementOptions options;
    options.refine_focal_length = true;
    options.refine_radial_distortion = true;
    ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                    AllIndices(problem.pixels.size()), options, &pose, &camera));
    EXPECT_NEAR(camera.focal_length_px, problem.focal_px, 1e-6 * problem.focal_px) << k;
    EXPECT_NEAR(camera.k, k, 1e-8);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
    // The residual it minimised is RadialCamera::Project's.
    for (size_t i = 0; i < problem.pixels.size(); ++i) {
      EXPECT_LT((camera.Project(pose.Apply(problem.points3D[i])) - problem.pixels[i]).norm(), 1e-6);
    }
  }
}

TEST(RefinePoseAndCamera, HoldsWhatItIsNotAskedToRefine) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions synth = Clean();
  synth.radial_k = -0.1;
  const auto problem = test::MakeSyntheticProblem(synth, rng);
  CameraPose pose = problem.pose;
  RadialCamera camera{problem.focal_px, 0.0};
  PoseRefinementOptions options;
  options.refine_focal_length = true;  // k stays 0: the focal length absorbs what it can
  ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                  AllIndices(problem.pixels.size()), options, &pose, &camera));
  EXPECT_EQ(camera.k, 0.0);
  EXPECT_NE(camera.focal_length_px, problem.focal_px);
  options.refine_focal_length = false;
  options.refine_radial_distortion = true;
  camera = {1.02 * problem.focal_px, 0.0};
  ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                  AllIndices(problem.pixels.size()), options, &pose, &camera));
  EXPECT_EQ(camera.focal_length_px, 1.02 * problem.focal_px);
  EXPECT_NE(camera.k, 0.0);
  // Too few correspondences for pose, focal length and k: nothing changes.
  options.refine_focal_length = true;
  const std::vector<uint32_t> five = {0, 1, 2, 3, 4};
  const RadialCamera before = camera;
  EXPECT_FALSE(
      RefinePoseAndCamera(problem.pixels, problem.points3D, five, options, &pose, &camera));
  EXPECT_EQ(camera.focal_length_px, before.focal_length_px);
  EXPECT_EQ(camera.k, before.k);
}

TEST(RefinePose, QuaternionOrderRoundTrips) {
  // A rotation whose w, x, y, z are all different: a w/x swap would be caught.
  auto& rng = test::Rng();
  auto problem = test::MakeSyntheticProblem(Clean(), rng);
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.9, 0.3, -0.2, 0.1).normalized();
  for (size_t i = 0; i < problem.points3D.size(); ++i) {
    const Eigen::Vector3d cam = problem.pose.Apply(problem.points3D[i]);
    problem.points3D[i] = q.conjugate() * (cam - problem.pose.translation);
  }
  CameraPose pose(q, problem.pose.translation);
  double f = problem.focal_px;
  ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()), {},
                         &pose, &f));
  EXPECT_LT(pose.rotation.angularDistance(q), 1e-9);
}

TEST(RefinePose, CauchyLossResistsOutliersAmongIndices) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options = Clean();
  options.noise_px = 0.5;
  PoseRefinementOptions cauchy;
  cauchy.loss_scale_px = 1.0;
  PoseRefinementOptions squared;
  squared.loss_scale_px = 0.0;
  // Summed over problems: one problem's noise can favour either.
  double robust_error = 0.0, plain_error = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    auto problem = test::MakeSyntheticProblem(options, rng);
    // 15% gross errors of 5.5 px (under a 6 px threshold, so they survive as inliers).
    for (int i = 0; i < 15; ++i) {
      const double angle = test::Uniform(rng, 0.0, 2.0 * std::numbers::pi);
      problem.pixels[i] += 5.5 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    const auto error = [&](const CameraPose& pose) {
      return test::RotationErrorDeg(pose, problem.pose) / 0.01 +
             (pose.Center() - problem.pose.Center()).norm() / 0.01;
    };
    CameraPose robust = problem.pose, plain = problem.pose;
    double f1 = problem.focal_px, f2 = problem.focal_px;
    const auto all = AllIndices(problem.pixels.size());
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, cauchy, &robust, &f1));
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, squared, &plain, &f2));
    robust_error += error(robust);
    plain_error += error(plain);
  }
  EXPECT_LT(robust_error, 0.75 * plain_error);
}

TEST(RefinePose, TooFewPoints) {
  CameraPose pose;
  double f = 1000.0;
  const std::vector<Eigen::Vector2d> pixels(3, Eigen::Vector2d::Zero());
  const std::vector<Eigen::Vector3d> points(3, Eigen::Vector3d(0, 0, 5));
  EXPECT_FALSE(RefinePose(pixels, points, AllIndices(3), {}, &pose, &f));
}

TEST(LocalOptimization, PoseConvergesWithFewIterations) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 20; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.02, 0.3, rng);
    LocalOptimizationOptions options;
    options.max_iterations = 20;
    OptimizePose(problem.normalized, problem.points3D, AllIndices(problem.pixels.size()), options,
                 &pose);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-7);
    EXPECT_LT((pose.Center() - problem.pose.Center()).norm(), 1e-7);
  }
}

TEST(LocalOptimization, PoseAndFocalConverge) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 20; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
    double f = problem.focal_px * test::Uniform(rng, 0.9, 1.1);
    LocalOptimizationOptions options;
    options.max_iterations = 30;
    options.loss_scale = 2.0;
    OptimizePoseAndFocal(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                         options, &pose, &f);
    EXPECT_NEAR(f, problem.focal_px, 1e-6 * problem.focal_px);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
  }
}

}  // namespace
}  // namespace cwloc
