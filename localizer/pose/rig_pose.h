#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "localizer/pose/absolute_pose.h"
#include "localizer/pose/refine_pose.h"
#include "robust/ransac.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// Robust absolute pose of a generalized camera: a rig of cameras with known relative poses
// (COLMAP 3.12's rigs), or a window of video frames whose relative poses VIO knows, possibly
// up to one scale. The transforms, as COLMAP names them: rig_from_world (X_rig = R X_world +
// t) is what is estimated; camera c sits on the rig at cam_from_rig (X_cam = R_c X_rig + s
// t_c, s = 1 unless the scale is unknown); its image's pose is cam_from_world = cam_from_rig *
// rig_from_world.
//
// Pipeline, as EstimateAbsolutePose's for one camera (absolute_pose.h): LO-RANSAC over the
// correspondences of every image with GeneralizedP3P (or GeneralizedP3PScale) hypotheses
// scored by each image's reprojection error in its own pixels, every new best hypothesis
// refined by Levenberg-Marquardt on its inliers; then the final refinement of the rig pose (and
// the scale, and each focal-prior camera's f and k) on every inlier with the Cauchy loss, kept
// unless it loses more than 2 % of the inliers; the inliers recomputed; the covariance.

// One camera of the rig.
struct RigCamera {
  CameraPose cam_from_rig;  // the translation at unit scale when the scale is unknown
  // Its pixels: f (1 + k |u|^2) u for u = x / z in the camera, measured from the principal
  // point. A known camera's observations are undistorted by its model first (k = 0, f its
  // mean focal length).
  RadialCamera camera;
  // A focal prior: f and k are refined with the pose (from 12 inliers in this camera).
  bool refine_intrinsics = false;
};

// One 2D-3D correspondence of a camera of the rig.
struct RigObservation {
  uint32_t camera = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // minus the principal point
  Eigen::Vector3d point3D = Eigen::Vector3d::Zero();
};

// A rig's pose, and the scale of its translations.
struct RigPose {
  CameraPose rig_from_world;
  double scale = 1.0;

  // Camera c's cam_from_world under this pose.
  CameraPose CameraFromWorld(const CameraPose& cam_from_rig) const;
};

struct RigPoseResult {
  bool success = false;
  std::string failure_reason;         // empty on success
  RigPose pose;                       // meaningful whenever num_inliers > 0
  std::vector<RadialCamera> cameras;  // as refined (focal-prior cameras), else as given
  std::vector<char> inliers;          // per observation
  int num_inliers = 0;
  std::vector<uint32_t> inliers_per_camera;
  RansacStats stats;
  bool refined = false;  // the final refinement was kept
  double mean_reprojection_error_px = 0.0;
  // On success: the rig pose's covariance over (theta, C) as PoseCovariance defines it for a
  // camera (the rig's orientation error in the model frame and its origin), with the scale and
  // intrinsics marginalised out; empty when the problem leaves it undetermined.
  std::optional<PoseCovariance> covariance;
  std::optional<double> scale_std;  // unknown scale, with the covariance
};

// options: the single-camera pose stage's (threshold, min_inliers, RANSAC, loss scale);
// context: RANSAC's seed and deadline (the gravity prior is not used). An unknown scale needs
// inliers in two cameras, three of the sample's four in one.
RigPoseResult EstimateRigPose(std::span<const RigCamera> cameras,
                              std::span<const RigObservation> observations, bool unknown_scale,
                              const AbsolutePoseOptions& options, const PoseContext& context = {});

// The final refinement's problem: minimises sum_i rho(|r_i|^2) of the observations `indices`,
// r_i = camera.Project(cam_from_world(X_i)) - pixel_i, over the rig's orientation and origin,
// the scale when refine_scale, and the intrinsics of cameras with refine_intrinsics; Cauchy
// loss with scale loss_scale_px (<= 0: least squares). Levenberg-Marquardt with Marquardt's
// damping. Updates *pose and *cameras and returns true when it converged to a finite pose
// with every point in front and positive focal lengths.
struct RigRefinementOptions {
  double loss_scale_px = 0.0;
  int max_iterations = 50;
  bool refine_scale = false;
  bool refine_intrinsics = true;  // of the cameras that ask for it
};
bool RefineRigPose(std::span<const RigCamera> rig, std::span<const RigObservation> observations,
                   std::span<const uint32_t> indices, const RigRefinementOptions& options,
                   RigPose* pose, std::vector<RadialCamera>* cameras);

}  // namespace cwloc
