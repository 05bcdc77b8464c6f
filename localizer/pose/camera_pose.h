#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cwloc {

// A camera pose as COLMAP stores it: cam_from_world, X_cam = R * X_world + t, with R a unit
// quaternion (w,x,y,z). Eigen keeps the coefficients in memory as x,y,z,w; use w()/x()/y()/z()
// and never coeffs() when writing COLMAP files or Ceres parameter blocks.
struct CameraPose {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  CameraPose() = default;
  CameraPose(const Eigen::Quaterniond& rotation_in, const Eigen::Vector3d& translation_in)
      : rotation(rotation_in), translation(translation_in) {}
  // R must be a rotation matrix (orthonormal, det +1).
  CameraPose(const Eigen::Matrix3d& rotation_matrix, const Eigen::Vector3d& translation_in)
      : rotation(rotation_matrix), translation(translation_in) {}

  Eigen::Matrix3d RotationMatrix() const { return rotation.toRotationMatrix(); }

  // Camera centre in world coordinates, C = -R^T t.
  Eigen::Vector3d Center() const { return -(rotation.conjugate() * translation); }

  // World point to camera coordinates.
  Eigen::Vector3d Apply(const Eigen::Vector3d& point_world) const {
    return rotation * point_world + translation;
  }
};

}  // namespace cwloc
