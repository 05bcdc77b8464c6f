#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "base/chi_square.h"
#include "base/enum_names.h"
#include "results/camera.h"
#include "results/pose.h"
#include "robust/gravity_prior.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// Final non-linear refinement of an absolute pose (and optionally the camera's focal length and
// radial distortion): sum_i rho(|f * pi(R X_i + t) - p_i|^2) over the given correspondences,
// with a Cauchy loss rho(s) = a^2 log(1 + s / a^2) so that the remaining outliers among the
// inliers of a 6 px threshold pull little, plus |w (R g_world - g_camera)|^2 with a gravity
// prior (PoseRefinementOptions::gravity). Two solvers minimise the same cost to the same
// minimum (docs/algorithm.md, section 4):
//   - kCeres: Ceres' Levenberg-Marquardt, the rotation a Ceres quaternion on
//     ceres::QuaternionManifold (only in builds with -DCWLOC_WITH_CERES=ON);
//   - kBuiltin: cwloc's own Levenberg-Marquardt in Eigen (refine_pose_builtin.cc), which
//     follows Ceres' trust-region rules step for step, so that a device build need not link
//     Ceres and its dependencies (glog, gflags, SuiteSparse, LAPACK, BLAS).
enum class PoseRefiner { kCeres, kBuiltin };

// The names the CLI takes and the JSON reports, in enum order.
inline constexpr std::array<std::string_view, 2> kPoseRefinerNames = {"ceres", "builtin"};

inline std::string_view PoseRefinerName(PoseRefiner refiner) {
  return kPoseRefinerNames[static_cast<size_t>(refiner)];
}

inline std::optional<PoseRefiner> ParsePoseRefiner(std::string_view name) {
  return ParseEnumName<PoseRefiner>(kPoseRefinerNames, name);
}

// Whether this build has the refiner (kCeres needs -DCWLOC_WITH_CERES=ON).
bool PoseRefinerAvailable(PoseRefiner refiner);

struct PoseRefinementOptions {
  double loss_scale_px = 1.0;        // Cauchy scale a, pixels; <= 0: plain least squares
  bool refine_focal_length = false;  // else the focal length is held constant
  int max_iterations = 50;           // Levenberg-Marquardt iterations
  // RefinePoseAndCamera only: also refine the radial distortion k (else held constant).
  bool refine_radial_distortion = false;
  // The builtin solver in every build: the same poses as Ceres (which stays the reference it is
  // tested against), 6 to 10 times faster, and the same on devices. Asking for one this build
  // does not have throws cwloc::InputError.
  PoseRefiner refiner = PoseRefiner::kBuiltin;
  // A gravity prior as one more residual block, weight (R in_world - in_camera) with the weight
  // in pixels per radian (robust/gravity_prior.h); none when absent.
  std::optional<GravityConstraint> gravity;
};

// Both refiners fill it with Ceres' conventions.
struct PoseRefinementSummary {
  // The solver converged or ran out of iterations (Ceres' IsSolutionUsable()) and the camera
  // is sane (f > 0, k finite).
  bool usable = false;
  int iterations = 0;         // Ceres' summary.iterations.size(): iteration 0 counts
  double initial_cost = 0.0;  // robust cost, 0.5 * sum rho, pixels^2
  double final_cost = 0.0;
};

// centered_pixels: pixel minus principal point (for a known focal length, normalised image
// coordinates times f); indices: the correspondences to use (typically RANSAC's inliers, all
// in front of the camera). Updates *pose and *focal_length_px in place when the solver reports
// a usable solution and returns whether it did. Needs at least 4 correspondences (5 with focal).
bool RefinePose(std::span<const Eigen::Vector2d> centered_pixels,
                std::span<const Eigen::Vector3d> points3D, std::span<const uint32_t> indices,
                const PoseRefinementOptions& options, CameraPose* pose, double* focal_length_px,
                PoseRefinementSummary* summary = nullptr);

// A COLMAP SIMPLE_RADIAL camera whose principal point is the origin of the centred pixels:
// (u, v) = (x / z, y / z), d = 1 + k (u^2 + v^2), centred pixel = f d (u, v).
struct RadialCamera {
  double focal_length_px = 0.0;
  double k = 0.0;

  // The centred pixel of a point in camera coordinates (z > 0).
  Eigen::Vector2d Project(const Eigen::Vector3d& point_cam) const {
    const Eigen::Vector2d uv = point_cam.hnormalized();
    return focal_length_px * (1.0 + k * uv.squaredNorm()) * uv;
  }
};

