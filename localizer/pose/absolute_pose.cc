#include "localizer/pose/absolute_pose.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "base/angles.h"
#include "localizer/pose/refine_pose.h"
#include "robust/pose_estimators.h"

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

// The gravity prior, normalised, if the context has one; false with result->failure_reason set
// when it is invalid.
bool CheckGravity(const PoseContext& context, std::optional<GravityPrior>* gravity,
                  AbsolutePoseResult* result) {
  if (!context.gravity.has_value()) return true;
  const std::string error = GravityPriorError(*context.gravity);
  if (!error.empty()) {
    result->failure_reason = "invalid gravity prior: " + error;
    return false;
  }
  *gravity = NormalizedGravityPrior(*context.gravity);
  return true;
}

// The prior's soft constraint for residuals measured in units of pixels_per_unit pixels (1 for
// pixels, the focal length for normalised image coordinates), with the pixel noise the
// refinement's Cauchy loss assumes.
std::optional<GravityConstraint> SoftGravity(const std::optional<GravityPrior>& gravity,
                                             const AbsolutePoseOptions& options,
                                             double pixels_per_unit) {
  if (!gravity.has_value()) return std::nullopt;
  return GravityWeight(*gravity, CauchyScaleNoise(options.loss_scale_px) / pixels_per_unit);
}

// The test of P3P's and P4Pf's hypotheses against the prior (absolute_pose.h).
std::optional<GravityCheck> HypothesisCheck(const std::optional<GravityPrior>& gravity,
                                            const AbsolutePoseOptions& options) {
  if (!gravity.has_value()) return std::nullopt;
  return GravityCheck{
      gravity->in_camera, gravity->in_world,
      GravityRejectionAngle(gravity->sigma_deg * kDegree, options.ransac.confidence)};
}

std::string GravityRejectionText(const std::optional<GravityCheck>& check) {
  if (!check.has_value()) return {};
  return Concat(" or disagreed with the gravity prior by more than ", check->max_angle / kDegree,
                " deg");
}

// Final inlier set, error and verdict for `pose` with residual camera.Project(X_c) - pixel
// (f * pi(X_c) - pixel for k = 0).
void Finish(std::span<const Eigen::Vector2d> pixels, std::span<const Eigen::Vector3d> points3D,
            const AbsolutePoseOptions& options, const PoseContext& context,
            AbsolutePoseResult* result) {
  const Eigen::Matrix3d rot = result->pose.rotation.toRotationMatrix();
  const RadialCamera camera{result->focal_length_px, result->radial_distortion};
  const double max_sq = options.max_error_px * options.max_error_px;
  result->inliers.assign(pixels.size(), 0);
  result->num_inliers = 0;
  double error_sum = 0.0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector3d z = rot * points3D[i] + result->pose.translation;
    if (!(z(2) > 0.0)) continue;
    const double r2 = (camera.Project(z) - pixels[i]).squaredNorm();
    if (r2 < max_sq) {
      result->inliers[i] = 1;
      ++result->num_inliers;
      error_sum += std::sqrt(r2);
    }
  }
  result->mean_reprojection_error_px =
      result->num_inliers > 0 ? error_sum / result->num_inliers : 0.0;
  if (context.gravity.has_value()) {
    result->gravity_angle_deg = GravityAngle(rot, context.gravity->in_world.normalized(),
                                             context.gravity->in_camera.normalized()) /
                                kDegree;
  }
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

// Indices of the correspondences in front of the camera with a squared error below max_sq.
void CollectInliers(std::span<const Eigen::Vector2d> pixels,
                    std::span<const Eigen::Vector3d> points3D, const CameraPose& pose,
                    const RadialCamera& camera, double max_sq, std::vector<uint32_t>* inliers) {
  const Eigen::Matrix3d rot = pose.rotation.toRotationMatrix();
  inliers->clear();
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector3d z = rot * points3D[i] + pose.translation;
    if (z(2) > 0.0 && (camera.Project(z) - pixels[i]).squaredNorm() < max_sq) {
      inliers->push_back(static_cast<uint32_t>(i));
    }
  }
}

// The robust refinement may move a few borderline inliers across the threshold; losing more
// than 2% of them means it went astray (e.g. an unobservable focal length drifted).
bool KeepsInliers(size_t refined_count, size_t ransac_count) {
  return refined_count >= ransac_count - ransac_count / 50;
}

// The focal length bounds of an uncalibrated camera and the image's half diagonal (options, or
// the extent of the points); false with result->failure_reason set when they make no sense.
struct FocalBounds {
  double min_focal = 0.0;
  double max_focal = 0.0;
  double image_radius = 0.0;  // half the image diagonal, pixels
};

