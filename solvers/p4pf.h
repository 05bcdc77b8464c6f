#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "solvers/camera_pose.h"

namespace cwloc {

// Absolute pose and focal length from four 2D-3D correspondences (P4Pf): the poses
// (cam_from_world) and focal lengths f with f * (X_c.x / X_c.z, X_c.y / X_c.z) = points2D[i]
// for X_c = R * points3D[i] + t.
//
// points2D are image points relative to the principal point (pixel minus principal point, in
// pixels or any pre-scaled unit; the focal lengths come out in the same unit), square pixels,
// no distortion.
//
// Method: the 8 projection equations are linear in the entries of the 3x4 camera matrix
// P ~ diag(fx, fy, 1) [R | t], which thus lies in a 4-dimensional null space (a DLT with four
// points). Requiring the three rows of P's left 3x3 block to be mutually orthogonal gives three
// quadrics in the three null space coordinates with up to 8 solutions (the formulation with
// independent fx, fy of Kukelova, Heller and Fitzgibbon, "Efficient Intersection of Three
// Quadrics and Applications in Computer Vision", CVPR 2016; cf. the general P4Pf of
// Bujnak, Kukelova and Pajdla, "A general solution to the P4P problem for camera with unknown
// focal length", CVPR 2008, which the cluster-wise ratio test paper uses). The quadrics are
// solved with our own hidden-variable resultant (three_quadrics.h: a degree-8 polynomial in one
// unknown, its real roots, the other two unknowns from a null vector). With exact data the true
// solution has fx = fy; solutions whose aspect ratio fx/fy is off by more than a factor 2, or that
// put a point behind the camera, are dropped, and f = (fx + fy) / 2 for the rest.
//
// Four exactly coplanar points make that elimination singular (the null space then holds the
// homography plus the free third column of P); nearly coplanar ones are still solved
// accurately. For flat configurations (thickness below 10% of the extent) the solver also,
// and for coplanar ones (below 1e-10) only, decomposes the plane-to-image homography
// H ~ diag(f, f, 1) [r1 r2 t] with Zhang's constraints r1.r2 = 0, |r1| = |r2|, which are
// linear in 1/f^2. A fronto-parallel plane leaves f unobservable and gives no solution.
//
// Preconditions: no three of the four world points collinear, image points distinct.
//
// Clears the outputs, fills them with the solutions sorted by their RMS reprojection error on
// the four points (best first) and returns their number (0..9).
int P4Pf(const std::array<Eigen::Vector2d, 4>& points2D,
         const std::array<Eigen::Vector3d, 4>& points3D, std::vector<CameraPose>* poses,
         std::vector<double>* focal_lengths);

}  // namespace cwloc
