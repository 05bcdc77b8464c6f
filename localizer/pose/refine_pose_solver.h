#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>

#include "localizer/pose/refine_pose.h"
#include "robust/gravity_prior.h"

namespace cwloc {

// What the two refiners of refine_pose.h share: the problem as data and the parameters as
// Ceres' parameter blocks, the rotation a unit quaternion in Ceres' (w, x, y, z) order.

struct RefinementProblem {
  std::span<const Eigen::Vector2d> pixels;  // centred
  std::span<const Eigen::Vector3d> points3D;
  std::span<const uint32_t> indices;
  // The residual (reprojection_residual.h): RadialResidual, else PinholeResidual.
  bool radial = false;
  bool refine_focal_length = false;
  bool refine_radial_distortion = false;  // radial only
  double loss_scale_px = 0.0;             // Cauchy scale a; <= 0: plain least squares
  int max_iterations = 50;
  // One more residual block, on the rotation only and without the loss:
  // weight * (R in_world - in_camera), pixels.
  std::optional<GravityConstraint> gravity;
};

struct RefinementParameters {
  double q_wxyz[4] = {1.0, 0.0, 0.0, 0.0};
  double t[3] = {0.0, 0.0, 0.0};
  double focal = 0.0;
  double k = 0.0;  // radial only
};

// Minimise the problem from *parameters. Return whether the solution is usable (converged or
// out of iterations, Ceres' IsSolutionUsable()) and only then overwrite *parameters; fill
// *summary's iterations and costs either way.
bool RefineWithCeres(const RefinementProblem& problem, RefinementParameters* parameters,
                     PoseRefinementSummary* summary);
bool RefineWithBuiltin(const RefinementProblem& problem, RefinementParameters* parameters,
                       PoseRefinementSummary* summary);

// The problem at `parameters` (a solution), in the builtin refiner's tangent space (rotation
// increment, t, then f and k when refined), as the two covariances of refine_pose.cc need it:
// the robust cost's exact Hessian H and the sum S of the points' gradient outer products
// (Huber's empirical sandwich H^-1 S H^-1); D the points' J^T J without loss weights, P the
// gravity prior's information, and over the points the sums of rho'^2 |r|^2 and of the mean
// curvature rho' + rho'' |r|^2 of 0.5 rho(|r|^2) and its square (Huber's covariance with one
// noise variance). False where the problem cannot be evaluated (a point behind the camera, a
// non-finite value).
struct Linearization {
  Eigen::MatrixXd hessian;
  Eigen::MatrixXd scores;
  Eigen::MatrixXd design;
  Eigen::MatrixXd prior;
  double squared_scores = 0.0;
  double curvature = 0.0;
  double squared_curvature = 0.0;
};
bool LinearizeWithBuiltin(const RefinementProblem& problem, const RefinementParameters& parameters,
                          Linearization* out);

// Huber's covariance of an M-estimator's parameters with one pixel noise variance estimated
// from the residuals (refine_pose.cc says how), from the design, prior and sums of `at` over
// num_points points of two residuals each; the rig's refinement (rig_pose.h) uses it too.
// Empty when there are no more residuals than parameters or the information is singular.
std::optional<Eigen::MatrixXd> HuberCovariance(const Linearization& at, size_t num_points);

}  // namespace cwloc
