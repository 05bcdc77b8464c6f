#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <variant>

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

// A pose from a file's or the API's numbers (a rig's cam_from_rig, a VIO motion): a quaternion
// (w, x, y, z) of unit length within 1e-3, then normalised, and a finite translation; else why
// not, for the caller to say where the numbers came from.
std::variant<CameraPose, std::string> PoseFromParts(const std::array<double, 4>& rotation_wxyz,
                                                    const std::array<double, 3>& translation);

}  // namespace cwloc
