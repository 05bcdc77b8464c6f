#pragma once

#include <optional>
#include <string>
#include <vector>

#include "localizer/localization_result.h"
#include "localizer/localizer.h"
#include "localizer/pose/camera_pose.h"
#include "localizer/pose/refine_pose.h"
#include "localizer/query.h"

namespace cwloc {

// Several images with known relative poses localized as one generalized camera
// (docs/algorithm.md, "Rigs and multi-frame queries"): a frame of a multi-camera rig (COLMAP
// 3.12's rig_config.json) or a window of video frames whose relative poses VIO gives.
//
// Which way the transforms go, as COLMAP names them: cam_from_rig takes a point from the rig's
// frame to the image's camera (X_cam = R X_rig + t); the estimate is rig_from_world; an
// image's pose is cam_from_world = cam_from_rig * rig_from_world. The reference camera of a
// COLMAP rig has the identity cam_from_rig, so that rig_from_world is its pose.

struct RigImage {
  // Its camera must be known or a focal prior (an unknown focal length cannot join a rig).
  Query query;
  CameraPose cam_from_rig;  // translation at unit scale when RigQuery::unknown_scale
};

struct RigQuery {
  std::string name;              // the frame's
  std::vector<RigImage> images;  // the first is the reference camera
  // The cam_from_rig translations are known up to one scale (VIO without a metric map): the
  // pose stage estimates it (rig_pose.h).
  bool unknown_scale = false;
};

struct RigImageResult {
  // The paper's matching on the image (forward matching, voting, back-matching; no pose
  // stage): its counts, and its correspondences (kept_correspondences), which the rig pools.
  LocalizationResult matched;
  CameraPose cam_from_rig;
  QueryCamera camera;  // as the rig's refinement left it (a focal prior's f and k refined)
  // On the rig's success: cam_from_rig * rig_from_world, and the rig's inliers in this image.
  std::optional<CameraPose> cam_from_world;
  uint32_t num_inliers = 0;
  std::vector<InlierMatch> inliers;
};

struct RigLocalizationResult {
  std::string name;
  bool success = false;
  std::string failure_reason;  // empty on success
  CameraPose rig_from_world;
  bool unknown_scale = false;
  double scale = 1.0;               // estimated when unknown_scale
  std::optional<double> scale_std;  // with the covariance
  uint32_t num_inliers = 0;         // over all images
  uint32_t correspondences = 0;     // pooled 2D-3D pairs given to RANSAC
  uint32_t ransac_iterations = 0;
  bool refined = false;
  double mean_reprojection_error_px = 0.0;
  // The rig pose's covariance (rig_pose.h), widened by the index's calibration for the
  // reference image's calibration mode when the index has one.
  std::optional<PoseCovariance> covariance;
  std::optional<CovarianceScales> covariance_calibration;
  // On a georeferenced index: the reference camera on the globe.
  std::optional<GeoPose> geo;
  std::vector<RigImageResult> images;
  double seconds_images = 0;    // the images' matching
  double seconds_rig_pose = 0;  // the rig's RANSAC, refinement and covariance
  double seconds_total = 0;     // with the images' photo extraction
};

// Matches each image (its correspondences), then fits the rig's pose to all of them. Throws
// InputError naming the frame for a frame that cannot be processed: no images, an image
// without a known camera or focal prior, a cam_from_rig that is not finite or whose quaternion
// is not of unit length, an unknown scale with one image.
RigLocalizationResult LocalizeRig(const Localizer& localizer, const RigQuery& query,
                                  const LocalizerOptions& options);

}  // namespace cwloc
