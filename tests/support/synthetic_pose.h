#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "base/split_mix64.h"
#include "solvers/camera_pose.h"

namespace cwloc::test {

// Every helper takes either generator: std::mt19937_64 (test::Rng(), the sequences the older
// tests were tuned with) or the project's SplitMix64 (base/split_mix64.h), which newer
// tests use, seeded from test::Rng() so that CWLOC_TEST_SEED still reseeds them.

// Uniform in [0, 1) from the top 53 bits.
inline double UnitUniform(SplitMix64& rng) {
  return static_cast<double>(rng.Next() >> 11) * 0x1.0p-53;
}

inline double Uniform(SplitMix64& rng, double lo, double hi) {
  return lo + (hi - lo) * UnitUniform(rng);
}

// A standard normal draw (Box-Muller; 1 - u lies in (0, 1], so the logarithm is finite).
inline double Gaussian(SplitMix64& rng) {
  const double u = 1.0 - UnitUniform(rng);
  const double v = UnitUniform(rng);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
}

// A direction uniform on the sphere.
inline Eigen::Vector3d RandomUnitVector(SplitMix64& rng) {
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(Gaussian(rng), Gaussian(rng), Gaussian(rng));
  } while (!(v.norm() > 1e-6));
  return v.normalized();
}

// N(mean, sigma^2) draws from either generator (std::normal_distribution for std::mt19937_64).
template <typename Rng>
class NormalSampler;

template <>
class NormalSampler<std::mt19937_64> {
 public:
  NormalSampler(double mean, double sigma) : distribution_(mean, sigma) {}
  double operator()(std::mt19937_64& rng) { return distribution_(rng); }

 private:
  std::normal_distribution<double> distribution_;
};

template <>
class NormalSampler<SplitMix64> {
 public:
  NormalSampler(double mean, double sigma) : mean_(mean), sigma_(sigma) {}
  double operator()(SplitMix64& rng) { return mean_ + sigma_ * Gaussian(rng); }

 private:
  double mean_, sigma_;
};

template <typename T>
void Shuffle(std::mt19937_64& rng, std::vector<T>* items) {
  std::shuffle(items->begin(), items->end(), rng);
}

template <typename T>
void Shuffle(SplitMix64& rng, std::vector<T>* items) {
  rng.Shuffle(std::span<T>(*items));
}

// A SplitMix64 seeded from the shared test generator.
inline SplitMix64 SplitMixFrom(std::mt19937_64& rng) { return SplitMix64(rng()); }

template <typename Rng>
Eigen::Quaterniond RandomRotation(Rng& rng) {
  NormalSampler<Rng> normal(0.0, 1.0);
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized();
}

inline double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A random cam_from_world with the camera centre in [-10, 10]^3.
template <typename Rng>
CameraPose RandomPose(Rng& rng) {
  const Eigen::Quaterniond q = RandomRotation(rng);
  const Eigen::Vector3d center(Uniform(rng, -10, 10), Uniform(rng, -10, 10), Uniform(rng, -10, 10));
  return CameraPose(q, -(q * center));
}

// A pose's distance from the truth: the rotation's angle (radians) plus the centre's distance
// relative to the truth's distance from the origin (and `scale`, for centres near it).
inline double PoseError(const CameraPose& estimate, const CameraPose& truth, double scale = 1.0) {
  return estimate.rotation.angularDistance(truth.rotation) +
         (estimate.Center() - truth.Center()).norm() / (scale + truth.Center().norm());
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
template <typename Rng>
SyntheticPoseProblem MakeSyntheticProblem(const SyntheticPoseOptions& options, Rng& rng) {
  SyntheticPoseProblem problem;
  problem.pose = RandomPose(rng);
  problem.focal_px = options.focal_px;
  NormalSampler<Rng> noise(0.0, options.noise_px);
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
  Shuffle(rng, &order);
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
