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

}  // namespace

RigLocalizationResult LocalizeRig(const Localizer& localizer, const RigQuery& query,
                                  const LocalizerOptions& options) {
  const Stopwatch total;
  ValidateRigQuery(query);
  const Index& index = localizer.index();
  RigLocalizationResult result;
  result.name = query.name;
  result.unknown_scale = query.unknown_scale;

  // Each image's correspondences: the paper's matching on it (forward matching, voting,
  // back-matching), without its own pose stage.
  LocalizerOptions image_options = options;
  image_options.keep_correspondences = true;
  image_options.estimate_pose = false;
  std::vector<RigCamera> cameras;
  std::vector<RigObservation> observations;
  std::vector<std::pair<uint32_t, uint32_t>> origin;  // (image, correspondence) per observation
  double extraction = 0.0;
  const Stopwatch images_time;
  for (uint32_t c = 0; c < query.images.size(); ++c) {
    const RigImage& image = query.images[c];
    RigImageResult& out = result.images.emplace_back();
    if (image.query.NumFeatures() == 0) {
      // A camera that sees nothing (the sky, a blank wall) adds nothing; the others may.
      out.matched.name = image.query.name;
      out.matched.failure_reason = "the image has no features";
    } else {
      out.matched = localizer.Localize(image.query, image_options);
    }
    out.cam_from_rig = image.cam_from_rig;
    extraction += out.matched.times.extraction;
    cameras.push_back(CameraOf(image));
    const QueryCamera& camera = image.query.camera;
    const std::array<double, 2> center = camera.ImageCenter();
    const std::vector<FeatureMatch>& pairs = out.matched.kept_correspondences;
    for (uint32_t k = 0; k < pairs.size(); ++k) {
      const std::array<double, 2> pixel = {image.query.keypoints[2 * pairs[k].feature],
                                           image.query.keypoints[2 * pairs[k].feature + 1]};
      RigObservation o;
      o.camera = c;
      if (camera.FocalKnown()) {
        std::array<double, 2> normalized;
        if (!PixelToNormalized(camera.model_id, camera.params, pixel, &normalized)) continue;
        o.pixel =
            cameras.back().camera.focal_length_px * Eigen::Vector2d(normalized[0], normalized[1]);
      } else {
        o.pixel = {pixel[0] - center[0], pixel[1] - center[1]};
      }
      const std::array<double, 3> xyz = index.PointXyz(index.view_points()[pairs[k].view]);
      o.point3D = {xyz[0], xyz[1], xyz[2]};
      observations.push_back(o);
      origin.push_back({c, k});
    }
  }
  result.seconds_images = images_time.Seconds() - extraction;
  result.correspondences = static_cast<uint32_t>(observations.size());

  const Stopwatch pose_time;
  PoseContext context;
  context.ransac.seed = options.seed;
  const RigPoseResult pose =
      EstimateRigPose(cameras, observations, query.unknown_scale, options.pose, context);
  result.num_inliers = static_cast<uint32_t>(pose.num_inliers);
  result.ransac_iterations = pose.stats.iterations;
  result.success = pose.success;
  result.failure_reason = pose.failure_reason;
  if (observations.empty()) {
    result.failure_reason = "no image matched the model";
  }
  for (uint32_t c = 0; c < result.images.size(); ++c) {
    RigImageResult& image = result.images[c];
    image.camera = query.images[c].query.camera;
    if (cameras[c].refine_intrinsics) {
      // A focal prior's camera as refined: SIMPLE_RADIAL (f, cx, cy, k).
      const std::array<double, 2> center = image.camera.ImageCenter();
      image.camera.model_id = CameraModelId::kSimpleRadial;
      image.camera.params = {pose.cameras[c].focal_length_px, center[0], center[1],
                             pose.cameras[c].k};
    }
  }
  if (pose.success) {
    result.rig_from_world = pose.pose.rig_from_world;
    result.scale = pose.pose.scale;
    result.scale_std = pose.scale_std;
    result.refined = pose.refined;
    result.mean_reprojection_error_px = pose.mean_reprojection_error_px;
    for (uint32_t c = 0; c < result.images.size(); ++c) {
      result.images[c].cam_from_world = pose.pose.CameraFromWorld(result.images[c].cam_from_rig);
      result.images[c].num_inliers = pose.inliers_per_camera[c];
    }
    for (size_t i = 0; i < observations.size(); ++i) {
      if (!pose.inliers[i]) continue;
      const auto [c, k] = origin[i];
      const FeatureMatch& match = result.images[c].matched.kept_correspondences[k];
      result.images[c].inliers.push_back(
          {match.feature, index.view_points()[match.view], match.view});
    }
    result.covariance = pose.covariance;
    if (result.covariance) {
      result.covariance_calibration = ApplyCovarianceCalibration(
          index.covariance_calibration(), query.images.front().query.camera.calibration,
          &*result.covariance);
    }
    if (const std::optional<IndexGeo>& geo = localizer.geo()) {
      const CameraPose& reference = *result.images.front().cam_from_world;
      result.geo = geo->PoseOnGlobe(reference.rotation, reference.Center());
    }
  }
  // The correspondences were the rig's input; the images' records need not carry them.
  if (!options.keep_correspondences) {
    for (RigImageResult& image : result.images) image.matched.kept_correspondences.clear();
  }
  result.seconds_rig_pose = pose_time.Seconds();
  result.seconds_total = total.Seconds();
  return result;
}

}  // namespace cwloc