// RefinePose for a RadialCamera: the pose, and the focal length and k as the options ask, under
// the same Cauchy loss; the residual is camera.Project(R X_i + t) - p_i. Updates *pose and
// *camera when the solver reports a usable solution with a positive focal length. Needs at
// least 4 correspondences, one more per refined intrinsic.
bool RefinePoseAndCamera(std::span<const Eigen::Vector2d> centered_pixels,
                         std::span<const Eigen::Vector3d> points3D,
                         std::span<const uint32_t> indices, const PoseRefinementOptions& options,
                         CameraPose* pose, RadialCamera* camera,
                         PoseRefinementSummary* summary = nullptr);

// How well a refined uncalibrated camera's focal length is told apart from its distance to the
// scene. A narrow view (a telephoto shot, a far facade) sees the scene almost as an affine
// camera does: the pixels fix f / depth, so a longer focal length and a camera further back
// explain them nearly as well, and the two estimates are strongly correlated. From the
// covariance of the refinement's parameters at its solution, H^-1 S H^-1 with H the robust
// cost's Hessian and S the sum of the points' gradient outer products (Huber's empirical
// sandwich: each point's noise its own, which on real photos gives f a larger spread than
// PoseCovariance's; the weak-constraint rule below was measured with it).
// (FocalDepth in results/camera.h.)
// A pose is reported as weakly constrained when its focal length is uncertain by more than
// kWeakRelativeFocalStd (1 sigma, relative) and that uncertainty moves the camera along its axis
// (|correlation| >= kWeakFocalDepthCorrelation): the depth is then uncertain by about as much,
// relative to the scene's distance. The correlation alone is no verdict: a full-frame photo
// with thousands of inliers can have 0.99 and a focal length known to 0.03 %.
inline constexpr double kWeakRelativeFocalStd = 0.005;
inline constexpr double kWeakFocalDepthCorrelation = 0.95;

inline bool WeaklyConstrained(const FocalDepth& uncertainty, double focal_length_px) {
  return uncertainty.focal_std_px > kWeakRelativeFocalStd * focal_length_px &&
         std::abs(uncertainty.correlation) >= kWeakFocalDepthCorrelation;
}

// How well a refined pose is known (PoseCovariance in results/pose.h): the covariance of the
// refinement's parameters (Huber's for an M-estimator with one pixel noise variance estimated
// from the residuals, calibrated on synthetic problems; refine_pose.cc) with the focal length and
// k marginalised out, over (theta, C): theta the rotation vector, radians in the model frame, of
// the camera orientation's error (world_from_cam_estimate = exp([theta]x) world_from_cam_true)
// and C the camera centre, model units. Its 6 x 6 block as a matrix:
inline Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> PoseBlock(
    const PoseCovariance& covariance) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(covariance.pose.data());
}
inline Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> PoseBlock(
    PoseCovariance& covariance) {
  return Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(covariance.pose.data());
}
inline Eigen::Matrix3d PositionBlock(const PoseCovariance& covariance) {
  return PoseBlock(covariance).bottomRightCorner<3, 3>();
}

// The radius of the smallest sphere around the estimate that holds the 95 % ellipsoid of a
// position covariance: sqrt(kChiSquare3Dof95 * its largest eigenvalue).
double Radius95(const Eigen::Matrix3d& covariance);

// The pose covariance of the problem RefinePose (radial false; camera.k is then unused) or
// RefinePoseAndCamera (radial) solves with these options, at `pose` and `camera`, with its
// position radius and, when the focal length is refined, its standard deviation; and in
// *distortion_std the standard deviation of k when k is refined. Empty when the problem cannot
// be evaluated there, has no more residuals than parameters, or its Hessian is singular.
std::optional<PoseCovariance> PoseCovarianceAt(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    std::span<const uint32_t> indices, const PoseRefinementOptions& options, const CameraPose& pose,
    const RadialCamera& camera, bool radial, std::optional<double>* distortion_std = nullptr);

// The focal length and depth above for the problem RefinePoseAndCamera solves (options as
// given to it, with refine_focal_length), at `pose` and `camera`, and whether they leave the pose
// weakly constrained; empty when the problem cannot be evaluated there or its Hessian is
// singular.
std::optional<FocalDepth> FocalDepthAt(std::span<const Eigen::Vector2d> centered_pixels,
                                       std::span<const Eigen::Vector3d> points3D,
                                       std::span<const uint32_t> indices,
                                       const PoseRefinementOptions& options, const CameraPose& pose,
                                       const RadialCamera& camera);

}  // namespace cwloc
