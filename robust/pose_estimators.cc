#include "robust/pose_estimators.h"

#include <algorithm>
#include <array>

#include "solvers/gravity_p2p.h"
#include "solvers/p3p.h"
#include "solvers/p4pf.h"

namespace cwloc {
namespace {

void CollectInliers(std::span<const Eigen::Vector2d> points2D,
                    std::span<const Eigen::Vector3d> points3D, const CameraPose& pose, double f,
                    double max_sq, std::vector<uint32_t>* inliers) {
  inliers->clear();
  const Eigen::Matrix3d rot = pose.rotation.toRotationMatrix();
  for (size_t i = 0; i < points2D.size(); ++i) {
    const Eigen::Vector3d z = rot * points3D[i] + pose.translation;
    if (z(2) > 0.0 && (f * z.hnormalized() - points2D[i]).squaredNorm() < max_sq) {
      inliers->push_back(static_cast<uint32_t>(i));
    }
  }
}

}  // namespace

ScoringColumns::ScoringColumns(std::span<const Eigen::Vector2d> points2D,
                               std::span<const Eigen::Vector3d> points3D) {
  const size_t n = std::min(points2D.size(), points3D.size());
  for (std::vector<double>* column : {&x, &y, &z, &u, &v}) column->resize(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = points3D[i](0), y[i] = points3D[i](1), z[i] = points3D[i](2);
    u[i] = points2D[i](0), v[i] = points2D[i](1);
  }
}

void Thin(uint32_t max_points, std::vector<uint32_t>* inliers) {
  if (max_points == 0 || inliers->size() <= max_points) return;
  const size_t stride = (inliers->size() + max_points - 1) / max_points;
  size_t kept = 0;
  for (size_t i = 0; i < inliers->size(); i += stride) (*inliers)[kept++] = (*inliers)[i];
  inliers->resize(kept);
}

// The score is the plain loop's to the bit; most of RANSAC's wrong hypotheses are dropped after
// a block or two.
double MsacScore(const ScoringColumns& points, const CameraPose& pose, double f, double max_sq,
                 double bound, uint32_t* num_inliers) {
  const Eigen::Matrix3d rot = pose.rotation.toRotationMatrix();
  const double r00 = rot(0, 0), r01 = rot(0, 1), r02 = rot(0, 2);
  const double r10 = rot(1, 0), r11 = rot(1, 1), r12 = rot(1, 2);
  const double r20 = rot(2, 0), r21 = rot(2, 1), r22 = rot(2, 2);
  const double t0 = pose.translation(0), t1 = pose.translation(1), t2 = pose.translation(2);
  const double* x = points.x.data();
  const double* y = points.y.data();
  const double* z = points.z.data();
  const double* u = points.u.data();
  const double* v = points.v.data();
  constexpr size_t kBlock = 64;
  double errors[kBlock], depths[kBlock];
  double score = 0.0;
  uint32_t inliers = 0;
  const size_t n = points.x.size();
  for (size_t begin = 0; begin < n; begin += kBlock) {
    const size_t count = std::min(kBlock, n - begin);
    for (size_t i = 0; i < count; ++i) {
      const size_t k = begin + i;
      const double cx = r00 * x[k] + r01 * y[k] + r02 * z[k] + t0;
      const double cy = r10 * x[k] + r11 * y[k] + r12 * z[k] + t1;
      const double cz = r20 * x[k] + r21 * y[k] + r22 * z[k] + t2;
      const double inv_z = f / cz;
      const double dx = cx * inv_z - u[k];
      const double dy = cy * inv_z - v[k];
      errors[i] = dx * dx + dy * dy;
      depths[i] = cz;
    }
    for (size_t i = 0; i < count; ++i) {
      if (depths[i] > 0.0 && errors[i] < max_sq) {
        score += errors[i];
        ++inliers;
      } else {
        score += max_sq;
      }
    }
    if (score >= bound) break;
  }
  *num_inliers = inliers;
  return score;
}

namespace {

bool PassesGravityCheck(const std::optional<GravityCheck>& check, const CameraPose& pose) {
  return !check.has_value() ||
         GravityAngle(pose.RotationMatrix(), check->in_world, check->in_camera) <= check->max_angle;
}

std::vector<Eigen::Vector3d> Bearings(std::span<const Eigen::Vector2d> points2D) {
  std::vector<Eigen::Vector3d> bearings;
  bearings.reserve(points2D.size());
  for (const Eigen::Vector2d& x : points2D) bearings.push_back(x.homogeneous().normalized());
  return bearings;
}

}  // namespace

AbsolutePoseEstimator::AbsolutePoseEstimator(std::span<const Eigen::Vector2d> points2D,
                                             std::span<const Eigen::Vector3d> points3D,
                                             double max_error,
                                             const LocalOptimizationOptions& lo_options,
                                             const std::optional<GravityCheck>& gravity_check)
    : points2D_(points2D),
      points3D_(points3D),
      bearings_(Bearings(points2D)),
      columns_(points2D, points3D),
      max_error_sq_(max_error * max_error),
      lo_options_(lo_options),
      gravity_check_(gravity_check) {}

void AbsolutePoseEstimator::GenerateModels(std::span<const uint32_t> sample,
                                           std::vector<Model>* models) const {
  const std::array<Eigen::Vector3d, 3> bearings = {bearings_[sample[0]], bearings_[sample[1]],
                                                   bearings_[sample[2]]};
  const std::array<Eigen::Vector3d, 3> points = {points3D_[sample[0]], points3D_[sample[1]],
                                                 points3D_[sample[2]]};
  P3P(bearings, points, models);
  if (gravity_check_.has_value()) {
    std::erase_if(*models,
                  [&](const Model& pose) { return !PassesGravityCheck(gravity_check_, pose); });
  }
}

double AbsolutePoseEstimator::Score(const Model& model, uint32_t* num_inliers, double bound) const {
  return MsacScore(columns_, model, 1.0, max_error_sq_, bound, num_inliers);
}

void AbsolutePoseEstimator::Refine(Model* model) const {
  Inliers(*model, &scratch_);
  if (scratch_.size() <= kSampleSize) return;  // the minimal solution is already exact
  Thin(lo_options_.max_points, &scratch_);
  OptimizePose(points2D_, points3D_, scratch_, lo_options_, model);
}

void AbsolutePoseEstimator::Inliers(const Model& model, std::vector<uint32_t>* inliers) const {
  CollectInliers(points2D_, points3D_, model, 1.0, max_error_sq_, inliers);
}

GravityPoseEstimator::GravityPoseEstimator(std::span<const Eigen::Vector2d> points2D,
                                           std::span<const Eigen::Vector3d> points3D,
                                           double max_error,
                                           const Eigen::Vector3d& gravity_in_camera,
                                           const Eigen::Vector3d& gravity_in_world,
                                           double lo_window,
                                           const LocalOptimizationOptions& lo_options)
    : points2D_(points2D),
      points3D_(points3D),
      bearings_(Bearings(points2D)),
      columns_(points2D, points3D),
      max_error_sq_(max_error * max_error),
      lo_window_sq_(std::max(lo_window, max_error) * std::max(lo_window, max_error)),
      gravity_in_camera_(gravity_in_camera),
      gravity_in_world_(gravity_in_world),
      lo_options_(lo_options) {}

void GravityPoseEstimator::GenerateModels(std::span<const uint32_t> sample,
                                          std::vector<Model>* models) const {
  const std::array<Eigen::Vector3d, 2> bearings = {bearings_[sample[0]], bearings_[sample[1]]};
  const std::array<Eigen::Vector3d, 2> points = {points3D_[sample[0]], points3D_[sample[1]]};
  GravityP2P(bearings, points, gravity_in_camera_, gravity_in_world_, models);
}

double GravityPoseEstimator::Score(const Model& model, uint32_t* num_inliers, double bound) const {
  return MsacScore(columns_, model, 1.0, max_error_sq_, bound, num_inliers);
}

void GravityPoseEstimator::Refine(Model* model) const {
  CollectInliers(points2D_, points3D_, *model, 1.0, lo_window_sq_, &scratch_);
  if (scratch_.size() <= kSampleSize) return;  // the minimal solution is already exact
  Thin(lo_options_.max_points, &scratch_);
  OptimizePose(points2D_, points3D_, scratch_, lo_options_, model);
}

void GravityPoseEstimator::Inliers(const Model& model, std::vector<uint32_t>* inliers) const {
  CollectInliers(points2D_, points3D_, model, 1.0, max_error_sq_, inliers);
}

AbsolutePoseFocalEstimator::AbsolutePoseFocalEstimator(
    std::span<const Eigen::Vector2d> centered_pixels, std::span<const Eigen::Vector3d> points3D,
    double max_error_px, double min_focal_px, double max_focal_px,
    const LocalOptimizationOptions& lo_options, const std::optional<GravityCheck>& gravity_check)
    : points2D_(centered_pixels),
      points3D_(points3D),
      columns_(centered_pixels, points3D),
      max_error_sq_(max_error_px * max_error_px),
      min_focal_(min_focal_px),
      max_focal_(max_focal_px),
      lo_options_(lo_options),
      gravity_check_(gravity_check) {}

void AbsolutePoseFocalEstimator::GenerateModels(std::span<const uint32_t> sample,
                                                std::vector<Model>* models) const {
  std::array<Eigen::Vector2d, 4> image;
  std::array<Eigen::Vector3d, 4> world;
  for (int i = 0; i < 4; ++i) {
    image[i] = points2D_[sample[i]];
    world[i] = points3D_[sample[i]];
  }
  P4Pf(image, world, &pose_scratch_, &focal_scratch_);
  models->clear();
  for (size_t k = 0; k < pose_scratch_.size(); ++k) {
    const double f = focal_scratch_[k];
    if (f >= min_focal_ && f <= max_focal_ &&
        PassesGravityCheck(gravity_check_, pose_scratch_[k])) {
      models->push_back({pose_scratch_[k], f});
    }
  }
}

double AbsolutePoseFocalEstimator::Score(const Model& model, uint32_t* num_inliers,
                                         double bound) const {
  return MsacScore(columns_, model.pose, model.focal_length, max_error_sq_, bound, num_inliers);
}

void AbsolutePoseFocalEstimator::Refine(Model* model) const {
  Inliers(*model, &scratch_);
  if (scratch_.size() <= kSampleSize) return;
  Thin(lo_options_.max_points, &scratch_);
  PoseAndFocal refined = *model;
  OptimizePoseAndFocal(points2D_, points3D_, scratch_, lo_options_, &refined.pose,
                       &refined.focal_length);
  if (refined.focal_length >= min_focal_ && refined.focal_length <= max_focal_) *model = refined;
}

void AbsolutePoseFocalEstimator::Inliers(const Model& model, std::vector<uint32_t>* inliers) const {
  CollectInliers(points2D_, points3D_, model.pose, model.focal_length, max_error_sq_, inliers);
}

}  // namespace cwloc
