#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "localizer/pose/refine_pose.h"
#include "robust/gravity_prior.h"
#include "robust/ransac.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// Robust absolute pose, the localizer's last stage (paper sec. 3: "RANSAC ... using a P3P
// solver and a focal length P4Pf solver ... an image is localized if the best pose has at least
// 12 inlier correspondences with a reprojection error less than 6 pixels").
//
// Pipeline: LO-RANSAC (robust/ransac.h) over minimal solutions (P3P with a known focal length
// or a focal prior, P4Pf without), each new best hypothesis refined by Levenberg-Marquardt on its
// inliers (robust/local_optimization.h); then a final refinement on the inliers with a Cauchy loss
// (refine_pose.h, Ceres or our own Levenberg-Marquardt); the inlier set and error are finally
// recomputed with the reported camera.
//
// Known camera: the refinement moves the pose only and is kept unless it loses more than 2% of
// the inliers.
//
// Uncalibrated camera (an unknown focal length or a focal prior), as COLMAP's registrator
// treats a camera no registered image has refined: the camera is a SIMPLE_RADIAL with its
// principal point given (the image centre), and the refinement moves the pose, the focal length
// and the radial distortion k together (refine_pose.h, RadialCamera). Each round re-scores every
// correspondence with the refined camera (a distorted point far from the centre that RANSAC's
// pinhole camera missed becomes an inlier) and refines again on the new inlier set, until the
// set stops changing or after camera_refinement_rounds rounds. A round is kept only if its
// camera is sane and it keeps the inliers:
//   - the focal length lies in [min_focal_px, max_focal_px];
//   - |k| <= max_radial_distortion, and the distortion is invertible over the whole image:
//     the distorted radius f r (1 + k r^2) grows with r up to the image corner, 1 + 3 k r_c^2 > 0
//     with r_c = (image diagonal / 2) / f (a strong barrel k folds the corners back);
//   - it does not lose more than 2% of RANSAC's inliers (re-scored with the refined camera).
// The first round that fails stops the loop; the camera of the last kept round is reported
// (RANSAC's own, with k = 0, when none was kept).
//
// A gravity prior (PoseContext::gravity, robust/gravity_prior.h; docs/algorithm.md):
//   - known focal length: RANSAC's minimal sample is 2 points and its solver GravityP2P
//     (gravity_p2p.h), whose poses honour the prior's direction exactly; the adaptive iteration
//     count uses the sample size 2, log(1 - confidence) / log(1 - w^2). Its local optimisation
//     starts from every correspondence a tilt error within the prior's bound can have moved
//     (GravityPoseEstimator). When its best pose has fewer than min_inliers inliers (the prior
//     may be further off than its sigma says), P3P RANSAC without the hypothesis check below runs
//     after it and the better pose is kept. A prior vaguer than kGravityP2PMaxSigmaDeg skips
//     GravityP2P and runs P3P as below;
//   - uncalibrated, and P3P for a known focal length: the solvers of the case without a prior,
//     but hypotheses whose gravity angle exceeds GravityRejectionAngle(sigma,
//     ransac.confidence) are dropped before they are scored;
//   - always: the local optimisation and the final refinement add the prior as a soft constraint,
//     a Gaussian on the angle with the prior's sigma next to reprojection residuals whose noise
//     is the one the Cauchy loss scale assumes (CauchyScaleNoise: 0.84 px for 2 px).
// Without a prior every result is bit for bit what it was before the prior existed.

// RANSAC's minimal solver for a focal prior (EstimateAbsolutePoseFocalPrior).
enum class FocalPriorSolver {
  kP3P,   // hold the prior focal length in RANSAC, as COLMAP does; the refinement frees it
  kP4Pf,  // ignore the prior in RANSAC and estimate the focal length as if it were unknown
};

struct AbsolutePoseOptions {
  // Inlier threshold on the reprojection error, pixels (paper: 6).
  double max_error_px = 6.0;
  // Success needs at least this many inliers (paper: 12).
  int min_inliers = 12;
  // The sampler: iteration limits, confidence (robust/ransac.h).
  RansacOptions ransac;
  // Levenberg-Marquardt iterations per local optimisation inside RANSAC.
  int lo_iterations = 10;
  // Final refinement of the best pose (and the focal length when unknown), and its solver.
  bool refine = true;
  PoseRefiner refiner = PoseRefinementOptions().refiner;
  // Cauchy loss scale of the final refinement, pixels: residuals well below it count as
  // squared errors, residuals near the 6 px threshold already weigh about 1/(1 + 36/a^2).
  double loss_scale_px = 2.0;
  // Uncalibrated cameras only: hypotheses and refinements with a focal length outside
  // [min_focal_px, max_focal_px] are rejected. A bound <= 0 is derived from the image
  // diagonal d (PoseContext::image_diagonal_px): min = 0.1 d, max = 10 d.
  double min_focal_px = 0.0;
  double max_focal_px = 0.0;
  // Uncalibrated cameras only (see above): refine k with the focal length (else k stays 0),
  // rounds of refinement and re-scoring, the bound on |k| (COLMAP's max_extra_param).
  bool refine_radial_distortion = true;
  int camera_refinement_rounds = 5;
  double max_radial_distortion = 1.0;
  // A focal prior's RANSAC solver. P3P with the prior: on sceaux_castle, whose EXIF prior is
  // 5% short of the refined focal length and whose lens distorts, it gives more RANSAC inliers
  // than P4Pf and the same refined poses (docs/algorithm.md).
  FocalPriorSolver focal_prior_solver = FocalPriorSolver::kP3P;
};

