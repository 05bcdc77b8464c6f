#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>

#include "localizer/pose/gravity_prior.h"
#include "localizer/pose/refine_pose.h"

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
// increment, t, then f and k when refined): the exact Hessian H of the robust cost and the sum
// S of the points' gradient outer products, whose sandwich H^-1 S H^-1 is the M-estimator's
// covariance (Huber's; it holds whatever the pixel noise's scale against the loss's). False
// where the problem cannot be evaluated (a point behind the camera, a non-finite value).
struct Linearization {
  Eigen::MatrixXd hessian;
  Eigen::MatrixXd scores;
};
bool LinearizeWithBuiltin(const RefinementProblem& problem, const RefinementParameters& parameters,
                          Linearization* out);

}  // namespace cwloc
