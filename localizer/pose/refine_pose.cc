#include "localizer/pose/refine_pose.h"

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
  RefinementProblem problem = MakeProblem(centered_pixels, points3D, indices, options);
  problem.radial = true;
  problem.refine_radial_distortion = options.refine_radial_distortion;
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

}  // namespace cwloc