// What one estimate is given besides the settings, which stay as they were set: the query's
// seed, deadlines, gravity prior and image size.
struct PoseContext {
  // RANSAC's seed and its latency budget: no new sample once the deadline has passed.
  RansacRun ransac;
  // The final refinement is skipped once this has passed (the result says so).
  Deadline refine_deadline;
  // The gravity direction in the camera and the model frame, known before the pose (see above).
  // An invalid prior (GravityPriorError) fails the estimate with failure_reason set.
  std::optional<GravityPrior> gravity;
  // Uncalibrated cameras: the image diagonal for the focal bounds' defaults, pixels; <= 0:
  // twice the largest distance of an image point from the principal point (the points'
  // extent, at most the true diagonal).
  double image_diagonal_px = 0.0;
};

struct AbsolutePoseResult {
  bool success = false;        // num_inliers >= min_inliers
  std::string failure_reason;  // empty on success, e.g. "best pose has 9 inliers < 12"
  // cam_from_world of the best pose found; meaningful whenever num_inliers > 0, even when
  // success is false (too few inliers).
  CameraPose pose;
  double focal_length_px = 0.0;  // the given focal length, or the estimated one
  // Uncalibrated cameras: the estimated SIMPLE_RADIAL distortion k (0 when not refined).
  double radial_distortion = 0.0;
  std::vector<char> inliers;  // per correspondence: 1 if in front, error < max_error_px
  int num_inliers = 0;
  RansacStats stats;                        // of the RANSAC run (before the final refinement)
  bool refined = false;                     // the final refinement was applied
  bool refinement_skipped = false;          // PoseContext::refine_deadline had passed
  int camera_refinement_rounds = 0;         // uncalibrated: refinement rounds kept
  double mean_reprojection_error_px = 0.0;  // over the inliers
  // Uncalibrated, refined and successful: how well the focal length and the depth are told
  // apart on the final inliers (refine_pose.h).
  std::optional<FocalDepth> focal_depth;
  // On success: the pose's covariance on the final inliers under the final refinement's
  // problem (refine_pose.h), at the reported pose, refined or not; and k's standard deviation
  // when k was refined.
  std::optional<PoseCovariance> covariance;
  std::optional<double> distortion_std;
  // With a gravity prior: the angle between the reported pose's R * in_world and in_camera.
  double gravity_angle_deg = 0.0;
  // Known focal length with a gravity prior: GravityP2P's best pose had fewer than min_inliers
  // inliers and P3P ran after it (stats then counts the iterations and refinements of both
  // runs; the rest of stats is the kept model's).
  bool gravity_fallback = false;
};

// Known focal length. normalized_points: undistorted image points on the normalised image
// plane (x/z, y/z), i.e. (pixel - principal point) / focal for a pinhole camera;
// focal_length_px converts the pixel threshold and errors (for fx != fy, use their mean).
AbsolutePoseResult EstimateAbsolutePose(std::span<const Eigen::Vector2d> normalized_points,
                                        std::span<const Eigen::Vector3d> points3D,
                                        double focal_length_px,
                                        const AbsolutePoseOptions& options = {},
                                        const PoseContext& context = {});

// Unknown focal length (square pixels, principal point known): P4Pf in RANSAC, then the
// uncalibrated refinement. centered_pixels: pixel minus principal point, as observed (the
// refinement estimates the radial distortion).
AbsolutePoseResult EstimateAbsolutePoseUnknownFocal(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    const AbsolutePoseOptions& options = {}, const PoseContext& context = {});

// A focal length prior (EXIF, a user's guess): RANSAC as options.focal_prior_solver says, then
// the uncalibrated refinement, which frees the focal length and k.
AbsolutePoseResult EstimateAbsolutePoseFocalPrior(std::span<const Eigen::Vector2d> centered_pixels,
                                                  std::span<const Eigen::Vector3d> points3D,
                                                  double prior_focal_length_px,
                                                  const AbsolutePoseOptions& options = {},
                                                  const PoseContext& context = {});

}  // namespace cwloc
