#include "solvers/gravity_p2p.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>

#include "base/angles.h"
#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using Eigen::Vector3d;

// A unit vector at exactly `angle` from the unit vector v, in a random direction.
Vector3d Tilt(const Vector3d& v, double angle, SplitMix64& rng) {
  const Vector3d axis = v.cross(test::RandomUnitVector(rng)).normalized();
  return Eigen::AngleAxisd(angle, axis) * v;
}

struct P2PProblem {
  CameraPose pose;
  std::array<Vector3d, 2> bearings;
  std::array<Vector3d, 2> points;
  Vector3d gravity_in_camera;
  Vector3d gravity_in_world;
};

// The camera point at image position xy (x/z, y/z) and depth z.
void SetPoint(P2PProblem* p, int i, const Eigen::Vector2d& xy, double depth) {
  const Vector3d point_cam = depth * xy.homogeneous();
  p->bearings[i] = point_cam.normalized();
  p->points[i] = p->pose.rotation.conjugate() * (point_cam - p->pose.translation);
}

// A random camera, a random world gravity and two points within a 120 degree field of view.
P2PProblem RandomProblem(SplitMix64& rng, double min_depth = 1.0, double max_depth = 10.0) {
  P2PProblem p;
  p.pose = test::RandomPose(rng);
  p.gravity_in_world = test::RandomUnitVector(rng);
  p.gravity_in_camera = p.pose.rotation * p.gravity_in_world;
  for (int i = 0; i < 2; ++i) {
    const double x = test::Uniform(rng, -1.7, 1.7);
    const double y = test::Uniform(rng, -1.7, 1.7);
    SetPoint(&p, i, Eigen::Vector2d(x, y), test::Uniform(rng, min_depth, max_depth));
  }
  return p;
}

// The rotation taking unit vector a to unit vector b: about a x b, or by pi about a vector
// orthogonal to a when they are opposite. (Eigen's FromTwoVectors compiles an SVD for that
// case: 4 of this file's 16 compile seconds.)
Eigen::Quaterniond RotationTaking(const Vector3d& a, const Vector3d& b) {
  const Vector3d axis = a.cross(b);
  if (axis.norm() < 1e-12) {
    if (a.dot(b) > 0.0) return Eigen::Quaterniond::Identity();
    return Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, a.unitOrthogonal()));
  }
  return Eigen::Quaterniond(
      Eigen::AngleAxisd(std::atan2(axis.norm(), a.dot(b)), axis.normalized()));
}

// A camera whose gravity is the given camera direction (e.g. +y: upright; +z: looking straight
// down), at a random heading about the world's gravity (0, 0, -1).
P2PProblem AlignedProblem(SplitMix64& rng, const Vector3d& gravity_in_camera) {
  P2PProblem p;
  p.gravity_in_world = Vector3d(0.0, 0.0, -1.0);
  p.gravity_in_camera = gravity_in_camera;
  const Eigen::Quaterniond heading(Eigen::AngleAxisd(
      test::Uniform(rng, -std::numbers::pi, std::numbers::pi), Vector3d::UnitZ()));
  const Eigen::Quaterniond rotation =
      RotationTaking(p.gravity_in_world, gravity_in_camera) * heading;
  const Vector3d center(test::Uniform(rng, -10, 10), test::Uniform(rng, -10, 10),
                        test::Uniform(rng, -10, 10));
  p.pose = CameraPose(rotation, -(rotation * center));
  for (int i = 0; i < 2; ++i) {
    const double x = test::Uniform(rng, -1.0, 1.0);
    const double y = test::Uniform(rng, -1.0, 1.0);
    SetPoint(&p, i, Eigen::Vector2d(x, y), test::Uniform(rng, 1.0, 10.0));
  }
  return p;
}

int Solve(const P2PProblem& p, std::vector<CameraPose>* poses) {
  return GravityP2P(p.bearings, p.points, p.gravity_in_camera, p.gravity_in_world, poses);
}

// Rotation error (rad) plus centre error relative to the distance from the origin, in a scene
// whose lengths are `scale` times those of RandomProblem's.
double BestError(const std::vector<CameraPose>& poses, const CameraPose& truth,
                 double scale = 1.0) {
  double best = std::numeric_limits<double>::infinity();
  for (const CameraPose& pose : poses) best = std::min(best, test::PoseError(pose, truth, scale));
  return best;
}

