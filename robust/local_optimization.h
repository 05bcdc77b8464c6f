#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>

#include "robust/gravity_prior.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// A small Levenberg-Marquardt on reprojection error for RANSAC's local optimisation steps,
// cheap enough for the many calls RANSAC makes (the final refinement is refine_pose.h's). The
// rotation is updated on the left, R <- exp([w]x) R, translation and focal length additively;
// damping is Marquardt's (scaled by the diagonal of J^T J).
struct LocalOptimizationOptions {
  int max_iterations = 10;  // LM iterations (accepted or rejected steps)
  // RANSAC's local optimisation fits at most this many of a hypothesis' inliers, spread evenly
  // over them (0: all). Lebeda et al. bound the least-squares set the same way: the refit only
  // has to rank hypotheses, and the final refinement uses every inlier. With thousands of
  // inliers it was most of the pose stage.
  uint32_t max_points = 256;
  // Cauchy loss scale in residual units: rho(r^2) = s^2 log(1 + r^2 / s^2). 0: plain least
  // squares.
  double loss_scale = 0.0;
  // A gravity prior: one more residual weight (R in_world - in_camera), never robustified, with
  // the weight in residual units (normalised image coordinates or pixels) per radian.
  std::optional<GravityConstraint> gravity;
};

// Minimises sum_i rho(|pi(R X_i + t) - x_i|^2) over i in `indices` (plus the gravity residual's
// square), with pi(X) = X.xy / X.z and x_i in normalised image coordinates (a calibrated
// camera). Points behind the camera are skipped. Returns the number of iterations run.
int OptimizePose(std::span<const Eigen::Vector2d> points2D,
                 std::span<const Eigen::Vector3d> points3D, std::span<const uint32_t> indices,
                 const LocalOptimizationOptions& options, CameraPose* pose);

// The same with an unknown focal length: residual f * pi(R X_i + t) - p_i with p_i relative to
// the principal point (pixels), over the pose and f.
int OptimizePoseAndFocal(std::span<const Eigen::Vector2d> centered_pixels,
                         std::span<const Eigen::Vector3d> points3D,
                         std::span<const uint32_t> indices, const LocalOptimizationOptions& options,
                         CameraPose* pose, double* focal_length);

}  // namespace cwloc
