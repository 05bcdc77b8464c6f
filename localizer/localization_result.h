#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "localizer/localizer_options.h"
#include "localizer/query.h"

namespace cwloc {

struct RankedImage {
  uint32_t image_id = 0;
  std::string name;
  uint32_t votes = 0;
};

// A RANSAC inlier of the reported pose: which query feature saw which 3D point of the index.
struct InlierMatch {
  uint32_t feature = 0;  // row of the query's keypoints and descriptors
  uint32_t point = 0;    // row of the index's points
};

// Wall-clock seconds per pipeline stage.
struct StageTimes {
  double extraction = 0;     // a photo's decoding and SIFT extraction; 0 for given features
  double forward_knn = 0;    // kd-forest searches of the query features
  double ratio_test = 0;     // cluster-wise ratio tests
  double query_tree = 0;     // building the kd-forest over the query features
  double back_matching = 0;  // prioritized back-matching and co-visibility votes
  double pose = 0;           // LO-RANSAC with the minimal solvers, then the final refinement
  double total = 0;
};

// A localized camera on the globe, when the index is georeferenced (docs/geo.md).
struct GeoPose {
  double latitude_deg = 0;
  double longitude_deg = 0;
  double height_m = 0;                 // ellipsoidal
  std::array<double, 3> enu{0, 0, 0};  // metres in the index's ENU frame
  double heading_deg = 0;              // of the optical axis, clockwise from true north
  double pitch_deg = 0;                // above the horizon
  double roll_deg = 0;
};

// The query's priors as given, and what they did.
struct PriorUse {
  std::optional<PositionPrior> position;
  uint32_t clusters_in_radius = 0;  // clusters with a camera within the position prior
  std::optional<std::array<double, 3>> gravity;
  // Angle between the prior gravity and the localized pose's; set when both exist.
  std::optional<double> gravity_error_deg;
};

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
  // An estimated focal length: how well it is told apart from the depth (refine_pose.h).
  std::optional<FocalDepthUncertainty> focal_depth;
  uint32_t num_features = 0;
  uint32_t features_searched = 0;
  uint32_t forward_matches = 0;
  uint32_t back_matches = 0;
  uint32_t correspondences = 0;  // unique 2D-3D pairs given to RANSAC
  uint32_t num_inliers = 0;
  double inlier_ratio = 0;
  uint32_t ransac_iterations = 0;
  uint32_t back_matched_clusters = 0;  // JSON: back_matched_images
  bool guided = false;                 // back-matching was guided by a pose hypothesis
  // With a latency budget (LocalizerOptions::budget_ms): the stages it cut short, in order
  // ("forward", "back_matching", "ransac", "refinement").
  std::vector<std::string> budget_cut;
  std::vector<InlierMatch> inliers;  // on success, in feature order
  std::vector<RankedImage> ranked_images;
  std::optional<GeoPose> geo;  // on success with a georeferenced index
  // On success (refine_pose.h), and with a georeferenced index the centre's covariance in
  // square metres in the local east-north-up frame at the camera.
  std::optional<PoseCovariance> covariance;
  std::optional<Eigen::Matrix3d> enu_position_covariance;
  PriorUse priors;
  std::optional<PhotoInfo> photo;
  StageTimes times;
};

}  // namespace cwloc
