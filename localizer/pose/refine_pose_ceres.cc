// The Ceres refiner of refine_pose.h; compiled only with -DCWLOC_WITH_CERES=ON.
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "localizer/pose/refine_pose_solver.h"
#include "localizer/pose/reprojection_residual.h"

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
    PinholeResidual(z, focal[0], pixel_, residuals);
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
    RadialResidual(z, focal[0], k[0], pixel_, residuals);
    return true;
  }

  Eigen::Vector2d pixel_;
  Eigen::Vector3d point_;
};

// A gravity prior: weight * (R(q) in_world - in_camera), on the rotation only.
struct GravityCost {
  explicit GravityCost(const GravityConstraint& gravity) : gravity_(gravity) {}

  template <typename T>
  bool operator()(const T* q_wxyz, T* residuals) const {
    const T p[3] = {T(gravity_.in_world(0)), T(gravity_.in_world(1)), T(gravity_.in_world(2))};
    T y[3];
    ceres::UnitQuaternionRotatePoint(q_wxyz, p, y);
    for (int i = 0; i < 3; ++i)
      residuals[i] = T(gravity_.weight) * (y[i] - T(gravity_.in_camera(i)));
    return true;
  }

  GravityConstraint gravity_;
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

}  // namespace

bool RefineWithCeres(const RefinementProblem& problem, RefinementParameters* parameters,
                     PoseRefinementSummary* summary) {
  RefinementParameters x = *parameters;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres::CauchyLoss loss(problem.loss_scale_px);
  ceres::LossFunction* loss_ptr = problem.loss_scale_px > 0.0 ? &loss : nullptr;
  for (const uint32_t i : problem.indices) {
    if (problem.radial) {
      auto* cost = new ceres::AutoDiffCostFunction<RadialReprojectionCost, 2, 4, 3, 1, 1>(
          new RadialReprojectionCost(problem.pixels[i], problem.points3D[i]));
      ceres_problem.AddResidualBlock(cost, loss_ptr, x.q_wxyz, x.t, &x.focal, &x.k);
    } else {
      auto* cost = new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3, 1>(
          new ReprojectionCost(problem.pixels[i], problem.points3D[i]));
      ceres_problem.AddResidualBlock(cost, loss_ptr, x.q_wxyz, x.t, &x.focal);
    }
  }
  if (problem.gravity.has_value()) {
    ceres_problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<GravityCost, 3, 4>(new GravityCost(*problem.gravity)),
        nullptr, x.q_wxyz);
  }
  ceres_problem.SetManifold(x.q_wxyz, new ceres::QuaternionManifold);
  if (!problem.refine_focal_length) ceres_problem.SetParameterBlockConstant(&x.focal);
  if (problem.radial && !problem.refine_radial_distortion) {
    ceres_problem.SetParameterBlockConstant(&x.k);
  }

  ceres::Solver::Summary ceres_summary;
  ceres::Solve(SolverOptions(problem.max_iterations), &ceres_problem, &ceres_summary);
  summary->usable = ceres_summary.IsSolutionUsable();
  summary->iterations = static_cast<int>(ceres_summary.iterations.size());
  summary->initial_cost = ceres_summary.initial_cost;
  summary->final_cost = ceres_summary.final_cost;
  if (summary->usable) *parameters = x;
  return summary->usable;
}

}  // namespace cwloc
