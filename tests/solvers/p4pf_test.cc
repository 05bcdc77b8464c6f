#include "solvers/p4pf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

struct P4PfProblem {
  CameraPose pose;
  double focal = 0.0;
  std::array<Eigen::Vector2d, 4> pixels;
  std::array<Eigen::Vector3d, 4> points;
};

// Four points in front of a random camera with a random focal length; `flatness` scales the
// points' spread along the viewing direction relative to a tilted plane (0: coplanar).
P4PfProblem RandomP4PfProblem(std::mt19937_64& rng, double flatness = 1.0) {
  P4PfProblem p;
  p.pose = test::RandomPose(rng);
  p.focal = test::Uniform(rng, 300.0, 3000.0);
  const double tilt_x = test::Uniform(rng, -0.5, 0.5), tilt_y = test::Uniform(rng, -0.5, 0.5);
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d pixel(test::Uniform(rng, -800, 800), test::Uniform(rng, -600, 600));
    const Eigen::Vector2d xy = pixel / p.focal;
    // Depth on a tilted plane, plus an off-plane part.
    const double plane_depth = 10.0 / (1.0 - tilt_x * xy.x() - tilt_y * xy.y());
    const double depth = plane_depth * (1.0 + flatness * test::Uniform(rng, -0.5, 0.5));
    const Eigen::Vector3d point_cam = depth * xy.homogeneous();
    p.pixels[i] = pixel;
    p.points[i] = p.pose.rotation.conjugate() * (point_cam - p.pose.translation);
  }
  return p;
}

// Relative focal error of the best matching solution (infinity if none matches the pose).
double BestFocalError(const P4PfProblem& problem, const std::vector<CameraPose>& poses,
                      const std::vector<double>& focals, double pose_tolerance) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < poses.size(); ++k) {
    const double rot = poses[k].rotation.angularDistance(problem.pose.rotation);
    const double center =
        (poses[k].Center() - problem.pose.Center()).norm() / (1.0 + problem.pose.Center().norm());
    if (rot < pose_tolerance && center < pose_tolerance) {
      best = std::min(best, std::abs(focals[k] - problem.focal) / problem.focal);
    }
  }
  return best;
}

TEST(P4Pf, RecoversPoseAndFocalOnRandomProblems) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  std::vector<double> focals;
  const int kTrials = 2000;
  int ok = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const P4PfProblem problem = RandomP4PfProblem(rng);
    const int n = P4Pf(problem.pixels, problem.points, &poses, &focals);
    ASSERT_EQ(n, static_cast<int>(poses.size()));
    ASSERT_EQ(poses.size(), focals.size());
    for (size_t k = 0; k < poses.size(); ++k) {
      ASSERT_TRUE(poses[k].rotation.coeffs().allFinite() && poses[k].translation.allFinite());
      ASSERT_GT(focals[k], 0.0);
      for (int i = 0; i < 4; ++i) EXPECT_GT(poses[k].Apply(problem.points[i]).z(), 0.0);
    }
    ok += BestFocalError(problem, poses, focals, 1e-6) < 1e-6;
  }
  EXPECT_GE(ok, kTrials * 99 / 100) << ok << " of " << kTrials;
}

TEST(P4Pf, PlanarAndNearlyPlanarScenes) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  std::vector<double> focals;
  // Exactly coplanar (homography branch), nearly coplanar (both branches) and flat but
  // clearly 3D. A few random planes are nearly fronto-parallel, where f is ill-conditioned.
  for (const double flatness : {0.0, 1e-6, 1e-4, 1e-2}) {
    int ok = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const P4PfProblem problem = RandomP4PfProblem(rng, flatness);
      P4Pf(problem.pixels, problem.points, &poses, &focals);
      ok += BestFocalError(problem, poses, focals, 1e-6) < 1e-6;
    }
    EXPECT_GE(ok, 291) << "flatness " << flatness;
  }
}

TEST(P4Pf, SolutionsAreSortedByReprojectionError) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  std::vector<double> focals;
  for (int trial = 0; trial < 100; ++trial) {
    const P4PfProblem problem = RandomP4PfProblem(rng);
    P4Pf(problem.pixels, problem.points, &poses, &focals);
    if (!(BestFocalError(problem, poses, focals, 1e-6) < 1e-6)) continue;  // the rare miss
    // With exact data the first solution reprojects exactly: it is the true one.
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d x = poses[0].Apply(problem.points[i]);
      EXPECT_LT((focals[0] * x.hnormalized() - problem.pixels[i]).norm(), 1e-6);
    }
  }
}

TEST(P4Pf, DegenerateInputGivesNoNaN) {
  auto& rng = test::Rng();
  std::vector<CameraPose> poses;
  std::vector<double> focals;
  P4PfProblem problem = RandomP4PfProblem(rng);

  P4PfProblem collinear = problem;  // all four world points on a line
  for (int i = 2; i < 4; ++i) {
    collinear.points[i] =
        collinear.points[0] + (i - 1.0) * (collinear.points[1] - collinear.points[0]);
  }
  EXPECT_EQ(P4Pf(collinear.pixels, collinear.points, &poses, &focals), 0);

  P4PfProblem centered = problem;  // every image point at the principal point
  for (auto& p : centered.pixels) p.setZero();
  EXPECT_EQ(P4Pf(centered.pixels, centered.points, &poses, &focals), 0);

  P4PfProblem nan = problem;
  nan.points[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(P4Pf(nan.pixels, nan.points, &poses, &focals), 0);

  // Fronto-parallel plane: f is unobservable; whatever comes back must be finite.
  P4PfProblem fronto = problem;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d point_cam = 10.0 * (fronto.pixels[i] / fronto.focal).homogeneous();
    fronto.points[i] = fronto.pose.rotation.conjugate() * (point_cam - fronto.pose.translation);
  }
  P4Pf(fronto.pixels, fronto.points, &poses, &focals);
  for (size_t k = 0; k < poses.size(); ++k) {
    EXPECT_TRUE(poses[k].rotation.coeffs().allFinite() && poses[k].translation.allFinite());
    EXPECT_TRUE(std::isfinite(focals[k]));
  }

  // Random pixels (an all-outlier sample).
  for (int trial = 0; trial < 500; ++trial) {
    P4PfProblem random = RandomP4PfProblem(rng);
    for (auto& p : random.pixels)
      p = Eigen::Vector2d(test::Uniform(rng, -800, 800), test::Uniform(rng, -600, 600));
    P4Pf(random.pixels, random.points, &poses, &focals);
    for (size_t k = 0; k < poses.size(); ++k) {
      ASSERT_TRUE(poses[k].rotation.coeffs().allFinite() && poses[k].translation.allFinite());
      ASSERT_TRUE(std::isfinite(focals[k]) && focals[k] > 0.0);
    }
  }
}

}  // namespace
}  // namespace cwloc
