#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "localizer/pose/camera_pose.h"
#include "localizer/pose/local_optimization.h"

namespace cwloc {

// RANSAC estimators (the RansacEstimator concept of ransac.h) for absolute pose from 2D-3D
// correspondences. Both keep views of the caller's arrays, which must outlive them, and a
// scratch buffer, so one estimator must not be used from several threads at once.

// Calibrated camera: P3P hypotheses, reprojection error in normalised image coordinates.
class AbsolutePoseEstimator {
 public:
  using Model = CameraPose;
  static constexpr size_t kSampleSize = 3;

  // points2D: normalised image coordinates (x/z, y/z); max_error in the same units (a pixel
  // threshold divided by the focal length).
  AbsolutePoseEstimator(std::span<const Eigen::Vector2d> points2D,
                        std::span<const Eigen::Vector3d> points3D, double max_error,
                        const LocalOptimizationOptions& lo_options = {});

  size_t NumData() const { return points2D_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const;
  double Score(const Model& model, uint32_t* num_inliers) const;
  void Refine(Model* model) const;

  // Indices of the correspondences with squared error below the threshold (and in front).
  void Inliers(const Model& model, std::vector<uint32_t>* inliers) const;

 private:
  std::span<const Eigen::Vector2d> points2D_;
  std::span<const Eigen::Vector3d> points3D_;
  std::vector<Eigen::Vector3d> bearings_;
  double max_error_sq_;
  LocalOptimizationOptions lo_options_;
  mutable std::vector<uint32_t> scratch_;
};

// A pose together with the focal length (pixels) of a square-pixel camera.
struct PoseAndFocal {
  CameraPose pose;
  double focal_length = 0.0;
};

// Unknown focal length: P4Pf hypotheses, reprojection error in pixels.
class AbsolutePoseFocalEstimator {
 public:
  using Model = PoseAndFocal;
  static constexpr size_t kSampleSize = 4;

  // centered_pixels: pixel minus principal point; max_error_px in pixels; hypotheses with a
  // focal length outside [min_focal_px, max_focal_px] are discarded.
  AbsolutePoseFocalEstimator(std::span<const Eigen::Vector2d> centered_pixels,
                             std::span<const Eigen::Vector3d> points3D, double max_error_px,
                             double min_focal_px, double max_focal_px,
                             const LocalOptimizationOptions& lo_options = {});

  size_t NumData() const { return points2D_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const;
  double Score(const Model& model, uint32_t* num_inliers) const;
  void Refine(Model* model) const;
  void Inliers(const Model& model, std::vector<uint32_t>* inliers) const;

 private:
  std::span<const Eigen::Vector2d> points2D_;
  std::span<const Eigen::Vector3d> points3D_;
  double max_error_sq_;
  double min_focal_, max_focal_;
  LocalOptimizationOptions lo_options_;
  mutable std::vector<uint32_t> scratch_;
  mutable std::vector<CameraPose> pose_scratch_;
  mutable std::vector<double> focal_scratch_;
};

}  // namespace cwloc
