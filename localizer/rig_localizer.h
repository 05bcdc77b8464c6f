#pragma once

#include <optional>
#include <string>
#include <vector>

#include "localizer/localizer.h"
#include "localizer/pose/refine_pose.h"
#include "localizer/query.h"
#include "results/rig_result.h"
#include "solvers/camera_pose.h"

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

// Matches each image (its correspondences), then fits the rig's pose to all of them. Throws
// InputError naming the frame for a frame that cannot be processed: no images, an image
// without a known camera or focal prior, a cam_from_rig that is not finite or whose quaternion
// is not of unit length, an unknown scale with one image.
RigResult LocalizeRig(const Localizer& localizer, const RigQuery& query,
                      const LocalizerOptions& options);

}  // namespace cwloc
