#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/query.h"
#include "localizer/result_types.h"

namespace cwloc {

// A RANSAC inlier of the reported pose: which query feature saw which 3D point of the index.
struct InlierMatch {
  uint32_t feature = 0;  // row of the query's keypoints and descriptors
  uint32_t point = 0;    // row of the index's points
  uint32_t view = 0;     // the model view (of that point) whose descriptor matched
};

// The query's priors as given, and what they did.
struct PriorUse {
  std::optional<PositionPrior> position;
  uint32_t clusters_in_radius = 0;  // clusters with a camera within the position prior
  std::optional<std::array<double, 3>> gravity;
  // Angle between the prior gravity and the localized pose's; set when both exist.
  std::optional<double> gravity_error_deg;
};

// How a localized query's lens distortion was fitted (the JSON's camera.distortion says why).
enum class DistortionFit {
  kGiven,       // a known camera: its own model and parameters, held fixed
  kEstimated,   // SIMPLE_RADIAL's k refined with the focal length
  kHeldAtZero,  // focal estimated, k left at 0: the refinement did not run or kept no camera
};
inline constexpr std::array<std::string_view, 3> kDistortionFitNames = {"given", "estimated",
                                                                        "held-at-zero"};

struct LocalizationResult {
  std::string name;
  bool success = false;
  std::string failure_reason;  // empty on success
  // COLMAP's cam_from_world: X_cam = R(q) X_world + t; q = (w, x, y, z).
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{0, 0, 0};
  std::array<double, 3> center{0, 0, 0};
  QueryCamera camera;  // as used; the estimated focal when it was unknown
  bool focal_estimated = false;
  DistortionFit distortion_fit = DistortionFit::kGiven;  // on success
  // An estimated focal length: how well it is told apart from the depth (refine_pose.h).
  std::optional<FocalDepthUncertainty> focal_depth;
  // The result's numbers: num_inliers, the match counts, ... (result_fields.inc).
#define CWLOC_RESULT_FIELD(name, type, group, key, help) type name{};
#include "localizer/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  // With a latency budget (LocalizerOptions::budget_ms): the stages it cut short, in order
  // ("forward", "back_matching", "ransac", "refinement").
  std::vector<std::string> budget_cut;
  std::vector<InlierMatch> inliers;  // on success, in feature order
  // RANSAC's input, unique per feature, when LocalizerOptions::keep_correspondences.
  std::vector<FeatureMatch> kept_correspondences;
  std::vector<RankedImage> ranked_images;
  std::optional<GeoPose> geo;  // on success with a georeferenced index
  // On success (refine_pose.h), and with a georeferenced index the centre's covariance in
  // square metres in the local east-north-up frame at the camera.
  std::optional<PoseCovariance> covariance;
  // The index's calibration that `covariance` holds; empty when the index has none for the
  // query's calibration mode (the covariance then knows the keypoints' noise only).
  std::optional<CovarianceScales> covariance_calibration;
  std::optional<Eigen::Matrix3d> enu_position_covariance;
  PriorUse priors;
  std::optional<PhotoInfo> photo;
  std::optional<TrackingInfo> tracking;  // a frame of a sequence
  StageTimes times;
};

}  // namespace cwloc
