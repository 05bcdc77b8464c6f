#include "localizer/rig_localizer.h"

#include <cmath>

#include "base/error.h"
#include "base/stopwatch.h"
#include "camera/camera_models.h"
#include "localizer/pose/rig_pose.h"

namespace cwloc {
namespace {

// An image's quaternion may be off unit length by rounding in a text file, no more.
constexpr double kUnitQuaternionTolerance = 1e-6;

void ValidateRigQuery(const RigQuery& query) {
  const std::string frame = "frame '" + query.name + "'";
  if (query.images.empty()) throw InputError(frame + ": no images");
  if (query.unknown_scale && query.images.size() < 2)
    throw InputError(frame + ": an unknown scale needs at least two images");
  for (const RigImage& image : query.images) {
    const std::string where = frame + ", image '" + image.query.name + "'";
    if (image.query.camera.calibration == Calibration::kUnknown) {
      throw InputError(where +
                       ": a rig image needs its camera ('MODEL W H PARAMS') or a focal prior");
    }
    const CameraPose& pose = image.cam_from_rig;
    if (!pose.rotation.coeffs().allFinite() || !pose.translation.allFinite())
      throw InputError(where + ": cam_from_rig is not finite");
    if (std::abs(pose.rotation.norm() - 1.0) > kUnitQuaternionTolerance) {
      throw InputError(where + ": cam_from_rig's rotation is not a unit quaternion (norm " +
                       std::to_string(pose.rotation.norm()) + ")");
    }
  }
}

// The rig's view of an image: its camera as the pose stage takes it. A known camera's
// keypoints are undistorted by its model; a focal prior's are pixels from the image centre, its
// f the prior's, refined with the rig.
RigCamera CameraOf(const RigImage& image) {
  RigCamera camera;
  camera.cam_from_rig = image.cam_from_rig;
  const QueryCamera& q = image.query.camera;
  camera.camera = {MeanFocalLength(q.model_id, q.params), 0.0};
  camera.refine_intrinsics = !q.FocalKnown();
  return camera;
}

// Each image's correspondences, the paper's matching on it (forward matching, voting,
// back-matching) without its own pose stage, as the rig's observations.
struct RigMatches {
  std::vector<std::vector<FeatureMatch>> pairs;  // per image
  std::vector<RigCamera> cameras;
  std::vector<RigObservation> observations;
  std::vector<std::pair<uint32_t, uint32_t>> origin;  // (image, correspondence) per observation
  double extraction = 0.0;                            // the images' photo extraction, seconds
};

RigMatches MatchImages(const Localizer& localizer, const RigQuery& query,
                       const LocalizerOptions& options, RigResult* result) {
  const Index& index = localizer.index();
  LocalizerOptions image_options = options;
  image_options.estimate_pose = false;
  RigMatches matches;
  matches.pairs.resize(query.images.size());
  for (uint32_t c = 0; c < query.images.size(); ++c) {
    const RigImage& image = query.images[c];
    RigImageResult& out = result->images.emplace_back();
    out.name = image.query.name;
    // A camera that sees nothing (the sky, a blank wall) adds nothing; the others may.
    if (image.query.NumFeatures() > 0) {
      const LocalizationResult matched =
          localizer.Localize(image.query, image_options, nullptr, &matches.pairs[c]);
      out.num_features = matched.num_features;
      out.forward_matches = matched.forward_matches;
      out.back_matches = matched.back_matches;
      out.correspondences = matched.correspondences;
      matches.extraction += matched.times.extraction;
    }
    out.cam_from_rig = Transform{PoseOf(image.cam_from_rig)};
    matches.cameras.push_back(CameraOf(image));
    const QueryCamera& camera = image.query.camera;
    const std::array<double, 2> center = camera.ImageCenter();
    const std::vector<FeatureMatch>& pairs = matches.pairs[c];
    for (uint32_t k = 0; k < pairs.size(); ++k) {
      const std::array<double, 2> pixel = {image.query.keypoints[2 * pairs[k].feature],
                                           image.query.keypoints[2 * pairs[k].feature + 1]};
      RigObservation o;
      o.camera = c;
      if (camera.FocalKnown()) {
        std::array<double, 2> normalized;
        if (!PixelToNormalized(camera.model_id, camera.params, pixel, &normalized)) continue;
        o.pixel = matches.cameras.back().camera.focal_length_px *
                  Eigen::Vector2d(normalized[0], normalized[1]);
      } else {
        o.pixel = {pixel[0] - center[0], pixel[1] - center[1]};
      }
      const std::array<double, 3> xyz = index.PointXyz(index.view_points()[pairs[k].view]);
      o.point3D = {xyz[0], xyz[1], xyz[2]};
      matches.observations.push_back(o);
      matches.origin.push_back({c, k});
    }
  }
  return matches;
}

// A localized rig's pose into the result: the rig's, each image's and its inliers, the
// covariance and, on a georeferenced index, the reference camera on the globe.
void ReportRigPose(const Localizer& localizer, const RigQuery& query, const RigMatches& matches,
                   const RigPoseResult& pose, RigResult* result) {
  const Index& index = localizer.index();
  result->rig.rig_from_world = PoseOf(pose.pose.rig_from_world);
  result->rig.scale = pose.pose.scale;
  result->rig.scale_std = pose.scale_std;
  result->rig.refined = pose.refined;
  result->rig.mean_reprojection_error_px = pose.mean_reprojection_error_px;
  for (uint32_t c = 0; c < result->images.size(); ++c) {
    result->images[c].pose = PoseOf(pose.pose.CameraFromWorld(query.images[c].cam_from_rig));
    result->images[c].num_inliers = pose.inliers_per_camera[c];
  }
  result->pose = result->images.front().pose;
  for (size_t i = 0; i < matches.observations.size(); ++i) {
    if (!pose.inliers[i]) continue;
    const auto [c, k] = matches.origin[i];
    const FeatureMatch& match = matches.pairs[c][k];
    const uint32_t point = index.view_points()[match.view];
    const std::vector<float>& keypoints = query.images[c].query.keypoints;
    result->images[c].inliers.push_back(
        {match.feature,
         {keypoints[2 * match.feature], keypoints[2 * match.feature + 1]},
         point,
         index.PointXyz(point),
         match.view});
  }
  const CameraPose reference = pose.pose.CameraFromWorld(query.images.front().cam_from_rig);
  result->covariance = pose.covariance;
  if (result->covariance) {
    // The rig's covariance is the origin's, not a georeferenced camera's: no ENU block.
    ReportCovariance(index, std::nullopt, query.images.front().query.camera.calibration,
                     reference.Center(), &*result->covariance);
  }
  if (const std::optional<IndexGeo>& geo = localizer.geo())
    result->geo = geo->PoseOnGlobe(reference.rotation, reference.Center());
}

}  // namespace

RigResult LocalizeRig(const Localizer& localizer, const RigQuery& query,
                      const LocalizerOptions& options) {
  const Stopwatch total;
  ValidateRigQuery(query);
  RigResult result;
  result.name = query.name;
  result.rig.reference_image = query.images.front().query.name;
  result.rig.unknown_scale = query.unknown_scale;

  const Stopwatch images_time;
  const RigMatches matches = MatchImages(localizer, query, options, &result);
  result.times.images = images_time.Seconds() - matches.extraction;
  result.rig.correspondences = static_cast<uint32_t>(matches.observations.size());

  const Stopwatch pose_time;
  PoseContext context;
  context.ransac.seed = options.seed;
  const RigPoseResult pose = EstimateRigPose(matches.cameras, matches.observations,
                                             query.unknown_scale, options.pose, context);
  result.rig.num_inliers = static_cast<uint32_t>(pose.num_inliers);
  result.rig.ransac_iterations = pose.stats.iterations;
  result.success = pose.success;
  result.failure_reason = pose.failure_reason;
  if (matches.observations.empty()) result.failure_reason = "no image matched the model";
  for (uint32_t c = 0; c < result.images.size(); ++c) {
    QueryCamera camera = query.images[c].query.camera;
    if (matches.cameras[c].refine_intrinsics) {
      // A focal prior's camera as refined: SIMPLE_RADIAL (f, cx, cy, k).
      const std::array<double, 2> center = camera.ImageCenter();
      camera.model_id = CameraModelId::kSimpleRadial;
      camera.params = {pose.cameras[c].focal_length_px, center[0], center[1], pose.cameras[c].k};
    }
    result.images[c].camera = CameraUsedOf(camera);
  }
  if (pose.success) ReportRigPose(localizer, query, matches, pose, &result);
  result.times.rig_pose = pose_time.Seconds();
  result.times.total = total.Seconds();
  return result;
}

}  // namespace cwloc
