#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "localizer/pose/camera_pose.h"
#include "localizer/pose/ransac.h"

namespace cwloc {

// Robust absolute pose, the localizer's last stage (paper sec. 3: "RANSAC ... using a P3P
// solver and a focal length P4Pf solver ... an image is localized if the best pose has at least
// 12 inlier correspondences with a reprojection error less than 6 pixels").
//
// Pipeline: LO-RANSAC (ransac.h) over minimal solutions (P3P with a known focal length, P4Pf
// without), each new best hypothesis refined by Levenberg-Marquardt on its inliers
// (local_optimization.h); then a Ceres refinement of the best pose (and focal length) on its
// inliers with a Cauchy loss (refine_pose.h), kept unless it loses more than 2% of the
// inliers; the inlier set and error are finally recomputed with the reported pose.
struct AbsolutePoseOptions {
  // Inlier threshold on the reprojection error, pixels (paper: 6).
  double max_error_px = 6.0;
  // Success needs at least this many inliers (paper: 12).
  int min_inliers = 12;
  // The sampler: iteration limits, confidence, seed (ransac.h).
  RansacOptions ransac;
  // Levenberg-Marquardt iterations per local optimisation inside RANSAC.
  int lo_iterations = 10;
  // Final Ceres refinement of the best pose (and the focal length when unknown).
  bool refine = true;
  // Cauchy loss scale of the final refinement, pixels: residuals well below it count as
  // squared errors, residuals near the 6 px threshold already weigh about 1/(1 + 36/a^2).
  double loss_scale_px = 2.0;
  // Unknown focal length only: hypotheses and refinements with a focal length outside
  // [min_focal_px, max_focal_px] are rejected. A bound <= 0 is derived from the image
  // diagonal d: min = 0.1 d, max = 10 d.
  double min_focal_px = 0.0;
  double max_focal_px = 0.0;
  // The image diagonal for those defaults, pixels; <= 0: twice the largest distance of an
  // image point from the principal point (the points' extent, at most the true diagonal).
  double image_diagonal_px = 0.0;
};

struct AbsolutePoseResult {
  bool success = false;        // num_inliers >= min_inliers
  std::string failure_reason;  // empty on success, e.g. "best pose has 9 inliers < 12"
  // cam_from_world of the best pose found; meaningful whenever num_inliers > 0, even when
  // success is false (too few inliers).
  CameraPose pose;
  double focal_length_px = 0.0;  // the given focal length, or the estimated one
  std::vector<char> inliers;     // per correspondence: 1 if in front, error < max_error_px
  int num_inliers = 0;
  RansacStats stats;                        // of the RANSAC run (before the final refinement)
  bool refined = false;                     // the Ceres refinement was applied
  double mean_reprojection_error_px = 0.0;  // over the inliers
};

// Known focal length. normalized_points: undistorted image points on the normalised image
// plane (x/z, y/z), i.e. (pixel - principal point) / focal for a pinhole camera;
// focal_length_px converts the pixel threshold and errors (for fx != fy, use their mean).
AbsolutePoseResult EstimateAbsolutePose(std::span<const Eigen::Vector2d> normalized_points,
                                        std::span<const Eigen::Vector3d> points3D,
                                        double focal_length_px,
                                        const AbsolutePoseOptions& options = {});

// Unknown focal length (square pixels, principal point known). centered_pixels: pixel minus
// principal point, undistorted as far as known.
AbsolutePoseResult EstimateAbsolutePoseUnknownFocal(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    const AbsolutePoseOptions& options = {});

}  // namespace cwloc
