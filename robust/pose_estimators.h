#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "robust/local_optimization.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// RANSAC estimators (the RansacEstimator concept of robust/ransac.h) for absolute pose from
// 2D-3D correspondences. All keep views of the caller's arrays, which must outlive them, and a
// scratch buffer, so one estimator must not be used from several threads at once.

// The correspondences as coordinate columns (x_i, p_i), which RANSAC's scoring reads in
// vectorizable loops.
struct ScoringColumns {
  ScoringColumns(std::span<const Eigen::Vector2d> points2D,
                 std::span<const Eigen::Vector3d> points3D);
  std::vector<double> x, y, z, u, v;
};

// MSAC score sum_i min(r_i^2, max_sq) of r_i = f * pi(R X_i + t) - (u_i, v_i) over the columns
// (u, v in the units of f times normalised coordinates); a point behind the camera counts as an
// outlier. The squared errors of a block of points are computed independently (the loop
// vectorizes), then summed in point order; stops after a block once the sum reaches `bound`.
double MsacScore(const ScoringColumns& points, const CameraPose& pose, double f, double max_sq,
                 double bound, uint32_t* num_inliers);

// Every k-th inlier, so that at most max_points remain (0: all): the local optimisation's
// share of a hypothesis' inliers (LocalOptimizationOptions::max_points).
void Thin(uint32_t max_points, std::vector<uint32_t>* inliers);

// A gravity prior's test of hypotheses (GravityRejectionAngle, gravity_prior.h): GenerateModels
// drops poses whose angle between R in_world and in_camera exceeds max_angle.
struct GravityCheck {
  Eigen::Vector3d in_camera = Eigen::Vector3d::Zero();  // unit
  Eigen::Vector3d in_world = Eigen::Vector3d::Zero();   // unit
  double max_angle = 0.0;                               // radians
};

// Calibrated camera: P3P hypotheses, reprojection error in normalised image coordinates.
class AbsolutePoseEstimator {
 public:
  using Model = CameraPose;
  static constexpr size_t kSampleSize = 3;

  // points2D: normalised image coordinates (x/z, y/z); max_error in the same units (a pixel
  // threshold divided by the focal length).
  AbsolutePoseEstimator(std::span<const Eigen::Vector2d> points2D,
                        std::span<const Eigen::Vector3d> points3D, double max_error,
                        const LocalOptimizationOptions& lo_options = {},
                        const std::optional<GravityCheck>& gravity_check = std::nullopt);

  size_t NumData() const { return points2D_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const;
  double Score(const Model& model, uint32_t* num_inliers, double bound) const;
  void Refine(Model* model) const;

  // Indices of the correspondences with squared error below the threshold (and in front).
  void Inliers(const Model& model, std::vector<uint32_t>* inliers) const;

 private:
  std::span<const Eigen::Vector2d> points2D_;
  std::span<const Eigen::Vector3d> points3D_;
  std::vector<Eigen::Vector3d> bearings_;
  ScoringColumns columns_;
  double max_error_sq_;
  LocalOptimizationOptions lo_options_;
  std::optional<GravityCheck> gravity_check_;
  mutable std::vector<uint32_t> scratch_;
};

// Calibrated camera with a known gravity direction: GravityP2P hypotheses from two points,
// scored as by AbsolutePoseEstimator. Its hypotheses inherit the prior's error: a tilt off by
// delta moves the other points by about f tan(delta) in the image, so that a hypothesis may
// keep only the inliers near its two samples. The local optimisation therefore starts from
// every correspondence within lo_window (>= max_error, e.g. what the prior's error bound can
// displace) and damps the outliers among them with lo_options.loss_scale; lo_options.gravity,
// if set, keeps the prior as a soft constraint.
class GravityPoseEstimator {
 public:
  using Model = CameraPose;
  static constexpr size_t kSampleSize = 2;

  // points2D, max_error: as AbsolutePoseEstimator's; the gravity directions have unit length;
  // lo_window in the units of max_error.
  GravityPoseEstimator(std::span<const Eigen::Vector2d> points2D,
                       std::span<const Eigen::Vector3d> points3D, double max_error,
                       const Eigen::Vector3d& gravity_in_camera,
                       const Eigen::Vector3d& gravity_in_world, double lo_window,
                       const LocalOptimizationOptions& lo_options = {});

  size_t NumData() const { return points2D_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const;
  double Score(const Model& model, uint32_t* num_inliers, double bound) const;
  void Refine(Model* model) const;
  // The correspondences within max_error (not the window).
  void Inliers(const Model& model, std::vector<uint32_t>* inliers) const;

 private:
  std::span<const Eigen::Vector2d> points2D_;
  std::span<const Eigen::Vector3d> points3D_;
  std::vector<Eigen::Vector3d> bearings_;
  ScoringColumns columns_;
  double max_error_sq_;
  double lo_window_sq_;
  Eigen::Vector3d gravity_in_camera_, gravity_in_world_;
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
  // focal length outside [min_focal_px, max_focal_px] are discarded, and so are those that fail
  // the gravity check.
  AbsolutePoseFocalEstimator(std::span<const Eigen::Vector2d> centered_pixels,
                             std::span<const Eigen::Vector3d> points3D, double max_error_px,
                             double min_focal_px, double max_focal_px,
                             const LocalOptimizationOptions& lo_options = {},
                             const std::optional<GravityCheck>& gravity_check = std::nullopt);

  size_t NumData() const { return points2D_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const;
  double Score(const Model& model, uint32_t* num_inliers, double bound) const;
  void Refine(Model* model) const;
  void Inliers(const Model& model, std::vector<uint32_t>* inliers) const;

 private:
  std::span<const Eigen::Vector2d> points2D_;
  std::span<const Eigen::Vector3d> points3D_;
  ScoringColumns columns_;
  double max_error_sq_;
  double min_focal_, max_focal_;
  LocalOptimizationOptions lo_options_;
  std::optional<GravityCheck> gravity_check_;
  mutable std::vector<uint32_t> scratch_;
  mutable std::vector<CameraPose> pose_scratch_;
  mutable std::vector<double> focal_scratch_;
};

}  // namespace cwloc
