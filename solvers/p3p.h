#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "solvers/camera_pose.h"

namespace cwloc {

// Perspective-three-point for a calibrated camera: the poses (cam_from_world) under which the
// three world points lie on the three camera rays at positive depth, lambda_i * bearing_i =
// R * point_i + t.
//
// Method: Lambda Twist, M. Persson and K. Nordberg, "Lambda Twist: An Accurate Fast Robust
// Perspective Three Point (P3P) Solver", ECCV 2018. The three distance constraints on the
// depths are combined into a pencil of conics; one degenerate member (a root of a cubic) splits
// into two lines, each giving at most two depth triples; each triple is polished with
// Gauss-Newton before the rotation is recovered from the two triangles.
//
// Preconditions: bearings have unit length (e.g. [x/z, y/z, 1].normalized()) and are pairwise
// distinct; the world points are distinct and not collinear. Degenerate or near-degenerate
// input (collinear points, a camera very far away, a tiny triangle) gives fewer, possibly zero,
// solutions but never a non-finite pose.
//
// Clears *poses, fills it with the up to four solutions and returns their number.
int P3P(const std::array<Eigen::Vector3d, 3>& bearings,
        const std::array<Eigen::Vector3d, 3>& points, std::vector<CameraPose>* poses);

}  // namespace cwloc
