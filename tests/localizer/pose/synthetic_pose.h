#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "localizer/pose/camera_pose.h"

namespace cwloc::test {

inline Eigen::Quaterniond RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized();
}

inline double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A random cam_from_world with the camera centre in [-10, 10]^3.
inline CameraPose RandomPose(std::mt19937_64& rng) {
  const Eigen::Quaterniond q = RandomRotation(rng);
  const Eigen::Vector3d center(Uniform(rng, -10, 10), Uniform(rng, -10, 10), Uniform(rng, -10, 10));
  return CameraPose(q, -(q * center));
}

// Angle between two rotations, degrees.
inline double RotationErrorDeg(const CameraPose& a, const CameraPose& b) {
  return a.rotation.angularDistance(b.rotation) * 180.0 / std::numbers::pi;
}

struct SyntheticPoseOptions {
  int num_points = 300;
  double outlier_ratio = 0.7;  // fraction of wrong correspondences
  double noise_px = 1.0;       // Gaussian noise (sigma, pixels) on the inliers
  double focal_px = 1000.0;
  double width_px = 1600.0;  // principal point at the image centre
  double height_px = 1200.0;
  double min_depth = 5.0;  // world units
  double max_depth = 50.0;
  double min_outlier_error_px = 20.0;  // outliers are at least this far off
  // SIMPLE_RADIAL distortion of the observed pixels: f d (u, v) with d = 1 + k (u^2 + v^2);
  // the undistorted projections f (u, v) are uniform over the image.
  double radial_k = 0.0;
};

struct SyntheticPoseProblem {
  CameraPose pose;
  double focal_px = 0.0;
  std::vector<Eigen::Vector2d> pixels;      // observed, minus the principal point
  std::vector<Eigen::Vector2d> normalized;  // pixels / focal_px
  std::vector<Eigen::Vector3d> points3D;
  std::vector<char> is_inlier;
  int num_inliers = 0;
  double mean_depth = 0.0;
};

// Points seen at uniformly random pixels and depths; an outlier keeps its 3D point but is
// observed at an unrelated random pixel (a wrong match).
inline SyntheticPoseProblem MakeSyntheticProblem(const SyntheticPoseOptions& options,
                                                 std::mt19937_64& rng) {
  SyntheticPoseProblem problem;
  problem.pose = RandomPose(rng);
  problem.focal_px = options.focal_px;
  std::normal_distribution<double> noise(0.0, options.noise_px);
  const int num_outliers =
      static_cast<int>(std::lround(options.outlier_ratio * options.num_points));
  const double hw = 0.5 * options.width_px, hh = 0.5 * options.height_px;
  for (int i = 0; i < options.num_points; ++i) {
    const Eigen::Vector2d pixel(Uniform(rng, -hw, hw), Uniform(rng, -hh, hh));
    const double depth = Uniform(rng, options.min_depth, options.max_depth);
    const Eigen::Vector3d point_cam = depth * (pixel / options.focal_px).homogeneous();
    problem.points3D.push_back(problem.pose.rotation.conjugate() *
                               (point_cam - problem.pose.translation));
    problem.mean_depth += depth / options.num_points;
    const bool inlier = i >= num_outliers;
    const Eigen::Vector2d uv = pixel / options.focal_px;
    const Eigen::Vector2d distorted = (1.0 + options.radial_k * uv.squaredNorm()) * pixel;
    Eigen::Vector2d observed = distorted + Eigen::Vector2d(noise(rng), noise(rng));
    if (!inlier) {
      do {
        observed = Eigen::Vector2d(Uniform(rng, -hw, hw), Uniform(rng, -hh, hh));
      } while ((observed - distorted).norm() < options.min_outlier_error_px);
    }
    problem.pixels.push_back(observed);
    problem.normalized.push_back(observed / options.focal_px);
    problem.is_inlier.push_back(inlier ? 1 : 0);
    problem.num_inliers += inlier;
  }
  // Outliers first would be a too friendly order for any sequential bug: shuffle.
  std::vector<size_t> order(problem.pixels.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  SyntheticPoseProblem shuffled = problem;
  for (size_t i = 0; i < order.size(); ++i) {
    shuffled.pixels[i] = problem.pixels[order[i]];
    shuffled.normalized[i] = problem.normalized[order[i]];
    shuffled.points3D[i] = problem.points3D[order[i]];
    shuffled.is_inlier[i] = problem.is_inlier[order[i]];
  }
  return shuffled;
}

}  // namespace cwloc::test