bool UncalibratedBounds(std::span<const Eigen::Vector2d> centered_pixels,
                        const AbsolutePoseOptions& options, const PoseContext& context,
                        FocalBounds* bounds, AbsolutePoseResult* result) {
  double diagonal = context.image_diagonal_px;
  if (!(diagonal > 0.0)) {
    for (const Eigen::Vector2d& p : centered_pixels) {
      if (p.allFinite()) diagonal = std::max(diagonal, 2.0 * p.norm());
    }
  }
  bounds->image_radius = 0.5 * diagonal;
  bounds->min_focal = options.min_focal_px > 0.0 ? options.min_focal_px : 0.1 * diagonal;
  bounds->max_focal = options.max_focal_px > 0.0 ? options.max_focal_px : 10.0 * diagonal;
  if (!(bounds->min_focal > 0.0) || !(bounds->max_focal >= bounds->min_focal) ||
      !std::isfinite(bounds->max_focal)) {
    result->failure_reason =
        Concat("invalid focal length range: [", bounds->min_focal, ", ", bounds->max_focal,
               "] px (all image points at the principal point?)");
    return false;
  }
  return true;
}

// The sanity rule of the uncalibrated refinement (absolute_pose.h).
bool SaneCamera(const RadialCamera& camera, const FocalBounds& bounds,
                const AbsolutePoseOptions& options) {
  const double f = camera.focal_length_px;
  if (!(f >= bounds.min_focal && f <= bounds.max_focal)) return false;
  if (!(std::abs(camera.k) <= options.max_radial_distortion)) return false;
  const double corner = bounds.image_radius / f;
  return 1.0 + 3.0 * camera.k * corner * corner > 0.0;
}

// The budget's deadline passed: the result keeps RANSAC's pose and says so.
bool SkipsRefinement(const PoseContext& context, AbsolutePoseResult* result) {
  result->refinement_skipped = context.refine_deadline.Passed();
  return result->refinement_skipped;
}

// The uncalibrated refinement's problem: pose, f and k under the Cauchy loss.
PoseRefinementOptions UncalibratedRefinement(const AbsolutePoseOptions& options,
                                             const std::optional<GravityPrior>& gravity) {
  PoseRefinementOptions refine;
  refine.loss_scale_px = options.loss_scale_px;
  refine.refine_focal_length = true;
  refine.refine_radial_distortion = options.refine_radial_distortion;
  refine.refiner = options.refiner;
  refine.gravity = SoftGravity(gravity, options, 1.0);
  return refine;
}

// The uncalibrated refinement: rounds of refining pose, f and k on the inliers, then
// re-scoring every correspondence, while the camera stays sane and the inliers are kept.
// Starts from *pose and *camera (RANSAC's, k = 0) with RANSAC's inliers.
void RefineUncalibrated(std::span<const Eigen::Vector2d> pixels,
                        std::span<const Eigen::Vector3d> points3D, std::vector<uint32_t> inliers,
                        const FocalBounds& bounds, const AbsolutePoseOptions& options,
                        const std::optional<GravityPrior>& gravity, AbsolutePoseResult* result) {
  const PoseRefinementOptions refine = UncalibratedRefinement(options, gravity);
  const double max_sq = options.max_error_px * options.max_error_px;
  const size_t ransac_count = inliers.size();
  std::vector<uint32_t> rescored;
  for (int round = 0; round < options.camera_refinement_rounds; ++round) {
    CameraPose pose = result->pose;
    RadialCamera camera{result->focal_length_px, result->radial_distortion};
    if (!RefinePoseAndCamera(pixels, points3D, inliers, refine, &pose, &camera) ||
        !SaneCamera(camera, bounds, options)) {
      break;
    }
    CollectInliers(pixels, points3D, pose, camera, max_sq, &rescored);
    if (!KeepsInliers(rescored.size(), ransac_count)) break;
    result->pose = pose;
    result->focal_length_px = camera.focal_length_px;
    result->radial_distortion = camera.k;
    result->refined = true;
    ++result->camera_refinement_rounds;
    if (rescored == inliers) break;
    inliers.swap(rescored);
  }
}

// After Finish, on success: the pose's covariance on the final inliers under the final
// refinement's problem and, for a refined uncalibrated camera, how well its focal length is told
// apart from the depth.
void ReportUncertainty(std::span<const Eigen::Vector2d> pixels,
                       std::span<const Eigen::Vector3d> points3D,
                       const PoseRefinementOptions& refinement, bool uncalibrated,
                       AbsolutePoseResult* result) {
  if (!result->success) return;
  std::vector<uint32_t> inliers;
  for (uint32_t i = 0; i < result->inliers.size(); ++i) {
    if (result->inliers[i]) inliers.push_back(i);
  }
  const RadialCamera camera{result->focal_length_px, result->radial_distortion};
  result->covariance = PoseCovarianceAt(pixels, points3D, inliers, refinement, result->pose, camera,
                                        uncalibrated, &result->distortion_std);
  if (uncalibrated && result->refined)
    result->focal_depth = FocalDepthAt(pixels, points3D, inliers, refinement, result->pose, camera);
}

}  // namespace

