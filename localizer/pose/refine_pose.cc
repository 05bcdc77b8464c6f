#include "localizer/pose/refine_pose.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "format/base/error.h"
#include "localizer/pose/refine_pose_solver.h"

namespace cwloc {

bool PoseRefinerAvailable(PoseRefiner refiner) {
#ifdef CWLOC_WITH_CERES
  return refiner == PoseRefiner::kCeres || refiner == PoseRefiner::kBuiltin;
#else
  return refiner == PoseRefiner::kBuiltin;
#endif
}

namespace {

RefinementProblem MakeProblem(std::span<const Eigen::Vector2d> centered_pixels,
                              std::span<const Eigen::Vector3d> points3D,
                              std::span<const uint32_t> indices,
                              const PoseRefinementOptions& options) {
  RefinementProblem problem;
  problem.pixels = centered_pixels;
  problem.points3D = points3D;
  problem.indices = indices;
  problem.refine_focal_length = options.refine_focal_length;
  problem.loss_scale_px = options.loss_scale_px;
  problem.max_iterations = options.max_iterations;
  problem.gravity = options.gravity;
  return problem;
}

// RefinePoseAndCamera's problem: the RadialCamera residual, f and k refined as options ask.
RefinementProblem MakeCameraProblem(std::span<const Eigen::Vector2d> centered_pixels,
                                    std::span<const Eigen::Vector3d> points3D,
                                    std::span<const uint32_t> indices,
                                    const PoseRefinementOptions& options) {
  RefinementProblem problem = MakeProblem(centered_pixels, points3D, indices, options);
  problem.radial = true;
  problem.refine_radial_distortion = options.refine_radial_distortion;
  return problem;
}

RefinementParameters MakeParameters(const CameraPose& pose, double focal, double k) {
  const Eigen::Quaterniond q = pose.rotation.normalized();
  RefinementParameters x;
  x.q_wxyz[0] = q.w();
  x.q_wxyz[1] = q.x();
  x.q_wxyz[2] = q.y();
  x.q_wxyz[3] = q.z();
  for (int i = 0; i < 3; ++i) x.t[i] = pose.translation(i);
  x.focal = focal;
  x.k = k;
  return x;
}

// Runs the chosen refiner; usable also needs a sane camera.
template <typename CameraOk>
bool Solve(const RefinementProblem& problem, PoseRefiner refiner, RefinementParameters* x,
           PoseRefinementSummary* summary, CameraOk camera_ok) {
  PoseRefinementSummary solved;
  bool usable = false;
  switch (refiner) {
    case PoseRefiner::kBuiltin:
      usable = RefineWithBuiltin(problem, x, &solved);
      break;
    case PoseRefiner::kCeres:
#ifdef CWLOC_WITH_CERES
      usable = RefineWithCeres(problem, x, &solved);
      break;
#else
      throw InputError(
          "pose refiner 'ceres': this build has no Ceres (configured with "
          "-DCWLOC_WITH_CERES=OFF); use 'builtin'");
#endif
  }
  solved.usable = usable && camera_ok();
  if (summary != nullptr) *summary = solved;
  return solved.usable;
}

void StorePose(const RefinementParameters& x, CameraPose* pose) {
  pose->rotation =
      Eigen::Quaterniond(x.q_wxyz[0], x.q_wxyz[1], x.q_wxyz[2], x.q_wxyz[3]).normalized();
  pose->translation = Eigen::Vector3d(x.t[0], x.t[1], x.t[2]);
}

}  // namespace

bool RefinePose(std::span<const Eigen::Vector2d> centered_pixels,
                std::span<const Eigen::Vector3d> points3D, std::span<const uint32_t> indices,
                const PoseRefinementOptions& options, CameraPose* pose, double* focal_length_px,
                PoseRefinementSummary* summary) {
  const size_t min_points = options.refine_focal_length ? 5 : 4;
  if (indices.size() < min_points || !(*focal_length_px > 0.0)) return false;
  const RefinementProblem problem = MakeProblem(centered_pixels, points3D, indices, options);
  RefinementParameters x = MakeParameters(*pose, *focal_length_px, 0.0);
  if (!Solve(problem, options.refiner, &x, summary, [&] { return x.focal > 0.0; })) return false;
  StorePose(x, pose);
  *focal_length_px = x.focal;
  return true;
}

bool RefinePoseAndCamera(std::span<const Eigen::Vector2d> centered_pixels,
                         std::span<const Eigen::Vector3d> points3D,
                         std::span<const uint32_t> indices, const PoseRefinementOptions& options,
                         CameraPose* pose, RadialCamera* camera, PoseRefinementSummary* summary) {
  const size_t min_points =
      4 + size_t{options.refine_focal_length} + size_t{options.refine_radial_distortion};
  if (indices.size() < min_points || !(camera->focal_length_px > 0.0)) return false;
  const RefinementProblem problem = MakeCameraProblem(centered_pixels, points3D, indices, options);
  RefinementParameters x = MakeParameters(*pose, camera->focal_length_px, camera->k);
  if (!Solve(problem, options.refiner, &x, summary,
             [&] { return x.focal > 0.0 && std::isfinite(x.k); })) {
    return false;
  }
  StorePose(x, pose);
  camera->focal_length_px = x.focal;
  camera->k = x.k;
  return true;
}

std::optional<FocalDepthUncertainty> FocalDepthUncertaintyAt(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    std::span<const uint32_t> indices, const PoseRefinementOptions& options, const CameraPose& pose,
    const RadialCamera& camera) {
  RefinementProblem problem = MakeCameraProblem(centered_pixels, points3D, indices, options);
  problem.refine_focal_length = true;
  Linearization linear;
  if (!LinearizeWithBuiltin(problem, MakeParameters(pose, camera.focal_length_px, camera.k),
                            &linear)) {
    return std::nullopt;
  }
  const Eigen::Index n = linear.hessian.rows();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(linear.hessian);
  if (2 * Eigen::Index(indices.size()) <= n || !lu.isInvertible()) return std::nullopt;
  const Eigen::MatrixXd inverse = lu.inverse();
  const Eigen::MatrixXd covariance = inverse * linear.scores * inverse;
  // Parameters: rotation increment d (R' = (I + 2 [d]x) R), t, f, k. The centre C = -R^T t
  // moves along the optical axis a = R^T e_z by a^T dC = -dt_z - 2 e_z^T [t]x d.
  const Eigen::Vector3d& t = pose.translation;
  Eigen::VectorXd depth = Eigen::VectorXd::Zero(n);
  depth(0) = 2.0 * t.y();
  depth(1) = -2.0 * t.x();
  depth(5) = -1.0;
  const Eigen::Index focal = 6;
  const double var_depth = depth.dot(covariance * depth);
  const double var_focal = covariance(focal, focal);
  if (!(var_depth > 0.0) || !(var_focal > 0.0)) return std::nullopt;
  FocalDepthUncertainty out;
  out.focal_std_px = std::sqrt(var_focal);
  out.depth_std = std::sqrt(var_depth);
  out.correlation =
      std::clamp(depth.dot(covariance.col(focal)) / (out.focal_std_px * out.depth_std), -1.0, 1.0);
  return out;
}

}  // namespace cwloc
