#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cwloc::eval {

// A COLMAP world-to-camera pose: X_cam = R(qvec) X_world + tvec.
struct Pose {
  Eigen::Quaterniond qvec = Eigen::Quaterniond::Identity();  // normalized
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();

  // The camera centre in world coordinates, -R^T t.
  Eigen::Vector3d Center() const;
};

// Distance between the camera centres, in model units.
double PositionError(const Pose& estimate, const Pose& truth);

// Angle of R_est R_gt^T in degrees, in [0, 180]. Computed as 2 atan2(|v|, |w|) of the
// relative quaternion, which stays accurate for small angles where acos((tr - 1) / 2) does not.
double RotationErrorDeg(const Pose& estimate, const Pose& truth);

}  // namespace cwloc::eval
