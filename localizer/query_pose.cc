#include "localizer/query_pose.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "camera/camera_models.h"

namespace cwloc {

std::vector<FeatureMatch> UniqueCorrespondences(const Index& index,
                                                std::vector<FeatureMatch> matches) {
  std::sort(matches.begin(), matches.end(), [](const FeatureMatch& a, const FeatureMatch& b) {
    // A total order: with ties left to std::sort, the kept view could differ between platforms.
    if (a.feature != b.feature) return a.feature < b.feature;
    return a.distance != b.distance ? a.distance < b.distance : a.view < b.view;
  });
  std::vector<FeatureMatch> unique;
  for (const FeatureMatch& match : matches) {
    // Views come from range-checked searches; their point is checked here, where it is read.
    if (match.view >= index.num_views() || index.view_points()[match.view] >= index.num_points())
      continue;
    if (!unique.empty() && unique.back().feature == match.feature) continue;
    unique.push_back(match);
  }
  return unique;
}

QueryPose EstimateQueryPose(const Index& index, const Query& query,
                            std::span<const FeatureMatch> correspondences,
                            const LocalizerOptions& options, PoseContext context) {
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  points2D.reserve(correspondences.size());
  points3D.reserve(correspondences.size());
  QueryPose result;
  result.used.reserve(correspondences.size());
  const QueryCamera& camera = query.camera;
  const std::array<double, 2> center = camera.ImageCenter();
  for (uint32_t i = 0; i < correspondences.size(); ++i) {
    const FeatureMatch& match = correspondences[i];
    const std::array<double, 2> pixel = {query.keypoints[2 * match.feature],
                                         query.keypoints[2 * match.feature + 1]};
    Eigen::Vector2d point2D;
    if (camera.FocalKnown()) {
      std::array<double, 2> normalized;
      if (!PixelToNormalized(camera.model_id, camera.params, pixel, &normalized)) continue;
      point2D = {normalized[0], normalized[1]};
    } else {
      point2D = {pixel[0] - center[0], pixel[1] - center[1]};
    }
    const std::array<double, 3> xyz = index.PointXyz(index.view_points()[match.view]);
    points2D.push_back(point2D);
    points3D.emplace_back(xyz[0], xyz[1], xyz[2]);
    result.used.push_back(i);
  }

  context.ransac.seed = options.seed;
  context.image_diagonal_px = std::hypot(double(camera.width), double(camera.height));
  switch (camera.calibration) {
    case Calibration::kKnown:
      result.pose =
          EstimateAbsolutePose(points2D, points3D, MeanFocalLength(camera.model_id, camera.params),
                               options.pose, context);
      break;
    case Calibration::kFocalPrior:
      result.pose = EstimateAbsolutePoseFocalPrior(points2D, points3D,
                                                   MeanFocalLength(camera.model_id, camera.params),
                                                   options.pose, context);
      break;
    case Calibration::kUnknown:
      result.pose = EstimateAbsolutePoseUnknownFocal(points2D, points3D, options.pose, context);
      break;
  }
  return result;
}

}  // namespace cwloc
