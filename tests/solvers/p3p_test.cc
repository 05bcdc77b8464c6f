#include "solvers/p3p.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

struct P3PProblem {
  CameraPose pose;
  std::array<Eigen::Vector3d, 3> bearings;
  std::array<Eigen::Vector3d, 3> points;
};

// Three points in front of a random camera, within a 120 degree field of view.
P3PProblem RandomP3PProblem(std::mt19937_64& rng, double min_depth = 1.0, double max_depth = 10.0) {
  P3PProblem p;
  p.pose = test::RandomPose(rng);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector2d xy(test::Uniform(rng, -1.7, 1.7), test::Uniform(rng, -1.7, 1.7));
    const Eigen::Vector3d point_cam = test::Uniform(rng, min_depth, max_depth) * xy.homogeneous();
    p.bearings[i] = point_cam.normalized();
    p.points[i] = p.pose.rotation.conjugate() * (point_cam - p.pose.translation);
  }
  return p;
}

void ExpectValidSolutions(const std::vector<CameraPose>& poses, const P3PProblem& problem) {
  EXPECT_LE(poses.size(), 4u);
  for (const CameraPose& pose : poses) {
    ASSERT_TRUE(pose.rotation.coeffs().allFinite());
    ASSERT_TRUE(pose.translation.allFinite());
    EXPECT_NEAR(pose.rotation.norm(), 1.0, 1e-12);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d x = pose.Apply(problem.points[i]);
      EXPECT_GT(x.z(), 0.0);
    }
  }
}

TEST(P3P, RecoversRandomPosesToMachinePrecision) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  double worst = 0.0;
  int accurate = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const P3PProblem problem = RandomP3PProblem(rng);
    const int n = P3P(problem.bearings, problem.points, &poses);
    ASSERT_EQ(n, static_cast<int>(poses.size()));
    ASSERT_GE(n, 1) << "trial " << trial;
    ExpectValidSolutions(poses, problem);
    double best = std::numeric_limits<double>::infinity();
    for (const CameraPose& pose : poses) best = std::min(best, test::PoseError(pose, problem.pose));
    worst = std::max(worst, best);
    accurate += best < 1e-8;
    // Every solution explains the three rays.
    for (const CameraPose& pose : poses) {
      for (int i = 0; i < 3; ++i) {
        EXPECT_LT((pose.Apply(problem.points[i]).normalized() - problem.bearings[i]).norm(), 1e-8);
      }
    }
  }
  // About one random problem in a million lies so close to the danger cylinder (the depth
  // Jacobian's condition ~1e7) that no solver gets 1e-8.
  EXPECT_GE(accurate, 1998);
  EXPECT_LT(worst, 1e-6);
}

TEST(P3P, NearDegenerateConfigurationsGiveNoNaN) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  for (int trial = 0; trial < 200; ++trial) {
    P3PProblem problem = RandomP3PProblem(rng);
    // Almost collinear world points (and the rays accordingly).
    P3PProblem collinear = problem;
    collinear.points[2] =
        0.5 * (collinear.points[0] + collinear.points[1]) + 1e-9 * Eigen::Vector3d::UnitX();
    collinear.bearings[2] = collinear.pose.Apply(collinear.points[2]).normalized();
    P3P(collinear.bearings, collinear.points, &poses);
    ExpectValidSolutions(poses, collinear);

    // Camera very far away: depth 1e6 for a triangle of size ~10.
    const P3PProblem far = RandomP3PProblem(rng, 1e6, 1e6 + 10.0);
    P3P(far.bearings, far.points, &poses);
    ExpectValidSolutions(poses, far);

    // A tiny triangle.
    P3PProblem tiny = problem;
    for (int i = 1; i < 3; ++i) {
      tiny.points[i] = tiny.points[0] + 1e-7 * (problem.points[i] - problem.points[0]);
      tiny.bearings[i] = tiny.pose.Apply(tiny.points[i]).normalized();
    }
    P3P(tiny.bearings, tiny.points, &poses);
    ExpectValidSolutions(poses, tiny);

    // Coincident points and identical rays: nothing to solve.
    P3PProblem coincident = problem;
    coincident.points[1] = coincident.points[0];
    coincident.bearings[1] = coincident.bearings[0];
    EXPECT_EQ(P3P(coincident.bearings, coincident.points, &poses), 0);

    // Identical rays for distinct points: no valid camera.
    P3PProblem same_rays = problem;
    same_rays.bearings[2] = same_rays.bearings[1];
    P3P(same_rays.bearings, same_rays.points, &poses);
    for (const CameraPose& pose : poses) {
      EXPECT_TRUE(pose.rotation.coeffs().allFinite() && pose.translation.allFinite());
    }
  }
  // Non-finite input.
  P3PProblem problem = RandomP3PProblem(rng);
  problem.points[1].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(P3P(problem.bearings, problem.points, &poses), 0);
  EXPECT_TRUE(poses.empty());
}

TEST(CameraPose, CenterAndApplyFollowColmap) {
  // A 90 degree rotation about z: x_cam = R x_world + t, C = -R^T t.
  const CameraPose pose(
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())),
      Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(pose.Apply(Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 3, 3)));
  EXPECT_TRUE(pose.Apply(pose.Center()).isZero(1e-12));
  EXPECT_TRUE(pose.Center().isApprox(Eigen::Vector3d(-2, 1, -3)));
}

}  // namespace
}  // namespace cwloc