AbsolutePoseResult EstimateAbsolutePose(std::span<const Eigen::Vector2d> normalized_points,
                                        std::span<const Eigen::Vector3d> points3D,
                                        double focal_length_px, const AbsolutePoseOptions& options,
                                        const PoseContext& context) {
  AbsolutePoseResult result;
  result.focal_length_px = focal_length_px;
  // GravityP2P for a valid prior not vaguer than kGravityP2PMaxSigmaDeg, else P3P.
  const bool p2p =
      context.gravity.has_value() && context.gravity->sigma_deg <= kGravityP2PMaxSigmaDeg;
  const size_t sample_size =
      p2p ? GravityPoseEstimator::kSampleSize : AbsolutePoseEstimator::kSampleSize;
  if (!CheckInput(normalized_points.size(), points3D.size(), sample_size, options, &result)) {
    return result;
  }
  if (!(focal_length_px > 0.0) || !std::isfinite(focal_length_px)) {
    result.failure_reason = Concat("invalid focal length: ", focal_length_px, " px");
    return result;
  }
  std::optional<GravityPrior> gravity;
  if (!CheckGravity(context, &gravity, &result)) return result;

  LocalOptimizationOptions lo;
  lo.max_iterations = options.lo_iterations;
  lo.gravity = SoftGravity(gravity, options, focal_length_px);
  const double max_error = options.max_error_px / focal_length_px;
  // P3P: without a prior; with a vague one, whose hypotheses must agree with it; or after
  // GravityP2P found too few inliers, when the prior may be further off than its sigma says and
  // no hypothesis is checked against it.
  const std::optional<GravityCheck> check = p2p ? std::nullopt : HypothesisCheck(gravity, options);
  const AbsolutePoseEstimator p3p(normalized_points, points3D, max_error, lo, check);
  if (p2p) {
    // GravityP2P's hypotheses are as far off in tilt as the prior (pose_estimators.h): the local
    // optimisation gathers what a tilt error up to the prior's bound moves (tan(bound) beyond
    // the threshold, in normalised coordinates) under a Cauchy loss whose scale adds the
    // displacement of a 1 sigma error.
    const double sigma = gravity->sigma_deg * kDegree;
    const double bound = GravityErrorBound(sigma, options.ransac.confidence);
    LocalOptimizationOptions p2p_lo = lo;
    p2p_lo.loss_scale = max_error + std::tan(sigma);
    const GravityPoseEstimator estimator(normalized_points, points3D, max_error, gravity->in_camera,
                                         gravity->in_world, max_error + std::tan(bound), p2p_lo);
    result.stats = Ransac(estimator, options.ransac, context.ransac, &result.pose);
  }
  if (!p2p || result.stats.num_inliers < static_cast<uint32_t>(std::max(options.min_inliers, 0))) {
    CameraPose pose;
    const RansacStats stats = Ransac(p3p, options.ransac, context.ransac, &pose);
    if (!p2p) {
      result.stats = stats;
      result.pose = pose;
    } else {
      result.gravity_fallback = true;
      RansacStats combined = stats.score < result.stats.score ? stats : result.stats;
      if (stats.score < result.stats.score) result.pose = pose;
      combined.iterations = stats.iterations + result.stats.iterations;
      combined.refinements = stats.refinements + result.stats.refinements;
      result.stats = combined;
    }
  }
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason =
        "no pose hypothesis: every minimal sample was degenerate" + GravityRejectionText(check);
    return result;
  }

  // Errors in pixels from here on.
  std::vector<Eigen::Vector2d> pixels(normalized_points.size());
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = focal_length_px * normalized_points[i];
  PoseRefinementOptions refine;
  refine.loss_scale_px = options.loss_scale_px;
  refine.refiner = options.refiner;
  refine.gravity = SoftGravity(gravity, options, 1.0);
  if (options.refine && !SkipsRefinement(context, &result)) {
    std::vector<uint32_t> inliers;
    p3p.Inliers(result.pose, &inliers);
    CameraPose refined = result.pose;
    double f = focal_length_px;
    const double max_sq = options.max_error_px * options.max_error_px;
    if (RefinePose(pixels, points3D, inliers, refine, &refined, &f) &&
        KeepsInliers(CountInliers(pixels, points3D, refined, f, max_sq), inliers.size())) {
      result.pose = refined;
      result.refined = true;
    }
  }
  Finish(pixels, points3D, options, context, &result);
  ReportUncertainty(pixels, points3D, refine, /*uncalibrated=*/false, &result);
  return result;
}