// At most two finite unit-quaternion poses, each point on the forward half of its ray.
void ExpectValidSolutions(const std::vector<CameraPose>& poses, const P2PProblem& problem) {
  EXPECT_LE(poses.size(), 2u);
  for (const CameraPose& pose : poses) {
    ASSERT_TRUE(pose.rotation.coeffs().allFinite());
    ASSERT_TRUE(pose.translation.allFinite());
    EXPECT_NEAR(pose.rotation.norm(), 1.0, 1e-12);
    for (int i = 0; i < 2; ++i) {
      EXPECT_GT(pose.Apply(problem.points[i]).dot(problem.bearings[i]), 0.0);
    }
  }
}

// Every solution satisfies the gravity and both rays, and the true pose is one of them.
void ExpectExactSolutions(const std::vector<CameraPose>& poses, const P2PProblem& problem,
                          double tolerance) {
  ExpectValidSolutions(poses, problem);
  for (const CameraPose& pose : poses) {
    EXPECT_LT((pose.rotation * problem.gravity_in_world - problem.gravity_in_camera).norm(), 1e-12);
    for (int i = 0; i < 2; ++i) {
      EXPECT_LT((pose.Apply(problem.points[i]).normalized() - problem.bearings[i]).norm(),
                tolerance);
    }
  }
  EXPECT_LT(BestError(poses, problem.pose), tolerance);
}

TEST(GravityP2P, RecoversRandomPosesToMachinePrecision) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  double worst = 0.0;
  int accurate = 0, two = 0;
  constexpr int kTrials = 5000;
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE(trial);
    const P2PProblem problem = RandomProblem(rng);
    const int n = Solve(problem, &poses);
    ASSERT_EQ(n, static_cast<int>(poses.size()));
    ASSERT_GE(n, 1);
    ExpectValidSolutions(poses, problem);
    for (const CameraPose& pose : poses) {
      EXPECT_LT((pose.rotation * problem.gravity_in_world - problem.gravity_in_camera).norm(),
                1e-12);
    }
    const double error = BestError(poses, problem.pose);
    worst = std::max(worst, error);
    accurate += error < 1e-8;
    two += n == 2;
  }
  std::cout << accurate << "/" << kTrials << " within 1e-8, worst " << worst << "; " << two
            << " with two solutions in front\n";
  EXPECT_GE(accurate, kTrials - 5);
  EXPECT_LT(worst, 1e-6);
}

TEST(GravityP2P, GravityAlongACameraAxis) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  // Upright (portrait and landscape, either way up), looking straight down and straight up.
  for (const Vector3d& axis : {Vector3d(0, 1, 0), Vector3d(0, -1, 0), Vector3d(1, 0, 0),
                               Vector3d(-1, 0, 0), Vector3d(0, 0, 1), Vector3d(0, 0, -1)}) {
    SCOPED_TRACE(axis.transpose());
    for (int trial = 0; trial < 500; ++trial) {
      const P2PProblem problem = AlignedProblem(rng, axis);
      ASSERT_GE(Solve(problem, &poses), 1);
      ExpectExactSolutions(poses, problem, 1e-8);
    }
  }
  // World gravity along each world axis, too.
  for (const Vector3d& world : {Vector3d(1, 0, 0), Vector3d(0, -1, 0), Vector3d(0, 0, 1)}) {
    for (int trial = 0; trial < 200; ++trial) {
      P2PProblem problem = RandomProblem(rng);
      problem.gravity_in_world = world;
      problem.gravity_in_camera = problem.pose.rotation * world;
      ASSERT_GE(Solve(problem, &poses), 1);
      ExpectExactSolutions(poses, problem, 1e-8);
    }
  }
}

// The problem with every length (camera centre, depths) multiplied by `scale`.
P2PProblem Scaled(P2PProblem problem, double scale) {
  problem.pose.translation *= scale;
  for (Vector3d& point : problem.points) point *= scale;
  return problem;
}

