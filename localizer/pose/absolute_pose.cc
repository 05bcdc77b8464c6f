#include "localizer/pose/absolute_pose.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "localizer/pose/pose_estimators.h"
#include "localizer/pose/refine_pose.h"

namespace cwloc {
namespace {

template <typename... Args>
std::string Concat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}

// Input checks shared by both entry points; returns false with result->failure_reason set.
bool CheckInput(size_t num_points2D, size_t num_points3D, size_t sample_size,
                const AbsolutePoseOptions& options, AbsolutePoseResult* result) {
  if (num_points2D != num_points3D) {
    result->failure_reason =
        Concat("size mismatch: ", num_points2D, " image points vs ", num_points3D, " 3D points");
    return false;
  }
  if (!(options.max_error_px > 0.0) || !std::isfinite(options.max_error_px)) {
    result->failure_reason = Concat("invalid max_error_px: ", options.max_error_px);
    return false;
  }
  const size_t needed = std::max<size_t>(sample_size, std::max(options.min_inliers, 0));
  if (num_points2D < needed) {
    result->failure_reason = Concat("too few correspondences: ", num_points2D, " < ", needed);
    return false;
  }
  return true;
}

// Final inlier set, error and verdict for `pose` with residual f * pi(X_c) - pixel.
void Finish(std::span<const Eigen::Vector2d> pixels, std::span<const Eigen::Vector3d> points3D,
            const AbsolutePoseOptions& options, AbsolutePoseResult* result) {
  const Eigen::Matrix3d rot = result->pose.rotation.toRotationMatrix();
  const double f = result->focal_length_px;
  const double max_sq = options.max_error_px * options.max_error_px;
  result->inliers.assign(pixels.size(), 0);
  result->num_inliers = 0;
  double error_sum = 0.0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector3d z = rot * points3D[i] + result->pose.translation;
    if (!(z(2) > 0.0)) continue;
    const double r2 = (f * z.hnormalized() - pixels[i]).squaredNorm();
    if (r2 < max_sq) {
      result->inliers[i] = 1;
      ++result->num_inliers;
      error_sum += std::sqrt(r2);
    }
  }
  result->mean_reprojection_error_px =
      result->num_inliers > 0 ? error_sum / result->num_inliers : 0.0;
  result->success = result->num_inliers >= options.min_inliers;
  if (!result->success) {
    result->failure_reason =
        Concat("best pose has ", result->num_inliers, " inliers < ", options.min_inliers);
  }
}

uint32_t CountInliers(std::span<const Eigen::Vector2d> pixels,
                      std::span<const Eigen::Vector3d> points3D, const CameraPose& pose, double f,
                      double max_sq) {
  const Eigen::Matrix3d rot = pose.rotation.toRotationMatrix();
  uint32_t count = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector3d z = rot * points3D[i] + pose.translation;
    count += z(2) > 0.0 && (f * z.hnormalized() - pixels[i]).squaredNorm() < max_sq;
  }
  return count;
}

// The robust refinement may move a few borderline inliers across the threshold; losing more
// than 2% of them means it went astray (e.g. an unobservable focal length drifted).
bool KeepsInliers(size_t refined_count, size_t ransac_count) {
  return refined_count >= ransac_count - ransac_count / 50;
}

}  // namespace

AbsolutePoseResult EstimateAbsolutePose(std::span<const Eigen::Vector2d> normalized_points,
                                        std::span<const Eigen::Vector3d> points3D,
                                        double focal_length_px,
                                        const AbsolutePoseOptions& options) {
  AbsolutePoseResult result;
  result.focal_length_px = focal_length_px;
  if (!CheckInput(normalized_points.size(), points3D.size(), AbsolutePoseEstimator::kSampleSize,
                  options, &result)) {
    return result;
  }
  if (!(focal_length_px > 0.0) || !std::isfinite(focal_length_px)) {
    result.failure_reason = Concat("invalid focal length: ", focal_length_px, " px");
    return result;
  }

  LocalOptimizationOptions lo;
  lo.max_iterations = options.lo_iterations;
  const AbsolutePoseEstimator estimator(normalized_points, points3D,
                                        options.max_error_px / focal_length_px, lo);
  result.stats = Ransac(estimator, options.ransac, &result.pose);
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason = "no pose hypothesis: every minimal sample was degenerate";
    return result;
  }

  // Errors in pixels from here on.
  std::vector<Eigen::Vector2d> pixels(normalized_points.size());
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = focal_length_px * normalized_points[i];
  if (options.refine) {
    std::vector<uint32_t> inliers;
    estimator.Inliers(result.pose, &inliers);
    PoseRefinementOptions refine;
    refine.loss_scale_px = options.loss_scale_px;
    CameraPose refined = result.pose;
    double f = focal_length_px;
    const double max_sq = options.max_error_px * options.max_error_px;
    if (RefinePose(pixels, points3D, inliers, refine, &refined, &f) &&
        KeepsInliers(CountInliers(pixels, points3D, refined, f, max_sq), inliers.size())) {
      result.pose = refined;
      result.refined = true;
    }
  }
  Finish(pixels, points3D, options, &result);
  return result;
}

AbsolutePoseResult EstimateAbsolutePoseUnknownFocal(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    const AbsolutePoseOptions& options) {
  AbsolutePoseResult result;
  if (!CheckInput(centered_pixels.size(), points3D.size(), AbsolutePoseFocalEstimator::kSampleSize,
                  options, &result)) {
    return result;
  }
  double diagonal = options.image_diagonal_px;
  if (!(diagonal > 0.0)) {
    for (const Eigen::Vector2d& p : centered_pixels) {
      if (p.allFinite()) diagonal = std::max(diagonal, 2.0 * p.norm());
    }
  }
  const double min_focal = options.min_focal_px > 0.0 ? options.min_focal_px : 0.1 * diagonal;
  const double max_focal = options.max_focal_px > 0.0 ? options.max_focal_px : 10.0 * diagonal;
  if (!(min_focal > 0.0) || !(max_focal >= min_focal) || !std::isfinite(max_focal)) {
    result.failure_reason = Concat("invalid focal length range: [", min_focal, ", ", max_focal,
                                   "] px (all image points at the principal point?)");
    return result;
  }

  LocalOptimizationOptions lo;
  lo.max_iterations = options.lo_iterations;
  const AbsolutePoseFocalEstimator estimator(centered_pixels, points3D, options.max_error_px,
                                             min_focal, max_focal, lo);
  PoseAndFocal model;
  result.stats = Ransac(estimator, options.ransac, &model);
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason = Concat(
        "no pose hypothesis: every minimal sample was degenerate or "
        "had a focal length outside [",
        min_focal, ", ", max_focal, "] px");
    return result;
  }
  result.pose = model.pose;
  result.focal_length_px = model.focal_length;

  if (options.refine) {
    std::vector<uint32_t> inliers;
    estimator.Inliers(model, &inliers);
    PoseRefinementOptions refine;
    refine.loss_scale_px = options.loss_scale_px;
    refine.refine_focal_length = true;
    CameraPose refined = model.pose;
    double f = model.focal_length;
    const double max_sq = options.max_error_px * options.max_error_px;
    if (RefinePose(centered_pixels, points3D, inliers, refine, &refined, &f) && f >= min_focal &&
        f <= max_focal &&
        KeepsInliers(CountInliers(centered_pixels, points3D, refined, f, max_sq), inliers.size())) {
      result.pose = refined;
      result.focal_length_px = f;
      result.refined = true;
    }
  }
  Finish(centered_pixels, points3D, options, &result);
  return result;
}

}  // namespace cwloc
