#include "localizer/pose/refine_pose.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>

namespace cwloc {
namespace {

// X_cam = R(q) X + t for a Ceres quaternion (w, x, y, z); false behind the camera, so that
// Ceres rejects the step rather than let the projection flip sign.
template <typename T>
bool PointInCamera(const T* q_wxyz, const T* t, const Eigen::Vector3d& point, T* z) {
  const T p[3] = {T(point(0)), T(point(1)), T(point(2))};
  ceres::UnitQuaternionRotatePoint(q_wxyz, p, z);
  z[0] += t[0];
  z[1] += t[1];
  z[2] += t[2];
  return z[2] > T(0.0);
}

struct ReprojectionCost {
  ReprojectionCost(const Eigen::Vector2d& pixel, const Eigen::Vector3d& point)
      : pixel_(pixel), point_(point) {}

  // q_wxyz in Ceres' order (w, x, y, z).
  template <typename T>
  bool operator()(const T* q_wxyz, const T* t, const T* focal, T* residuals) const {
    T z[3];
    if (!PointInCamera(q_wxyz, t, point_, z)) return false;
    residuals[0] = focal[0] * z[0] / z[2] - T(pixel_(0));
    residuals[1] = focal[0] * z[1] / z[2] - T(pixel_(1));
    return true;
  }

  Eigen::Vector2d pixel_;
  Eigen::Vector3d point_;
};

// The same with a SIMPLE_RADIAL camera: params = (f, k).
struct RadialReprojectionCost {
  RadialReprojectionCost(const Eigen::Vector2d& pixel, const Eigen::Vector3d& point)
      : pixel_(pixel), point_(point) {}

  template <typename T>
  bool operator()(const T* q_wxyz, const T* t, const T* focal, const T* k, T* residuals) const {
    T z[3];
    if (!PointInCamera(q_wxyz, t, point_, z)) return false;
    const T u = z[0] / z[2];
    const T v = z[1] / z[2];
    const T scale = focal[0] * (T(1.0) + k[0] * (u * u + v * v));
    residuals[0] = scale * u - T(pixel_(0));
    residuals[1] = scale * v - T(pixel_(1));
    return true;
  }

  Eigen::Vector2d pixel_;
  Eigen::Vector3d point_;
};

ceres::Solver::Options SolverOptions(int max_iterations) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = max_iterations;
  solver_options.function_tolerance = 1e-10;
  solver_options.parameter_tolerance = 1e-10;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  return solver_options;
}

// Solves the problem; the solution is usable when Ceres says so and camera_ok() holds.
template <typename CameraOk>
bool SolveRefinement(ceres::Problem* problem, int max_iterations, PoseRefinementSummary* summary,
                     CameraOk camera_ok) {
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(SolverOptions(max_iterations), problem, &ceres_summary);
  const bool usable = ceres_summary.IsSolutionUsable() && camera_ok();
  if (summary != nullptr) {
    summary->usable = usable;
    summary->iterations = static_cast<int>(ceres_summary.iterations.size());
    summary->initial_cost = ceres_summary.initial_cost;
    summary->final_cost = ceres_summary.final_cost;
  }
  return usable;
}

void StorePose(const double* q_wxyz, const double* t, CameraPose* pose) {
  pose->rotation = Eigen::Quaterniond(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]).normalized();
  pose->translation = Eigen::Vector3d(t[0], t[1], t[2]);
}

}  // namespace

bool RefinePose(std::span<const Eigen::Vector2d> centered_pixels,
                std::span<const Eigen::Vector3d> points3D, std::span<const uint32_t> indices,
                const PoseRefinementOptions& options, CameraPose* pose, double* focal_length_px,
                PoseRefinementSummary* summary) {
  const size_t min_points = options.refine_focal_length ? 5 : 4;
  if (indices.size() < min_points || !(*focal_length_px > 0.0)) return false;

  const Eigen::Quaterniond q = pose->rotation.normalized();
  double q_wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  double t[3] = {pose->translation(0), pose->translation(1), pose->translation(2)};
  double focal = *focal_length_px;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::CauchyLoss loss(options.loss_scale_px);
  ceres::LossFunction* loss_ptr = options.loss_scale_px > 0.0 ? &loss : nullptr;
  for (const uint32_t i : indices) {
    auto* cost = new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3, 1>(
        new ReprojectionCost(centered_pixels[i], points3D[i]));
    problem.AddResidualBlock(cost, loss_ptr, q_wxyz, t, &focal);
  }
  problem.SetManifold(q_wxyz, new ceres::QuaternionManifold);
  if (!options.refine_focal_length) problem.SetParameterBlockConstant(&focal);

  if (!SolveRefinement(&problem, options.max_iterations, summary, [&] { return focal > 0.0; }))
    return false;
  StorePose(q_wxyz, t, pose);
  *focal_length_px = focal;
  return true;
}

bool RefinePoseAndCamera(std::span<const Eigen::Vector2d> centered_pixels,
                         std::span<const Eigen::Vector3d> points3D,
                         std::span<const uint32_t> indices, const PoseRefinementOptions& options,
                         CameraPose* pose, RadialCamera* camera, PoseRefinementSummary* summary) {
  const size_t min_points =
      4 + size_t{options.refine_focal_length} + size_t{options.refine_radial_distortion};
  if (indices.size() < min_points || !(camera->focal_length_px > 0.0)) return false;

  const Eigen::Quaterniond q = pose->rotation.normalized();
  double q_wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  double t[3] = {pose->translation(0), pose->translation(1), pose->translation(2)};
  double focal = camera->focal_length_px;
  double k = camera->k;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::CauchyLoss loss(options.loss_scale_px);
  ceres::LossFunction* loss_ptr = options.loss_scale_px > 0.0 ? &loss : nullptr;
  for (const uint32_t i : indices) {
    auto* cost = new ceres::AutoDiffCostFunction<RadialReprojectionCost, 2, 4, 3, 1, 1>(
        new RadialReprojectionCost(centered_pixels[i], points3D[i]));
    problem.AddResidualBlock(cost, loss_ptr, q_wxyz, t, &focal, &k);
  }
  problem.SetManifold(q_wxyz, new ceres::QuaternionManifold);
  if (!options.refine_focal_length) problem.SetParameterBlockConstant(&focal);
  if (!options.refine_radial_distortion) problem.SetParameterBlockConstant(&k);

  if (!SolveRefinement(&problem, options.max_iterations, summary,
                       [&] { return focal > 0.0 && std::isfinite(k); }))
    return false;
  StorePose(q_wxyz, t, pose);
  camera->focal_length_px = focal;
  camera->k = k;
  return true;
}

}  // namespace cwloc