TEST(GravityP2P, PointsNearAndFar) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  double worst[2] = {}, worst_offset = 0.0, worst_small = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    // Points millimetres or 1e5 to 1e6 from the camera (the whole scene scaled): as accurate
    // as at depths 1 to 10.
    for (int k = 0; k < 2; ++k) {
      const double scale = k == 0 ? 1e-3 : 1e5;
      const P2PProblem problem = Scaled(RandomProblem(rng), scale);
      ASSERT_GE(Solve(problem, &poses), 1);
      ExpectValidSolutions(poses, problem);
      worst[k] = std::max(worst[k], BestError(poses, problem.pose, scale));
    }
    // Points millimetres from a camera 1e4 from the world origin: their coordinates carry only
    // ~1e-16 * 1e4 / 1e-3 = 1e-9 of their spread, which bounds any solver.
    P2PProblem offset = Scaled(RandomProblem(rng), 1e-3);
    const Vector3d shift = 1e4 * test::RandomUnitVector(rng);
    for (Vector3d& point : offset.points) point += shift;
    offset.pose.translation -= offset.pose.rotation * shift;
    Solve(offset, &poses);
    ExpectValidSolutions(poses, offset);
    double best = std::numeric_limits<double>::infinity();
    for (const CameraPose& pose : poses) {
      best = std::min(best, pose.rotation.angularDistance(offset.pose.rotation) +
                                (pose.Center() - offset.pose.Center()).norm() / 1e-3);
    }
    if (!poses.empty()) worst_offset = std::max(worst_offset, best);
    // A pair 10 apart seen from 1e6: rays 1e-5 apart.
    P2PProblem small = RandomProblem(rng);
    const Vector3d ray = test::Uniform(rng, -0.5, 0.5) * Vector3d::UnitX() +
                         test::Uniform(rng, -0.5, 0.5) * Vector3d::UnitY() + Vector3d::UnitZ();
    const Vector3d cam0 = 1e6 * ray, cam1 = cam0 + 10.0 * test::RandomUnitVector(rng);
    small.bearings = {cam0.normalized(), cam1.normalized()};
    small.points = {small.pose.rotation.conjugate() * (cam0 - small.pose.translation),
                    small.pose.rotation.conjugate() * (cam1 - small.pose.translation)};
    Solve(small, &poses);
    ExpectValidSolutions(poses, small);
    if (!poses.empty()) worst_small = std::max(worst_small, BestError(poses, small.pose));
  }
  std::cout << "worst error: depths 1e-3 to 1e-2 " << worst[0] << ", 1e5 to 1e6 " << worst[1]
            << "; millimetres away 1e4 from the origin " << worst_offset
            << " (rad + depths); a pair 10 apart at 1e6 " << worst_small << "\n";
  EXPECT_LT(worst[0], 1e-8);
  EXPECT_LT(worst[1], 1e-8);
  EXPECT_LT(worst_offset, 1e-3);
}

TEST(GravityP2P, TwoPointsNearlyOnOneRay) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  const double separations[] = {1e-2, 1e-3, 1e-6, 1e-9, 0.0};
  double worst[5] = {};
  for (int trial = 0; trial < 300; ++trial) {
    P2PProblem problem = RandomProblem(rng);
    // The second point behind the first on its ray, moved sideways by an angle of
    // `separation` as seen from the camera.
    const Vector3d cam0 = problem.pose.Apply(problem.points[0]);
    for (int k = 0; k < 5; ++k) {
      const double separation = separations[k];
      SCOPED_TRACE(separation);
      const Vector3d side = cam0.cross(test::RandomUnitVector(rng)).normalized();
      const Vector3d cam1 = 2.0 * cam0 + separation * 2.0 * cam0.norm() * side;
      problem.bearings[1] = cam1.normalized();
      problem.points[1] = problem.pose.rotation.conjugate() * (cam1 - problem.pose.translation);
      const int n = Solve(problem, &poses);
      ExpectValidSolutions(poses, problem);
      if (separation == 0.0) {
        EXPECT_EQ(n, 0);  // one ray: the rotation about gravity is free
      } else if (separation >= 1e-3) {
        ASSERT_GE(n, 1);
      }
      if (n > 0) worst[k] = std::max(worst[k], BestError(poses, problem.pose));
    }
  }
  std::cout << "worst error for rays 1e-2, 1e-3, 1e-6, 1e-9 apart: " << worst[0] << ", " << worst[1]
            << ", " << worst[2] << ", " << worst[3] << "\n";
  // The problem itself loses accuracy as the rays merge (depth along the ray is unobservable).
  EXPECT_LT(worst[0], 1e-8);
  EXPECT_LT(worst[1], 1e-6);
}

TEST(GravityP2P, TwoPointsOnOneVerticalLine) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  for (int trial = 0; trial < 300; ++trial) {
    P2PProblem problem = RandomProblem(rng);
    // The second point straight above or below the first: any heading about the vertical line
    // explains the rays, so there is no isolated solution.
    const double height = test::Uniform(rng, 0.5, 5.0) * (trial % 2 == 0 ? 1.0 : -1.0);
    problem.points[1] = problem.points[0] + height * problem.gravity_in_world;
    problem.bearings[1] = problem.pose.Apply(problem.points[1]).normalized();
    EXPECT_EQ(Solve(problem, &poses), 0);
    // Nearly vertical (1e-3 rad): finite, and still solved.
    const Vector3d leaning = Tilt(problem.gravity_in_world, 1e-3, rng);
    problem.points[1] = problem.points[0] + height * leaning;
    const Vector3d cam1 = problem.pose.Apply(problem.points[1]);
    problem.bearings[1] = cam1.normalized();
    const int n = Solve(problem, &poses);
    ExpectValidSolutions(poses, problem);
    if (cam1.z() > 0.0 && problem.pose.Apply(problem.points[0]).z() > 0.0) {
      ASSERT_GE(n, 1);
      EXPECT_LT(BestError(poses, problem.pose), 1e-6);
    }
  }
}

