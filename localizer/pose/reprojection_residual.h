#pragma once

#include <Eigen/Core>

namespace cwloc {

// The residuals of the final refinement's two camera models (refine_pose.h), written once for
// both refiners: Ceres evaluates them on its Jets, the builtin Levenberg-Marquardt on doubles
// (refine_pose_builtin.cc adds their derivatives). point_cam: the point in camera coordinates,
// z > 0; pixel: the observation minus the principal point.

// Pinhole: f (x / z, y / z) - pixel.
template <typename T>
void PinholeResidual(const T* point_cam, const T& focal, const Eigen::Vector2d& pixel,
                     T* residual) {
  residual[0] = focal * point_cam[0] / point_cam[2] - T(pixel(0));
  residual[1] = focal * point_cam[1] / point_cam[2] - T(pixel(1));
}

// SIMPLE_RADIAL, RadialCamera::Project(point_cam) - pixel: f (1 + k (u^2 + v^2)) (u, v) - pixel
// with (u, v) = (x / z, y / z).
template <typename T>
void RadialResidual(const T* point_cam, const T& focal, const T& k, const Eigen::Vector2d& pixel,
                    T* residual) {
  const T u = point_cam[0] / point_cam[2];
  const T v = point_cam[1] / point_cam[2];
  const T scale = focal * (T(1.0) + k * (u * u + v * v));
  residual[0] = scale * u - T(pixel(0));
  residual[1] = scale * v - T(pixel(1));
}

}  // namespace cwloc
