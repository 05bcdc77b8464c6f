#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "solvers/camera_pose.h"

namespace cwloc {

// Absolute pose of a calibrated camera from two 2D-3D correspondences and a known vertical
// direction ("up-P2P"): the poses (cam_from_world, R, t) with R * gravity_in_world =
// gravity_in_camera under which both world points lie on their camera rays at positive depth,
// lambda_i * bearing_i = R * point_i + t, lambda_i > 0.
//
// Method (the problem of Kukelova, Bujnak and Pajdla, "Closed-form solutions to the minimal
// absolute pose problems with known vertical direction", ACCV 2010, and of Sweeney et al.,
// "Efficient computation of absolute pose for gravity-aware augmented reality", ISMAR 2015;
// our own elimination): rotations B_c, B_w take the gravity of each frame to the z axis, so
// R = B_c^T R_z(theta) B_w with one unknown angle about z. In the aligned frames (b'_i = B_c b_i,
// X'_i = B_w X_i, t' = B_c t) the two ray equations lambda_i b'_i = R_z X'_i + t' lose t' by
// subtraction: lambda_1 b'_1 - lambda_2 b'_2 = R_z (X'_1 - X'_2). Both depths drop out on the
// normal n = b'_1 x b'_2 of the plane of the two rays: n . R_z (X'_1 - X'_2) = 0, one equation
// alpha cos(theta) + beta sin(theta) + gamma = 0 that is linear in (cos, sin, 1). Its line meets
// the unit circle in at most two points; for each, the depths follow from cross products with
// the bearings and t' from either ray. No step divides by anything but |n|^2 and
// |(alpha, beta)|, and both are checked against the scale of the data first.
//
// Degenerate input gives no solution (never a non-finite pose): identical or opposite rays,
// coincident world points, two world points on one vertical line, or two rays whose plane is
// horizontal (in these last cases the rotation about gravity is not determined). Near such
// configurations the solutions are finite but inaccurate. Gravity may point along any camera
// axis, including the optical axis (a camera looking straight down or up).
//
// Preconditions: bearings and both gravity directions have unit length.
//
// Clears *poses, fills it with the up to two solutions and returns their number.
int GravityP2P(const std::array<Eigen::Vector3d, 2>& bearings,
               const std::array<Eigen::Vector3d, 2>& points,
               const Eigen::Vector3d& gravity_in_camera, const Eigen::Vector3d& gravity_in_world,
               std::vector<CameraPose>* poses);

}  // namespace cwloc