TEST(GravityP2P, HorizontalRaysAtCameraHeight) {
  // Both rays horizontal and both points at the camera's height: a circle of cameras sees them
  // the same (the inscribed angle), so there is no isolated solution.
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  for (int trial = 0; trial < 100; ++trial) {
    P2PProblem problem = AlignedProblem(rng, Vector3d(0, 1, 0));
    for (int i = 0; i < 2; ++i) {
      SetPoint(&problem, i, Eigen::Vector2d(test::Uniform(rng, -1, 1), 0.0),
               test::Uniform(rng, 1, 10));
    }
    EXPECT_EQ(Solve(problem, &poses), 0);
  }
}

TEST(GravityP2P, NoisyGravity) {
  // The camera's gravity 1 degree off in a random direction: the nearest solution is off by
  // about as much in rotation.
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  std::vector<double> rotation_errors, center_errors;
  int none = 0;
  constexpr int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    P2PProblem problem = RandomProblem(rng);
    problem.gravity_in_camera = Tilt(problem.gravity_in_camera, 1.0 * kDegree, rng);
    Solve(problem, &poses);
    ExpectValidSolutions(poses, problem);
    if (poses.empty()) {
      ++none;
      continue;
    }
    // The solutions honour the noisy gravity and both rays exactly.
    for (const CameraPose& pose : poses) {
      EXPECT_LT((pose.rotation * problem.gravity_in_world - problem.gravity_in_camera).norm(),
                1e-12);
      for (int i = 0; i < 2; ++i) {
        EXPECT_LT((pose.Apply(problem.points[i]).normalized() - problem.bearings[i]).norm(), 1e-8);
      }
    }
    double best_rotation = std::numeric_limits<double>::infinity(), best_center = 0.0;
    for (const CameraPose& pose : poses) {
      const double rotation = pose.rotation.angularDistance(problem.pose.rotation) / kDegree;
      if (rotation < best_rotation) {
        best_rotation = rotation;
        best_center = (pose.Center() - problem.pose.Center()).norm();
      }
    }
    rotation_errors.push_back(best_rotation);
    center_errors.push_back(best_center);
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::cout << none << "/" << kTrials << " without a solution; median rotation error "
            << median(rotation_errors) << " deg, median centre error " << median(center_errors)
            << " (points at depths 1 to 10)\n";
  EXPECT_LT(none, kTrials / 10);  // 3.5 to 4.6% over seeds 1 to 5
  EXPECT_LT(median(rotation_errors), 2.0);
}

TEST(GravityP2P, NeverReturnsNonFinitePoses) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  const double scales[] = {1e-12, 1e-6, 1.0, 1e6, 1e12};
  for (int trial = 0; trial < 5000; ++trial) {
    // Unrelated rays, points, gravities and scales.
    P2PProblem problem;
    for (int i = 0; i < 2; ++i) {
      problem.bearings[i] = test::RandomUnitVector(rng);
      problem.points[i] = scales[rng.Uniform(5)] * test::RandomUnitVector(rng);
    }
    if (trial % 7 == 0) problem.points[1] = problem.points[0];
    if (trial % 11 == 0) problem.bearings[1] = problem.bearings[0];
    if (trial % 13 == 0) problem.bearings[1] = -problem.bearings[0];
    problem.gravity_in_camera = test::RandomUnitVector(rng);
    problem.gravity_in_world = test::RandomUnitVector(rng);
    if (trial % 5 == 0) problem.gravity_in_world = Vector3d::Unit(rng.Uniform(3));
    Solve(problem, &poses);
    EXPECT_LE(poses.size(), 2u);
    for (const CameraPose& pose : poses) {
      ASSERT_TRUE(pose.rotation.coeffs().allFinite() && pose.translation.allFinite());
      EXPECT_NEAR(pose.rotation.norm(), 1.0, 1e-12);
    }
  }
  // Non-finite input.
  P2PProblem problem = RandomProblem(rng);
  problem.points[1].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(Solve(problem, &poses), 0);
  problem = RandomProblem(rng);
  problem.gravity_in_camera.y() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Solve(problem, &poses), 0);
  EXPECT_TRUE(poses.empty());
}

}  // namespace
}  // namespace cwloc