AbsolutePoseResult EstimateAbsolutePoseUnknownFocal(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    const AbsolutePoseOptions& options, const PoseContext& context) {
  AbsolutePoseResult result;
  if (!CheckInput(centered_pixels.size(), points3D.size(), AbsolutePoseFocalEstimator::kSampleSize,
                  options, &result)) {
    return result;
  }
  FocalBounds bounds;
  if (!UncalibratedBounds(centered_pixels, options, context, &bounds, &result)) return result;
  std::optional<GravityPrior> gravity;
  if (!CheckGravity(context, &gravity, &result)) return result;

  LocalOptimizationOptions lo;
  lo.max_iterations = options.lo_iterations;
  lo.gravity = SoftGravity(gravity, options, 1.0);
  const std::optional<GravityCheck> check = HypothesisCheck(gravity, options);
  const AbsolutePoseFocalEstimator estimator(centered_pixels, points3D, options.max_error_px,
                                             bounds.min_focal, bounds.max_focal, lo, check);
  PoseAndFocal model;
  result.stats = Ransac(estimator, options.ransac, context.ransac, &model);
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason = Concat(
        "no pose hypothesis: every minimal sample was degenerate or "
        "had a focal length outside [",
        bounds.min_focal, ", ", bounds.max_focal, "] px", GravityRejectionText(check));
    return result;
  }
  result.pose = model.pose;
  result.focal_length_px = model.focal_length;

  if (options.refine && !SkipsRefinement(context, &result)) {
    std::vector<uint32_t> inliers;
    estimator.Inliers(model, &inliers);
    RefineUncalibrated(centered_pixels, points3D, std::move(inliers), bounds, options, gravity,
                       &result);
  }
  Finish(centered_pixels, points3D, options, context, &result);
  ReportUncertainty(centered_pixels, points3D, UncalibratedRefinement(options, gravity),
                    /*uncalibrated=*/true, &result);
  return result;
}

AbsolutePoseResult EstimateAbsolutePoseFocalPrior(std::span<const Eigen::Vector2d> centered_pixels,
                                                  std::span<const Eigen::Vector3d> points3D,
                                                  double prior_focal_length_px,
                                                  const AbsolutePoseOptions& options,
                                                  const PoseContext& context) {
  if (options.focal_prior_solver == FocalPriorSolver::kP4Pf) {
    return EstimateAbsolutePoseUnknownFocal(centered_pixels, points3D, options, context);
  }
  AbsolutePoseResult result;
  result.focal_length_px = prior_focal_length_px;
  if (!CheckInput(centered_pixels.size(), points3D.size(), AbsolutePoseEstimator::kSampleSize,
                  options, &result)) {
    return result;
  }
  if (!(prior_focal_length_px > 0.0) || !std::isfinite(prior_focal_length_px)) {
    result.failure_reason = Concat("invalid focal length prior: ", prior_focal_length_px, " px");
    return result;
  }
  FocalBounds bounds;
  if (!UncalibratedBounds(centered_pixels, options, context, &bounds, &result)) return result;
  std::optional<GravityPrior> gravity;
  if (!CheckGravity(context, &gravity, &result)) return result;

  std::vector<Eigen::Vector2d> normalized(centered_pixels.size());
  for (size_t i = 0; i < normalized.size(); ++i) {
    normalized[i] = centered_pixels[i] / prior_focal_length_px;
  }
  LocalOptimizationOptions lo;
  lo.max_iterations = options.lo_iterations;
  lo.gravity = SoftGravity(gravity, options, prior_focal_length_px);
  const std::optional<GravityCheck> check = HypothesisCheck(gravity, options);
  const AbsolutePoseEstimator estimator(normalized, points3D,
                                        options.max_error_px / prior_focal_length_px, lo, check);
  result.stats = Ransac(estimator, options.ransac, context.ransac, &result.pose);
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason =
        "no pose hypothesis: every minimal sample was degenerate" + GravityRejectionText(check);
    return result;
  }
  if (options.refine && !SkipsRefinement(context, &result)) {
    std::vector<uint32_t> inliers;
    estimator.Inliers(result.pose, &inliers);
    RefineUncalibrated(centered_pixels, points3D, std::move(inliers), bounds, options, gravity,
                       &result);
  }
  Finish(centered_pixels, points3D, options, context, &result);
  ReportUncertainty(centered_pixels, points3D, UncalibratedRefinement(options, gravity),
                    /*uncalibrated=*/true, &result);
  return result;
}

}  // namespace cwloc
