#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "solvers/camera_pose.h"

namespace cwloc {

// Minimal solvers for a generalized camera: several cameras fixed to one rig, each ray with its
// own origin. Conventions, as COLMAP 3.12 names them: a camera's pose on the rig is
// cam_from_rig (X_cam = R_c X_rig + t_c), the rig's pose is rig_from_world, so that an image's
// cam_from_world = cam_from_rig * rig_from_world. A ray is given in the rig frame: it starts at
// the camera's centre, origin = -R_c^T t_c, and points along R_c^T bearing.

// A ray of the rig: the points origin + lambda direction, lambda > 0; direction unit length.
struct RigRay {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

// Generalized P3P: the rig poses (rig_from_world) under which the three world points lie on
// the three rays at positive depth, R X_i + t = origin_i + lambda_i direction_i.
//
// Method: the problem of Nister and Stewenius, "A Minimal Solution to the Generalised 3-Point
// Pose Problem", J. Math. Imaging Vis. 27(1), 2007, solved by our own route: the three
// distances between the points, |P_i - P_j| = |X_i - X_j| with P_i = origin_i + lambda_i
// direction_i, are three quadrics in the depths (Grunert's P3P equations, with the origins
// apart), whose at most 8 real solutions SolveThreeQuadrics finds (three_quadrics.h); each
// triple with positive depths gives the rigid motion from the world triangle to the rig's
// (Umeyama, without scale). Rays from one origin (a central camera) give P3P's solutions.
//
// Degenerate input (collinear world points, two equal points, parallel rays through one
// origin) gives fewer, possibly zero, solutions and never a non-finite pose. Clears *poses,
// fills it and returns the number of solutions (0..8).
int GeneralizedP3P(const std::array<RigRay, 3>& rays, const std::array<Eigen::Vector3d, 3>& points,
                   std::vector<CameraPose>* poses);

// A rig whose translations are known up to one scale s (a VIO window without a metric map):
// camera c's cam_from_rig is (R_c, s t_c). The pose of such a rig from four points, three seen
// by one camera and the fourth by another: P3P in the first camera gives its cam_from_world
// (so R = R_a^T R_cam and t = R_a^T (t_cam - s t_a)), and the fourth ray, whose camera depends
// on s linearly, gives s in closed form (the least-squares s of bearing x (A + s B) = 0).
// A documented alternative to the minimal gP4Ps of Ventura et al., "A Minimal Solution to the
// Generalized Pose-and-Scale Problem", CVPR 2014: the same four points, without its Groebner
// basis, at the price of needing three of them in one camera (the rig's RANSAC samples so).
//
// `bearings`: unit rays in their own camera; camera_a holds the first three, camera_b the
// fourth, with unit-scale translations. The fourth ray over-determines s (two equations): a
// solution must put the fourth point within max_fourth_error of its ray (the sine of the
// angle; RANSAC passes its threshold, since a noisy sample misses by its noise), at a positive
// scale and in front of both cameras. A fourth camera whose baseline to the first is parallel
// to the fourth ray does not fix s and gives none. Clears both vectors and returns the number
// of solutions (0..4).
int GeneralizedP3PScale(const std::array<Eigen::Vector3d, 4>& bearings,
                        const std::array<Eigen::Vector3d, 4>& points, const CameraPose& camera_a,
                        const CameraPose& camera_b, double max_fourth_error,
                        std::vector<CameraPose>* poses, std::vector<double>* scales);

}  // namespace cwloc
